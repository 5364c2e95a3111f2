//! Layout objectives built on eigenray's rays and their derivatives, as argmin problems: the
//! outer optimisation of a layout tool, with eigenray's ray solve inside each evaluation.

use std::cell::RefCell;

use argmin::core::{CostFunction, Error, Gradient as ArgminGradient};
use nalgebra::DVector;

use crate::derivatives::Gradient;
use crate::geom::{Point, Vec2};
use crate::trace::{Tracer, Workspace};

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
///     "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.7 } },
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
/// let solver = LBFGS::new(MoreThuenteLineSearch::new(), 5).with_tolerance_grad(1e-12).unwrap();
/// let result = Executor::new(problem, solver)
///     .configure(|s| s.param(DVector::from_vec(vec![-2.0, 4.0])).max_iters(100))
///     .run()
///     .unwrap();
/// let found = result.state().best_param.clone().unwrap();
/// assert!((found[0] - 1.0).abs() < 1e-6 && (found[1] - 2.5).abs() < 1e-6);
/// ```
pub struct SourceLocation<'a> {
    tracer: &'a Tracer<'a>,
    observed: Vec<ObservedArrival>,
    scratch: RefCell<(Workspace, Gradient)>,
}

impl<'a> SourceLocation<'a> {
    /// The problem of the source that `observed` were observed from, in `tracer`'s scene.
    pub fn new(tracer: &'a Tracer<'a>, observed: Vec<ObservedArrival>) -> SourceLocation<'a> {
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
            let ray = self.tracer.solve(source, o.receiver, o.path, ws);
            if !ray.status.has_time() {
                return Err(Error::msg(format!(
                    "observation {i}: no ray of path {} from the trial source ({}, {}) to \
                     ({}, {}) ({})",
                    o.path, source.x, source.y, o.receiver.x, o.receiver.y, ray.status
                )));
            }
            gradient.solved_into(scene, o.path, ws)?;
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
