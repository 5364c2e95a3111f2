//! The diffracted arrivals of a search (`"diffraction": true`): every path of the form
//! (reflections) + one diffraction + (reflections), `[R₁ … R_a, {"diffract": I, "vertex": k},
//! R'₁ … R'_b]`, with `a + 1 + b` ≤ `max_steps` (the diffraction is a step) and its time ≤
//! `max_time`, the reflections off the allowed interfaces (when the search reflects).
//!
//! A diffraction holds its point on the vertex, so such a path is two pieces solved apart
//! (`Tracer::diffracted_sequence` does the same for a prescribed path): the specular paths of
//! `R₁ … R_a` from the source to the vertex, and of `R'₁ … R'_b` from the vertex to the
//! receiver, each found by the complete stationary search between fixed points (`piece_of`),
//! joined where both legs at the vertex lie outside its wedge (`through_vertex`). The pieces
//! before a vertex depend on the source only, so they are searched once per (source, vertex)
//! and shared by every receiver; the pieces after it once per (pair, vertex), and combined
//! with every piece before it whose steps fit in `max_steps`. The arrivals and their times
//! are those of the prescribed paths, bit for bit (the same pieces, joined the same way).
//!
//! Each side's reflection sequences are walked depth first, a prefix `I₁ … I_k` pruned with
//! everything below it where `w·(d(A, B₁) + Σ d(Bᵢ, Bᵢ₊₁) + d(B_k, Z))` (with `A` and `Z` the
//! piece's fixed ends, `Bᵢ` the bounding box of `Iᵢ`, `w` the least slowness of every medium)
//! plus what the other side takes at least (before the vertex: `w` times the distance from
//! the vertex to the nearest receiver; after it: the earliest arrival of the pieces before)
//! exceeds `max_time`; a reflection off a one-segment interface right after one off the same
//! interface has no path and is not tried. A piece of more than
//! [`MAX_STATIONARY_STEPS`] steps still possible leaves the search incomplete.
//!
//! The work, one per sequence visited plus the pieces' complete searches, is counted into the
//! walks' (`work`), per (source, vertex) and per pair against the scene's `solver.max_work`;
//! a side that reaches it (or the run's limits) stops, and its pairs say `complete: false`.
//!
//! With diffraction on, the `vertex` (edge-held) arrivals of reflect-only sequences held on
//! one vertex are the same paths as diffracted ones: [`drop_listed_twice`] removes them.

use rayon::prelude::*;

use crate::geom::{Aabb, Point};
use crate::leg::{LegModel, Uniform};
use crate::options::{Progress, Run};
use crate::scene::{MAX_STATIONARY_STEPS, SearchOptions, Step, StepKind};
use crate::trace::diffract::{first_piece, through_vertex};
use crate::trace::{Arrival, Sequence, Status, Tracer};

use super::sequences::PairWalk;
use super::{Control, SearchArrival, StreamedArrival};

/// The bound's relative margin against round-off.
const TIME_MARGIN: f64 = 1e-9;

/// Combinations of the two pieces' arrivals kept at most per diffracted sequence (as
/// `Tracer::diffracted_sequence` keeps them); beyond, the pair is not complete.
const MAX_COMBINATIONS: usize = 1 << 14;

/// One reflection sequence of a side of a vertex, with its piece's arrivals.
struct Piece {
    steps: Vec<Step>,
    arrivals: Vec<Arrival>,
}

/// The pieces of one side of a vertex (from the source to it, or from it to the receiver).
struct Side {
    pieces: Vec<Piece>,
    complete: bool,
    work: u64,
}

impl Side {
    fn new() -> Side {
        Side {
            pieces: Vec::new(),
            complete: true,
            work: 0,
        }
    }
}

/// What the diffraction search shares over all its pairs.
struct Diffraction<'a> {
    tracer: &'a Tracer,
    options: &'a SearchOptions,
    run: &'a Run,
    /// Each vertex tried: its `diffract` step and point.
    vertices: Vec<(Step, Point)>,
    /// The reflections a piece may take, in a fixed order.
    reflections: Vec<Step>,
    /// Per interface (scene index): its bounding box.
    boxes: Vec<Aabb>,
    /// Per interface: whether it is one segment (two reflections off it in a row: no path).
    one_segment: Vec<bool>,
    /// The least slowness of every medium.
    least: f64,
    /// `max_time` (infinite without it).
    limit: f64,
    /// `max_steps` (unbounded without it).
    steps: usize,
    /// Work per side before it stops.
    max_work: u64,
}

/// Where a side's walk is: its fixed ends and bounds.
#[derive(Clone, Copy)]
struct Ends {
    from: Point,
    to: Point,
    /// The medium at `from`.
    medium: Option<usize>,
    /// What the rest of the path takes at least (the other side).
    rest: f64,
    /// The longest sequence of the side.
    depth: usize,
}

impl Tracer {
    /// The diffracted arrivals of every pair, in parallel: (pair index, what it found). The
    /// work of the pieces before each vertex comes as one more entry per source (its first
    /// pair, nothing listed).
    pub(super) fn diffraction_pairs(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> Vec<(usize, PairWalk)> {
        let scene = self.scene();
        let (ns, nr) = (scene.sources().len(), scene.receivers().len());
        if options.step_limit() == 0 || nr == 0 {
            return Vec::new();
        }
        let d = Diffraction::new(self, options, control.run);
        let nv = d.vertices.len();
        let media: Vec<Option<usize>> = scene
            .sources()
            .iter()
            .map(|&s| self.source_medium(false, s))
            .collect();
        // The pieces before each vertex, per (source, vertex).
        let before: Vec<Side> = (0..ns * nv)
            .into_par_iter()
            .map(|sv| {
                let (source, v) = (sv / nv, sv % nv);
                let at = d.vertices[v].1;
                let nearest = scene
                    .receivers()
                    .iter()
                    .map(|&r| (r - at).length())
                    .fold(f64::INFINITY, f64::min);
                let ends = Ends {
                    from: scene.sources()[source],
                    to: at,
                    medium: media[source],
                    rest: d.least * nearest,
                    depth: d.steps - 1,
                };
                let mut side = Side::new();
                if control.run.keep_going(Progress::work(0)) {
                    control.run.within(|| d.side(ends, 0.0, &mut side));
                } else {
                    side.complete = false;
                }
                side
            })
            .collect();
        let mut out: Vec<(usize, PairWalk)> = (0..ns)
            .map(|source| {
                let sides = &before[source * nv..(source + 1) * nv];
                let walk = PairWalk {
                    arrivals: Vec::new(),
                    complete: sides.iter().all(|s| s.complete),
                    work: sides.iter().map(|s| s.work).sum(),
                };
                (source * nr, walk)
            })
            .collect();
        let pairs: Vec<(usize, PairWalk)> = (0..ns * nr)
            .into_par_iter()
            .map(|pair| {
                let (source, receiver) = (pair / nr, pair % nr);
                let sides = &before[source * nv..(source + 1) * nv];
                let mut found = if control.run.keep_going(Progress { work: 0, items: 1 }) {
                    control
                        .run
                        .within(|| d.pair(control, sides, media[source], source, receiver))
                } else {
                    PairWalk::not_begun()
                };
                found.complete &= sides.iter().all(|s| s.complete);
                (pair, found)
            })
            .collect();
        out.extend(pairs);
        out
    }
}

impl<'a> Diffraction<'a> {
    fn new(tracer: &'a Tracer, options: &'a SearchOptions, run: &'a Run) -> Diffraction<'a> {
        let scene = tracer.scene();
        let vertices = options
            .interfaces
            .iter()
            .flat_map(|&interface| {
                let line = &scene.interfaces()[interface].polyline;
                line.vertices().iter().enumerate().map(move |(k, &p)| {
                    let kind = StepKind::Diffract {
                        vertex: u32::try_from(k).unwrap_or(u32::MAX),
                    };
                    (Step { kind, interface }, p)
                })
            })
            .collect();
        let reflections = if options.reflect {
            (options.interfaces.iter())
                .map(|&interface| Step {
                    kind: StepKind::Reflect,
                    interface,
                })
                .collect()
        } else {
            Vec::new()
        };
        Diffraction {
            tracer,
            options,
            run,
            vertices,
            reflections,
            boxes: scene
                .interfaces()
                .iter()
                .map(|i| i.polyline.bbox())
                .collect(),
            one_segment: scene
                .interfaces()
                .iter()
                .map(|i| !i.polyline.is_closed() && i.polyline.num_segments() == 1)
                .collect(),
            least: scene
                .media()
                .iter()
                .map(|m| m.slowness)
                .fold(f64::INFINITY, f64::min),
            limit: options.time_limit(),
            steps: options.step_limit(),
            max_work: scene.solver().max_work,
        }
    }

    /// Whether a path bounded below by `bound` may still arrive by `max_time`.
    fn in_time(&self, bound: f64) -> bool {
        bound * (1.0 - TIME_MARGIN) <= self.limit
    }

    /// Every reflection sequence of one side (`ends`) whose paths may arrive by `max_time`,
    /// with its piece's arrivals, into `side`; `base` the bound on the legs of the side's
    /// sequence so far (`steps`, walked depth first).
    fn side(&self, ends: Ends, base: f64, side: &mut Side) {
        let mut steps = Vec::new();
        self.extend(
            ends,
            base,
            Aabb::from_points(ends.from, ends.from),
            &mut steps,
            side,
        );
    }

    fn extend(&self, ends: Ends, bound: f64, at: Aabb, steps: &mut Vec<Step>, side: &mut Side) {
        let tail = Uniform::new(self.least).least_time_to(at, ends.to);
        if !self.in_time(bound + tail + ends.rest) {
            return;
        }
        side.work += 1;
        if side.work > self.max_work || !self.run.keep_going(Progress::work(1)) {
            side.complete = false;
            return;
        }
        let mut arrivals = Vec::new();
        let sequence = Sequence {
            steps,
            path: None,
            curved: &[],
        };
        let outcome = self.tracer.piece_of(
            sequence,
            None,
            ends.from,
            ends.medium,
            ends.to,
            self.tracer.search_budget(),
            self.run,
            &mut arrivals,
        );
        side.work += outcome.work as u64;
        side.complete &= outcome.complete;
        if !arrivals.is_empty() {
            side.pieces.push(Piece {
                steps: steps.clone(),
                arrivals,
            });
        }
        if steps.len() >= ends.depth {
            return;
        }
        for &step in &self.reflections {
            let repeat = steps
                .last()
                .is_some_and(|l| l.interface == step.interface && self.one_segment[l.interface]);
            if repeat {
                continue;
            }
            let to = self.boxes[step.interface];
            let next = bound + Uniform::new(self.least).least_time(at, to);
            let beyond = Uniform::new(self.least).least_time_to(to, ends.to);
            if !self.in_time(next + beyond + ends.rest) {
                continue;
            }
            if steps.len() == MAX_STATIONARY_STEPS {
                // A possible piece longer than the complete search takes.
                side.complete = false;
                return;
            }
            steps.push(step);
            self.extend(ends, next, to, steps, side);
            steps.pop();
            if !side.complete && side.work > self.max_work {
                return;
            }
        }
    }

    /// The diffracted arrivals of one pair, given the pieces before each vertex (`before`,
    /// the source's), `medium` the source's.
    fn pair(
        &self,
        control: &Control<'_>,
        before: &[Side],
        medium: Option<usize>,
        source: usize,
        receiver: usize,
    ) -> PairWalk {
        let tracer = self.tracer;
        let scene = tracer.scene();
        let (s, r) = (scene.sources()[source], scene.receivers()[receiver]);
        let mut walk = PairWalk {
            arrivals: Vec::new(),
            complete: true,
            work: 0,
        };
        for (v, pre) in before.iter().enumerate() {
            let Some(earliest) = (pre.pieces.iter())
                .flat_map(|p| &p.arrivals)
                .map(|a| a.time)
                .reduce(f64::min)
            else {
                continue;
            };
            let shortest = pre.pieces.iter().map(|p| p.steps.len()).min().unwrap_or(0);
            let (step, at) = self.vertices[v];
            // The partial paths before the vertex, per piece.
            let started: Vec<Vec<Arrival>> = (pre.pieces.iter())
                .map(|p| {
                    p.arrivals
                        .iter()
                        .map(|a| first_piece(scene, s, a))
                        .collect()
                })
                .collect();
            // The pieces after it, from the medium every piece before ends in (the source's:
            // reflections and diffractions keep it).
            let ends = Ends {
                from: at,
                to: r,
                medium,
                rest: 0.0,
                depth: self.steps - 1 - shortest,
            };
            let mut post = Side::new();
            self.side(ends, earliest, &mut post);
            walk.work += post.work;
            walk.complete &= post.complete;
            for q in &post.pieces {
                for (p, partial) in pre.pieces.iter().zip(&started) {
                    if p.steps.len() + 1 + q.steps.len() > self.steps {
                        continue;
                    }
                    let mut steps = p.steps.clone();
                    steps.push(step);
                    steps.extend_from_slice(&q.steps);
                    let cut = p.steps.len();
                    let mut combined = 0;
                    for pa in partial {
                        if pa.media.last().copied() != medium {
                            // Only reflections before the vertex: never (see above).
                            walk.complete = false;
                            continue;
                        }
                        for b in &q.arrivals {
                            let Some(a) = through_vertex(scene, &steps, cut, pa, b) else {
                                continue;
                            };
                            combined += 1;
                            if combined > MAX_COMBINATIONS {
                                walk.complete = false;
                                break;
                            }
                            if !Tracer::listed(a.status, self.options) || a.time > self.limit {
                                continue;
                            }
                            if !self.hand_on(control, source, receiver, &steps, a, &mut walk) {
                                walk.complete = false;
                                return walk;
                            }
                        }
                    }
                }
            }
            if walk.work > self.max_work {
                walk.complete = false;
                return walk;
            }
        }
        walk
    }

    /// Lists one diffracted arrival into `walk`, or streams it (with its amplitude): whether
    /// the search may go on (the arrivals' limit).
    fn hand_on(
        &self,
        control: &Control<'_>,
        source: usize,
        receiver: usize,
        steps: &[Step],
        mut arrival: Arrival,
        walk: &mut PairWalk,
    ) -> bool {
        if let Some(sink) = control.sink {
            control.listed.stream();
            self.tracer
                .arrival_amplitudes(steps, std::slice::from_mut(&mut arrival));
            sink(StreamedArrival {
                source,
                receiver,
                steps: steps.len(),
                diffractions: super::diffractions(steps),
                vertical_reflections: 0,
                status: arrival.status,
                time: arrival.time,
                amplitude: arrival.amplitude,
            });
            return true;
        }
        if !control.listed.take(steps.len()) {
            return false;
        }
        walk.arrivals.push(SearchArrival {
            source,
            receiver,
            steps: steps.to_vec(),
            arrival,
            complete: true,
            heights: Vec::new(),
        });
        true
    }
}

/// Removes the `vertex` arrivals of reflect-only sequences held on one vertex (one step's
/// point on a vertex of its interface) for which the same path is listed as diffracted: the
/// sequence with that step a diffraction at that vertex, the same points. Listed once, as
/// diffracted.
pub(super) fn drop_listed_twice(tracer: &Tracer, arrivals: &mut Vec<SearchArrival>) {
    let scene = tracer.scene();
    // Diffracted arrivals by pair, for the look-up.
    let mut diffracted: Vec<&SearchArrival> = arrivals
        .iter()
        .filter(|a| super::diffractions(&a.steps) == 1)
        .collect();
    if diffracted.is_empty() {
        return;
    }
    diffracted.sort_by_key(|a| (a.source, a.receiver));
    let near = |p: Point, q: Point| {
        let scale = 1.0 + p.x.abs().max(p.y.abs());
        (p - q).length() <= 1e-9 * scale
    };
    let listed_twice = |a: &SearchArrival| -> bool {
        if a.arrival.status != Status::Vertex || a.steps.iter().any(|s| s.kind != StepKind::Reflect)
        {
            return false;
        }
        // The one step held on a vertex, and which.
        let mut held = None;
        for (i, step) in a.steps.iter().enumerate() {
            let point = a.arrival.points[i + 1];
            let line = &scene.interfaces()[step.interface].polyline;
            if let Some(k) = line.vertices().iter().position(|&v| near(point, v)) {
                if held.is_some() {
                    return false;
                }
                held = Some((i, k));
            }
        }
        let Some((i, k)) = held else {
            return false;
        };
        let vertex = u32::try_from(k).unwrap_or(u32::MAX);
        let lo = diffracted.partition_point(|d| (d.source, d.receiver) < (a.source, a.receiver));
        diffracted[lo..]
            .iter()
            .take_while(|d| (d.source, d.receiver) == (a.source, a.receiver))
            .any(|d| {
                d.steps.len() == a.steps.len()
                    && d.steps.iter().zip(&a.steps).enumerate().all(|(j, (x, y))| {
                        x.interface == y.interface
                            && if j == i {
                                x.kind == StepKind::Diffract { vertex }
                            } else {
                                x.kind == y.kind
                            }
                    })
                    && d.arrival.points.len() == a.arrival.points.len()
                    && (d.arrival.points.iter())
                        .zip(&a.arrival.points)
                        .all(|(&p, &q)| near(p, q))
            })
    };
    let drop: Vec<bool> = arrivals.iter().map(listed_twice).collect();
    let mut k = 0;
    arrivals.retain(|_| {
        k += 1;
        !drop[k - 1]
    });
}
