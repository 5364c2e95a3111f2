//! The tracer's entry to amplitudes (`crate::amplitude`): the one function that gives a
//! solved ray or arrival its [`Amplitude`], called by one-by-one solving, batches, every
//! stationary path and the search alike.

use crate::amplitude::{
    Amplitude, NoAmplitude, OnSegment, PathGeometry, UnfoldedLaws, caustics_of_path, of_diffracted,
    of_one, of_path, of_straight_path,
};
use crate::geom::Point;
use crate::scene::{Amplitudes, Step};

use super::{Arrival, RayRecord, Status, Tracer, Workspace};

impl Tracer {
    /// The amplitude of a ray of `steps` through `points` (source, interaction points,
    /// receiver) with leg media `media` that ended as `status`: `None` when the scene does not
    /// ask for amplitudes (`"amplitudes"`) or the status has no time. A `vertex` or
    /// `obstructed` ray has an amplitude without a value, with its reason ([`NoAmplitude`]).
    /// Allocates nothing.
    ///
    /// ```
    /// use eigenray::{Scene, Tracer};
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 343 } },
    ///     "interfaces": { "floor": { "points": [[-10, 0], [10, 0]],
    ///                                "reflection": { "absorption": 0.36 } } },
    ///     "sources": [[0, 1]], "receivers": [[4, 2]],
    ///     "paths": [{ "steps": [{ "reflect": "floor" }], "media": ["air", "air"] }],
    ///     "amplitudes": { "source": "point" }
    /// }"#).unwrap();
    /// let ray = &Tracer::new(&scene).unwrap().trace_all()[0];
    /// let a = ray.amplitude.unwrap();
    /// // The image source at (0, −1): √(1 − α) / (4π L).
    /// let l = (16.0f64 + 9.0).sqrt();
    /// assert!((a.value.re - 0.8 / (4.0 * std::f64::consts::PI * l)).abs() < 1e-15);
    /// assert_eq!(a.value.im, 0.0);
    /// ```
    pub fn amplitude_of(
        &self,
        steps: &[Step],
        status: Status,
        points: &[Point],
        media: &[usize],
    ) -> Option<Amplitude> {
        self.amplitude_with(steps, status, points, media, None)
    }

    /// The amplitude of the ray of path `path` last solved in `ws`, which ended as `record`
    /// (see [`amplitude_of`](Self::amplitude_of)): what [`trace`](Self::trace) puts on its
    /// [`Ray`](super::Ray).
    pub fn amplitude(&self, path: usize, record: &RayRecord, ws: &Workspace) -> Option<Amplitude> {
        let steps = &self.scene.paths().get(path)?.steps;
        let segments = ws.newton.seg.get(..steps.len());
        self.amplitude_with(steps, record.status, ws.points(), ws.media(), segments)
    }

    /// Solves path `path` between two points as [`solve`](Self::solve) does, and puts the
    /// ray's amplitude in `amplitude` (as [`amplitude`](Self::amplitude) gives it, bit for
    /// bit): the call of a loop over receivers. A refraction at an interface of one segment
    /// (the flat kernel's plan) takes the segment and the media the solve already knows.
    ///
    /// ```
    /// use eigenray::{Scene, Tracer, Workspace};
    /// let mut spec = eigenray::demo::air_water(10, 7);
    /// spec.amplitudes = Some(eigenray::scene::AmplitudesSpec::new(
    ///     eigenray::scene::SourceModel::Point,
    /// ));
    /// let scene = Scene::from_spec(&spec).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let (mut ws, mut amplitude) = (Workspace::new(), None);
    /// let (s, r) = (scene.sources()[0], scene.receivers()[3]);
    /// let record = tracer.solve_with_amplitude(s, r, 0, &mut ws, &mut amplitude);
    /// assert_eq!(amplitude, tracer.amplitude(0, &record, &ws));
    /// assert!(amplitude.unwrap().value.re > 0.0);
    /// ```
    ///
    /// # Panics
    /// As [`solve`](Self::solve).
    pub fn solve_with_amplitude(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
        amplitude: &mut Option<Amplitude>,
    ) -> RayRecord {
        let record = self.solve(source, receiver, path, ws);
        let flat = self.flat_segment(path);
        *amplitude = match (self.scene.amplitudes(), flat, ws.points(), ws.media()) {
            (Some(settings), Some(frame), &[p0, p1, p2], &[m0, m1])
                if record.status == Status::Converged =>
            {
                let step = &self.scene.paths()[path].steps[0];
                let at = OnSegment {
                    seg: 0,
                    tangent: frame.tangent,
                };
                let regions = self.regions.as_ref();
                Some(of_one(
                    &self.scene,
                    settings,
                    regions,
                    step,
                    at,
                    [p0, p1, p2],
                    [m0, m1],
                ))
            }
            _ => self.amplitude(path, &record, ws),
        };
        record
    }

    /// [`amplitude_of`](Self::amplitude_of) with the segment of each interaction point when
    /// the solve knows it (tried before a search for it).
    #[inline]
    pub(crate) fn amplitude_with(
        &self,
        steps: &[Step],
        status: Status,
        points: &[Point],
        media: &[usize],
        segments: Option<&[usize]>,
    ) -> Option<Amplitude> {
        let settings = self.scene.amplitudes()?;
        if status != Status::Converged {
            return Self::no_amplitude(status);
        }
        let path = PathGeometry {
            steps,
            points,
            media,
            segments,
        };
        if self.scene.curved() {
            return self.curved_amplitude(settings, path);
        }
        // Every leg straight: the uniform passes, inlined (a diffracted path among them).
        of_straight_path(&self.scene, settings, self.regions.as_ref(), path)
    }

    /// [`amplitude_with`](Self::amplitude_with) of a converged ray in a scene with a gradient
    /// medium (curved legs): a `profile` medium's direct ray or walled ray, a diffracted path,
    /// or [`of_path`]'s curved pass. Out of line, so that a uniform scene's amplitude does not
    /// carry it.
    #[inline(never)]
    fn curved_amplitude(&self, settings: &Amplitudes, path: PathGeometry<'_>) -> Option<Amplitude> {
        let PathGeometry {
            steps,
            points,
            media,
            ..
        } = path;
        if steps.is_empty()
            && let (&[s, r], &[m]) = (points, media)
            && let Some(profile) = self.scene.media()[m].profile_model()
        {
            // The default mode's ray: the earliest one no interface crosses.
            let (rays, _) = self.profile_rays(&profile, s, r);
            let chosen = rays.iter().find(|x| x.status == Status::Converged)?;
            return self.profile_amplitude(m, s, r, chosen);
        }
        if let Some((m, sloped)) = self.sloped_ray_of(steps, points, media) {
            return self.sloped_amplitude(steps, m, &sloped);
        }
        if let Some((m, walled)) = self.walled_ray_of(steps, points, media) {
            return self.walled_amplitude(m, &walled);
        }
        if steps.iter().any(|s| s.kind.vertex().is_some()) {
            return Some(self.diffracted_amplitude(settings, path));
        }
        Some(of_path(&self.scene, settings, self.regions.as_ref(), path))
    }

    /// The amplitude of a converged diffracted path ([`of_diffracted`]), out of line.
    #[cold]
    #[inline(never)]
    fn diffracted_amplitude(&self, settings: &Amplitudes, path: PathGeometry<'_>) -> Amplitude {
        of_diffracted(&self.scene, settings, self.regions.as_ref(), path)
    }

    /// The reflection laws of a rectangular room's walls (each an interface and a segment,
    /// on the local lines x = 0, x = L₁, y = 0, y = L₂) for the amplitudes of its image paths
    /// in closed form, in medium `medium` from `inside` (a point in the room): `None` where
    /// the scene asks for no amplitudes or the closed form does not hold
    /// ([`UnfoldedLaws::new`]), in a scene with a gradient medium (curved legs) and for an
    /// axisymmetric source (its width reads the path's points).
    pub(crate) fn unfolded_laws(
        &self,
        medium: usize,
        walls: [(usize, usize); 4],
        inside: Point,
    ) -> Option<UnfoldedLaws<'_, 4>> {
        let settings = self.scene.amplitudes()?;
        if self.scene.curved() || settings.source == crate::scene::SourceModel::Axisymmetric {
            return None;
        }
        let regions = self.regions.as_ref();
        UnfoldedLaws::new(&self.scene, settings, regions, medium, walls, inside)
    }

    /// The amplitude of a ray that is not `converged`: none without a time, no value on a
    /// `vertex` or `obstructed` path.
    #[cold]
    fn no_amplitude(status: Status) -> Option<Amplitude> {
        match status {
            Status::Vertex => Some(Amplitude::none(NoAmplitude::Vertex)),
            Status::Obstructed => Some(Amplitude::none(NoAmplitude::Obstructed)),
            Status::Converged | Status::NoPath | Status::NotConverged => None,
        }
    }

    /// The number of caustics the ray tube of a converged ray of `steps` through `points` in
    /// the leg media `media` passed, in a scene with a `gradient` medium (the Morse index of
    /// its path's Hessian); `None` for any other ray (see [`caustics_of_path`]).
    pub(crate) fn gradient_caustics(
        &self,
        steps: &[Step],
        status: Status,
        points: &[Point],
        media: &[usize],
        segments: Option<&[usize]>,
    ) -> Option<u32> {
        if status != Status::Converged || !self.scene.curved() {
            return None;
        }
        let path = PathGeometry {
            steps,
            points,
            media,
            segments,
        };
        caustics_of_path(&self.scene, path)
    }

    /// Gives each of `arrivals` (stationary paths of `steps`) its amplitude, when the scene
    /// asks for amplitudes, and its caustics in a scene with a `gradient` medium.
    pub(crate) fn arrival_amplitudes(&self, steps: &[Step], arrivals: &mut [Arrival]) {
        for a in arrivals.iter_mut().filter(|a| a.turns.is_none()) {
            let segments = Some(&a.segments[..]);
            a.caustics = a
                .caustics
                .or_else(|| self.gradient_caustics(steps, a.status, &a.points, &a.media, segments));
        }
        if self.scene.amplitudes().is_none() {
            return;
        }
        for a in arrivals.iter_mut().filter(|a| a.turns.is_none()) {
            let segments = Some(&a.segments[..]);
            a.amplitude = self.amplitude_with(steps, a.status, &a.points, &a.media, segments);
        }
    }
}
