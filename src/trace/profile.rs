//! Rays through a `profile` medium (speed piecewise linear in `y`): a path without steps
//! whose source lies in such a medium has, between its source and its receiver, every ray
//! of [`Profile::arrivals`] (the ray-parameter form, `leg/profile.rs`). `"stationary":
//! "all"` lists each; the default mode's ray is the earliest one that no interface crosses.
//! Each ray is tested for obstruction as the polygon inscribed in its arcs.

use crate::geom::Point;
use crate::leg::profile::{Profile, ProfileArrivals, ProfileRay};
use crate::scene::{Scene, SegmentRef};

use super::classify::END_MARGIN;
use super::complete::Arrival;
use super::{RayRecord, Reason, SearchOutcome, Status, Tracer, Workspace};

/// Points drawn per piece of a ray (between knots and turning points) for its obstruction
/// test.
const PIECE_POINTS: usize = 16;

/// One ray of a profile medium with what the tracer decided of it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TracedProfileRay {
    /// The ray.
    pub ray: ProfileRay,
    /// `converged`, or `obstructed` (with the interface crossed).
    pub status: Status,
    /// Why it is not `converged`.
    pub reason: Option<Reason>,
}

impl Tracer {
    /// The profile medium of path `path` from `source` when the path has no steps and its
    /// one leg's medium (given, or found at the source) has a profile.
    pub(crate) fn profile_medium(
        &self,
        path: usize,
        source: Point,
        src_medium: Option<usize>,
    ) -> Option<(usize, Profile)> {
        let spec = self.scene.paths().get(path)?;
        if !spec.steps.is_empty() || !self.scene.curved() {
            return None;
        }
        let m = match &spec.media {
            Some(m) => *m.first()?,
            None => src_medium.or_else(|| self.source_medium(false, source))?,
        };
        Some((m, self.scene.media()[m].profile_model()?))
    }

    /// Every ray of `profile` from `source` to `receiver`, each with its status.
    pub(crate) fn profile_rays(
        &self,
        profile: &Profile,
        source: Point,
        receiver: Point,
    ) -> (Vec<TracedProfileRay>, ProfileArrivals) {
        let found = profile.arrivals_cached(source.to_vec2(), receiver.to_vec2());
        let rays = found
            .rays
            .iter()
            .map(|ray| {
                let hit = profile_crossing(&self.scene, profile, ray, source, receiver);
                TracedProfileRay {
                    ray: *ray,
                    status: if hit.is_some() {
                        Status::Obstructed
                    } else {
                        Status::Converged
                    },
                    reason: hit.map(|interface| Reason::Crosses { leg: 0, interface }),
                }
            })
            .collect();
        (rays, found)
    }

    /// The default mode's ray of a path through a profile medium: the earliest ray that no
    /// interface crosses (else the earliest, `obstructed`), into `ws`.
    pub(crate) fn solve_profile(
        &self,
        medium: usize,
        profile: &Profile,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> RayRecord {
        ws.resize(0);
        ws.ray.slowness.clear();
        ws.ray.curved.clear();
        ws.ray.media.clear();
        ws.ray.points.clear();
        ws.ray.media.push(medium);
        let (rays, _) = self.profile_rays(profile, source, receiver);
        let chosen = rays
            .iter()
            .find(|r| r.status == Status::Converged)
            .or(rays.first());
        let Some(r) = chosen else {
            return RayRecord::failed(Status::NoPath, Reason::NoStationaryPath);
        };
        ws.ray.points.extend([source, receiver]);
        ws.ray.slowness.push(1.0 / r.ray.speeds[0]);
        RayRecord {
            status: r.status,
            time: r.ray.sums.t,
            iterations: 0,
            residual: 0.0,
            reason: r.reason,
        }
    }

    /// Every ray of a path through a profile medium as stationary paths, by time, each with
    /// its turns, caustics and amplitude.
    pub(crate) fn profile_stationary_paths(
        &self,
        medium: usize,
        profile: &Profile,
        source: Point,
        receiver: Point,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        let (rays, _) = self.profile_rays(profile, source, receiver);
        for r in &rays {
            out.push(Arrival {
                status: r.status,
                time: r.ray.sums.t,
                points: vec![source, receiver],
                parameters: Vec::new(),
                segments: Vec::new(),
                media: vec![medium],
                iterations: 0,
                reason: r.reason,
                kink: None,
                residual: 0.0,
                amplitude: self.profile_amplitude(medium, source, receiver, r),
                turns: Some(r.ray.turns),
                caustics: Some(r.ray.caustics),
                launch_angle: Some(launch_angle(&r.ray)),
            });
        }
        SearchOutcome {
            complete: false,
            solves: 1,
            work: rays.len(),
            ..SearchOutcome::new()
        }
    }

    /// The amplitude of one ray of a profile medium, when the scene asks for amplitudes.
    pub(crate) fn profile_amplitude(
        &self,
        medium: usize,
        source: Point,
        receiver: Point,
        r: &TracedProfileRay,
    ) -> Option<crate::amplitude::Amplitude> {
        let settings = self.scene.amplitudes()?;
        if r.status != Status::Converged {
            return Some(crate::amplitude::Amplitude::none(
                crate::amplitude::NoAmplitude::Obstructed,
            ));
        }
        Some(crate::amplitude::of_profile(
            &self.scene,
            settings,
            [source, receiver],
            medium,
            &r.ray,
        ))
    }
}

/// The first interface the ray crosses (its inscribed polygon's pieces, the ends' own
/// margins left out).
fn profile_crossing(
    scene: &Scene,
    profile: &Profile,
    ray: &ProfileRay,
    source: Point,
    receiver: Point,
) -> Option<usize> {
    if scene.interfaces().is_empty() {
        return None;
    }
    let curve = profile.curve(ray, source.to_vec2(), receiver.to_vec2(), PIECE_POINTS);
    let n = curve.len().saturating_sub(1);
    let at = |j: usize| Point::new(curve[j].x, curve[j].y);
    (0..n).find_map(|j| {
        let margin = if j == 0 || j + 1 == n {
            (END_MARGIN * n as f64).min(0.25)
        } else {
            0.0
        };
        scene
            .first_crossing(at(j), at(j + 1), margin, [SegmentRef::NONE; 2])
            .map(|r| r.interface as usize)
    })
}

/// The direction of a ray at its source, radians from +x.
fn launch_angle(ray: &ProfileRay) -> f64 {
    let d = ray.direction_at_start();
    d.y.atan2(d.x)
}

/// What the path alone does not say of a ray through a profile medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ProfileShape {
    /// Its turning points.
    pub turns: u32,
    /// The caustics its tube passed.
    pub caustics: u32,
    /// Its direction at the source (radians from +x).
    pub launch_angle: f64,
}

/// The shape of the default mode's ray of a path without steps through a profile medium
/// between `points` (its source and receiver) in leg medium `media`: the earliest ray no
/// interface crosses, else the earliest; `None` for any other path.
pub(crate) fn profile_shape(
    scene: &Scene,
    points: &[Point],
    media: &[usize],
) -> Option<ProfileShape> {
    let (&[s, r], &[m]) = (points, media) else {
        return None;
    };
    let profile = scene.media().get(m)?.profile_model()?;
    let found = profile.arrivals_cached(s.to_vec2(), r.to_vec2());
    let chosen = found
        .rays
        .iter()
        .find(|x| profile_crossing(scene, &profile, x, s, r).is_none())
        .or(found.rays.first())?;
    Some(ProfileShape {
        turns: chosen.turns,
        caustics: chosen.caustics,
        launch_angle: launch_angle(chosen),
    })
}
