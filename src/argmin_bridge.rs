//! The path problem as an argmin problem, and argmin's solvers run on it for cross-checks;
//! and layout objectives built on whole rays and their derivatives ([`SourceLocation`]:
//! locating a source from arrival times; [`ReflectorPlacement`]: placing a reflector for a
//! prescribed delay; [`LensProfile`]: shaping a lens for Fermat's imaging condition), each an
//! argmin [`CostFunction`] and [`Gradient`] for argmin's optimisers.
//!
//! [`ArgminPath`] wraps a [`PathProblem`] for argmin's solvers, with the interaction
//! parameters (arclengths `s`) as a `nalgebra::DVector<f64>`:
//!
//! | argmin trait     | value                                                        |
//! |------------------|--------------------------------------------------------------|
//! | [`CostFunction`] | travel time `T(s)`                                           |
//! | [`Gradient`]     | `∂T/∂s`                                                      |
//! | [`Hessian`]      | the analytic (tridiagonal) Hessian of `T`, as a dense matrix |
//! | [`Operator`]     | the residual `r(s) = ∂T/∂s` (the stationarity equations)     |
//! | [`Jacobian`]     | `∂r/∂s`: the same Hessian                                    |
//!
//! so that minimisers of `T` (BFGS, L-BFGS, Newton) and least-squares solvers of `r(s) = 0`
//! (Gauss-Newton, which minimises `½‖r‖²`) both apply. The `solve_*` functions run one argmin
//! solver from a start and report the result as an [`ArgminOutcome`]; they exist to
//! cross-check eigenray's own solver, not to replace it (argmin's solvers know nothing of
//! polyline vertices, ends or pinning). They never panic.
//!
//! What to expect of them, near a ray on straight segments:
//! - Gauss-Newton and Newton take full Newton steps and converge quadratically to round-off,
//!   like eigenray's solver; but with no line search or trust region they can diverge from a
//!   start far from the ray, where eigenray's damped Newton iteration converges.
//! - BFGS and L-BFGS converge from anywhere on the convex `T` of fixed segments, but see `T`
//!   through line searches on its values, and `T` is flat to round-off within some `10⁻⁸`
//!   (`√(ε T / H)`) of a minimum. They usually reach round-off all the same, but their line
//!   search can break down there; the outcome is then the last iterate, typically within a
//!   relative residual of `10⁻⁸` (see [`solve_bfgs`]).

mod layout;

pub use layout::{
    LensProfile, ObservedArrival, Placement, PlacementMisfit, ProfileMisfit, ReflectorPlacement,
    SourceLocation, SourceMisfit,
};

use std::cell::RefCell;
use std::rc::Rc;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    ArgminError, CostFunction, Error, Executor, Gradient, Hessian, IterState, Jacobian, KV,
    Operator, Problem, Solver, State, TerminationReason, TerminationStatus,
};
use argmin::solver::gaussnewton::GaussNewton;
use argmin::solver::linesearch::HagerZhangLineSearch;
use argmin::solver::newton::Newton;
use argmin::solver::quasinewton::{BFGS, LBFGS};
use argmin_math::{ArgminAdd, ArgminDot, ArgminEye, ArgminMul, ArgminSub, ArgminTranspose};
use nalgebra::{DMatrix, DVector};

use crate::problem::PathProblem;

/// A [`PathProblem`] as an argmin problem over the interaction parameters `s`
/// (`DVector<f64>`, one arclength per interaction).
///
/// Every evaluation checks that the parameter vector has one finite entry per interaction and
/// returns an [`ArgminError::InvalidParameter`] otherwise (it never panics).
///
/// ```
/// use argmin::core::{CostFunction, Executor, Gradient, State};
/// use argmin::solver::gaussnewton::GaussNewton;
/// use eigenray::argmin_bridge::ArgminPath;
/// use eigenray::problem::PathProblem;
/// use eigenray::Scene;
/// use nalgebra::DVector;
///
/// let scene = Scene::from_json(r#"{
///     "media": { "a": { "speed": 1.0 }, "b": { "speed": 0.5 } },
///     "interfaces": { "flat": { "points": [[-10, 0], [10, 0]] } },
///     "sources": [[0, 1]], "receivers": [[2, -1]],
///     "paths": [{ "steps": [{ "refract": "flat" }], "media": ["a", "b"] }]
/// }"#).unwrap();
/// let problem = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
/// let path = ArgminPath::new(problem);
///
/// // s = 11 is the point (1, 0) on the interface (arclength from its first vertex (-10, 0)).
/// let s0 = DVector::from_vec(vec![11.0]);
/// assert!((path.cost(&s0).unwrap() - 3.0 * 2f64.sqrt()).abs() < 1e-12);
/// assert!(path.gradient(&s0).unwrap()[0] != 0.0); // not Snell's law yet
///
/// // Gauss-Newton on the stationarity equations ∂T/∂s = 0.
/// let result = Executor::new(path.clone(), GaussNewton::new())
///     .configure(|state| state.param(s0).max_iters(50))
///     .run()
///     .unwrap();
/// let s = result.state().get_param().unwrap().as_slice().to_vec();
/// assert!(path.relative_residual(&s) < 1e-12);
///
/// // The same through the convenience function.
/// let outcome =
///     eigenray::argmin_bridge::solve_gauss_newton(path.problem(), &[11.0], 50, 1e-12).unwrap();
/// assert!(outcome.converged);
/// assert!((outcome.s[0] - s[0]).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct ArgminPath<'a> {
    problem: PathProblem<'a>,
}

impl<'a> ArgminPath<'a> {
    /// Wraps a path problem.
    pub fn new(problem: PathProblem<'a>) -> ArgminPath<'a> {
        ArgminPath { problem }
    }

    /// The wrapped path problem.
    pub fn problem(&self) -> &PathProblem<'a> {
        &self.problem
    }

    /// Unwraps the path problem.
    pub fn into_inner(self) -> PathProblem<'a> {
        self.problem
    }

    /// The relative residual at `s`: `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)` (eigenray's own measure of
    /// convergence, dimensionless: the difference of the sines in Snell's law). `0` for the
    /// direct ray, `NaN` if `s` has the wrong length.
    pub fn relative_residual(&self, s: &[f64]) -> f64 {
        if s.len() != self.problem.len() {
            return f64::NAN;
        }
        relative_residual(&self.problem, s)
    }

    /// `Ok(s)` as a slice when it has one finite entry per interaction.
    fn check<'s>(&self, s: &'s DVector<f64>) -> Result<&'s [f64], Error> {
        check_parameters(&self.problem, s.as_slice(), "parameters")?;
        Ok(s.as_slice())
    }
}

impl<'a> From<PathProblem<'a>> for ArgminPath<'a> {
    fn from(problem: PathProblem<'a>) -> ArgminPath<'a> {
        ArgminPath::new(problem)
    }
}

impl CostFunction for ArgminPath<'_> {
    type Param = DVector<f64>;
    type Output = f64;

    /// Travel time `T(s)`.
    fn cost(&self, s: &DVector<f64>) -> Result<f64, Error> {
        Ok(self.problem.time(self.check(s)?))
    }
}

impl Gradient for ArgminPath<'_> {
    type Param = DVector<f64>;
    type Gradient = DVector<f64>;

    /// `∂T/∂s`.
    fn gradient(&self, s: &DVector<f64>) -> Result<DVector<f64>, Error> {
        Ok(DVector::from_vec(self.problem.gradient(self.check(s)?)))
    }
}

impl Hessian for ArgminPath<'_> {
    type Param = DVector<f64>;
    type Hessian = DMatrix<f64>;

    /// The analytic Hessian of `T`, dense.
    fn hessian(&self, s: &DVector<f64>) -> Result<DMatrix<f64>, Error> {
        Ok(dense_hessian(&self.problem, self.check(s)?))
    }
}

impl Operator for ArgminPath<'_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;

    /// The residual `r(s) = ∂T/∂s`: a ray solves `r(s) = 0`.
    fn apply(&self, s: &DVector<f64>) -> Result<DVector<f64>, Error> {
        self.gradient(s)
    }
}

impl Jacobian for ArgminPath<'_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;

    /// `∂r/∂s`: the Hessian of `T` (symmetric).
    fn jacobian(&self, s: &DVector<f64>) -> Result<DMatrix<f64>, Error> {
        self.hessian(s)
    }
}

/// The result of one argmin solve.
#[derive(Clone, Debug, PartialEq)]
pub struct ArgminOutcome {
    /// Final interaction parameters (the solver's last iterate).
    pub s: Vec<f64>,
    /// Travel time at `s`.
    pub time: f64,
    /// Iterations of the outer solver (line-search iterations not counted).
    pub iterations: u64,
    /// Relative residual at `s`: `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)`.
    pub residual: f64,
    /// Whether `residual ≤ tol`.
    pub converged: bool,
    /// Why argmin stopped: its termination reason (e.g. `Target cost value reached`), or the
    /// error that stopped it after at least one iteration.
    pub termination: String,
}

/// Gauss-Newton (argmin's [`GaussNewton`], full steps) on the stationarity equations
/// `r(s) = ∂T/∂s = 0`, from `s0`.
///
/// Stops when `‖r‖₂ ≤ tol · minᵢ (wᵢ + wᵢ₊₁)` (which implies a relative residual `≤ tol`), when
/// `‖r‖₂` changes by less than that between iterations, or after `max_iters` iterations.
/// As `r`'s Jacobian is square, each step is a Newton step on `r`: it converges to whichever
/// stationary point (minimum, saddle or maximum of `T`) is near `s0`.
///
/// # Errors
/// `s0` of the wrong length or not finite, `tol` not positive and finite, or an error of the
/// solver in its first iteration (e.g. a singular Hessian); see [`ArgminOutcome::termination`]
/// for errors after that.
pub fn solve_gauss_newton(
    problem: &PathProblem,
    s0: &[f64],
    max_iters: u64,
    tol: f64,
) -> Result<ArgminOutcome, Error> {
    let abs_tol = check_inputs(problem, s0, tol)?;
    if problem.is_empty() {
        return Ok(direct(problem));
    }
    let solver = GaussNewton::new().with_tolerance(abs_tol)?;
    run(problem, solver, tol, |state| {
        state
            .param(DVector::from_column_slice(s0))
            .max_iters(max_iters)
            .target_cost(abs_tol)
    })
}

/// Newton's method (argmin's [`Newton`], full steps `δ = −H⁻¹ ∇T`) on `T`, from `s0`.
///
/// argmin's `Newton` has no stopping rule of its own; this one stops when the relative
/// residual is `≤ tol` or after `max_iters` iterations. Like Gauss-Newton, it converges to the
/// stationary point near `s0`, whatever its kind.
///
/// # Errors
/// As [`solve_gauss_newton`].
pub fn solve_newton(
    problem: &PathProblem,
    s0: &[f64],
    max_iters: u64,
    tol: f64,
) -> Result<ArgminOutcome, Error> {
    check_inputs(problem, s0, tol)?;
    if problem.is_empty() {
        return Ok(direct(problem));
    }
    let solver = UntilStationary {
        inner: Newton::new(),
        tol,
        scale: leg_pair_slowness(problem),
    };
    run(problem, solver, tol, |state| {
        state
            .param(DVector::from_column_slice(s0))
            .max_iters(max_iters)
    })
}

/// BFGS (argmin's [`BFGS`] with a Hager-Zhang line search) minimising `T`, from `s0`.
///
/// The initial inverse Hessian is the identity scaled by `1 / meanᵢ (wᵢ/ℓᵢ + wᵢ₊₁/ℓᵢ₊₁)` (the
/// natural scale of `T`'s curvature, from the leg lengths `ℓ` at `s0`). Stops when
/// `‖∇T‖₂ ≤ tol · minᵢ (wᵢ + wᵢ₊₁)` (which implies a relative residual `≤ tol`) or after
/// `max_iters` iterations. There is no stopping rule on the change of `T`: near a minimum `T`
/// is flat to round-off (`½ H δ²` is below one ulp of `T` for `|δ| ≲ √(ε T / H)`, some `10⁻⁸`)
/// long before the parameters have converged, and the iteration goes on there on slopes.
///
/// Finds minima of `T` only: from near a saddle or a maximum it goes elsewhere.
///
/// # Errors
/// As [`solve_gauss_newton`]. Once `T` is flat to round-off, argmin's Hager-Zhang line search
/// can break down (a secant step through two equal slopes, to an infinite step): the outcome is
/// then the last iterate, not an error, with the error in [`ArgminOutcome::termination`]. Over
/// 18,000 starts 0.1–0.3 from the rays of the tests, that happened in 1.5 % of them (5 % on a
/// path through three interfaces), at worst at a relative residual of `2.4·10⁻⁸` and `4·10⁻⁸`
/// from the ray.
pub fn solve_bfgs(
    problem: &PathProblem,
    s0: &[f64],
    max_iters: u64,
    tol: f64,
) -> Result<ArgminOutcome, Error> {
    let abs_tol = check_inputs(problem, s0, tol)?;
    if problem.is_empty() {
        return Ok(direct(problem));
    }
    let k = problem.len();
    let inv_hessian =
        InverseHessian(DMatrix::identity(k, k) * inverse_curvature_scale(problem, s0));
    let solver = BFGS::new(HagerZhangLineSearch::new())
        .with_tolerance_grad(abs_tol)?
        .with_tolerance_cost(0.0)?;
    run(problem, solver, tol, |state| {
        state
            .param(DVector::from_column_slice(s0))
            .inv_hessian(inv_hessian)
            .max_iters(max_iters)
    })
}

/// Number of correction pairs kept by [`solve_lbfgs`].
pub const LBFGS_MEMORY: usize = 7;

/// L-BFGS (argmin's [`LBFGS`] with [`LBFGS_MEMORY`] correction pairs and a Hager-Zhang line
/// search) minimising `T`, from `s0`. Stopping rules and errors as for [`solve_bfgs`].
///
/// # Errors
/// As [`solve_gauss_newton`].
pub fn solve_lbfgs(
    problem: &PathProblem,
    s0: &[f64],
    max_iters: u64,
    tol: f64,
) -> Result<ArgminOutcome, Error> {
    let abs_tol = check_inputs(problem, s0, tol)?;
    if problem.is_empty() {
        return Ok(direct(problem));
    }
    let solver = LBFGS::new(HagerZhangLineSearch::new(), LBFGS_MEMORY)
        .with_tolerance_grad(abs_tol)?
        .with_tolerance_cost(0.0)?;
    run(problem, solver, tol, |state| {
        state
            .param(DVector::from_column_slice(s0))
            .max_iters(max_iters)
    })
}

/// The last parameters seen after an iteration, and how many iterations that was.
type LastIterate = Rc<RefCell<Option<(DVector<f64>, u64)>>>;

/// An observer that records every iterate into a [`LastIterate`].
struct Recorder(LastIterate);

impl<I: State<Param = DVector<f64>>> Observe<I> for Recorder {
    fn observe_init(&mut self, _name: &str, state: &I, _kv: &KV) -> Result<(), Error> {
        if let Some(p) = state.get_param() {
            *self.0.borrow_mut() = Some((p.clone(), 0));
        }
        Ok(())
    }
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), Error> {
        // Called before the iteration counter is incremented.
        if let Some(p) = state.get_param() {
            *self.0.borrow_mut() = Some((p.clone(), state.get_iter() + 1));
        }
        Ok(())
    }
}

/// Runs `solver` on `problem` from the state `configure` builds and reports the outcome.
///
/// An error of the solver after at least one completed iteration does not discard the work
/// done: the outcome is the last iterate, with the error in `termination` (argmin's own L-BFGS
/// does the same with line-search errors, but drops the parameters, which are recovered here).
fn run<'a, S, I>(
    problem: &PathProblem<'a>,
    solver: S,
    tol: f64,
    configure: impl FnOnce(I) -> I,
) -> Result<ArgminOutcome, Error>
where
    S: Solver<ArgminPath<'a>, I>,
    I: State<Param = DVector<f64>, Float = f64>,
{
    let last: LastIterate = Rc::default();
    let result = Executor::new(ArgminPath::new(problem.clone()), solver)
        .configure(configure)
        .add_observer(Recorder(Rc::clone(&last)), ObserverMode::Always)
        .ctrlc(false)
        .run();
    let last = last.borrow_mut().take();
    match result {
        Ok(result) => {
            let state = result.state();
            let termination = state
                .get_termination_reason()
                .map_or_else(|| "running".to_string(), |r| r.text().to_string());
            match (state.get_param(), last) {
                (Some(s), _) => outcome(problem, s, state.get_iter(), tol, termination),
                (None, Some((s, iterations))) => outcome(problem, &s, iterations, tol, termination),
                (None, None) => Err(ArgminError::PotentialBug {
                    text: "no final parameters".to_string(),
                }
                .into()),
            }
        }
        Err(error) => match last {
            Some((s, iterations)) if iterations > 0 => outcome(
                problem,
                &s,
                iterations,
                tol,
                format!("stopped by an error after {iterations} iterations: {error}"),
            ),
            _ => Err(error),
        },
    }
}

/// The dense Hessian of `T` at `s` (of the right length).
fn dense_hessian(problem: &PathProblem, s: &[f64]) -> DMatrix<f64> {
    let h = problem.hessian(s);
    let k = h.diag.len();
    DMatrix::from_fn(k, k, |i, j| {
        if i == j {
            h.diag[i]
        } else if i + 1 == j {
            h.off[i]
        } else if j + 1 == i {
            h.off[j]
        } else {
            0.0
        }
    })
}

/// `wᵢ + wᵢ₊₁` for every interaction `i`.
fn leg_pair_slowness(problem: &PathProblem) -> Vec<f64> {
    problem.slowness().windows(2).map(|w| w[0] + w[1]).collect()
}

/// `maxᵢ |rᵢ| / (wᵢ + wᵢ₊₁)` at `s` (of the right length); `NaN` if any term is `NaN`.
fn relative_residual(problem: &PathProblem, s: &[f64]) -> f64 {
    let r = problem.gradient(s);
    max_relative(&r, &leg_pair_slowness(problem))
}

fn max_relative(r: &[f64], scale: &[f64]) -> f64 {
    let mut m: f64 = 0.0;
    for (ri, wi) in r.iter().zip(scale) {
        let v = ri.abs() / wi;
        if v.is_nan() {
            return f64::NAN;
        }
        m = m.max(v);
    }
    m
}

/// Checks the inputs of a `solve_*` function; returns the absolute tolerance on `‖r‖₂` that
/// implies the relative one.
/// `Ok` when `s` has one finite entry per interaction; `what` names it in the error.
fn check_parameters(problem: &PathProblem, s: &[f64], what: &str) -> Result<(), Error> {
    let k = problem.len();
    if s.len() != k {
        return Err(invalid(format!(
            "expected {k} {what} (one per interaction), got {}",
            s.len()
        )));
    }
    if s.iter().any(|v| !v.is_finite()) {
        return Err(invalid(format!("{what} must be finite")));
    }
    Ok(())
}

fn check_inputs(problem: &PathProblem, s0: &[f64], tol: f64) -> Result<f64, Error> {
    check_parameters(problem, s0, "start parameters")?;
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(invalid(format!(
            "tolerance must be positive and finite, got {tol}"
        )));
    }
    let min_pair = leg_pair_slowness(problem)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    Ok(if min_pair.is_finite() {
        tol * min_pair
    } else {
        tol
    })
}

/// `1 / meanᵢ (wᵢ/ℓᵢ + wᵢ₊₁/ℓᵢ₊₁)` at `s`: a scalar inverse Hessian of `T`'s natural scale
/// (1 when that is not a positive finite number, e.g. with a zero-length leg).
fn inverse_curvature_scale(problem: &PathProblem, s: &[f64]) -> f64 {
    let points = problem.points(s);
    let w = problem.slowness();
    let k = problem.len();
    let per_leg: Vec<f64> = points
        .windows(2)
        .zip(w)
        .map(|(p, &w)| w / p[0].distance(p[1]))
        .collect();
    let mean = (0..k).map(|i| per_leg[i] + per_leg[i + 1]).sum::<f64>() / k as f64;
    let scale = 1.0 / mean;
    if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    }
}

fn invalid(text: String) -> Error {
    ArgminError::InvalidParameter { text }.into()
}

/// The outcome of the direct ray (no unknowns).
fn direct(problem: &PathProblem) -> ArgminOutcome {
    ArgminOutcome {
        s: Vec::new(),
        time: problem.time(&[]),
        iterations: 0,
        residual: 0.0,
        converged: true,
        termination: "no interactions".to_string(),
    }
}

/// The outcome at parameters `s` after `iterations` iterations.
fn outcome(
    problem: &PathProblem,
    s: &DVector<f64>,
    iterations: u64,
    tol: f64,
    termination: String,
) -> Result<ArgminOutcome, Error> {
    if s.len() != problem.len() || s.iter().any(|v| !v.is_finite()) {
        return Err(ArgminError::ConditionViolated {
            text: "the solver ended on non-finite parameters".to_string(),
        }
        .into());
    }
    let s = s.as_slice().to_vec();
    let residual = relative_residual(problem, &s);
    Ok(ArgminOutcome {
        time: problem.time(&s),
        iterations,
        residual,
        converged: residual <= tol,
        termination,
        s,
    })
}

/// The state of argmin's Newton solver on a path.
type NewtonState = IterState<DVector<f64>, DVector<f64>, (), DMatrix<f64>, (), f64>;

/// An argmin solver on `T` (here argmin's [`Newton`], which has no stopping rule) made to stop
/// once the relative residual is at most `tol`: after every iteration it stores `T` and `∇T`
/// at the new parameters in the state.
#[derive(Clone)]
struct UntilStationary<S> {
    inner: S,
    tol: f64,
    /// `wᵢ + wᵢ₊₁`.
    scale: Vec<f64>,
}

impl<S> UntilStationary<S> {
    fn measure(
        &self,
        problem: &mut Problem<ArgminPath<'_>>,
        state: NewtonState,
    ) -> Result<NewtonState, Error> {
        let param = state.get_param().ok_or_else(|| {
            Error::from(ArgminError::NotInitialized {
                text: "no parameters".to_string(),
            })
        })?;
        let cost = problem.cost(param)?;
        let gradient = problem.gradient(param)?;
        Ok(state.cost(cost).gradient(gradient))
    }
}

impl<'a, S> Solver<ArgminPath<'a>, NewtonState> for UntilStationary<S>
where
    S: Solver<ArgminPath<'a>, NewtonState>,
{
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn init(
        &mut self,
        problem: &mut Problem<ArgminPath<'a>>,
        state: NewtonState,
    ) -> Result<(NewtonState, Option<KV>), Error> {
        let (state, kv) = self.inner.init(problem, state)?;
        Ok((self.measure(problem, state)?, kv))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<ArgminPath<'a>>,
        state: NewtonState,
    ) -> Result<(NewtonState, Option<KV>), Error> {
        let (state, kv) = self.inner.next_iter(problem, state)?;
        Ok((self.measure(problem, state)?, kv))
    }

    fn terminate(&mut self, state: &NewtonState) -> TerminationStatus {
        let inner = self.inner.terminate(state);
        if inner.terminated() {
            return inner;
        }
        match state.get_gradient() {
            Some(g) if max_relative(g.as_slice(), &self.scale) <= self.tol => {
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            _ => TerminationStatus::NotTerminated,
        }
    }
}

/// BFGS's inverse-Hessian approximation: a dense matrix behind a newtype.
///
/// argmin's BFGS forms outer products `s sᵀ` as `ArgminDot<P, H>` of two parameter vectors,
/// which argmin-math's nalgebra backend does not provide (its vector-vector `dot` is the
/// inner product; argmin issue #337), so BFGS cannot use `DMatrix` directly. With this
/// newtype as the Hessian type, the outer product below is ours and everything else is
/// nalgebra's arithmetic.
#[derive(Clone, Debug)]
struct InverseHessian(DMatrix<f64>);

impl ArgminDot<DVector<f64>, InverseHessian> for DVector<f64> {
    /// The outer product `self otherᵀ`.
    fn dot(&self, other: &DVector<f64>) -> InverseHessian {
        InverseHessian(self * other.transpose())
    }
}

impl ArgminDot<DVector<f64>, DVector<f64>> for InverseHessian {
    fn dot(&self, other: &DVector<f64>) -> DVector<f64> {
        &self.0 * other
    }
}

impl ArgminDot<InverseHessian, InverseHessian> for InverseHessian {
    fn dot(&self, other: &InverseHessian) -> InverseHessian {
        InverseHessian(&self.0 * &other.0)
    }
}

impl ArgminAdd<InverseHessian, InverseHessian> for InverseHessian {
    fn add(&self, other: &InverseHessian) -> InverseHessian {
        InverseHessian(&self.0 + &other.0)
    }
}

impl ArgminSub<InverseHessian, InverseHessian> for InverseHessian {
    fn sub(&self, other: &InverseHessian) -> InverseHessian {
        InverseHessian(&self.0 - &other.0)
    }
}

impl ArgminMul<f64, InverseHessian> for InverseHessian {
    fn mul(&self, other: &f64) -> InverseHessian {
        InverseHessian(&self.0 * *other)
    }
}

impl ArgminTranspose<InverseHessian> for InverseHessian {
    fn t(self) -> InverseHessian {
        InverseHessian(self.0.transpose())
    }
}

impl ArgminEye for InverseHessian {
    fn eye(n: usize) -> InverseHessian {
        InverseHessian(DMatrix::identity(n, n))
    }
    fn eye_like(&self) -> InverseHessian {
        InverseHessian(DMatrix::identity(self.0.nrows(), self.0.ncols()))
    }
}
