//! The diffracted arrivals of a search (`"diffraction": true`): every path of the form
//! (reflections) + one diffraction + (reflections), `[R₁ … R_a, {"diffract": I, "vertex": k},
//! R'₁ … R'_b]`, with `a + 1 + b` ≤ `max_steps` (the diffraction is a step) and its time ≤
//! `max_time`, the reflections off the allowed interfaces (when the search reflects).
//!
//! A diffraction holds its point on the vertex, so such a path is two reflect-only pieces
//! joined at the vertex where both legs there lie outside its wedge (`through_vertex`, the
//! join of `Tracer::diffracted_sequence`): a path from the source to the vertex, and one from
//! the vertex to the receiver. Both are the beam tree's (`trace/mirrors.rs`: the image method,
//! exact and complete for reflect-only sequences in the source's medium, validated as the
//! classifier validates a ray): one tree per source with the vertices as its receivers (the
//! pieces before), then one tree per vertex (and medium) with the scene's receivers (the
//! pieces after), each path of which is joined on the spot with every piece before that
//! vertex whose steps fit in `max_steps`. The trees' bounds: before, `max_steps` − 1 and
//! `max_time`; after, `max_steps` − 1 − the fewest reflections before and `max_time` − the
//! earliest arrival before. Nothing but the pieces before is held.
//!
//! The work is the trees' (`solver.max_work` for each of a tree's receivers), counted into
//! the walks' (`work`); a tree that stops (at a limit of the run or its work) leaves the pairs
//! it serves `complete: false`.
//!
//! With diffraction on, the `vertex` (edge-held) arrivals of reflect-only sequences held on
//! one vertex are the same paths as diffracted ones: [`drop_listed_twice`] removes them.

use std::sync::Mutex;

use rayon::prelude::*;

use crate::geom::Point;
use crate::options::Progress;
use crate::scene::{SearchOptions, Step, StepKind};
use crate::trace::diffract::{first_piece, through_vertex};
use crate::trace::{Arrival, MirrorPath, MirrorScratch, MirrorSearch, MirrorWalls, Status, Tracer};

use super::beams::beam_arrival;
use super::{Control, SearchArrival, StreamedArrival};

/// The relative margin of the time left for a piece after the vertex, against round-off.
const TIME_MARGIN: f64 = 1e-9;

/// What the diffraction search found and did.
pub(super) struct Diffracted {
    /// The arrivals listed (none when the search streams them).
    pub arrivals: Vec<SearchArrival>,
    /// The trees' work.
    pub work: u64,
    /// Per pair, whether the trees that serve it were complete.
    pub complete: Vec<bool>,
}

/// A piece before a vertex: its reflections and its path from the source, begun as a
/// diffracted path (`first_piece`).
struct Before {
    steps: Vec<Step>,
    partial: Arrival,
}

/// A vertex of the diffraction search with what a piece after it is joined to: its step,
/// its index, the sources whose pieces before it are joined, and those pieces per source.
struct Joint<'a> {
    step: Step,
    vertex: usize,
    sources: &'a [usize],
    before: &'a [(Vec<Vec<Before>>, u64, bool)],
}

impl Tracer {
    /// The diffracted arrivals of every pair (see the module).
    pub(super) fn diffraction_search(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> Diffracted {
        let scene = self.scene();
        let (ns, nr) = (scene.sources().len(), scene.receivers().len());
        let mut out = Diffracted {
            arrivals: Vec::new(),
            work: 0,
            complete: vec![true; ns * nr],
        };
        let max_steps = options.step_limit();
        let max_time = options.time_limit();
        if max_steps == 0 || nr == 0 {
            return out;
        }
        let walls = if options.reflect {
            MirrorWalls::new(scene, &options.interfaces)
        } else {
            MirrorWalls::new(scene, &[])
        };
        let vertices: Vec<(Step, Point)> = options
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
        if vertices.is_empty() {
            return out;
        }
        let points: Vec<Point> = vertices.iter().map(|v| v.1).collect();
        let limits = &control.run.limits;
        let max_work = scene.solver().max_work;
        let media: Vec<Option<usize>> = scene
            .sources()
            .iter()
            .map(|&s| self.source_medium(false, s))
            .collect();
        // The pieces before each vertex, per source: (per vertex, its pieces), work, stopped.
        let before = self.pieces_before(options, control, &walls, &points, &media);
        for (source, b) in before.iter().enumerate() {
            out.work += b.1;
            if b.2 {
                out.complete[source * nr..(source + 1) * nr].fill(false);
            }
        }
        // The pieces after each vertex, one tree per vertex and medium, joined on the spot.
        let found = Mutex::new(Vec::new());
        let incomplete = Mutex::new(Vec::new());
        let work = std::sync::atomic::AtomicU64::new(0);
        let after = |v: usize, scratch: &mut MirrorScratch| {
            let (step, at) = vertices[v];
            let mut tried: Vec<usize> = Vec::new();
            for m in media.iter().flatten().copied() {
                if tried.contains(&m) {
                    continue;
                }
                tried.push(m);
                let sources: Vec<usize> = (0..ns)
                    .filter(|&i| media[i] == Some(m) && !before[i].0[v].is_empty())
                    .collect();
                let pieces = || sources.iter().flat_map(|&i| &before[i].0[v]);
                let Some(earliest) = pieces().map(|b| b.partial.time).reduce(f64::min) else {
                    continue;
                };
                let fewest = pieces().map(|b| b.steps.len()).min().unwrap_or(0);
                let left = max_time - earliest;
                let search = MirrorSearch {
                    scene,
                    source: at,
                    receivers: scene.receivers(),
                    max_steps: max_steps - 1 - fewest,
                    max_time: left + TIME_MARGIN * max_time.abs().max(left.abs()),
                    slowness: scene.media()[m].slowness,
                    obstructed: options.obstructed,
                    max_beams: limits.beams,
                    max_depth: limits.depth,
                    max_work: max_work.saturating_mul(nr as u64),
                };
                let mut listed = Vec::new();
                let mut full = false;
                let stats = if control.run.keep_going(Progress::default()) {
                    control.run.within(|| {
                        walls.arrivals(
                            &search,
                            scratch,
                            &mut |p: MirrorPath<'_>| {
                                if p.points.len() > 2 && vanishes(p.points[0], p.points[1]) {
                                    return true;
                                }
                                let q = beam_arrival(&walls, 0, m, p);
                                let joint = Joint {
                                    step,
                                    vertex: v,
                                    sources: &sources,
                                    before: &before,
                                };
                                if !self.join_at_vertex(options, control, &joint, q, &mut listed) {
                                    full = true;
                                    return false;
                                }
                                true
                            },
                            &mut |beams| control.run.keep_going(Progress::work(beams)),
                        )
                    })
                } else {
                    crate::trace::MirrorStats {
                        stopped: true,
                        ..Default::default()
                    }
                };
                work.fetch_add(stats.work, std::sync::atomic::Ordering::Relaxed);
                if stats.stopped || full {
                    let mut inc = incomplete.lock().unwrap_or_else(|e| e.into_inner());
                    inc.extend(sources.iter().copied());
                }
                if !listed.is_empty() {
                    let mut f = found.lock().unwrap_or_else(|e| e.into_inner());
                    f.push((v, listed));
                }
            }
        };
        if control.sink.is_some() {
            // Streamed: the vertices in turn, so that a pair's arrivals come in one order.
            let mut scratch = MirrorScratch::default();
            (0..vertices.len()).for_each(|v| after(v, &mut scratch));
        } else {
            (0..vertices.len())
                .into_par_iter()
                .for_each_init(MirrorScratch::default, |scratch, v| after(v, scratch));
        }
        out.work += work.into_inner();
        for source in incomplete.into_inner().unwrap_or_else(|e| e.into_inner()) {
            out.complete[source * nr..(source + 1) * nr].fill(false);
        }
        let mut found = found.into_inner().unwrap_or_else(|e| e.into_inner());
        found.sort_by_key(|f| f.0);
        out.arrivals = found.into_iter().flat_map(|f| f.1).collect();
        out
    }

    /// Joins `q`, a piece from `joint`'s vertex to a receiver, with every piece before the
    /// vertex of `joint.sources` (by time: the joined time is their sum, bit for bit), each
    /// joined arrival within the limits handed on ([`hand_on`](Self::hand_on)): `false` once
    /// the caller's limit on arrivals is reached.
    fn join_at_vertex(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
        joint: &Joint<'_>,
        q: SearchArrival,
        listed: &mut Vec<SearchArrival>,
    ) -> bool {
        let scene = self.scene();
        let (max_steps, max_time) = (options.step_limit(), options.time_limit());
        for &source in joint.sources {
            for b in &joint.before[source].0[joint.vertex] {
                if b.partial.time + q.arrival.time > max_time {
                    break;
                }
                if b.steps.len() + 1 + q.steps.len() > max_steps {
                    continue;
                }
                let mut steps = b.steps.clone();
                steps.push(joint.step);
                steps.extend_from_slice(&q.steps);
                let cut = b.steps.len();
                let Some(a) = through_vertex(scene, &steps, cut, &b.partial, &q.arrival) else {
                    continue;
                };
                if !Tracer::listed(a.status, options) || a.time > max_time {
                    continue;
                }
                let arrival = SearchArrival {
                    source,
                    receiver: q.receiver,
                    steps,
                    arrival: a,
                    complete: true,
                    heights: Vec::new(),
                };
                if !self.hand_on(control, arrival, listed) {
                    return false;
                }
            }
        }
        true
    }

    /// The pieces before each vertex (`points`), per source (`media` theirs): per vertex its
    /// pieces by time, the tree's work, and whether it stopped.
    fn pieces_before(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
        walls: &MirrorWalls,
        points: &[Point],
        media: &[Option<usize>],
    ) -> Vec<(Vec<Vec<Before>>, u64, bool)> {
        let scene = self.scene();
        let limits = &control.run.limits;
        let max_work = scene.solver().max_work;
        let (max_steps, max_time) = (options.step_limit(), options.time_limit());
        (0..scene.sources().len())
            .into_par_iter()
            .map_init(MirrorScratch::default, |scratch, source| {
                let s = scene.sources()[source];
                let mut pieces: Vec<Vec<Before>> = points.iter().map(|_| Vec::new()).collect();
                let Some(medium) = media[source] else {
                    return (pieces, 0, false);
                };
                if !control.run.keep_going(Progress::default()) {
                    return (pieces, 0, true);
                }
                let search = MirrorSearch {
                    scene,
                    source: s,
                    receivers: points,
                    max_steps: max_steps - 1,
                    max_time,
                    slowness: scene.media()[medium].slowness,
                    obstructed: options.obstructed,
                    max_beams: limits.beams,
                    max_depth: limits.depth,
                    max_work: max_work.saturating_mul(points.len() as u64),
                };
                let stats = control.run.within(|| {
                    walls.arrivals(
                        &search,
                        scratch,
                        &mut |p: MirrorPath<'_>| {
                            let n = p.points.len();
                            if n > 2 && vanishes(p.points[n - 2], p.points[n - 1]) {
                                // A reflection on the vertex itself (a free end): no piece.
                                return true;
                            }
                            let a = beam_arrival(walls, source, medium, p);
                            pieces[p.receiver].push(Before {
                                partial: first_piece(scene, s, &a.arrival),
                                steps: a.steps,
                            });
                            true
                        },
                        &mut |beams| control.run.keep_going(Progress::work(beams)),
                    )
                });
                for list in &mut pieces {
                    list.sort_by(|a, b| a.partial.time.total_cmp(&b.partial.time));
                }
                (pieces, stats.work, stats.stopped)
            })
            .collect()
    }

    /// Lists one diffracted arrival into `listed`, or streams it (with its amplitude):
    /// whether the search may go on (the arrivals' limit).
    fn hand_on(
        &self,
        control: &Control<'_>,
        mut a: SearchArrival,
        listed: &mut Vec<SearchArrival>,
    ) -> bool {
        if let Some(sink) = control.sink {
            control.listed.stream();
            self.arrival_amplitudes(&a.steps, std::slice::from_mut(&mut a.arrival));
            sink.arrival(StreamedArrival {
                source: a.source,
                receiver: a.receiver,
                steps: a.steps.len(),
                diffractions: super::diffractions(&a.steps),
                vertical_reflections: 0,
                status: a.arrival.status,
                time: a.arrival.time,
                amplitude: a.arrival.amplitude,
            });
            return true;
        }
        if !control.listed.take(a.steps.len()) {
            return false;
        }
        listed.push(a);
        true
    }
}

/// Whether the leg from `a` to vertex `b` (or from vertex `a`) vanishes: a piece's
/// reflection on the vertex itself (a free end, where the tree reflects), to round-off.
fn vanishes(a: Point, b: Point) -> bool {
    let scale = 1.0 + b.x.abs().max(b.y.abs()).max(a.x.abs().max(a.y.abs()));
    (a - b).length() <= 1e-12 * scale
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
