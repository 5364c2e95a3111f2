//! The search of an extruded room (`"extrusion"`): every plan path the search finds (the beam
//! tree's and the walk's, as without `extrusion`) combined with its vertical family in closed
//! form. The floor and the ceiling are never searched as walls.
//!
//! In a prism whose walls are vertical and whose floor (z = 0) and ceiling (z = H) are flat,
//! the plan projection of a 3-D specular path is a 2-D specular path and its height unfolds on
//! its own: the floor and ceiling reflections alternate, so a path of `n` of them starting at
//! the floor has the unfolded vertical length `Z = z_s + (n − 1) H + (z_r` or `H − z_r)` (the
//! last reflection the floor or the ceiling; starting at the ceiling, `z_s` becomes `H − z_s`
//! and the last term swaps), and `Z = |z_r − z_s|` without any. Its time is `√(L² + Z²)/c`,
//! with `L` the plan length; its visibility is the plan path's; at a wall its incidence
//! cosine is the plan's times `L/√(L² + Z²)`, at the floor or ceiling `Z/√(L² + Z²)`.
//!
//! The plan search runs within the plan time that a 3-D time of `max_time` still allows (the
//! least `Z` of any pair is `|z_s − z_r|`), and within `max_steps` wall reflections; each plan
//! path then takes the members of its family within both bounds (`max_steps` counts every
//! reflection). Each plan path goes to [`Expansion::arrivals`] the moment it is found, so a
//! streaming search holds none of them.

use std::sync::Mutex;

use crate::amplitude::{Amplitude, Complex64, reflection_against};
use crate::geom::Point;
use crate::options::Run;
use crate::scene::{Extrusion, Reflection, Scene, SearchOptions, Step, StepKind};
use crate::trace::{Status, Tracer};

use super::{
    ArrivalCount, Control, SearchArrival, SearchError, SearchReport, StreamReport, StreamedArrival,
    diffractions, sort_arrivals,
};

/// Which of the two flat faces a vertical family's first reflection is off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Face {
    Floor,
    Ceiling,
}

/// One member of a plan path's vertical family: how many floor and ceiling reflections, off
/// which face first, and its unfolded vertical length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Vertical {
    /// Floor and ceiling reflections (0: none).
    count: usize,
    /// The first one's face (meaningless without any).
    first: Face,
    /// The unfolded vertical length `Z`.
    length: f64,
    /// The 3-D length `√(L² + Z²)` with the plan length `L` ([`length_3d`]).
    distance: f64,
}

/// The unfolded vertical length of `count` alternating reflections, the first off `first`,
/// between heights `zs` and `zr` in a room of height `h`.
fn unfolded(count: usize, first: Face, zs: f64, zr: f64, h: f64) -> f64 {
    if count == 0 {
        return (zr - zs).abs();
    }
    // The last reflection's face: the first's when `count` is odd.
    let last_floor = (first == Face::Floor) == (count % 2 == 1);
    let to_first = if first == Face::Floor { zs } else { h - zs };
    let from_last = if last_floor { zr } else { h - zr };
    to_first + (count - 1) as f64 * h + from_last
}

/// `√(L² + Z²)`: the square root of the sum of squares (within an ulp or so of `hypot`, at
/// a fraction of its cost: one per arrival), `hypot` itself where the squares would
/// overflow or lose digits to underflow.
#[inline]
fn length_3d(plan: f64, z: f64) -> f64 {
    let squares = plan * plan + z * z;
    if squares.is_finite() && squares >= f64::MIN_POSITIVE {
        squares.sqrt()
    } else {
        plan.hypot(z)
    }
}

/// The vertical family of a plan path of plan length `plan` (slowness `slowness`): every
/// member within `max_vertical` reflections and a time of `max_time`, in order of count.
fn family(
    plan: f64,
    slowness: f64,
    [zs, zr, h]: [f64; 3],
    max_vertical: usize,
    max_time: f64,
    out: &mut Vec<Vertical>,
) {
    out.clear();
    let within = |z: f64| {
        let distance = length_3d(plan, z);
        ((distance * slowness) <= max_time).then_some(distance)
    };
    let direct = unfolded(0, Face::Floor, zs, zr, h);
    if let Some(distance) = within(direct) {
        out.push(Vertical {
            count: 0,
            first: Face::Floor,
            length: direct,
            distance,
        });
    }
    for count in 1..=max_vertical {
        let mut any = false;
        for first in [Face::Floor, Face::Ceiling] {
            let length = unfolded(count, first, zs, zr, h);
            if let Some(distance) = within(length) {
                any = true;
                out.push(Vertical {
                    count,
                    first,
                    length,
                    distance,
                });
            }
        }
        // Each face's length grows with the count: none within now, none later.
        if !any {
            break;
        }
    }
}

/// The height at vertical distance `d` along a path from height `zs` that first goes toward
/// `first` (with no flat reflection, `toward` the receiver's height `zr` over `length`).
fn height_at(v: Vertical, zs: f64, zr: f64, h: f64, d: f64) -> f64 {
    if v.count == 0 {
        if v.length == 0.0 {
            return zs;
        }
        return zs + (zr - zs) * (d / v.length);
    }
    let w = if v.first == Face::Floor {
        zs - d
    } else {
        zs + d
    };
    let m = w.rem_euclid(2.0 * h);
    if m > h { 2.0 * h - m } else { m }
}

/// What expands each plan path of one search into its 3-D arrivals.
pub(super) struct Expansion<'a> {
    tracer: &'a Tracer,
    extrusion: &'a Extrusion,
    options: &'a SearchOptions,
    /// The step index of the floor (the scene's count of interfaces) and of the ceiling
    /// (one more).
    floor: usize,
}

impl<'a> Expansion<'a> {
    fn new(tracer: &'a Tracer, extrusion: &'a Extrusion, options: &'a SearchOptions) -> Self {
        Expansion {
            tracer,
            extrusion,
            options,
            floor: tracer.scene().interfaces().len(),
        }
    }

    /// The source's and the receiver's heights of plan path `plan`, and the room's height.
    fn heights(&self, plan: &SearchArrival) -> [f64; 3] {
        let x = self.extrusion;
        [
            x.source_heights[plan.source],
            x.receiver_heights[plan.receiver],
            x.height,
        ]
    }

    /// The 3-D arrivals of plan path `plan`, each handed to `out` (which says whether to go
    /// on); `false` when `out` said stop.
    pub(super) fn arrivals(
        &self,
        plan: &SearchArrival,
        out: &mut dyn FnMut(SearchArrival) -> bool,
    ) -> bool {
        let [zs, zr, h] = self.heights(plan);
        let a = &plan.arrival;
        let medium = a.media.first().copied().unwrap_or(0);
        let slowness = self.tracer.scene().media()[medium].slowness;
        // Cumulative plan arclength at each point.
        let mut at = Vec::with_capacity(a.points.len());
        let mut length = 0.0;
        for (i, p) in a.points.iter().enumerate() {
            if i > 0 {
                length += a.points[i - 1].distance(*p);
            }
            at.push(length);
        }
        let walls = plan.steps.len();
        let max_vertical = self.options.step_limit().saturating_sub(walls);
        let mut members = Vec::new();
        family(
            length,
            slowness,
            [zs, zr, h],
            max_vertical,
            self.options.time_limit(),
            &mut members,
        );
        for v in members {
            if !out(self.member(plan, &at, v, slowness)) {
                return false;
            }
        }
        true
    }

    /// The 3-D arrival of plan path `plan` (cumulative plan arclengths `at`) with vertical
    /// member `v`.
    fn member(
        &self,
        plan: &SearchArrival,
        at: &[f64],
        v: Vertical,
        slowness: f64,
    ) -> SearchArrival {
        let [zs, zr, h] = self.heights(plan);
        let a = &plan.arrival;
        let length = at.last().copied().unwrap_or(0.0);
        let k = plan.steps.len() + v.count;
        let mut steps = Vec::with_capacity(k);
        let mut points = Vec::with_capacity(k + 2);
        let mut heights = Vec::with_capacity(k + 2);
        let mut parameters = Vec::with_capacity(k);
        let mut segments = Vec::with_capacity(k);
        points.push(a.points[0]);
        heights.push(zs);
        // The plan arclength of the j-th flat reflection (vertical distance d₁ + j H).
        let d1 = if v.first == Face::Floor { zs } else { h - zs };
        let flat_at = |j: usize| {
            if v.length > 0.0 {
                length * ((d1 + j as f64 * h) / v.length)
            } else {
                0.0
            }
        };
        let vertical_at = |s: f64| {
            if length > 0.0 {
                v.length * (s / length)
            } else {
                0.0
            }
        };
        let (mut wall, mut flat) = (0, 0);
        while wall < plan.steps.len() || flat < v.count {
            let wall_s = (wall < plan.steps.len()).then(|| at[wall + 1]);
            let flat_s = (flat < v.count).then(|| flat_at(flat));
            let take_wall = match (wall_s, flat_s) {
                (Some(w), Some(f)) => w <= f,
                (Some(_), None) => true,
                _ => false,
            };
            if take_wall {
                steps.push(plan.steps[wall]);
                points.push(a.points[wall + 1]);
                heights.push(height_at(v, zs, zr, h, vertical_at(at[wall + 1])));
                parameters.push(a.parameters.get(wall).copied().unwrap_or(f64::NAN));
                segments.push(a.segments.get(wall).copied().unwrap_or(0));
                wall += 1;
            } else {
                let s = flat_at(flat);
                // The flat faces alternate from the first.
                let floor = (v.first == Face::Floor) == (flat % 2 == 0);
                steps.push(Step {
                    kind: StepKind::Reflect,
                    interface: if floor { self.floor } else { self.floor + 1 },
                });
                points.push(plan_point(&a.points, at, s));
                heights.push(if floor { 0.0 } else { h });
                parameters.push(f64::NAN);
                segments.push(0);
                flat += 1;
            }
        }
        points.push(*a.points.last().unwrap_or(&a.points[0]));
        heights.push(zr);
        let time = v.distance * slowness;
        let medium = a.media.first().copied().unwrap_or(0);
        let mut arrival = a.clone();
        arrival.time = time;
        arrival.points = points;
        arrival.parameters = parameters;
        arrival.segments = segments;
        arrival.media = vec![medium; k + 1];
        arrival.amplitude = None;
        let mut out = SearchArrival {
            source: plan.source,
            receiver: plan.receiver,
            steps,
            arrival,
            complete: true,
            heights,
        };
        if self.tracer.scene().amplitudes().is_some() {
            out.arrival.amplitude = Some(self.amplitude(plan, length, v, None));
        }
        out
    }

    /// The amplitude of the 3-D arrival of plan path `plan` (plan length `length`) with
    /// vertical member `v`: `1/(4π D)` spreading over the path's length `D`, each wall's law
    /// at its 3-D incidence angle, the floor's and ceiling's (alternating from `v`'s first,
    /// in order along the path), the medium's attenuation over `D`. `walls`: the walls'
    /// product of coefficients where it was computed once for the whole family (a plan path
    /// of no `"media"` law, whose coefficients do not depend on the angle), the same number.
    fn amplitude(
        &self,
        plan: &SearchArrival,
        length: f64,
        v: Vertical,
        walls: Option<Complex64>,
    ) -> Amplitude {
        let scene: &Scene = self.tracer.scene();
        if scene.amplitudes().is_none() {
            return Amplitude::none(crate::amplitude::NoAmplitude::UnknownMedia);
        }
        match plan.arrival.status {
            Status::Vertex => return Amplitude::none(crate::amplitude::NoAmplitude::Vertex),
            Status::Obstructed => {
                return Amplitude::none(crate::amplitude::NoAmplitude::Obstructed);
            }
            _ => {}
        }
        let distance = v.distance;
        // The plan leg's share of each 3-D leg: the wall cosines scale by it.
        let horizontal = if distance > 0.0 {
            length / distance
        } else {
            0.0
        };
        let mut coefficient = match walls {
            Some(c) => c,
            None => match self.walls_coefficient(plan, horizontal) {
                Ok(c) => c,
                Err(none) => return none,
            },
        };
        // The flat faces alternate from the first, in order along the path.
        for flat in 0..v.count {
            coefficient *= self.flat_coefficient(v.first, flat);
        }
        self.amplitude_with(plan, v, coefficient)
    }

    /// The coefficient of the `flat`-th floor or ceiling reflection (from 0) of a member
    /// whose first is off `first`: the faces alternate from the first.
    #[inline]
    fn flat_coefficient(&self, first: Face, flat: usize) -> f64 {
        if (first == Face::Floor) == flat.is_multiple_of(2) {
            self.extrusion.floor
        } else {
            self.extrusion.ceiling
        }
    }

    /// [`Expansion::amplitude`] of a converged plan path `plan`'s member `v` whose
    /// reflections' product of coefficients, in order, is `coefficient`.
    fn amplitude_with(
        &self,
        plan: &SearchArrival,
        v: Vertical,
        coefficient: Complex64,
    ) -> Amplitude {
        let scene: &Scene = self.tracer.scene();
        let Some(settings) = scene.amplitudes() else {
            return Amplitude::none(crate::amplitude::NoAmplitude::UnknownMedia);
        };
        let distance = v.distance;
        let medium = plan.arrival.media.first().copied().unwrap_or(0);
        let spreading = 1.0 / (4.0 * std::f64::consts::PI * distance);
        let attenuation_db = settings.attenuation[medium] * distance;
        // 10⁰ is 1 exactly: no power to take without attenuation.
        let attenuation = if attenuation_db == 0.0 {
            1.0
        } else {
            10f64.powf(-attenuation_db / 20.0)
        };
        Amplitude {
            value: coefficient * spreading * attenuation,
            spreading,
            coefficient,
            attenuation_db,
            reason: None,
        }
    }

    /// The product of plan path `plan`'s wall coefficients, in order, each wall's law at its
    /// 3-D incidence angle (the plan cosine times `horizontal`, the plan leg's share of the
    /// 3-D leg); the amplitude without one where a `"media"` law finds no medium across.
    fn walls_coefficient(
        &self,
        plan: &SearchArrival,
        horizontal: f64,
    ) -> Result<Complex64, Amplitude> {
        let scene: &Scene = self.tracer.scene();
        let Some(settings) = scene.amplitudes() else {
            return Err(Amplitude::none(crate::amplitude::NoAmplitude::UnknownMedia));
        };
        let medium = plan.arrival.media.first().copied().unwrap_or(0);
        let slowness = scene.media()[medium].slowness;
        let mut coefficient = Complex64::new(1.0, 0.0);
        let p = &plan.arrival.points;
        for (i, step) in plan.steps.iter().enumerate() {
            if step.kind != StepKind::Reflect {
                // A refraction between one medium and itself: the wave passes on.
                continue;
            }
            let r = match settings.reflection[step.interface] {
                Reflection::Fixed(r) => Complex64::new(r, 0.0),
                Reflection::Media => {
                    let line = &scene.interfaces()[step.interface].polyline;
                    let seg = plan.arrival.segments.get(i).copied().unwrap_or(0);
                    let (from, here) = (p[i], p[i + 1]);
                    let start = line.segment(seg).start;
                    let tangent = line.tangent(seg);
                    let s = line.start(seg) + (here - start).dot(tangent);
                    let across = self
                        .tracer
                        .regions()
                        .and_then(|r| r.medium_across(step.interface, seg, s, from));
                    let Some(across) = across else {
                        return Err(Amplitude::none(
                            crate::amplitude::NoAmplitude::NoMediumAcross { step: i },
                        ));
                    };
                    let leg = here - from;
                    let plan_cos = if leg.length() > 0.0 {
                        leg.cross(tangent).abs() / leg.length()
                    } else {
                        0.0
                    };
                    let w_across = scene.media()[across].slowness;
                    reflection_against(
                        settings,
                        [medium, across],
                        [slowness, w_across],
                        plan_cos * horizontal,
                    )
                }
            };
            coefficient *= r;
        }
        Ok(coefficient)
    }

    /// [`Expansion::arrivals`] for a streaming search: each 3-D arrival of plan path `plan`
    /// as [`SearchArrival::streamed`] gives it (the same steps, time and amplitude, to the
    /// bit), handed to `out` without its points; `false` when `out` said stop. A plan path
    /// of no `"media"` law takes its walls' coefficients once for its whole family.
    pub(super) fn streamed(
        &self,
        plan: &SearchArrival,
        out: &mut dyn FnMut(StreamedArrival) -> bool,
    ) -> bool {
        let [zs, zr, h] = self.heights(plan);
        let a = &plan.arrival;
        let medium = a.media.first().copied().unwrap_or(0);
        let slowness = self.tracer.scene().media()[medium].slowness;
        // The plan length, summed as `arrivals` sums it.
        let mut length = 0.0;
        for i in 1..a.points.len() {
            length += a.points[i - 1].distance(a.points[i]);
        }
        let walls = plan.steps.len();
        let max_vertical = self.options.step_limit().saturating_sub(walls);
        let mut members = Vec::new();
        family(
            length,
            slowness,
            [zs, zr, h],
            max_vertical,
            self.options.time_limit(),
            &mut members,
        );
        // The wall reflections without a parameter count as vertical ones, as `streamed`
        // counts them.
        let unplaced = (plan.steps.iter().enumerate())
            .filter(|&(i, s)| {
                s.kind == StepKind::Reflect && a.parameters.get(i).is_none_or(|t| t.is_nan())
            })
            .count();
        let diffractions = diffractions(&plan.steps);
        let amplitudes = self.tracer.scene().amplitudes();
        let fixed = amplitudes.and_then(|settings| {
            let angle_free = (plan.steps.iter())
                .all(|s| !matches!(settings.reflection[s.interface], Reflection::Media));
            let ready = angle_free && matches!(a.status, Status::Converged);
            ready.then(|| self.walls_coefficient(plan, 0.0).ok())?
        });
        // Where the walls' product is fixed, each member's product of coefficients is that
        // of the member one flat reflection fewer off the same first face, times the next
        // face's: per first face, the flats multiplied so far and their product (the same
        // multiplications in the same order as `amplitude`'s, so the same bits).
        let mut products = fixed.map(|c| [(0, c), (0, c)]);
        for v in members {
            let amplitude = amplitudes.map(|_| match &mut products {
                Some(products) => {
                    let (done, product) = &mut products[usize::from(v.first == Face::Ceiling)];
                    while *done < v.count {
                        *product *= self.flat_coefficient(v.first, *done);
                        *done += 1;
                    }
                    self.amplitude_with(plan, v, *product)
                }
                None => self.amplitude(plan, length, v, fixed),
            });
            let arrival = StreamedArrival {
                source: plan.source,
                receiver: plan.receiver,
                steps: walls + v.count,
                diffractions,
                vertical_reflections: unplaced + v.count,
                status: a.status,
                time: v.distance * slowness,
                amplitude,
            };
            if !out(arrival) {
                return false;
            }
        }
        true
    }
}

/// The most arrivals of one vertical family handed to a streaming search's sink at once.
const FAMILY_BATCH: usize = 256;

/// The plan point at arclength `s` along the plan path through `points` (cumulative
/// arclengths `at`).
fn plan_point(points: &[Point], at: &[f64], s: f64) -> Point {
    let i = at.partition_point(|&a| a <= s).clamp(1, points.len() - 1);
    let (a, b) = (points[i - 1], points[i]);
    let span = at[i] - at[i - 1];
    if span > 0.0 {
        a.lerp(b, ((s - at[i - 1]) / span).clamp(0.0, 1.0))
    } else {
        a
    }
}

/// The plan search's options: its time bound the plan time that `max_time` still allows with
/// the least unfolded vertical length of any pair, `|z_s − z_r|`.
fn plan_options(scene: &Scene, options: &SearchOptions, x: &Extrusion) -> SearchOptions {
    let mut plan = options.clone();
    if let Some(t) = options.max_time {
        let least_slowness = scene
            .media()
            .iter()
            .map(|m| m.slowness)
            .fold(f64::INFINITY, f64::min);
        let least_dz = x
            .source_heights
            .iter()
            .flat_map(|zs| x.receiver_heights.iter().map(move |zr| (zs - zr).abs()))
            .fold(f64::INFINITY, f64::min);
        let vertical_time = least_dz * least_slowness;
        if vertical_time.is_finite() && vertical_time < t {
            // √(T² − (Z/c)²), rounded up so that no plan path of a listed arrival is cut.
            let plan_time = ((t - vertical_time) * (t + vertical_time)).sqrt();
            plan.max_time = Some((plan_time * (1.0 + 4.0 * f64::EPSILON)).min(t));
        }
    }
    plan
}

impl Tracer {
    /// [`search`](Tracer::search) of an extruded scene: every plan path expanded into its
    /// vertical family, listed, ordered and with amplitudes as without `extrusion`.
    pub(super) fn search_extruded(
        &self,
        options: &SearchOptions,
        run: &Run,
        x: &Extrusion,
    ) -> Result<SearchReport, SearchError> {
        let scene = self.scene();
        let nr = scene.receivers().len();
        let mut pairs = self.pair_table()?;
        let listed = ArrivalCount::new(&run.limits);
        let plan = plan_options(scene, options, x);
        let expansion = Expansion::new(self, x, options);
        let found: Mutex<Vec<SearchArrival>> = Mutex::new(Vec::new());
        let paths = |p: SearchArrival| {
            let mut mine = Vec::new();
            let go_on = expansion.arrivals(&p, &mut |a| {
                if !listed.take(a.steps.len()) {
                    return false;
                }
                mine.push(a);
                true
            });
            found.lock().unwrap_or_else(|e| e.into_inner()).extend(mine);
            go_on
        };
        let control = Control {
            run,
            listed: &listed,
            sink: None,
            paths: Some(&paths),
        };
        let (mut report, _) = self.strategies(&plan, &control, &mut pairs);
        let mut arrivals = found.into_inner().unwrap_or_else(|e| e.into_inner());
        for a in &mut arrivals {
            a.complete = pairs[a.source * nr + a.receiver].complete;
        }
        if !run.stop_requested() {
            sort_arrivals(&mut arrivals);
        }
        report.arrivals = arrivals;
        Ok(report)
    }

    /// [`search_into`](Tracer::search_into) of an extruded scene: each 3-D arrival handed to
    /// `sink` with its amplitude the moment its plan path is found; nothing kept.
    pub(super) fn search_extruded_into(
        &self,
        options: &SearchOptions,
        run: &Run,
        x: &Extrusion,
        sink: &dyn super::ArrivalSink,
    ) -> Result<StreamReport, SearchError> {
        let scene = self.scene();
        let mut pairs = self.pair_table()?;
        let listed = ArrivalCount::new(&run.limits);
        let plan = plan_options(scene, options, x);
        let expansion = Expansion::new(self, x, options);
        // A family's arrivals go to the sink in batches (one lock per output a batch, not
        // per arrival), in order.
        let paths = |p: SearchArrival| {
            let mut batch = Vec::with_capacity(FAMILY_BATCH);
            expansion.streamed(&p, &mut |a| {
                batch.push(a);
                if batch.len() == FAMILY_BATCH {
                    listed.stream_many(batch.len());
                    sink.arrivals(&batch);
                    batch.clear();
                }
                true
            });
            if !batch.is_empty() {
                listed.stream_many(batch.len());
                sink.arrivals(&batch);
            }
            true
        };
        let control = Control {
            run,
            listed: &listed,
            sink: None,
            paths: Some(&paths),
        };
        let (report, _) = self.strategies(&plan, &control, &mut pairs);
        Ok(StreamReport {
            arrivals: listed.count.load(std::sync::atomic::Ordering::Relaxed),
            beams: report.beams,
            leaves: report.leaves,
            tree_work: report.tree_work,
            work: report.work,
            incomplete_pairs: report.incomplete_pairs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unfolded lengths against the image sources of the floor (z → −z) and the ceiling
    /// (z → 2H − z) applied in order.
    #[test]
    fn unfolded_lengths_are_the_image_sources_distances() {
        let (zs, zr, h): (f64, f64, f64) = (0.7, 2.1, 3.0);
        for count in 0..7 {
            for first in [Face::Floor, Face::Ceiling] {
                let mut z = zs;
                let mut floor = first == Face::Floor;
                for _ in 0..count {
                    z = if floor { -z } else { 2.0 * h - z };
                    floor = !floor;
                }
                let expected = (zr - z).abs();
                let got = unfolded(count, first, zs, zr, h);
                assert!(
                    (got - expected).abs() < 1e-12,
                    "{count} {first:?}: {got} {expected}"
                );
            }
        }
    }

    /// The 3-D length is `hypot`'s to an ulp or two everywhere, and exactly where one side
    /// is 0, with no overflow or underflow at the ends of the range.
    #[test]
    fn the_3d_length_is_hypot() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut cases = vec![
            (0.0, 0.0),
            (0.0, 3.0),
            (4.0, 0.0),
            (3.0, 4.0),
            (1e-200, 1e-200),
            (1e200, 1e200),
            (1e300, 1.0),
            (f64::MIN_POSITIVE, 0.0),
        ];
        for _ in 0..100_000 {
            let scale = 10f64.powf(next() * 40.0 - 20.0);
            cases.push((next() * scale * 200.0, next() * scale * 20.0));
        }
        for (l, z) in cases {
            let (got, want) = (length_3d(l, z), l.hypot(z));
            assert!(
                got.is_finite() && (got - want).abs() <= 2.0 * f64::EPSILON * want,
                "{l} {z}: {got} {want}"
            );
        }
        assert_eq!(length_3d(0.0, 2.5), 2.5);
        assert_eq!(length_3d(7.0, 0.0), 7.0);
    }

    /// The heights along a path fold back at the faces: at each flat reflection's distance,
    /// the floor's or the ceiling's height; at the end, the receiver's.
    #[test]
    fn heights_fold_at_the_faces() {
        let (zs, zr, h): (f64, f64, f64) = (0.7, 2.1, 3.0);
        for count in 1..6 {
            for first in [Face::Floor, Face::Ceiling] {
                let v = Vertical {
                    count,
                    first,
                    length: unfolded(count, first, zs, zr, h),
                    distance: f64::NAN,
                };
                let end = height_at(v, zs, zr, h, v.length);
                assert!((end - zr).abs() < 1e-12, "{count} {first:?}: {end}");
            }
        }
    }
}
