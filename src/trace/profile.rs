//! Rays through a `profile` medium (speed piecewise linear in `y`): a path without steps
//! whose source lies in such a medium has, between its source and its receiver, every ray
//! of [`Profile::arrivals`] (the ray-parameter form, `leg/profile.rs`). `"stationary":
//! "all"` lists each; the default mode's ray is the earliest one that no interface crosses.
//! Each ray is tested for obstruction as the polygon inscribed in its arcs.

use crate::geom::{Point, Vec2};
use crate::leg::profile::{Bounds, Profile, ProfileArrivals, ProfileRay, Walls};
use crate::scene::{Scene, SegmentRef, Step, StepKind};

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
        ws.ray.clear();
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
            None,
            [source, receiver],
            medium,
            &r.ray,
            &[],
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
    if points.len() > 2 {
        // A ray between walls: the one whose reflection points these are.
        let (&m, [s, .., r]) = (media.first()?, points) else {
            return None;
        };
        let profile = scene.media().get(m)?.profile_model()?;
        let bounds = Bounds {
            reflections: u32::try_from(points.len() - 2).unwrap_or(u32::MAX),
            time: f64::INFINITY,
        };
        let (rays, _) = walled_rays(scene, &profile, *s, *r, bounds);
        let chosen = rays.iter().find(|w| w.points == points)?;
        return Some(ProfileShape {
            turns: chosen.ray.turns,
            caustics: chosen.ray.caustics,
            launch_angle: launch_angle(&chosen.ray),
        });
    }
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

/// One ray through a profile medium found again from what an entry says of it
/// ([`profile_ray_of`]).
#[derive(Clone, Debug)]
pub(crate) struct FoundProfileRay {
    /// The profile, with the walls its ray reflects at.
    pub profile: Profile,
    /// The ray.
    pub ray: ProfileRay,
    /// Each reflection's arriving direction (unit), sine with the horizontal and speed.
    pub at_walls: Vec<(Vec2, f64, f64)>,
}

/// Of `candidates`, the one whose launch angle is nearest `launch` when given, else the
/// first that `clear` holds for, else the first.
fn choose<T>(
    candidates: impl Iterator<Item = T> + Clone,
    angle: impl Fn(&T) -> f64,
    launch: Option<f64>,
    clear: impl Fn(&T) -> bool,
) -> Option<T> {
    match launch {
        Some(at) => candidates.min_by(|x, y| {
            let (dx, dy) = ((angle(x) - at).abs(), (angle(y) - at).abs());
            dx.total_cmp(&dy)
        }),
        None => candidates
            .clone()
            .find(|c| clear(c))
            .or_else(|| candidates.clone().next()),
    }
}

/// The ray through the profile medium `medium` (every leg's) of an entry with `steps` (none,
/// or reflections at the walls) through `points`: for a path without steps, one of the
/// rays between its ends; between walls, one whose reflections are `steps` at `points`.
/// With `launch` (the entry's `launch_angle`), the one nearest that direction; without, the
/// default mode's (the earliest no interface crosses, else the earliest). `None` when no ray
/// fits.
pub(crate) fn profile_ray_of(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    medium: usize,
    launch: Option<f64>,
) -> Option<FoundProfileRay> {
    let profile = scene.media().get(medium)?.profile_model()?;
    let (&s, &r) = (points.first()?, points.last()?);
    if steps.is_empty() {
        if points.len() != 2 {
            return None;
        }
        let found = profile.arrivals_cached(s.to_vec2(), r.to_vec2());
        let ray = choose(
            found.rays.iter(),
            |x| launch_angle(x),
            launch,
            |x| profile_crossing(scene, &profile, x, s, r).is_none(),
        )?;
        return Some(FoundProfileRay {
            profile,
            ray: *ray,
            at_walls: Vec::new(),
        });
    }
    let bounds = Bounds {
        reflections: u32::try_from(steps.len()).unwrap_or(u32::MAX),
        time: f64::INFINITY,
    };
    let (rays, _) = walled_rays(scene, &profile, s, r, bounds);
    let fits = rays
        .iter()
        .filter(|w| w.steps == steps && w.points == points);
    let w = choose(
        fits,
        |w| launch_angle(&w.ray),
        launch,
        |w| w.status == Status::Converged,
    )?;
    Some(FoundProfileRay {
        profile: profile.with_walls(waveguide(scene, s).walls),
        ray: w.ray,
        at_walls: w.at_walls.clone(),
    })
}

/// The walls of a waveguide through a profile medium: the nearest flat horizontal
/// interfaces above and below a point (`Scene` validation keeps a profile scene's reflecting
/// steps and searched interfaces to such lines).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Waveguide {
    /// Their heights.
    pub walls: Walls,
    /// The interface of the upper and of the lower wall.
    pub top: Option<usize>,
    pub bottom: Option<usize>,
}

impl Waveguide {
    /// Whether `y` lies strictly between the walls.
    fn holds(&self, y: f64) -> bool {
        self.walls.top.is_none_or(|t| y < t) && self.walls.bottom.is_none_or(|b| y > b)
    }
    /// Whether interface `i` is one of the walls.
    fn is_wall(&self, i: usize) -> bool {
        self.top == Some(i) || self.bottom == Some(i)
    }
}

/// One ray of a waveguide between a source and a receiver: the profile's ray, its
/// reflections as steps with their points, and what the tracer decided of it.
#[derive(Clone, Debug)]
pub(crate) struct WalledRay {
    /// The ray.
    pub ray: ProfileRay,
    /// Its reflections, in order.
    pub steps: Vec<Step>,
    /// Source, reflection points, receiver.
    pub points: Vec<Point>,
    /// Each reflection's segment and arclength on its interface.
    pub segments: Vec<usize>,
    pub parameters: Vec<f64>,
    /// Each reflection's arriving direction, sine with the horizontal and speed.
    pub at_walls: Vec<(Vec2, f64, f64)>,
    /// `converged`, or `obstructed` (with the interface crossed).
    pub status: Status,
    /// Why it is not `converged`.
    pub reason: Option<Reason>,
}

/// The waveguide around `at`: the nearest flat horizontal interface above it and below.
pub(crate) fn waveguide(scene: &Scene, at: Point) -> Waveguide {
    let mut out = Waveguide::default();
    for (i, itf) in scene.interfaces().iter().enumerate() {
        let line = &itf.polyline;
        let v = line.vertices();
        if line.is_closed() || v.iter().any(|p| p.y != v[0].y) {
            continue;
        }
        let y = v[0].y;
        if y > at.y && out.walls.top.is_none_or(|t| y < t) {
            (out.walls.top, out.top) = (Some(y), Some(i));
        } else if y < at.y && out.walls.bottom.is_none_or(|b| y > b) {
            (out.walls.bottom, out.bottom) = (Some(y), Some(i));
        }
    }
    out
}

impl Tracer {
    /// The profile medium of path `path` from `source` when the path has reflect steps only
    /// and its first leg's medium (given, or found at the source) has a profile.
    pub(crate) fn profile_walled_medium(
        &self,
        path: usize,
        source: Point,
        src_medium: Option<usize>,
    ) -> Option<(usize, Profile)> {
        let spec = self.scene.paths().get(path)?;
        if spec.steps.is_empty()
            || !self.scene.curved()
            || spec.steps.iter().any(|s| s.kind != StepKind::Reflect)
        {
            return None;
        }
        let m = match &spec.media {
            Some(m) => *m.first()?,
            None => src_medium.or_else(|| self.source_medium(false, source))?,
        };
        Some((m, self.scene.media()[m].profile_model()?))
    }

    /// Every ray of `profile` between the walls around `source` from `source` to
    /// `receiver` within `bounds`, by time, each with its reflections and status. A ray
    /// whose reflection point misses its wall's extent is left out (it passes the wall's
    /// end); one that crosses another interface is `obstructed`.
    pub(crate) fn walled_rays(
        &self,
        profile: &Profile,
        source: Point,
        receiver: Point,
        bounds: Bounds,
    ) -> (Vec<WalledRay>, bool) {
        walled_rays(&self.scene, profile, source, receiver, bounds)
    }

    /// The rays of a path of reflect steps through a profile medium between walls: those
    /// of [`walled_rays`](Self::walled_rays) whose reflections are the path's steps.
    pub(crate) fn path_walled_rays(
        &self,
        path: usize,
        profile: &Profile,
        source: Point,
        receiver: Point,
    ) -> Vec<WalledRay> {
        let steps = &self.scene.paths()[path].steps;
        let bounds = Bounds {
            reflections: u32::try_from(steps.len()).unwrap_or(u32::MAX),
            time: f64::INFINITY,
        };
        let (rays, _) = self.walled_rays(profile, source, receiver, bounds);
        rays.into_iter().filter(|r| r.steps == *steps).collect()
    }

    /// The amplitude of one ray between walls, when the scene asks for amplitudes.
    pub(crate) fn walled_amplitude(
        &self,
        medium: usize,
        r: &WalledRay,
    ) -> Option<crate::amplitude::Amplitude> {
        let settings = self.scene.amplitudes()?;
        if r.status != Status::Converged {
            return Some(crate::amplitude::Amplitude::none(
                crate::amplitude::NoAmplitude::Obstructed,
            ));
        }
        let n = r.points.len();
        let reflections: Vec<crate::amplitude::ProfileReflection<'_>> = (r.steps.iter())
            .enumerate()
            .map(|(i, step)| {
                let (direction, sine, speed) = r.at_walls[i];
                crate::amplitude::ProfileReflection {
                    step,
                    segment: r.segments[i],
                    from: r.points[i],
                    here: r.points[i + 1],
                    direction,
                    sine,
                    speed,
                }
            })
            .collect();
        Some(crate::amplitude::of_profile(
            &self.scene,
            settings,
            self.regions.as_ref(),
            [r.points[0], r.points[n - 1]],
            medium,
            &r.ray,
            &reflections,
        ))
    }

    /// The arrival of one ray between walls, with its amplitude.
    pub(crate) fn walled_arrival(&self, medium: usize, r: &WalledRay) -> Arrival {
        Arrival {
            status: r.status,
            time: r.ray.sums.t,
            points: r.points.clone(),
            parameters: r.parameters.clone(),
            segments: r.segments.clone(),
            media: vec![medium; r.steps.len() + 1],
            iterations: 0,
            reason: r.reason,
            kink: None,
            residual: 0.0,
            amplitude: self.walled_amplitude(medium, r),
            turns: Some(r.ray.turns),
            caustics: Some(r.ray.caustics),
            launch_angle: Some(launch_angle(&r.ray)),
        }
    }

    /// Every ray of a path of reflect steps through a profile medium as stationary paths,
    /// by time.
    pub(crate) fn walled_stationary_paths(
        &self,
        path: usize,
        medium: usize,
        profile: &Profile,
        source: Point,
        receiver: Point,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        let rays = self.path_walled_rays(path, profile, source, receiver);
        out.extend(rays.iter().map(|r| self.walled_arrival(medium, r)));
        SearchOutcome {
            complete: false,
            solves: 1,
            work: rays.len(),
            ..SearchOutcome::new()
        }
    }

    /// The default mode's ray of a path of reflect steps through a profile medium: the
    /// earliest that no interface crosses (else the earliest, `obstructed`), into `ws`.
    pub(crate) fn solve_walled(
        &self,
        path: usize,
        medium: usize,
        profile: &Profile,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> RayRecord {
        let k = self.scene.paths()[path].steps.len();
        ws.resize(k);
        ws.ray.clear();
        ws.ray.media.extend(std::iter::repeat_n(medium, k + 1));
        let rays = self.path_walled_rays(path, profile, source, receiver);
        let Some(r) = default_choice(&rays, |r| r.status) else {
            return RayRecord::failed(Status::NoPath, Reason::NoStationaryPath);
        };
        let slowness = std::iter::repeat_n(1.0 / r.ray.speeds[0], k + 1);
        ws.keep_profile_ray(&r.points, slowness, &r.parameters, &r.segments);
        RayRecord {
            status: r.status,
            time: r.ray.sums.t,
            iterations: 0,
            residual: 0.0,
            reason: r.reason,
        }
    }

    /// The ray between walls that a default-mode solve chose, found again from its points
    /// (`None` for any other path).
    pub(crate) fn walled_ray_of(
        &self,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
    ) -> Option<(usize, WalledRay)> {
        if steps.is_empty() || points.len() != steps.len() + 2 || !self.scene.curved() {
            return None;
        }
        let m = *media.first()?;
        let profile = self.scene.media().get(m)?.profile_model()?;
        let (s, r) = (points[0], points[points.len() - 1]);
        let bounds = Bounds {
            reflections: u32::try_from(steps.len()).unwrap_or(u32::MAX),
            time: f64::INFINITY,
        };
        let (rays, _) = self.walled_rays(&profile, s, r, bounds);
        rays.into_iter()
            .find(|w| w.steps == steps && w.points == points)
            .map(|w| (m, w))
    }
}

/// [`Tracer::walled_rays`] of `scene`.
pub(crate) fn walled_rays(
    scene: &Scene,
    profile: &Profile,
    source: Point,
    receiver: Point,
    bounds: Bounds,
) -> (Vec<WalledRay>, bool) {
    let guide = waveguide(scene, source);
    if !guide.holds(receiver.y) {
        return (Vec::new(), true);
    }
    let profile = profile.clone().with_walls(guide.walls);
    let (a, b) = (source.to_vec2(), receiver.to_vec2());
    let found = profile.arrivals_within_cached(a, b, Some(bounds));
    let mut out = Vec::new();
    'rays: for ray in &found.rays {
        let sx = if ray.p < 0.0 { -1.0 } else { 1.0 };
        let p = ray.p.abs();
        let mut walled = WalledRay {
            ray: *ray,
            steps: Vec::new(),
            points: vec![source],
            segments: Vec::new(),
            parameters: Vec::new(),
            at_walls: Vec::new(),
            status: Status::Converged,
            reason: None,
        };
        for e in profile.events(ray, a, b).iter().filter(|e| e.wall) {
            let up = guide.walls.top == Some(e.y);
            let Some(interface) = (if up { guide.top } else { guide.bottom }) else {
                continue 'rays;
            };
            let here = Point::new(source.x + sx * e.x, e.y);
            let line = &scene.interfaces()[interface].polyline;
            let Some(seg) = (0..line.num_segments()).find(|&j| {
                let g = line.segment(j);
                let (lo, hi) = (g.start.x.min(g.end.x), g.start.x.max(g.end.x));
                here.x >= lo && here.x <= hi
            }) else {
                continue 'rays;
            };
            let g = line.segment(seg);
            walled
                .parameters
                .push(line.start(seg) + (here - g.start).dot(line.tangent(seg)));
            walled.segments.push(seg);
            walled.steps.push(Step {
                kind: StepKind::Reflect,
                interface,
            });
            walled.points.push(here);
            let vertical = if up { e.sine } else { -e.sine };
            walled
                .at_walls
                .push((Vec2::new(sx * p * e.speed, vertical), e.sine, e.speed));
        }
        walled.points.push(receiver);
        if let Some(hit) = walled_crossing(scene, &profile, ray, source, receiver, &guide) {
            walled.status = Status::Obstructed;
            walled.reason = Some(Reason::Crosses {
                leg: 0,
                interface: hit,
            });
        }
        out.push(walled);
    }
    (out, found.every_branch)
}

/// The first interface other than the waveguide's walls that the ray crosses (its
/// inscribed polygon's pieces, the ends' own margins left out).
fn walled_crossing(
    scene: &Scene,
    profile: &Profile,
    ray: &ProfileRay,
    source: Point,
    receiver: Point,
    guide: &Waveguide,
) -> Option<usize> {
    if scene.interfaces().len()
        <= usize::from(guide.top.is_some()) + usize::from(guide.bottom.is_some())
    {
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
            .first_crossing_except(at(j), at(j + 1), margin, |i| guide.is_wall(i))
            .map(|r| r.interface as usize)
    })
}

/// The ray of a profile medium an entry between `points` (its source, its reflections at
/// the waveguide's walls, its receiver) through medium `medium` is, with the profile it was
/// traced in (between its walls for a ray with reflections or one of a search): the one
/// that leaves at `launch_angle` (radians from +x, within 1e-9) when given, else the one
/// the default mode chose (the earliest no interface crosses, else the earliest; between
/// walls, the one whose reflection points are `points`). `None` where there is none.
/// (`leaving`: the launch angle asked for.)
pub(crate) fn profile_ray_between(
    scene: &Scene,
    points: &[Point],
    medium: usize,
    leaving: Option<f64>,
) -> Option<(Profile, ProfileRay)> {
    let profile = scene.media().get(medium)?.profile_model()?;
    let (&s, &r) = (points.first()?, points.last()?);
    let reflections = points.len().checked_sub(2)?;
    let nearest = |rays: &mut dyn Iterator<Item = (Profile, ProfileRay)>, angle: f64| {
        rays.map(|(pr, ray)| {
            let off = (launch_angle(&ray) - angle).rem_euclid(std::f64::consts::TAU);
            (off.min(std::f64::consts::TAU - off), pr, ray)
        })
        .filter(|(off, ..)| *off <= 1e-9)
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, pr, ray)| (pr, ray))
    };
    if reflections == 0 {
        let found = profile.arrivals_cached(s.to_vec2(), r.to_vec2());
        let chosen = match leaving {
            Some(angle) => nearest(
                &mut found.rays.iter().map(|ray| (profile.clone(), *ray)),
                angle,
            ),
            None => found
                .rays
                .iter()
                .find(|x| profile_crossing(scene, &profile, x, s, r).is_none())
                .or(found.rays.first())
                .map(|ray| (profile.clone(), *ray)),
        };
        if chosen.is_some() || leaving.is_none() {
            return chosen;
        }
    }
    let guide = waveguide(scene, s);
    let walled = profile.clone().with_walls(guide.walls);
    let bounds = Bounds {
        reflections: u32::try_from(reflections).unwrap_or(u32::MAX),
        time: f64::INFINITY,
    };
    let (rays, _) = walled_rays(scene, &profile, s, r, bounds);
    let mut own = rays.into_iter().filter(|w| w.points.len() == points.len());
    match leaving {
        Some(angle) => nearest(&mut own.map(|w| (walled.clone(), w.ray)), angle),
        None => own
            .find(|w| w.points == points)
            .map(|w| (walled.clone(), w.ray)),
    }
}

/// The ray the default mode reports of a profile route's rays (by time): the earliest that
/// converged (no interface crosses it), else the earliest.
pub(super) fn default_choice<T>(rays: &[T], status: impl Fn(&T) -> Status) -> Option<&T> {
    rays.iter()
        .find(|r| status(r) == Status::Converged)
        .or(rays.first())
}

impl Workspace {
    /// Keeps the ray a profile route chose (its leg media already set): its points, each
    /// leg's slowness, its interactions' parameters and segments.
    pub(super) fn keep_profile_ray(
        &mut self,
        points: &[Point],
        slowness: impl Iterator<Item = f64>,
        parameters: &[f64],
        segments: &[usize],
    ) {
        self.ray.points.extend_from_slice(points);
        self.ray.slowness.extend(slowness);
        self.newton.s.clear();
        self.newton.s.extend_from_slice(parameters);
        self.newton.seg.clear();
        self.newton.seg.extend_from_slice(segments);
    }
}
