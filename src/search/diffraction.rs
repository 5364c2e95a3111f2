//! The diffracted arrivals of a search (`"diffraction": true`): per (source, receiver) pair,
//! every vertex of every allowed interface is tried as the first-order diffracted path
//! `[{"diffract": I, "vertex": k}]` (one step, so `max_steps` ≥ 1), each of its two legs
//! searched as the direct path between fixed points (`Tracer::diffracted_sequence`), kept
//! where both legs lie outside the vertex's wedge; a vertex whose two legs cannot arrive by
//! `max_time` (their length at the least slowness) is not tried. The work, one per vertex
//! tried plus the legs' complete searches, is counted into the walk's.
//!
//! With diffraction on, the `vertex` (edge-held) arrivals of one-reflection sequences are
//! the same paths as these: [`drop_listed_twice`] removes them.

use rayon::prelude::*;

use crate::geom::Point;
use crate::options::Progress;
use crate::scene::{SearchOptions, Step, StepKind};
use crate::trace::{Arrival, Status, Tracer};

use super::sequences::PairWalk;
use super::{Control, SearchArrival};

/// The bound's relative margin against round-off.
const TIME_MARGIN: f64 = 1e-9;

impl Tracer {
    /// The diffracted arrivals of every pair, in parallel: (pair index, what it found).
    pub(super) fn diffraction_pairs(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> Vec<(usize, PairWalk)> {
        let scene = self.scene();
        let nr = scene.receivers().len();
        if options.step_limit() == 0 {
            return Vec::new();
        }
        let least = scene
            .media()
            .iter()
            .map(|m| m.slowness)
            .fold(f64::INFINITY, f64::min);
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
        (0..scene.sources().len() * nr)
            .into_par_iter()
            .map(|pair| {
                let (source, receiver) = (pair / nr, pair % nr);
                let found = if control.run.keep_going(Progress { work: 0, items: 1 }) {
                    control.run.within(|| {
                        self.diffracted_pair(options, control, &vertices, least, source, receiver)
                    })
                } else {
                    PairWalk::not_begun()
                };
                (pair, found)
            })
            .collect()
    }

    /// The diffracted arrivals of one pair.
    fn diffracted_pair(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
        vertices: &[(Step, Point)],
        least: f64,
        source: usize,
        receiver: usize,
    ) -> PairWalk {
        let scene = self.scene();
        let (s, r) = (scene.sources()[source], scene.receivers()[receiver]);
        let limit = options.time_limit();
        let mut walk = PairWalk {
            arrivals: Vec::new(),
            complete: true,
            work: 0,
        };
        let mut found: Vec<Arrival> = Vec::new();
        for &(step, v) in vertices {
            if !control.run.keep_going(Progress::work(1)) {
                walk.complete = false;
                break;
            }
            walk.work += 1;
            let bound = least * ((v - s).length() + (r - v).length());
            if bound > limit * (1.0 + TIME_MARGIN) {
                continue;
            }
            let steps = [step];
            let (stats, _) =
                self.diffracted_sequence(&steps, None, s, r, self.search_budget(), &mut found);
            walk.work += stats.work as u64;
            walk.complete &= stats.complete;
            for a in found.drain(..) {
                if !Tracer::listed(a.status, options) || a.time > limit {
                    continue;
                }
                if !control.listed.take(1) {
                    walk.complete = false;
                    return walk;
                }
                walk.arrivals.push(SearchArrival {
                    source,
                    receiver,
                    steps: vec![step],
                    arrival: a,
                    complete: true,
                    heights: Vec::new(),
                });
            }
        }
        walk
    }
}

/// Removes the `vertex` arrivals of one-reflection sequences held on a vertex for which the
/// diffracted arrival of the same pair is listed (the same path: listed once, as diffracted).
pub(super) fn drop_listed_twice(tracer: &Tracer, arrivals: &mut Vec<SearchArrival>) {
    let scene = tracer.scene();
    let diffracted: std::collections::HashSet<(usize, usize, usize, u32)> = arrivals
        .iter()
        .filter_map(|a| match a.steps.as_slice() {
            [
                Step {
                    kind: StepKind::Diffract { vertex },
                    interface,
                },
            ] => Some((a.source, a.receiver, *interface, *vertex)),
            _ => None,
        })
        .collect();
    if diffracted.is_empty() {
        return;
    }
    arrivals.retain(|a| {
        let [step] = a.steps.as_slice() else {
            return true;
        };
        if a.arrival.status != Status::Vertex || step.kind != StepKind::Reflect {
            return true;
        }
        let held = a.arrival.points[1];
        let line = &scene.interfaces()[step.interface].polyline;
        let at = line.vertices().iter().position(|&v| {
            let scale = 1.0 + v.x.abs().max(v.y.abs());
            (held - v).length() <= 1e-9 * scale
        });
        !at.is_some_and(|k| {
            let k = u32::try_from(k).unwrap_or(u32::MAX);
            diffracted.contains(&(a.source, a.receiver, step.interface, k))
        })
    });
}
