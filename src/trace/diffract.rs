//! Paths with `diffract` steps. A diffraction holds its point on a vertex: it has no unknown,
//! so the time of the path is the sum of the times of its pieces (the specular paths from the
//! source to the first vertex, between vertices, and from the last vertex to the receiver),
//! and the path is stationary exactly when each piece is. Each piece is searched completely
//! on its own (`stationary_of`, from one fixed point to the next), and the diffracted paths
//! are every combination of the pieces' arrivals whose legs at each vertex lie outside its
//! wedge (both in the side of the vertex that the incoming leg comes from; at an open end,
//! anywhere). A diffraction keeps the medium, as a reflection does.
//!
//! `"stationary": "all"` lists every combination; the default mode reports the earliest one
//! that is not `obstructed` (else the earliest), so that its `no_path` is a proof too.

use crate::amplitude::diffraction::Wedge;
use crate::geom::Point;
use crate::scene::{SegmentRef, Step};

use super::classify::{END_MARGIN, Sequence};
use super::complete::{Arrival, Kink, SearchBudget};
use super::{RayRecord, Reason, SearchOutcome, Status, Tracer, Workspace};

/// Combinations of the pieces' arrivals a search of one diffracted ray keeps at most; beyond,
/// it is not complete.
const MAX_COMBINATIONS: usize = 1 << 14;

/// The leg directions within this angle (rad) beyond a face still count as outside the wedge
/// (a leg along a face, to round-off).
const FACE_SLACK: f64 = 1e-9;

impl Tracer {
    /// Every diffracted path of path `path` (which has `diffract` steps) from `source` to
    /// `receiver` into `out` (emptied first), by time; the reason of an empty list (a leg
    /// into a wedge, when that is what ruled the paths out).
    pub(crate) fn diffracted_paths(
        &self,
        path: usize,
        source: Point,
        receiver: Point,
        budget: SearchBudget,
        out: &mut Vec<Arrival>,
    ) -> (SearchOutcome, Option<Reason>) {
        let spec = &self.scene.paths()[path];
        let (steps, given) = (&spec.steps, spec.media.as_deref());
        self.diffracted_sequence(steps, given, source, receiver, budget, out)
    }

    /// [`diffracted_paths`](Self::diffracted_paths) of any sequence `steps` with `diffract`
    /// steps (the leg media `given`, or looked up): what the search's diffraction calls.
    pub(crate) fn diffracted_sequence(
        &self,
        steps: &[Step],
        given: Option<&[usize]>,
        source: Point,
        receiver: Point,
        budget: SearchBudget,
        out: &mut Vec<Arrival>,
    ) -> (SearchOutcome, Option<Reason>) {
        out.clear();
        let scene = &*self.scene;
        let cuts: Vec<usize> = (0..steps.len())
            .filter(|&i| steps[i].kind.vertex().is_some())
            .collect();
        let mut stats = SearchOutcome::new();
        let mut into_wedge = None;
        let mut partial = vec![Arrival {
            status: Status::Converged,
            time: 0.0,
            points: vec![source],
            ..empty_arrival()
        }];
        let mut pieces = Vec::new();
        let mut start = 0;
        for (j, end) in cuts.iter().copied().chain([steps.len()]).enumerate() {
            let from = partial_end(&partial, source);
            let to = match cuts.get(j) {
                Some(&i) => vertex_point(scene, steps[i]),
                None => receiver,
            };
            let piece_steps = &steps[start..end];
            let media = given.map(|m| &m[start..=end]);
            // Per medium at `from` (with region lookup), the piece's arrivals.
            let mut searched: Vec<(Option<usize>, Vec<Arrival>)> = Vec::new();
            let mut next = Vec::new();
            for p in &partial {
                let medium = match (given, j) {
                    (Some(_), _) => None,
                    (None, 0) => self.source_medium(false, source),
                    (None, _) => p.media.last().copied(),
                };
                let at = match searched.iter().position(|(m, _)| *m == medium) {
                    Some(at) => at,
                    None => {
                        let sequence = Sequence {
                            steps: piece_steps,
                            path: None,
                            curved: &[],
                        };
                        let found = crate::options::with_current(|run| {
                            self.piece_of(
                                sequence,
                                media,
                                from,
                                medium,
                                to,
                                budget,
                                run,
                                &mut pieces,
                            )
                        });
                        stats.add(found);
                        searched.push((medium, std::mem::take(&mut pieces)));
                        searched.len() - 1
                    }
                };
                for a in &searched[at].1 {
                    if j > 0 {
                        let i = cuts[j - 1];
                        if !outside_wedge(scene, steps[i], p, a) {
                            into_wedge.get_or_insert(Reason::WrongSide { step: i });
                            continue;
                        }
                    }
                    if next.len() >= MAX_COMBINATIONS {
                        stats.complete = false;
                        break;
                    }
                    next.push(joined(
                        scene,
                        steps,
                        j.checked_sub(1).map(|c| cuts[c]),
                        p,
                        a,
                    ));
                }
            }
            partial = next;
            start = end + 1;
            if partial.is_empty() {
                break;
            }
        }
        partial.sort_by(|a, b| a.time.total_cmp(&b.time));
        *out = partial;
        let reason = if out.is_empty() { into_wedge } else { None };
        (stats, reason)
    }

    /// The default mode's ray of a diffracted path (see the module): the earliest diffracted
    /// path that is not `obstructed` (else the earliest), left in `ws` as a solve leaves its
    /// ray.
    pub(crate) fn solve_diffracted(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
    ) -> RayRecord {
        let spec = &self.scene.paths()[path];
        if let [step] = spec.steps[..] {
            return self.solve_one_diffraction(source, receiver, step, spec.media.as_deref(), ws);
        }
        let mut arrivals = Vec::new();
        let (stats, into_wedge) =
            self.diffracted_paths(path, source, receiver, self.search_budget(), &mut arrivals);
        let best = arrivals
            .iter()
            .find(|a| a.status != Status::Obstructed)
            .or(arrivals.first());
        ws.ray.points.clear();
        ws.ray.media.clear();
        let Some(a) = best else {
            let reason = match (stats.complete, into_wedge) {
                (true, Some(r)) => r,
                _ => stats.reason_without_arrivals(),
            };
            return RayRecord {
                status: if stats.complete {
                    Status::NoPath
                } else {
                    Status::NotConverged
                },
                time: f64::NAN,
                iterations: 0,
                residual: f64::NAN,
                reason: Some(reason),
            };
        };
        let k = self.scene.paths()[path].steps.len();
        ws.resize(k);
        ws.newton.s[..k].copy_from_slice(&a.parameters);
        ws.newton.seg[..k].copy_from_slice(&a.segments);
        ws.ray.points.extend_from_slice(&a.points);
        ws.ray.media.extend_from_slice(&a.media);
        RayRecord {
            status: a.status,
            time: a.time,
            iterations: u32::try_from(a.iterations).unwrap_or(u32::MAX),
            residual: a.residual,
            reason: a.reason,
        }
    }
}

impl Tracer {
    /// The arrivals of one piece of a diffracted sequence (`sequence`: the steps between two
    /// diffractions, or before the first, or after the last) from `from` (in `medium`, or with
    /// `media` given) to `to`, into `out`: its complete search, or the straight leg of a piece
    /// without steps. What [`diffracted_sequence`](Self::diffracted_sequence) combines.
    #[expect(
        clippy::too_many_arguments,
        reason = "the complete search's arguments, passed through"
    )]
    fn piece_of(
        &self,
        sequence: Sequence<'_>,
        media: Option<&[usize]>,
        from: Point,
        medium: Option<usize>,
        to: Point,
        budget: SearchBudget,
        run: &crate::options::Run,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        if media.is_none() && medium.is_none() {
            // No medium where the piece starts: no path.
            out.clear();
            SearchOutcome::new()
        } else if sequence.steps.is_empty() {
            let m = media.map_or(medium, |m| m.first().copied());
            self.direct_piece(from, to, m, media.is_none(), out);
            SearchOutcome::new()
        } else {
            self.stationary_of(sequence, media, from, medium, to, budget, run, out)
        }
    }

    /// The one arrival of a piece without steps (a straight leg from `from` to `to` in medium
    /// `medium`), as the complete search of the direct path gives it: `converged`, or
    /// `obstructed` where the leg crosses an interface; none where the leg vanishes or, with
    /// the media looked up (`lookup`), where its middle lies in another medium.
    fn direct_piece(
        &self,
        from: Point,
        to: Point,
        medium: Option<usize>,
        lookup: bool,
        out: &mut Vec<Arrival>,
    ) {
        out.clear();
        let Some(leg) = self.straight_leg(from, to, medium, lookup) else {
            return;
        };
        out.push(Arrival {
            status: leg.status,
            time: leg.time,
            points: vec![from, to],
            media: vec![leg.medium],
            reason: leg.reason,
            ..empty_arrival()
        });
    }

    /// [`direct_piece`](Self::direct_piece)'s arrival without its points: what a path of one
    /// diffraction is made of.
    fn straight_leg(
        &self,
        from: Point,
        to: Point,
        medium: Option<usize>,
        lookup: bool,
    ) -> Option<StraightLeg> {
        let m = medium?;
        let length = (to - from).length();
        if length == 0.0 {
            return None;
        }
        let scene = &*self.scene;
        let crossing = scene.first_crossing(from, to, END_MARGIN, [SegmentRef::NONE; 2]);
        if lookup
            && crossing.is_none()
            && let Some(regions) = self.regions.as_ref()
            && regions.medium_at(from.lerp(to, 0.5)) != Some(m)
        {
            return None;
        }
        let (status, reason) = match crossing {
            Some(r) => (
                Status::Obstructed,
                Some(Reason::Crosses {
                    leg: 0,
                    interface: r.interface as usize,
                }),
            ),
            None => (Status::Converged, None),
        };
        Some(StraightLeg {
            status,
            time: length * scene.media()[m].slowness,
            medium: m,
            reason,
        })
    }

    /// The ray of a path of one diffraction `step` (leg media `given`, or looked up), left in
    /// `ws`: what [`solve_diffracted`](Self::solve_diffracted) gives through the pieces'
    /// arrivals, bit for bit, from the two straight legs without a list of arrivals.
    fn solve_one_diffraction(
        &self,
        source: Point,
        receiver: Point,
        step: Step,
        given: Option<&[usize]>,
        ws: &mut Workspace,
    ) -> RayRecord {
        let scene = &*self.scene;
        let vertex = vertex_point(scene, step);
        ws.ray.points.clear();
        ws.ray.media.clear();
        let lookup = given.is_none();
        let first = match given {
            Some(m) => m.first().copied(),
            None => self.source_medium(false, source),
        };
        let legs = self
            .straight_leg(source, vertex, first, lookup)
            .and_then(|a| {
                let second = given.map_or(Some(a.medium), |m| m.get(1).copied());
                let b = self.straight_leg(vertex, receiver, second, lookup)?;
                Some((a, b))
            });
        let Some((a, b)) = legs else {
            return no_path(SearchOutcome::new().reason_without_arrivals());
        };
        if !outside_wedge_at(scene, step, source, vertex, receiver) {
            return no_path(Reason::WrongSide { step: 0 });
        }
        let (status, reason) = match (a.status, b.status) {
            (Status::Obstructed, _) => (Status::Obstructed, a.reason),
            (_, Status::Obstructed) => (Status::Obstructed, b.reason.map(|r| shift_reason(r, 1))),
            _ => (Status::Converged, None),
        };
        let line = &scene.interfaces()[step.interface].polyline;
        let v = step.kind.vertex().unwrap_or(0);
        ws.resize(1);
        ws.newton.s[0] = line.start(v);
        ws.newton.seg[0] = v.min(line.num_segments() - 1);
        ws.ray.points.extend_from_slice(&[source, vertex, receiver]);
        ws.ray.media.extend_from_slice(&[a.medium, b.medium]);
        RayRecord {
            status,
            time: (0.0 + a.time) + b.time,
            iterations: 0,
            residual: 0.0,
            reason,
        }
    }
}

/// A straight leg of a diffracted path: its status, time, medium and (when `obstructed`) the
/// crossing.
struct StraightLeg {
    status: Status,
    time: f64,
    medium: usize,
    reason: Option<Reason>,
}

/// The ray record of a diffracted path that has no path, for `reason`.
fn no_path(reason: Reason) -> RayRecord {
    RayRecord {
        status: Status::NoPath,
        time: f64::NAN,
        iterations: 0,
        residual: f64::NAN,
        reason: Some(reason),
    }
}

/// An arrival with nothing in it yet.
fn empty_arrival() -> Arrival {
    Arrival {
        status: Status::Converged,
        time: 0.0,
        points: Vec::new(),
        parameters: Vec::new(),
        segments: Vec::new(),
        media: Vec::new(),
        iterations: 0,
        reason: None,
        kink: None,
        residual: 0.0,
        amplitude: None,
        turns: None,
        caustics: None,
        launch_angle: None,
    }
}

/// The partial path of a diffracted sequence made of its first piece's arrival `a` from
/// `source` (what [`Tracer::diffracted_sequence`] begins with, bit for bit).
pub(crate) fn first_piece(scene: &crate::Scene, source: Point, a: &Arrival) -> Arrival {
    let start = Arrival {
        status: Status::Converged,
        time: 0.0,
        points: vec![source],
        ..empty_arrival()
    };
    joined(scene, &[], None, &start, a)
}

/// The partial path `p` (ending at the vertex of diffraction `steps[cut]`) continued by the
/// next piece's arrival `a`, where both legs at the vertex lie outside its wedge (else
/// `None`): [`Tracer::diffracted_sequence`]'s join, bit for bit.
pub(crate) fn through_vertex(
    scene: &crate::Scene,
    steps: &[Step],
    cut: usize,
    p: &Arrival,
    a: &Arrival,
) -> Option<Arrival> {
    outside_wedge(scene, steps[cut], p, a).then(|| joined(scene, steps, Some(cut), p, a))
}

/// Where the partial paths end (all at the same point: the last vertex, or the source).
fn partial_end(partial: &[Arrival], source: Point) -> Point {
    partial
        .first()
        .and_then(|p| p.points.last().copied())
        .unwrap_or(source)
}

/// The point of diffraction step `step`: its vertex.
fn vertex_point(scene: &crate::Scene, step: Step) -> Point {
    let line = &scene.interfaces()[step.interface].polyline;
    line.vertices()[step.kind.vertex().unwrap_or(0)]
}

/// Whether the legs of `p` (ending at the vertex of `step`) and `a` (leaving it) lie outside
/// the vertex's wedge, on the side the incoming leg comes from.
fn outside_wedge(scene: &crate::Scene, step: Step, p: &Arrival, a: &Arrival) -> bool {
    let n = p.points.len();
    outside_wedge_at(scene, step, p.points[n - 2], p.points[n - 1], a.points[1])
}

/// Whether the legs from `before` to `here` (the vertex of `step`) and on to `after` lie
/// outside the vertex's wedge, on the side `before` lies on.
fn outside_wedge_at(
    scene: &crate::Scene,
    step: Step,
    before: Point,
    here: Point,
    after: Point,
) -> bool {
    let (d_in, d_out) = (before - here, after - here);
    if d_in.length() == 0.0 || d_out.length() == 0.0 {
        return false;
    }
    let line = &scene.interfaces()[step.interface].polyline;
    let vertex = step.kind.vertex().unwrap_or(0);
    let wedge = Wedge::at(line.vertices(), line.is_closed(), vertex, d_in);
    wedge.angle_of(d_out, FACE_SLACK).is_some()
}

/// The partial path `p` continued by piece arrival `a` through the diffraction at step `cut`
/// (none for the first piece).
fn joined(
    scene: &crate::Scene,
    steps: &[Step],
    cut: Option<usize>,
    p: &Arrival,
    a: &Arrival,
) -> Arrival {
    let mut out = p.clone();
    let offset = out.parameters.len() + usize::from(cut.is_some());
    if let Some(i) = cut {
        let line = &scene.interfaces()[steps[i].interface].polyline;
        let v = steps[i].kind.vertex().unwrap_or(0);
        // The segment its vertex starts (the last one at an open polyline's end).
        let seg = v.min(line.num_segments() - 1);
        out.parameters.push(line.start(v));
        out.segments.push(seg);
    }
    out.time += a.time;
    out.points.extend_from_slice(&a.points[1..]);
    out.parameters.extend_from_slice(&a.parameters);
    out.segments.extend_from_slice(&a.segments);
    out.media.extend_from_slice(&a.media);
    out.iterations += a.iterations;
    out.residual = out.residual.max(a.residual);
    let shifted = a.reason.map(|r| shift_reason(r, offset));
    out.status = match (out.status, a.status) {
        (Status::Obstructed, _) => Status::Obstructed,
        (_, Status::Obstructed) => {
            out.reason = shifted;
            Status::Obstructed
        }
        (Status::Vertex, _) | (_, Status::Vertex) => {
            out.reason = out.reason.or(shifted);
            Status::Vertex
        }
        (s, _) => s,
    };
    out.kink = match (out.kink, a.kink) {
        (None, k) | (k, None) => k,
        (Some(x), Some(y)) if x == y => Some(x),
        _ => Some(Kink::Mixed),
    };
    out
}

/// A piece's reason with its step and leg indices made the whole path's.
fn shift_reason(r: Reason, offset: usize) -> Reason {
    match r {
        Reason::LeavesEnd { step } => Reason::LeavesEnd {
            step: step + offset,
        },
        Reason::WrongSide { step } => Reason::WrongSide {
            step: step + offset,
        },
        Reason::AtVertex { step } => Reason::AtVertex {
            step: step + offset,
        },
        Reason::Crosses { leg, interface } => Reason::Crosses {
            leg: leg + offset,
            interface,
        },
        Reason::NoMedium { leg } => Reason::NoMedium { leg: leg + offset },
        Reason::Coincident { step } => Reason::Coincident {
            step: step + offset,
        },
        Reason::AtEnd { step } => Reason::AtEnd {
            step: step + offset,
        },
        Reason::BeyondEnd { step } => Reason::BeyondEnd {
            step: step + offset,
        },
        other => other,
    }
}
