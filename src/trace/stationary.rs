//! Every stationary path of a ray: the tracer's entry to the complete search (`complete.rs`)
//! with its leg media given or enumerated from the regions, and the default mode's fallback
//! that makes its `no_path` a proof.
//!
//! With region lookup the media of a sequence are not known before its points are: each
//! sequence of media that the interfaces allow (a reflection keeps the medium, a refraction
//! takes a medium found across the interface from the present one) is searched, and an
//! arrival is kept when the lookup at its own points gives the media it was solved with.

use std::cell::Cell;

use crate::geom::Point;
use crate::options::{self, Run};
use crate::regions::Regions;
use crate::scene::{MAX_STATIONARY_STEPS, StepKind};

use super::classify::Sequence;
use super::complete::{self, Arrival, Hierarchy, SearchBudget, SequenceSearch};
use super::{RayRecord, Reason, SearchOutcome, StationaryError, Status, Tracer, Workspace};

/// The number of starts of the search for every stationary path through curved legs
/// ([`Tracer::stationary_paths`] in a scene with a gradient medium), over all its steps.
pub(crate) const CURVED_STARTS: usize = 1024;

/// Tuples (and assignments solved) the default mode's search of one ray visits at most,
/// beyond which it answers `not_converged` (`Reason::SearchLimit`); its work is bounded by
/// the run's [`Limits::fallback_work`](crate::options::Limits) (about 10 ms of one core), or
/// `solver.max_work` when that is less.
const FALLBACK_TUPLES: usize = 1 << 14;

thread_local! {
    /// Each thread's arrivals for the default mode's fallback, reused from ray to ray.
    static FALLBACK: Cell<Vec<Arrival>> = const { Cell::new(Vec::new()) };
}

impl Tracer {
    /// Every stationary path of path `path` from `source` to `receiver` into `out` (emptied
    /// first): `converged`, `vertex` (with its [`Kink`](super::Kink)) and `obstructed` ones, each once,
    /// ordered by time. A search that is [`complete`](SearchOutcome::complete) lists them all (an
    /// empty `out` then says that the sequence has no stationary path).
    ///
    /// On one assignment of segments the time is convex in the parameters; the search runs
    /// a branch-and-bound over each polyline's segment hierarchy with certain bounds on the
    /// residuals, and solves each surviving assignment, with every choice of held vertices, to
    /// the solver's tolerance. A path without `media` takes them from the regions: each
    /// sequence of media that its interfaces allow is searched, and a path is kept where the
    /// lookup at its points gives the media it was solved with. The path may have at most
    /// [`MAX_STATIONARY_STEPS`] steps. The first call on an interface builds its
    /// hierarchy (`O(M)`); a later one visits about `log M` nodes per arrival and interface
    /// (measured on a digitised sea floor: 24 tuples per ray at M = 1e3, 40 at 1e5).
    ///
    /// The search runs with `run` ([`Run::keep_going`] before each tuple and solve, a unit of
    /// work per point moved and weighed): a stop request or a spent budget ends it, not
    /// [`complete`](SearchOutcome::complete).
    ///
    /// ```
    /// use eigenray::trace::Kink;
    /// use eigenray::{Point, Scene, Status, Tracer, options::Run};
    /// // A mirror bent into a valley, seen from above: a specular point on each slope, and
    /// // the bottom, where the time has a maximum-type kink.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0 } },
    ///     "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
    ///     "sources": [[-0.5, 2]], "receivers": [[0.5, 2]],
    ///     "paths": [{ "steps": [{ "reflect": "valley" }], "media": ["air", "air"] }]
    /// }"#).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let mut arrivals = Vec::new();
    /// let search = tracer
    ///     .stationary_paths(Point::new(-0.5, 2.0), Point::new(0.5, 2.0), 0, &Run::new(), &mut arrivals)
    ///     .unwrap();
    /// assert!(search.complete);
    /// let statuses: Vec<Status> = arrivals.iter().map(|a| a.status).collect();
    /// assert_eq!(statuses, [Status::Converged, Status::Converged, Status::Vertex]);
    /// assert_eq!(arrivals[2].kink, Some(Kink::Maximum));
    /// assert!((arrivals[0].time - 45f64.sqrt()).abs() < 1e-12);
    /// assert!(arrivals.windows(2).all(|w| w[0].time <= w[1].time));
    /// ```
    ///
    /// # Errors
    /// A path index out of range, or one of more than
    /// [`MAX_STATIONARY_STEPS`] steps.
    ///
    /// # Panics
    /// If a point is not finite or lies beyond ±[`MAX_COORDINATE`](crate::scene::MAX_COORDINATE)
    /// ([`Scene::check_solve`](crate::Scene::check_solve) tells beforehand).
    pub fn stationary_paths(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        run: &Run,
        out: &mut Vec<Arrival>,
    ) -> Result<SearchOutcome, StationaryError> {
        out.clear();
        let spec = self
            .scene
            .paths()
            .get(path)
            .ok_or(StationaryError::NoSuchPath { path })?;
        let steps = spec.steps.len();
        if steps > MAX_STATIONARY_STEPS {
            return Err(StationaryError::TooManySteps { path, steps });
        }
        self.assert_solvable(source, receiver, path, "Tracer::stationary_paths");
        if self.plan_of(path).diffracted() {
            let (search, _) =
                self.diffracted_paths(path, source, receiver, self.search_budget(), out);
            self.arrival_amplitudes(&spec.steps, out);
            return Ok(search);
        }
        if let Some((m, profile)) = self.profile_medium(path, source, None) {
            return Ok(self.profile_stationary_paths(m, &profile, source, receiver, out));
        }
        if let Some(m) = self.profile_sloped_medium(path, source, None) {
            return Ok(self.sloped_stationary_paths(path, m, [source, receiver], run, out));
        }
        if let Some((m, profile)) = self.profile_walled_medium(path, source, None) {
            return Ok(self.walled_stationary_paths(path, m, &profile, source, receiver, out));
        }
        if self.scene.curved() {
            let outcome = self.curved_stationary_paths(source, receiver, path, run, out);
            self.arrival_amplitudes(&spec.steps, out);
            return Ok(outcome);
        }
        let source_medium = self.source_medium(spec.media.is_some(), source);
        let search = self.stationary_of(
            Sequence::of(&self.scene, path),
            spec.media.as_deref(),
            source,
            source_medium,
            receiver,
            self.search_budget(),
            run,
            out,
        );
        self.arrival_amplitudes(&spec.steps, out);
        Ok(search)
    }

    /// [`stationary_paths`](Self::stationary_paths) in a scene with curved legs: the path's
    /// steps and media through [`curved_paths_of`](Self::curved_paths_of).
    fn curved_stationary_paths(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        run: &Run,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        let spec = &self.scene.paths()[path];
        let source_medium = self.source_medium(spec.media.is_some(), source);
        let budget = SearchBudget {
            tuples: usize::MAX,
            work: usize::MAX,
        };
        self.curved_paths_of(
            &spec.steps,
            spec.media.as_deref(),
            source,
            source_medium,
            receiver,
            budget,
            run,
            out,
        )
    }

    /// Every stationary path of the step sequence `steps` in a scene with curved legs into
    /// `out` (emptied first): Newton from a grid of starts over the interfaces
    /// ([`CURVED_STARTS`] in all, the same number along each step's polyline, at the middles
    /// of equal pieces of its length), its media `media` or looked up from `source_medium`,
    /// each distinct ray with a time kept (points within 1e-8 of the path's length are one
    /// ray), ordered by time. The complete search's leaf problems are convex only for
    /// straight legs (with arcs one sequence can have a minimum and a saddle on the same
    /// segments), so this search is not a proof: its outcome is never `complete` (but for
    /// the direct ray, which has its one arc), and a ray without an arrival says
    /// `search_limit`, not `no_path`. `run` is asked before each solve (its iterations the
    /// work), and the search stops, not complete, where `budget`'s work is spent.
    #[expect(
        clippy::too_many_arguments,
        reason = "a ray's ends, its sequence and media, the search's limit and its output"
    )]
    pub(crate) fn curved_paths_of(
        &self,
        steps: &[crate::scene::Step],
        media: Option<&[usize]>,
        source: Point,
        source_medium: Option<usize>,
        receiver: Point,
        budget: SearchBudget,
        run: &Run,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        out.clear();
        let k = steps.len();
        let mut ws = Workspace::new();
        let per_step = if k == 0 {
            1
        } else {
            ((CURVED_STARTS as f64).powf(1.0 / k as f64).floor() as usize).clamp(2, 64)
        };
        let starts = per_step.pow(k as u32);
        let mut outcome = SearchOutcome {
            complete: k == 0,
            ..SearchOutcome::new()
        };
        let mut guess = vec![0.0; k];
        let mut index = vec![0usize; k];
        for _ in 0..starts {
            if outcome.work >= budget.work || !run.keep_going(options::Progress::work(1)) {
                outcome.complete = false;
                break;
            }
            for (i, step) in steps.iter().enumerate() {
                let line = &self.scene.interfaces()[step.interface].polyline;
                guess[i] = line.length() * (index[i] as f64 + 0.5) / per_step as f64;
            }
            // The next start: the indices count in base `per_step`.
            for i in index.iter_mut() {
                *i += 1;
                if *i < per_step {
                    break;
                }
                *i = 0;
            }
            let record = self.solve_steps_curved(
                steps,
                media,
                source,
                source_medium,
                receiver,
                &guess,
                &mut ws,
            );
            outcome.solves += 1;
            outcome.work += record.iterations as usize;
            if !record.status.has_time() {
                continue;
            }
            let points = &ws.ray.points;
            let length: f64 = points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
            let same = |a: &Arrival| {
                a.points
                    .iter()
                    .zip(points)
                    .all(|(p, q)| (*p - *q).length() <= 1e-8 * length)
            };
            if out.iter().any(same) {
                continue;
            }
            out.push(Arrival {
                status: record.status,
                time: record.time,
                points: points.clone(),
                parameters: ws.parameters().to_vec(),
                segments: ws.newton.seg[..k].to_vec(),
                media: ws.media().to_vec(),
                iterations: record.iterations as usize,
                reason: record.reason,
                kink: None,
                residual: record.residual,
                amplitude: None,
                turns: None,
                caustics: None,
                launch_angle: None,
            });
        }
        out.sort_by(|a, b| a.time.total_cmp(&b.time));
        outcome
    }

    /// The budget of one complete search with `"stationary": "all"` (and of one pair's in a
    /// `search`): the tuples' limit, and `solver.max_work`.
    pub(crate) fn search_budget(&self) -> SearchBudget {
        SearchBudget {
            tuples: complete::MAX_TUPLES,
            work: work_units(self.scene.solver().max_work),
        }
    }

    /// The medium at `source` when the media are looked up (`given`: they are not).
    pub(crate) fn source_medium(&self, given: bool, source: Point) -> Option<usize> {
        if given {
            return None;
        }
        self.regions
            .as_ref()
            .and_then(|r| r.source_medium(&self.scene, source))
    }

    /// Every stationary path of `sequence` into `out` (emptied first), ordered by time: with
    /// `media` given, one search; otherwise one per sequence of media the interfaces allow
    /// from `source_medium` (none: no path), each arrival kept when the lookup at its points
    /// agrees.
    #[expect(
        clippy::too_many_arguments,
        reason = "a ray's ends, its sequence and media, the search's limit and its output"
    )]
    pub(crate) fn stationary_of(
        &self,
        sequence: Sequence<'_>,
        media: Option<&[usize]>,
        source: Point,
        source_medium: Option<usize>,
        receiver: Point,
        budget: SearchBudget,
        run: &Run,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        complete::recycle(out);
        let mut stats = SearchOutcome::new();
        let k = sequence.steps.len();
        let mut held: [&Hierarchy; MAX_STATIONARY_STEPS];
        let hierarchies: &[&Hierarchy] = match sequence.steps.first() {
            None => &[],
            Some(first) => {
                held = [self.hierarchy(first.interface); MAX_STATIONARY_STEPS];
                for (h, step) in held.iter_mut().zip(sequence.steps) {
                    *h = self.hierarchy(step.interface);
                }
                &held[..k]
            }
        };
        let base = SequenceSearch {
            scene: &self.scene,
            classifier: &self.classifier,
            hierarchies,
            tolerance: self.newton.tolerance,
            sequence,
            media: &[],
            source,
            receiver,
            budget,
            run,
        };
        match (media, self.regions.as_ref(), source_medium) {
            (Some(media), _, _) => {
                complete::search_sequence(SequenceSearch { media, ..base }, out, &mut stats);
            }
            (None, Some(regions), Some(first)) => {
                let mut legs = Legs {
                    media: [first; MAX_STATIONARY_STEPS + 1],
                    len: 1,
                };
                self.search_media(base, &mut legs, out, &mut stats);
                complete::retain(out, |a| media_hold(regions, &base, a));
            }
            // No medium at the source: no path.
            (None, _, _) => {}
        }
        complete::finish(out);
        stats
    }

    /// The searches of every sequence of leg media that starts with `legs` (the media of the
    /// legs so far).
    fn search_media(
        &self,
        base: SequenceSearch<'_>,
        legs: &mut Legs,
        out: &mut Vec<Arrival>,
        stats: &mut SearchOutcome,
    ) {
        let i = legs.len - 1;
        let Some(step) = base.sequence.steps.get(i) else {
            let search = SequenceSearch {
                media: &legs.media[..legs.len],
                ..base
            };
            complete::search_sequence(search, out, stats);
            return;
        };
        let here = legs.media[i];
        match step.kind {
            // A diffraction keeps the medium too (a wedge of rigid or soft faces).
            StepKind::Reflect | StepKind::Diffract { .. } => {
                legs.push(here);
                self.search_media(base, legs, out, stats);
                legs.len -= 1;
            }
            StepKind::Refract => {
                let sides = self.interface_sides(step.interface);
                for (n, s) in sides.iter().enumerate() {
                    let across = match (s.left, s.right) {
                        (Some(l), r) if l == here => r,
                        (l, Some(r)) if r == here => l,
                        _ => None,
                    };
                    let Some(next) = across else { continue };
                    // Each medium once.
                    let seen = sides[..n].iter().any(|t| {
                        (t.left == Some(here) && t.right == Some(next))
                            || (t.right == Some(here) && t.left == Some(next))
                    });
                    if !seen {
                        legs.push(next);
                        self.search_media(base, legs, out, stats);
                        legs.len -= 1;
                    }
                }
            }
        }
    }

    /// The segment hierarchy of interface `interface`, built on first use.
    fn hierarchy(&self, interface: usize) -> &Hierarchy {
        self.hierarchies[interface]
            .get_or_init(|| Hierarchy::new(&self.scene.interfaces()[interface].polyline))
    }

    /// The pairs of media on the sides of interface `interface`, found on first use.
    pub(crate) fn interface_sides(&self, interface: usize) -> &[crate::regions::Sides] {
        self.sides[interface].get_or_init(|| {
            self.regions
                .as_ref()
                .map(|r| r.interface_sides(interface))
                .unwrap_or_default()
        })
    }

    /// The default mode's answer where the documented start led to no stationary path
    /// (`record`): the earliest `converged` or `vertex` path of a complete search of the
    /// sequence (else its earliest `obstructed` one), left in `ws` as a solve leaves its ray;
    /// `no_path` when the search rules every path out, `not_converged` when it cannot.
    #[cold]
    #[inline(never)]
    pub(crate) fn search_instead(
        &self,
        record: RayRecord,
        source: Point,
        source_medium: Option<usize>,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
    ) -> RayRecord {
        // Already proofs: the image method's one stationary point beyond an end or a leg from
        // behind a mirror, and a source where no medium is. With no iterations allowed, the
        // start is the answer (a way to inspect it).
        let proof = matches!(
            record.reason,
            Some(Reason::BeyondEnd { .. } | Reason::NoStationaryPath | Reason::NoMedium { leg: 0 })
        );
        // A diffracted path's pieces were searched completely already. Curved legs: the
        // complete search is the straight leg's (convex leaf problems), so the solve's own
        // answer stands.
        if proof
            || self.newton.max_iterations == 0
            || self.plan_of(path).diffracted()
            || self.scene().curved()
        {
            return record;
        }
        let spec = &self.scene.paths()[path];
        let k = spec.steps.len();
        let given = spec.media.is_some();
        if k > MAX_STATIONARY_STEPS || (!given && self.regions.is_none()) {
            return RayRecord {
                status: Status::NotConverged,
                time: f64::NAN,
                reason: Some(Reason::SearchLimit),
                ..record
            };
        }
        let mut arrivals = FALLBACK.take();
        // A single ray's search: it runs with the run of its thread (`Run::within`).
        let stats = options::with_current(|run| {
            self.stationary_of(
                Sequence::of(&self.scene, path),
                spec.media.as_deref(),
                source,
                if given { None } else { source_medium },
                receiver,
                SearchBudget {
                    tuples: FALLBACK_TUPLES,
                    work: work_units(self.scene.solver().max_work.min(run.limits.fallback_work)),
                },
                run,
                &mut arrivals,
            )
        });
        let best = arrivals
            .iter()
            .find(|a| a.status != Status::Obstructed)
            .or(arrivals.first());
        let answer = match best {
            Some(a) => {
                ws.resize(k);
                ws.newton.s[..k].copy_from_slice(&a.parameters);
                ws.newton.seg[..k].copy_from_slice(&a.segments);
                ws.ray.points.clear();
                ws.ray.points.extend_from_slice(&a.points);
                ws.ray.media.clear();
                ws.ray.media.extend_from_slice(&a.media);
                RayRecord {
                    status: a.status,
                    time: a.time,
                    // The solve's iterations, within `max_iterations`; the search's own steps
                    // are not iterations of that solve.
                    iterations: record.iterations,
                    residual: a.residual,
                    reason: a.reason,
                }
            }
            None => RayRecord {
                status: if stats.complete {
                    Status::NoPath
                } else {
                    Status::NotConverged
                },
                time: f64::NAN,
                // A proof whose start collapsed onto an end says so: the path is the one
                // without that step.
                reason: Some(match record.reason {
                    Some(at @ Reason::AtEnd { .. }) if stats.complete => at,
                    _ => stats.reason_without_arrivals(),
                }),
                ..record
            },
        };
        FALLBACK.set(arrivals);
        answer
    }
}

/// `work` as a count of this machine's words (saturating).
fn work_units(work: u64) -> usize {
    usize::try_from(work).unwrap_or(usize::MAX)
}

/// The media of the legs of a sequence so far.
struct Legs {
    media: [usize; MAX_STATIONARY_STEPS + 1],
    len: usize,
}

impl Legs {
    fn push(&mut self, medium: usize) {
        self.media[self.len] = medium;
        self.len += 1;
    }
}

/// Whether arrival `a`'s legs lie in the media it was solved with: each leg of an
/// unobstructed path in the region of its medium (looked up at its middle); an obstructed
/// path's legs cross regions, so there the lookup rule of the default mode decides (a
/// reflection keeps the medium, a refraction takes the one across the interface).
fn media_hold(regions: &Regions, search: &SequenceSearch<'_>, a: &Arrival) -> bool {
    if a.status != Status::Obstructed {
        return a.points.windows(2).zip(&a.media).all(|(leg, &m)| {
            leg[0] == leg[1] || regions.medium_at(leg[0].lerp(leg[1], 0.5)) == Some(m)
        });
    }
    search.sequence.steps.iter().enumerate().all(|(i, step)| {
        let after = a.media[i + 1];
        match step.kind {
            StepKind::Reflect | StepKind::Diffract { .. } => after == a.media[i],
            StepKind::Refract => {
                let (seg, s) = (a.segments[i], a.parameters[i]);
                regions.medium_across(step.interface, seg, s, a.points[i]) == Some(after)
            }
        }
    })
}
