//! The walk over step sequences that the beam tree does not cover: sequences with refractions
//! and, when `vertex` arrivals are asked for, reflect-only sequences through interfaces with
//! vertices (their edge-held arrivals; the tree lists their specular ones): what
//! `strategy.rs` gives the walk, asked per sequence. Each is searched
//! completely (`Tracer::stationary_of`, at most [`MAX_STATIONARY_STEPS`] steps) per (source,
//! receiver) pair, depth first, each prefix pruned where no extension can hold a path:
//!
//! - **Repeats.** A reflection off the one-segment interface of the reflection before it has
//!   its two points on one line: no path (with straight legs; an arc may leave a line and
//!   turn back to it).
//! - **Media.** Each leg's possible media, as a set: the source's medium first; a reflection
//!   keeps the set; a refraction at interface `I` takes every medium across `I` from one in
//!   the set (the pairs of media on `I`'s sides). This is the rule by which the complete
//!   search enumerates a sequence's media, so an empty set means that the search of the
//!   sequence, and of every sequence it begins, has nothing to search.
//! - **Need.** A reflect-only prefix (which the beam tree covers) is extended only where a
//!   refraction can still follow (some allowed interface has a medium across from one in the
//!   set) or `vertex` arrivals are asked for and an allowed interface has vertices: where
//!   some extension is the walk's (`strategy.rs`, `walk_may_extend`).
//! - **Time.** For a prefix of steps at interfaces `I₁ … I_k` with leg media sets
//!   `S₀ … S_k`, every path that begins with it takes at least
//!   `w(S₀)·d(s, B₁) + Σ w(Sᵢ)·d(Bᵢ, Bᵢ₊₁) + w_min·d(B_k, r)`, with `Bᵢ` the bounding box of
//!   `Iᵢ`, `w(S)` the least slowness in `S`, `w_min` the least of every medium, and `d` the
//!   distance between boxes (or from a point to a box): leg `i` runs from a point of `Bᵢ` to
//!   a point of `Bᵢ₊₁` in a medium of `Sᵢ`, and whatever follows the point on `I_k` reaches
//!   the receiver. The bound holds for every extension of the prefix, so a prefix whose bound
//!   exceeds `max_time` (by more than its round-off) is pruned with everything below it.
//!   Each term is the leg model's lower bound (`LegModel::least_time`, `leg.rs`) of the
//!   fastest medium of the set: for uniform media, slowness times distance.
//!
//! In a scene with curved legs (a medium with a gradient) the walk takes every sequence, the
//! direct ray and the reflect-only ones too (`strategy.rs`: no image method through arcs),
//! and the time bound is the leg model's per medium: leg `i` the least over the media of
//! `Sᵢ` of each medium's `least_time(Bᵢ, Bᵢ₊₁)` (an arc's time grows with its chord and falls
//! with the speeds at its ends, at most the greatest over each box's corners), and the
//! last term the least time of a last leg: from `B_k` in a medium of `S_k` (the sequence
//! itself), or from the box of any allowed interface in any medium (an extension), to the
//! receiver. Each sequence is then searched by [`Tracer::curved_paths_of`] (Newton from a grid
//! of starts, the media looked up), which is no proof: such a pair says `complete: false`.
//!
//! The work, counted against the scene's `solver.max_work` per pair, is one per sequence
//! visited plus the work units of each complete search (what that budget counts: points moved
//! by Newton steps and weighed in bounds); each complete search gets what is left of it. A pair whose walk stops at that limit, or at
//! [`MAX_STATIONARY_STEPS`] with longer sequences allowed and still possible, or whose
//! complete search of some sequence is itself incomplete, says `complete: false`.

use rayon::prelude::*;

use crate::geom::{Aabb, Point};
use crate::leg::{LegMedium, LegModel, Uniform};
use crate::options::{Progress, Run};
use crate::scene::{MAX_STATIONARY_STEPS, SearchOptions, Step, StepKind};
use crate::trace::{Arrival, SearchBudget, Sequence, Status, Tracer};

use super::strategy::{Claim, Shape, Strategy, walk_may_extend};
use super::{ArrivalCount, Control, SearchArrival, StreamedArrival};

/// A set of media as bits (media beyond 128 are not told apart: [`MediaSets`] then keeps
/// every set full).
type MediaSet = u128;

/// Media sets are exact up to this many media.
const MAX_SET_MEDIA: usize = 128;

/// The prefix bound's relative margin: far more than its round-off.
const TIME_MARGIN: f64 = 1e-9;

/// The media-set rules of the scene's interfaces.
#[derive(Clone, Debug)]
struct MediaSets {
    /// Per interface (scene index), per medium `m`: the media across from `m`.
    across: Vec<Vec<MediaSet>>,
    /// Per medium: its slowness.
    slowness: Vec<f64>,
    /// Per medium, in a scene with curved legs: its leg model (absolute positions); empty
    /// otherwise.
    models: Vec<LegMedium<'static>>,
    /// Whether the sets are exact (at most [`MAX_SET_MEDIA`] media); otherwise every set is
    /// taken as full.
    exact: bool,
}

impl MediaSets {
    fn new(tracer: &Tracer) -> MediaSets {
        let scene = tracer.scene();
        let media = scene.media().len();
        let exact = media <= MAX_SET_MEDIA;
        let across = (0..scene.interfaces().len())
            .map(|i| {
                let mut across = vec![0 as MediaSet; media.min(MAX_SET_MEDIA)];
                if exact {
                    for s in tracer.interface_sides(i) {
                        if let (Some(l), Some(r)) = (s.left, s.right) {
                            across[l] |= 1 << r;
                            across[r] |= 1 << l;
                        }
                    }
                }
                across
            })
            .collect();
        let models = if scene.curved() {
            let origin = Point::new(0.0, 0.0);
            scene.media().iter().map(|m| m.leg_model(origin)).collect()
        } else {
            Vec::new()
        };
        MediaSets {
            across,
            slowness: scene.media().iter().map(|m| m.slowness).collect(),
            models,
            exact,
        }
    }

    /// The set of the one medium `m`.
    fn only(&self, m: usize) -> MediaSet {
        if self.exact { 1 << m } else { MediaSet::MAX }
    }

    /// The media a leg after `step` may have, from a leg in `set`.
    fn after(&self, set: MediaSet, step: Step) -> MediaSet {
        if !self.exact || step.kind == StepKind::Reflect {
            return set;
        }
        let mut out = 0;
        let mut rest = set;
        while rest != 0 {
            let m = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            out |= self.across[step.interface][m];
        }
        out
    }

    /// The media of `set`, by index.
    fn members(&self, set: MediaSet) -> impl Iterator<Item = usize> + '_ {
        let n = self.slowness.len();
        (0..n).filter(move |&m| !self.exact || set & (1 << m) != 0)
    }

    /// The least time of a leg in a medium of `set` (curved legs: each medium's model) from
    /// a point of `from` to a point of `to`.
    fn least_leg(&self, set: MediaSet, from: Aabb, to: Aabb) -> f64 {
        if self.models.is_empty() {
            return Uniform::new(self.least(set)).least_time(from, to);
        }
        self.members(set)
            .map(|m| self.models[m].least_time(from, to))
            .fold(f64::INFINITY, f64::min)
    }

    /// The least time of a leg in a medium of `set` (curved legs: each medium's model) from
    /// a point of `from` to `to`.
    fn least_leg_to(&self, set: MediaSet, from: Aabb, to: Point) -> f64 {
        if self.models.is_empty() {
            return Uniform::new(self.least(set)).least_time_to(from, to);
        }
        self.members(set)
            .map(|m| self.models[m].least_time_to(from, to))
            .fold(f64::INFINITY, f64::min)
    }

    /// The least slowness of a medium in `set`.
    fn least(&self, set: MediaSet) -> f64 {
        if !self.exact {
            return self.slowness.iter().copied().fold(f64::INFINITY, f64::min);
        }
        let mut least = f64::INFINITY;
        let mut rest = set;
        while rest != 0 {
            let m = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            least = least.min(self.slowness[m]);
        }
        least
    }
}

/// The walk's view of the scene, built once per search: the step choices and the rules of
/// its pruning.
struct Walk<'a> {
    tracer: &'a Tracer,
    options: &'a SearchOptions,
    /// The steps a sequence may take next, in a fixed order.
    choices: Vec<Step>,
    media: MediaSets,
    /// Per interface (scene index): its bounding box.
    boxes: Vec<Aabb>,
    /// Per interface: whether it has a vertex a path can be held on (a closed polyline, or an
    /// open one of two or more segments).
    has_vertices: Vec<bool>,
    /// The least slowness of every medium.
    least: f64,
    /// Whether `vertex` arrivals are asked for and some allowed reflection is off an
    /// interface with vertices.
    vertex_reflections: bool,
    /// Whether the scene has curved legs (the walk then takes every sequence).
    curved: bool,
    /// The deepest sequence walked: `max_steps`, at most [`MAX_STATIONARY_STEPS`].
    depth: usize,
    /// Work per pair before the walk stops.
    max_work: u64,
    /// The arrivals listed over the whole search.
    listed: &'a ArrivalCount,
    /// The search's run: each sequence visited is a unit of its work.
    run: &'a Run,
    /// Where each arrival goes when the search streams them.
    sink: Option<&'a dyn super::ArrivalSink>,
    /// Where each arrival goes with its points, when the search expands them (`extruded.rs`).
    paths: Option<&'a (dyn Fn(SearchArrival) -> bool + Sync)>,
}

/// One pair's walk: its arrivals and what it did.
pub(super) struct PairWalk {
    /// The arrivals listed (their `complete` is the caller's to set).
    pub arrivals: Vec<SearchArrival>,
    /// Whether the walk covered every sequence it had to.
    pub complete: bool,
    /// Sequences visited plus the work units of their complete searches.
    pub work: u64,
}

impl PairWalk {
    /// A pair the run refused before its walk began: nothing listed, not complete.
    pub(super) fn not_begun() -> Self {
        PairWalk {
            arrivals: Vec::new(),
            complete: false,
            work: 0,
        }
    }
}

/// What the walk knows of a prefix of steps.
#[derive(Clone, Copy, Debug)]
struct Prefix {
    /// The media its last leg may have.
    set: MediaSet,
    /// The bound on its legs before the last (the module's sum without its last term).
    bound: f64,
    /// The box its last leg starts in (the source's point at first).
    from: Aabb,
    /// What it is made of: which strategy lists what of it (`strategy.rs`).
    shape: Shape,
}

/// The state of one pair's walk.
struct PairState<'w> {
    walk: &'w Walk<'w>,
    source: usize,
    receiver: usize,
    s: Point,
    r: Point,
    /// With curved legs: the least time of a last leg from any allowed interface to the
    /// receiver, in any medium (the bound of what an extension adds); 0 otherwise.
    last: f64,
    medium: usize,
    steps: Vec<Step>,
    found: Vec<Arrival>,
    out: PairWalk,
    /// Whether the walk stopped at a limit.
    stopped: bool,
}

impl Tracer {
    /// The walk over sequences of every pair that needs it, in parallel: (pair index, walk).
    pub(super) fn walks(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> Vec<(usize, PairWalk)> {
        let scene = self.scene();
        let mut walk = Walk::new(self, options, control.listed, control.run);
        walk.sink = control.sink;
        walk.paths = control.paths;
        let nr = scene.receivers().len();
        let media: Vec<Option<usize>> = scene
            .sources()
            .iter()
            .map(|&s| self.source_medium(false, s))
            .collect();
        let needed: Vec<usize> = (0..scene.sources().len() * nr)
            .filter(|&pair| media[pair / nr].is_some_and(|m| walk.needed(m)))
            .collect();
        // No pair to walk (a reflect-only search, the beam trees' alone): no work for the
        // thread pool, which is then not started for nothing.
        if needed.is_empty() {
            return Vec::new();
        }
        needed
            .into_par_iter()
            .map(|pair| {
                let (source, receiver) = (pair / nr, pair % nr);
                let medium = media[source].expect("a pair that needs the walk has a medium");
                let begun = control.run.keep_going(Progress { work: 0, items: 1 });
                let found = if begun {
                    walk.pair(source, receiver, medium)
                } else {
                    PairWalk::not_begun()
                };
                (pair, found)
            })
            .collect()
    }
}

impl<'a> Walk<'a> {
    fn new(
        tracer: &'a Tracer,
        options: &'a SearchOptions,
        listed: &'a ArrivalCount,
        run: &'a Run,
    ) -> Walk<'a> {
        let scene = tracer.scene();
        let mut choices = Vec::new();
        for &interface in &options.interfaces {
            if options.reflect {
                choices.push(Step {
                    kind: StepKind::Reflect,
                    interface,
                });
            }
            if options.refract {
                choices.push(Step {
                    kind: StepKind::Refract,
                    interface,
                });
            }
        }
        let media = MediaSets::new(tracer);
        let has_vertices: Vec<bool> = scene
            .interfaces()
            .iter()
            .map(|i| i.polyline.is_closed() || i.polyline.num_segments() > 1)
            .collect();
        let vertex_reflections = options.vertex
            && choices
                .iter()
                .any(|c| c.kind == StepKind::Reflect && has_vertices[c.interface]);
        Walk {
            tracer,
            options,
            least: media.slowness.iter().copied().fold(f64::INFINITY, f64::min),
            choices,
            media,
            boxes: scene
                .interfaces()
                .iter()
                .map(|i| i.polyline.bbox())
                .collect(),
            has_vertices,
            vertex_reflections,
            curved: scene.curved(),
            depth: options.step_limit().min(MAX_STATIONARY_STEPS),
            max_work: scene.solver().max_work,
            listed,
            run,
            sink: None,
            paths: None,
        }
    }

    /// Whether a pair whose source lies in `medium` needs the walk.
    fn needed(&self, medium: usize) -> bool {
        self.curved
            || (self.depth > 0
                && (self.can_refract(self.media.only(medium)) || self.vertex_reflections))
    }

    /// Whether a refraction is allowed and possible from a leg in `set`.
    fn can_refract(&self, set: MediaSet) -> bool {
        self.choices
            .iter()
            .any(|&c| c.kind == StepKind::Refract && self.media.after(set, c) != 0)
    }

    /// The walk of one pair, `medium` the source's.
    fn pair(&self, source: usize, receiver: usize, medium: usize) -> PairWalk {
        let scene = self.tracer.scene();
        let s = scene.sources()[source];
        let r = scene.receivers()[receiver];
        let last = if self.curved {
            let all = MediaSet::MAX;
            (self.choices.iter())
                .map(|c| self.media.least_leg_to(all, self.boxes[c.interface], r))
                .fold(f64::INFINITY, f64::min)
        } else {
            0.0
        };
        let mut state = PairState {
            walk: self,
            source,
            receiver,
            s,
            r,
            last,
            medium,
            steps: Vec::with_capacity(self.depth),
            found: Vec::new(),
            out: PairWalk {
                arrivals: Vec::new(),
                complete: true,
                work: 0,
            },
            stopped: false,
        };
        state.extend(Prefix {
            set: self.media.only(medium),
            bound: 0.0,
            from: Aabb::from_points(s, s),
            shape: Shape {
                curved: self.curved,
                ..Shape::default()
            },
        });
        state.out.complete &= !state.stopped;
        state.out
    }

    /// The prefix after `prefix` takes `step`, if some path may begin with it.
    fn child(
        &self,
        prefix: &Prefix,
        last: Option<Step>,
        step: Step,
        r: Point,
        extension: f64,
    ) -> Option<Prefix> {
        let interfaces = self.tracer.scene().interfaces();
        // Through arcs a leg may leave a line and turn back to it (a duct): no repeat rule.
        let repeat = !self.curved
            && last.is_some_and(|l| {
                l.interface == step.interface
                    && l.kind == StepKind::Reflect
                    && step.kind == StepKind::Reflect
                    && interfaces[step.interface].polyline.num_segments() == 1
            });
        if repeat {
            return None;
        }
        let set = self.media.after(prefix.set, step);
        if set == 0 {
            return None;
        }
        let shape = prefix.shape.then(step, &self.has_vertices);
        if !walk_may_extend(shape, self.vertex_reflections, || self.can_refract(set)) {
            return None;
        }
        let to = self.boxes[step.interface];
        // The leg model's bounds: the least slowness's legs are the fastest.
        let bound = prefix.bound + self.media.least_leg(prefix.set, prefix.from, to);
        let rest = if self.curved {
            // The sequence's own last leg, or an extension's (`extension`).
            self.media.least_leg_to(set, to, r).min(extension)
        } else {
            Uniform::new(self.least).least_time_to(to, r)
        };
        if let Some(t) = self.options.max_time
            && (bound + rest) * (1.0 - TIME_MARGIN) > t
        {
            return None;
        }
        Some(Prefix {
            set,
            bound,
            from: to,
            shape,
        })
    }
}

impl PairState<'_> {
    /// Searches the sequence in `steps` (begun by `prefix`), then every extension of it.
    fn extend(&mut self, prefix: Prefix) {
        let walk = self.walk;
        let k = self.steps.len();
        let claim = Claim::of(Strategy::Walk, prefix.shape, walk.options);
        if (k > 0 || walk.curved) && claim.any() {
            self.search(claim);
        }
        self.out.work += 1;
        if self.out.work > walk.max_work || !walk.run.keep_going(Progress::work(1)) {
            self.stopped = true;
        }
        if self.stopped || k == walk.options.step_limit() {
            return;
        }
        for c in 0..walk.choices.len() {
            let step = walk.choices[c];
            let last = self.steps.last().copied();
            let Some(next) = walk.child(&prefix, last, step, self.r, self.last) else {
                continue;
            };
            if k == walk.depth {
                // A possible sequence longer than the complete search takes.
                self.stopped = true;
                return;
            }
            self.steps.push(step);
            self.extend(next);
            self.steps.pop();
            if self.stopped {
                return;
            }
        }
    }

    /// The complete search of the sequence in `steps`: its listed arrivals of the kinds the
    /// walk claims (`claim`: a reflect-only sequence's specular arrivals are the beam tree's)
    /// by `max_time`.
    fn search(&mut self, claim: Claim) {
        let walk = self.walk;
        let options = walk.options;
        let sequence = Sequence {
            steps: &self.steps,
            path: None,
            curved: &[],
        };
        let left = walk.max_work.saturating_sub(self.out.work);
        let budget = SearchBudget {
            tuples: walk.run.limits.walk_tuples,
            work: usize::try_from(left).unwrap_or(usize::MAX),
        };
        let outcome = if walk.curved {
            walk.tracer.curved_paths_of(
                &self.steps,
                None,
                self.s,
                Some(self.medium),
                self.r,
                budget,
                walk.run,
                &mut self.found,
            )
        } else {
            walk.tracer.stationary_of(
                sequence,
                None,
                self.s,
                Some(self.medium),
                self.r,
                budget,
                walk.run,
                &mut self.found,
            )
        };
        self.out.work += outcome.work as u64;
        self.out.complete &= outcome.complete;
        for a in self.found.drain(..) {
            let kept = match a.status {
                Status::Vertex => claim.vertex,
                status => claim.specular && Tracer::listed(status, options),
            };
            if !kept || a.time > options.time_limit() {
                continue;
            }
            if let Some(paths) = walk.paths {
                let plan = SearchArrival {
                    source: self.source,
                    receiver: self.receiver,
                    steps: self.steps.clone(),
                    arrival: a,
                    complete: true,
                    heights: Vec::new(),
                };
                if !paths(plan) {
                    self.stopped = true;
                    return;
                }
                continue;
            }
            if let Some(sink) = walk.sink {
                walk.listed.stream();
                let mut a = a;
                walk.tracer
                    .arrival_amplitudes(&self.steps, std::slice::from_mut(&mut a));
                sink.arrival(StreamedArrival {
                    source: self.source,
                    receiver: self.receiver,
                    steps: self.steps.len(),
                    diffractions: super::diffractions(&self.steps),
                    vertical_reflections: 0,
                    status: a.status,
                    time: a.time,
                    amplitude: a.amplitude,
                });
                continue;
            }
            if !walk.listed.take(self.steps.len()) {
                self.stopped = true;
                return;
            }
            self.out.arrivals.push(SearchArrival {
                source: self.source,
                receiver: self.receiver,
                steps: self.steps.clone(),
                arrival: a,
                complete: true,
                heights: Vec::new(),
            });
        }
    }
}
