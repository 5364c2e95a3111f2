//! Layout objectives built on eigenray's rays and their derivatives, as argmin problems: the
//! outer optimisation of a layout tool, with eigenray's ray solve inside each evaluation.

use std::cell::RefCell;

use argmin::core::{CostFunction, Error, Gradient as ArgminGradient};
use nalgebra::DVector;

use crate::derivatives::Gradient;
use crate::geom::{Point, Vec2};
use crate::trace::{Tracer, Workspace};

/// What a layout objective changes and solves with between evaluations: its own tracer (the
/// scene updated in place), a workspace and a gradient.
struct LayoutScratch {
    tracer: Tracer,
    ws: Workspace,
    gradient: Gradient,
}

impl LayoutScratch {
    fn new(tracer: Tracer) -> LayoutScratch {
        LayoutScratch {
            tracer,
            ws: Workspace::new(),
            gradient: Gradient::default(),
        }
    }
}

/// One observed arrival: the time at which path `path` from the unknown source reached
/// `receiver`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObservedArrival {
    /// Where it was observed.
    pub receiver: Point,
    /// The path (index into the scene's paths) it travelled.
    pub path: usize,
    /// The observed travel time.
    pub time: f64,
}

/// The misfit of a trial source: the cost, its gradient, and the predicted times.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceMisfit {
    /// `½ Σ (T(S, Rᵢ) − tᵢ)²`.
    pub cost: f64,
    /// Its gradient with respect to the source: `Σ (T − tᵢ) dT/dS`.
    pub gradient: Vec2,
    /// The predicted time of each observation.
    pub predicted: Vec<f64>,
}

/// Locating a source from arrival times at several receivers (an inversion, as in seismology
/// or acoustic localisation): minimise `½ Σ (T(S, Rᵢ) − tᵢ)²` over the source `S`, each time
/// `T` a ray solved by the tracer and its derivative `dT/dS` exact ([`Gradient`]). As an argmin
/// problem its parameter is `S` as a `DVector` `[x, y]`.
///
/// ```
/// use argmin::core::{CostFunction, Executor};
/// use argmin::solver::linesearch::MoreThuenteLineSearch;
/// use argmin::solver::quasinewton::LBFGS;
/// use eigenray::argmin_bridge::{ObservedArrival, SourceLocation};
/// use eigenray::{Point, Scene, Tracer, Workspace};
/// use nalgebra::DVector;
/// let scene = Scene::from_json(r#"{
///     "media": { "air": { "speed": 343.0 }, "water": { "speed": 1480.0 } },
///     "interfaces": { "surface": { "points": [[-20, 0], [20, 0]] } },
///     "sources": [[0, 2]], "receivers": [[-3, -2], [0, -3], [4, -2], [1, -1]],
///     "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
/// }"#).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let truth = Point::new(1.0, 2.5);
/// let mut ws = Workspace::new();
/// let observed: Vec<ObservedArrival> = scene.receivers().iter().map(|&receiver| {
///     let time = tracer.solve(truth, receiver, 0, &mut ws).time;
///     ObservedArrival { receiver, path: 0, time }
/// }).collect();
/// let problem = SourceLocation::new(&tracer, observed);
/// let solver = LBFGS::new(MoreThuenteLineSearch::new(), 5)
///     .with_tolerance_grad(1e-14).unwrap()
///     .with_tolerance_cost(0.0).unwrap();
/// let result = Executor::new(problem, solver)
///     .configure(|s| s.param(DVector::from_vec(vec![-2.0, 4.0])).max_iters(100))
///     .run()
///     .unwrap();
/// let found = result.state().best_param.clone().unwrap();
/// assert!((found[0] - 1.0).abs() < 1e-6 && (found[1] - 2.5).abs() < 1e-6);
/// ```
pub struct SourceLocation<'a> {
    tracer: &'a Tracer,
    observed: Vec<ObservedArrival>,
    scratch: RefCell<(Workspace, Gradient)>,
}

impl<'a> SourceLocation<'a> {
    /// The problem of the source that `observed` were observed from, in `tracer`'s scene.
    pub fn new(tracer: &'a Tracer, observed: Vec<ObservedArrival>) -> SourceLocation<'a> {
        SourceLocation {
            tracer,
            observed,
            scratch: RefCell::new((Workspace::new(), Gradient::default())),
        }
    }

    /// The observations.
    pub fn observed(&self) -> &[ObservedArrival] {
        &self.observed
    }

    /// The misfit of the trial source `source`.
    ///
    /// # Errors
    /// A source the tracer cannot solve from (not finite, beyond the scene's coordinates, a
    /// path index out of range), or an observation whose ray has no time from `source`.
    pub fn misfit(&self, source: Point) -> Result<SourceMisfit, Error> {
        let scene = self.tracer.scene();
        let mut scratch = self.scratch.borrow_mut();
        let (ws, gradient) = &mut *scratch;
        let (mut cost, mut grad) = (0.0, Vec2::default());
        let mut predicted = Vec::with_capacity(self.observed.len());
        for (i, o) in self.observed.iter().enumerate() {
            scene.check_solve(source, o.receiver, o.path)?;
            let ray = self
                .tracer
                .solve_with_gradient(source, o.receiver, o.path, ws, gradient)?;
            if !ray.status.has_time() {
                return Err(Error::msg(format!(
                    "observation {i}: no ray of path {} from the trial source ({}, {}) to \
                     ({}, {}) ({})",
                    o.path, source.x, source.y, o.receiver.x, o.receiver.y, ray.status
                )));
            }
            let miss = ray.time - o.time;
            cost += 0.5 * miss * miss;
            grad += gradient.source * miss;
            predicted.push(ray.time);
        }
        Ok(SourceMisfit {
            cost,
            gradient: grad,
            predicted,
        })
    }
}

/// `[x, y]` as a point.
fn point_of(p: &DVector<f64>) -> Result<Point, Error> {
    match p.as_slice() {
        [x, y] => Ok(Point::new(*x, *y)),
        other => Err(Error::msg(format!(
            "a source is two coordinates [x, y], got {}",
            other.len()
        ))),
    }
}

impl CostFunction for SourceLocation<'_> {
    type Param = DVector<f64>;
    type Output = f64;

    fn cost(&self, p: &DVector<f64>) -> Result<f64, Error> {
        Ok(self.misfit(point_of(p)?)?.cost)
    }
}

impl ArgminGradient for SourceLocation<'_> {
    type Param = DVector<f64>;
    type Gradient = DVector<f64>;

    fn gradient(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
        let g = self.misfit(point_of(p)?)?.gradient;
        Ok(DVector::from_vec(vec![g.x, g.y]))
    }
}

/// A straight reflector's placement: its centre and the angle of its direction (radians from
/// the x axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The centre.
    pub center: Point,
    /// The angle of the direction from its first vertex to its second.
    pub angle: f64,
}

impl Placement {
    /// The end points of a reflector of `length` so placed.
    pub fn endpoints(&self, length: f64) -> [Point; 2] {
        let half = Vec2::new(self.angle.cos(), self.angle.sin()) * (0.5 * length);
        [self.center - half, self.center + half]
    }
}

/// How far a placement is from giving the prescribed delay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacementMisfit {
    /// The objective (see [`ReflectorPlacement`]).
    pub cost: f64,
    /// Its gradient with respect to the centre's `x`, `y` and the angle.
    pub gradient: [f64; 3],
    /// The first reflection's delay after the direct sound.
    pub delay: f64,
}

/// Placing and tilting a reflector (an interface of one segment of fixed length) so that a
/// listener hears its first reflection a prescribed `delay` after the direct sound: minimise
/// `½ (c (Δ − Δ*) / L)² + ½ μ (|C − C₀|² / L² + (θ − θ₀)² / 4)` over the centre `C` and angle
/// `θ`, with `Δ` the reflection's time minus the direct ray's, `c` the speed of the direct
/// ray's medium and `L` the reflector's length (so that every term is dimensionless and a unit
/// step moves the reflector by about its length), the second term (`μ` small) choosing, among
/// the placements that give the delay, the one nearest to the start. The time's derivative
/// with respect to the reflector's two vertices ([`Gradient`]) gives the gradient by the chain
/// rule. Each evaluation moves the reflector in the problem's own tracer
/// ([`Tracer::set_interface_points`], not a scene built again from its spec) and solves the
/// two rays. As an argmin problem its parameter is `[x, y, θ]`.
pub struct ReflectorPlacement {
    scratch: RefCell<LayoutScratch>,
    reflector: usize,
    length: f64,
    reflection: usize,
    direct: usize,
    source: Point,
    listener: Point,
    delay: f64,
    start: Placement,
    weight: f64,
}

impl ReflectorPlacement {
    /// The problem for the scene `spec` (which has an interface named `reflector`, whose
    /// points are replaced, a path `reflection` that reflects off it and a path `direct`, the
    /// direct ray, both with media given), the ray from `source` to `listener`, the reflector's
    /// `length`, the prescribed `delay`, the `start` placement and the weight `μ` of staying
    /// near it.
    ///
    /// # Errors
    /// A `reflector` that the scene does not have, path indices out of range, the direct path
    /// with steps, a length, delay or weight that is not a finite number (the length positive,
    /// the weight not negative), or a scene that is not valid with the reflector at `start`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of the problem, each named in the documentation"
    )]
    pub fn new(
        spec: crate::scene::SceneSpec,
        reflector: &str,
        reflection: usize,
        direct: usize,
        source: Point,
        listener: Point,
        length: f64,
        delay: f64,
        start: Placement,
        weight: f64,
    ) -> Result<ReflectorPlacement, crate::scene::SceneError> {
        use crate::scene::SceneError;
        if !spec.interfaces.contains_key(reflector) {
            return Err(SceneError::new(
                format!("interfaces.{reflector}"),
                "no such interface to place",
            ));
        }
        for (what, p) in [("reflection", reflection), ("direct", direct)] {
            if p >= spec.paths.len() {
                return Err(SceneError::new(
                    format!("paths[{p}]"),
                    format!("no such path (the {what} path)"),
                ));
            }
        }
        if !spec.paths[direct].steps.is_empty() {
            return Err(SceneError::new(
                format!("paths[{direct}].steps"),
                "the direct path has no steps",
            ));
        }
        let fine = length.is_finite() && length > 0.0 && delay.is_finite();
        if !(fine && weight.is_finite() && weight >= 0.0) {
            return Err(SceneError::new(
                "reflector",
                "length (> 0), delay and weight (≥ 0) must be finite numbers",
            ));
        }
        let mut spec = spec;
        let [a, b] = start.endpoints(length);
        if let Some(i) = spec.interfaces.get_mut(reflector) {
            i.points = vec![[a.x, a.y], [b.x, b.y]];
            i.closed = false;
        }
        let scene = crate::scene::Scene::from_spec(&spec)?;
        let index = scene.interface_index(reflector).ok_or_else(|| {
            SceneError::new(format!("interfaces.{reflector}"), "not in the scene")
        })?;
        Ok(ReflectorPlacement {
            scratch: RefCell::new(LayoutScratch::new(Tracer::new(scene)?)),
            reflector: index,
            length,
            reflection,
            direct,
            source,
            listener,
            delay,
            start,
            weight,
        })
    }

    /// The scene with the reflector placed at `p`.
    ///
    /// # Errors
    /// A placement that makes the scene invalid (the reflector crossing another interface).
    pub fn scene(&self, p: Placement) -> Result<crate::scene::Scene, crate::scene::SceneError> {
        let mut scene = self.scratch.borrow().tracer.scene().clone();
        scene.set_interface_points(self.reflector, &p.endpoints(self.length))?;
        Ok(scene)
    }

    /// The misfit of placement `p`.
    ///
    /// # Errors
    /// An invalid scene, or a ray without a time (the reflection point off the reflector).
    pub fn misfit(&self, p: Placement) -> Result<PlacementMisfit, Error> {
        let mut scratch = self.scratch.borrow_mut();
        let LayoutScratch {
            tracer,
            ws,
            gradient: g,
        } = &mut *scratch;
        tracer.set_interface_points(self.reflector, &p.endpoints(self.length))?;
        let direct = tracer.solve(self.source, self.listener, self.direct, ws);
        if !direct.status.has_time() {
            return Err(Error::msg("the direct ray has no time"));
        }
        let speed = ws
            .media()
            .first()
            .map_or(1.0, |&m| 1.0 / tracer.scene().media()[m].slowness);
        let reflected =
            tracer.solve_with_gradient(self.source, self.listener, self.reflection, ws, g)?;
        if !reflected.status.has_time() {
            return Err(Error::msg(format!(
                "no reflection off the placed reflector ({}) at centre ({}, {}), angle {}",
                reflected.status, p.center.x, p.center.y, p.angle
            )));
        }
        let iface = self.reflector;
        let (da, db) = (g.vertex(iface, 0), g.vertex(iface, 1));
        let delay = reflected.time - direct.time;
        let l = self.length;
        let miss = speed * (delay - self.delay) / l;
        // d(endpoints)/dθ: a = C − h, b = C + h with h = (L/2)(cos θ, sin θ).
        let dh = Vec2::new(-p.angle.sin(), p.angle.cos()) * (0.5 * l);
        let dt = [da.x + db.x, da.y + db.y, db.dot(dh) - da.dot(dh)];
        let moved = [
            (p.center.x - self.start.center.x) / l,
            (p.center.y - self.start.center.y) / l,
            0.5 * (p.angle - self.start.angle),
        ];
        let cost = 0.5 * miss * miss
            + 0.5 * self.weight * (moved[0] * moved[0] + moved[1] * moved[1] + moved[2] * moved[2]);
        let k = miss * speed / l;
        let gradient = [
            k * dt[0] + self.weight * moved[0] / l,
            k * dt[1] + self.weight * moved[1] / l,
            k * dt[2] + self.weight * moved[2] * 0.5,
        ];
        Ok(PlacementMisfit {
            cost,
            gradient,
            delay,
        })
    }
}

/// `[x, y, θ]` as a placement.
fn placement_of(p: &DVector<f64>) -> Result<Placement, Error> {
    match p.as_slice() {
        [x, y, angle] => Ok(Placement {
            center: Point::new(*x, *y),
            angle: *angle,
        }),
        other => Err(Error::msg(format!(
            "a placement is [x, y, angle], got {} numbers",
            other.len()
        ))),
    }
}

impl CostFunction for ReflectorPlacement {
    type Param = DVector<f64>;
    type Output = f64;

    fn cost(&self, p: &DVector<f64>) -> Result<f64, Error> {
        Ok(self.misfit(placement_of(p)?)?.cost)
    }
}

impl ArgminGradient for ReflectorPlacement {
    type Param = DVector<f64>;
    type Gradient = DVector<f64>;

    fn gradient(&self, p: &DVector<f64>) -> Result<DVector<f64>, Error> {
        Ok(DVector::from_vec(
            self.misfit(placement_of(p)?)?.gradient.to_vec(),
        ))
    }
}

/// Shaping a lens's back surface so that a point source images onto a focus: Fermat's imaging
/// condition, every path from the source through the lens to the focus taking the same time.
///
/// The lens has a flat front face (not part of the scene) and a back surface, an open polyline
/// of the scene between the glass (on the front side) and the air. A path from the source
/// enters the front face at the point `Pᵢ` and then takes the ray from `Pᵢ` to the focus
/// refracted by the back surface (path `path`, media given): its time is
/// `τᵢ = w |Pᵢ − S| + T(Pᵢ, F)`, `w` the slowness before the lens. The objective is
/// `½ Σᵢ (τᵢ − τ̄)² / n` over the `n` entry points (`τ̄` their mean), minimised over the `x`
/// coordinates of the back surface's `free` vertices (the others stay put, which fixes the
/// lens's thickness). The derivative of each `T` with respect to the vertices ([`Gradient`])
/// gives the gradient: `Σᵢ (τᵢ − τ̄) ∂τᵢ/∂xⱼ / n`. As an argmin problem its parameter is
/// those `x` coordinates, in the order of `free`. Each evaluation moves the vertices in the
/// problem's own tracer ([`Tracer::set_interface_points`], not a scene built again from its
/// spec).
pub struct LensProfile {
    scratch: RefCell<LayoutScratch>,
    surface: usize,
    free: Vec<usize>,
    path: usize,
    source: Point,
    slowness_before: f64,
    entries: Vec<Point>,
    focus: Point,
}

/// The times through a lens profile: the objective, its gradient, and each path's time.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileMisfit {
    /// `½ Σ (τᵢ − τ̄)² / n`.
    pub cost: f64,
    /// Its gradient with respect to the free vertices' `x`.
    pub gradient: Vec<f64>,
    /// `τᵢ` of each entry point.
    pub times: Vec<f64>,
}

impl LensProfile {
    /// The problem for the scene `spec` whose interface `surface` is the back surface, its
    /// vertices `free` moving along `x`, path `path` one refraction at it with media given,
    /// the `source` in a medium of slowness `slowness_before` in front of the lens, the
    /// `entries` on the front face and the `focus`.
    ///
    /// # Errors
    /// A `surface` the scene does not have, a free vertex it does not have, a path out of
    /// range, fewer than two entries, a slowness that is not a positive number, or a scene
    /// that is not valid.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of the problem, each named in the documentation"
    )]
    pub fn new(
        spec: crate::scene::SceneSpec,
        surface: &str,
        free: Vec<usize>,
        path: usize,
        source: Point,
        slowness_before: f64,
        entries: Vec<Point>,
        focus: Point,
    ) -> Result<LensProfile, crate::scene::SceneError> {
        use crate::scene::SceneError;
        let Some(line) = spec.interfaces.get(surface) else {
            return Err(SceneError::new(
                format!("interfaces.{surface}"),
                "no such interface to shape",
            ));
        };
        if let Some(&v) = free.iter().find(|&&v| v >= line.points.len()) {
            return Err(SceneError::new(
                format!("interfaces.{surface}.points[{v}]"),
                "no such vertex to move",
            ));
        }
        if path >= spec.paths.len() {
            return Err(SceneError::new(format!("paths[{path}]"), "no such path"));
        }
        if entries.len() < 2 || !(slowness_before.is_finite() && slowness_before > 0.0) {
            return Err(SceneError::new(
                "lens",
                "needs two entry points or more and a positive slowness before the lens",
            ));
        }
        let scene = crate::scene::Scene::from_spec(&spec)?;
        let index = scene
            .interface_index(surface)
            .ok_or_else(|| SceneError::new(format!("interfaces.{surface}"), "not in the scene"))?;
        Ok(LensProfile {
            scratch: RefCell::new(LayoutScratch::new(Tracer::new(scene)?)),
            surface: index,
            free,
            path,
            source,
            slowness_before,
            entries,
            focus,
        })
    }

    /// The surface's vertices with the free ones at `x`, from `tracer`'s scene.
    fn profile(&self, tracer: &Tracer, x: &[f64]) -> Result<Vec<Point>, crate::scene::SceneError> {
        use crate::scene::SceneError;
        if x.len() != self.free.len() {
            return Err(SceneError::new(
                "lens",
                format!("{} free vertices, {} coordinates", self.free.len(), x.len()),
            ));
        }
        let line = &tracer.scene().interfaces()[self.surface].polyline;
        let mut points = line.vertices().to_vec();
        for (&v, &xv) in self.free.iter().zip(x) {
            points[v].x = xv;
        }
        Ok(points)
    }

    /// The scene with the free vertices at `x`.
    ///
    /// # Errors
    /// `x` of the wrong length, or a profile that makes the scene invalid.
    pub fn scene(&self, x: &[f64]) -> Result<crate::scene::Scene, crate::scene::SceneError> {
        let scratch = self.scratch.borrow();
        let points = self.profile(&scratch.tracer, x)?;
        let mut scene = scratch.tracer.scene().clone();
        scene.set_interface_points(self.surface, &points)?;
        Ok(scene)
    }

    /// The misfit of the profile with the free vertices at `x`.
    ///
    /// # Errors
    /// An invalid profile, or a path without a time.
    pub fn misfit(&self, x: &[f64]) -> Result<ProfileMisfit, Error> {
        let mut scratch = self.scratch.borrow_mut();
        let points = self.profile(&scratch.tracer, x)?;
        let LayoutScratch {
            tracer,
            ws,
            gradient: g,
        } = &mut *scratch;
        tracer.set_interface_points(self.surface, &points)?;
        let n = self.entries.len();
        let mut times = Vec::with_capacity(n);
        let mut partials = vec![0.0; n * self.free.len()];
        for (i, &p) in self.entries.iter().enumerate() {
            let ray = tracer.solve_with_gradient(p, self.focus, self.path, ws, g)?;
            if !ray.status.has_time() {
                return Err(Error::msg(format!(
                    "no ray from the entry point ({}, {}) to the focus ({})",
                    p.x, p.y, ray.status
                )));
            }
            times.push(self.slowness_before * (p - self.source).length() + ray.time);
            for (j, &v) in self.free.iter().enumerate() {
                partials[i * self.free.len() + j] = g.vertex(self.surface, v).x;
            }
        }
        let mean = times.iter().sum::<f64>() / n as f64;
        let cost = times.iter().map(|t| (t - mean) * (t - mean)).sum::<f64>() / (2 * n) as f64;
        let mut gradient = vec![0.0; self.free.len()];
        for (i, t) in times.iter().enumerate() {
            for (j, d) in gradient.iter_mut().enumerate() {
                *d += (t - mean) * partials[i * self.free.len() + j] / n as f64;
            }
        }
        Ok(ProfileMisfit {
            cost,
            gradient,
            times,
        })
    }
}

impl CostFunction for LensProfile {
    type Param = DVector<f64>;
    type Output = f64;

    fn cost(&self, x: &DVector<f64>) -> Result<f64, Error> {
        Ok(self.misfit(x.as_slice())?.cost)
    }
}

impl ArgminGradient for LensProfile {
    type Param = DVector<f64>;
    type Gradient = DVector<f64>;

    fn gradient(&self, x: &DVector<f64>) -> Result<DVector<f64>, Error> {
        Ok(DVector::from_vec(self.misfit(x.as_slice())?.gradient))
    }
}
