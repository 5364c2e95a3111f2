//! Cross-checks of eigenray's solver against argmin's (Gauss-Newton, Newton, BFGS, L-BFGS)
//! through the argmin bridge, and of the analytic Hessian against finite differences.
#![cfg(feature = "argmin")]

use argmin::core::{CostFunction, Gradient, Hessian, Jacobian, Operator};
use eigenray::argmin_bridge::{
    ArgminOutcome, ArgminPath, solve_bfgs, solve_gauss_newton, solve_lbfgs, solve_newton,
};
use eigenray::{Point, Ray, Scene, SolverOptions, Status, Tracer, Workspace, problem::PathProblem};
use nalgebra::DVector;

/// Relative residual tolerance given to every argmin solver (eigenray's default).
const TOL: f64 = 1e-12;
/// Iteration limit given to every argmin solver.
const MAX_ITERS: u64 = 500;

/// What one argmin solver must achieve: its final relative residual and the distance of its
/// interaction points from eigenray's.
struct Accuracy {
    residual: f64,
    points: f64,
}

/// Gauss-Newton and Newton take full Newton steps on `r(s) = 0` and converge quadratically to
/// round-off: they must meet `TOL` and place the points within 1e-8 (in fact ~1e-11).
const NEWTON_ACCURACY: Accuracy = Accuracy {
    residual: TOL,
    points: 1e-8,
};

/// BFGS and L-BFGS are loosened, and only they. They minimise `T` with line searches on
/// values of `T`, and near the minimum `T` is flat to round-off (`T − T* = ½ H δ²` is below one
/// ulp of `T` for `|δ| ≲ 5e-8`), so there a line search decides on noise. Usually the full
/// quasi-Newton step is accepted on its slope and they reach `TOL` anyway (from nearly all the
/// fixed starts below); but sometimes argmin's Hager-Zhang line search breaks down there (a
/// secant step through two equal slopes, an infinite step) and they stop where they are. Over
/// 18,000 random starts (0.1–0.3 from the ray) that stop was at worst a relative residual of
/// 2.4e-8 and 3.9e-8 from eigenray's points; `random_starts_agree` keeps checking it. The
/// travel time, quadratic in the error, still agrees to 1e-12.
const QUASI_NEWTON_ACCURACY: Accuracy = Accuracy {
    residual: 1e-7,
    points: 1e-7,
};

/// All the scenes of the cross-checks, with their names.
const SCENES: [(&str, &str); 5] = [
    (REFRACTION, "refraction"),
    (REFLECTION, "reflection"),
    (LAYERS, "layers"),
    (TWO_MIRRORS, "two mirrors"),
    (TILTED, "tilted"),
];

/// Single refraction through a flat interface, several receivers (one per ray).
const REFRACTION: &str = r#"{
    "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.6 } },
    "interfaces": { "surface": { "points": [[-20, 0], [20, 0]] } },
    "sources": [[0, 2]],
    "receivers": [[1, -1], [3, -2], [-4, -0.5], [0.5, -3], [8, -1]],
    "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
}"#;

/// Single reflection off a flat mirror.
const REFLECTION: &str = r#"{
    "media": { "air": { "index": 1.0 } },
    "interfaces": { "mirror": { "points": [[-10, 0], [10, 0]] } },
    "sources": [[-2, 1.5], [0, 3]],
    "receivers": [[3, 0.5], [1, 4]],
    "paths": [{ "steps": [{ "reflect": "mirror" }], "media": ["air", "air"] }]
}"#;

/// Refraction down through three flat interfaces (four layers).
const LAYERS: &str = r#"{
    "media": {
        "l0": { "speed": 1.0 }, "l1": { "speed": 1.6 },
        "l2": { "speed": 1.2 }, "l3": { "speed": 2.0 }
    },
    "interfaces": {
        "a": { "points": [[-30, 0], [30, 0]] },
        "b": { "points": [[-30, -1], [30, -1]] },
        "c": { "points": [[-30, -2.5], [30, -2.5]] }
    },
    "sources": [[0, 1]],
    "receivers": [[4, -4], [-2, -3.5], [1, -2.8]],
    "paths": [{
        "steps": [{ "refract": "a" }, { "refract": "b" }, { "refract": "c" }],
        "media": ["l0", "l1", "l2", "l3"]
    }]
}"#;

/// Two reflections between two non-parallel mirrors: off the floor, then off the tilted roof.
const TWO_MIRRORS: &str = r#"{
    "media": { "air": { "speed": 1.0 } },
    "interfaces": {
        "floor": { "points": [[-10, 0], [20, 0]] },
        "roof": { "points": [[-10, 4], [20, 7]] }
    },
    "sources": [[0, 1]],
    "receivers": [[6, 2], [10, 1], [3, 4]],
    "paths": [{
        "steps": [{ "reflect": "floor" }, { "reflect": "roof" }],
        "media": ["air", "air", "air"]
    }]
}"#;

/// Refraction through a tilted interface.
const TILTED: &str = r#"{
    "media": { "fast": { "speed": 2.0 }, "slow": { "speed": 0.7 } },
    "interfaces": { "slope": { "points": [[-6, -3], [6, 3]] } },
    "sources": [[-2, 2]],
    "receivers": [[2, -2], [4, 0.5], [-1, -3]],
    "paths": [{ "steps": [{ "refract": "slope" }], "media": ["fast", "slow"] }]
}"#;

/// Iterations used by Gauss-Newton, Newton, BFGS and L-BFGS on one ray from one start
/// (`None`: did not converge).
type Iterations = [Option<u64>; 4];

/// `Iterations` for the log.
fn show(it: &Iterations) -> String {
    let names = ["Gauss-Newton", "Newton", "BFGS", "L-BFGS"];
    let part = |(name, n): (&str, &Option<u64>)| match n {
        Some(n) => format!("{name} {n}"),
        None => format!("{name} diverged"),
    };
    names
        .into_iter()
        .zip(it)
        .map(part)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The largest coordinate difference between two point lists of the same length.
fn max_point_difference(a: &[Point], b: &[Point]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (p.x - q.x).abs().max((p.y - q.y).abs()))
        .fold(0.0, f64::max)
}

/// A start perturbed from `s` by 0.1–0.3 per parameter, with alternating signs.
fn perturbed(s: &[f64]) -> Vec<f64> {
    const SHIFTS: [f64; 4] = [0.2, -0.3, 0.1, -0.25];
    s.iter()
        .enumerate()
        .map(|(i, v)| v + SHIFTS[i % SHIFTS.len()])
        .collect()
}

/// eigenray's own initial guess for one ray: its parameters after zero iterations.
fn initial_guess(scene: &Scene, source: usize, receiver: usize, path: usize) -> Vec<f64> {
    let mut scene = scene.clone();
    scene
        .set_solver(SolverOptions {
            max_iterations: 0,
            ..scene.solver()
        })
        .expect("valid solver options");
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let ray = tracer.trace(source, receiver, path, &mut ws);
    assert_eq!(ray.iterations, 0);
    ws.parameters().to_vec()
}

/// Runs the four argmin solvers from `s0`, checks each against eigenray's ray (`points`,
/// `time`) and returns their iteration counts (`None`: did not converge, allowed only for the
/// full-step Newton methods when `newton_may_fail`).
fn solve_all(
    label: &str,
    problem: &PathProblem,
    s0: &[f64],
    points: &[Point],
    time: f64,
    newton_may_fail: bool,
) -> Iterations {
    let solvers = [
        (
            "Gauss-Newton",
            solve_gauss_newton as Solve,
            NEWTON_ACCURACY,
            newton_may_fail,
        ),
        ("Newton", solve_newton, NEWTON_ACCURACY, newton_may_fail),
        ("BFGS", solve_bfgs, QUASI_NEWTON_ACCURACY, false),
        ("L-BFGS", solve_lbfgs, QUASI_NEWTON_ACCURACY, false),
    ];
    let mut iterations = [None; 4];
    for (i, (name, solve, accuracy, may_fail)) in solvers.into_iter().enumerate() {
        let label = format!("{label}: {name}");
        let out = solve(problem, s0, MAX_ITERS, TOL).unwrap();
        if may_fail && !out.converged {
            println!(
                "  {label}: no convergence after {} iterations ({})",
                out.iterations, out.termination
            );
            continue;
        }
        check_outcome(&label, problem, &out, &accuracy, points, time);
        iterations[i] = Some(out.iterations);
    }
    iterations
}

type Solve = fn(&PathProblem, &[f64], u64, f64) -> Result<ArgminOutcome, argmin::core::Error>;

/// Checks that one argmin outcome matches eigenray's ray.
fn check_outcome(
    label: &str,
    problem: &PathProblem,
    out: &ArgminOutcome,
    accuracy: &Accuracy,
    points: &[Point],
    time: f64,
) {
    let d = max_point_difference(&problem.points(&out.s), points);
    let rel = (out.time - time).abs() / time;
    println!(
        "  {label}: {} iterations, residual {:.1e}, points {d:.1e}, time {rel:.1e} ({})",
        out.iterations, out.residual, out.termination
    );
    assert!(
        out.residual <= accuracy.residual,
        "{label}: residual {:e} after {} iterations ({})",
        out.residual,
        out.iterations,
        out.termination
    );
    assert_eq!(out.converged, out.residual <= TOL, "{label}");
    assert!(d <= accuracy.points, "{label}: points differ by {d:e}");
    assert!(
        rel <= 1e-12,
        "{label}: time {} vs {time} (relative {rel:e})",
        out.time
    );
    assert_eq!(
        out.time,
        problem.time(&out.s),
        "{label}: reported time is T(s)"
    );
}

/// eigenray's solution of every ray of a scene: the ray, its path problem and its parameters.
fn solved_rays(scene: &Scene) -> Vec<(Ray, PathProblem<'_>, Vec<f64>)> {
    let tracer = Tracer::new(scene).unwrap();
    let mut ws = Workspace::new();
    tracer
        .trace_all()
        .into_iter()
        .map(|traced| {
            let ray = tracer.trace(traced.source, traced.receiver, traced.path, &mut ws);
            assert_eq!(ray, traced, "trace and trace_all agree");
            assert_eq!(ray.status, Status::Converged, "{:?}", ray.reason);
            let (src, rcv) = (scene.sources()[ray.source], scene.receivers()[ray.receiver]);
            let problem = PathProblem::new(scene, ray.path, src, rcv).unwrap();
            let s = ws.parameters().to_vec();
            // The bridge's problem reproduces eigenray's ray at eigenray's parameters.
            assert!(max_point_difference(&problem.points(&s), &ray.points) <= 1e-12);
            assert!((problem.time(&s) - ray.time).abs() <= 1e-13 * ray.time);
            (ray, problem, s)
        })
        .collect()
}

/// Solves every ray of a scene with eigenray and with the argmin solvers, from a start
/// perturbed from eigenray's solution and from eigenray's own initial guess; checks they all
/// agree.
fn cross_check(json: &str, name: &str) {
    let scene = Scene::from_json(json).unwrap();
    for (ray_index, (ray, problem, s_ours)) in solved_rays(&scene).into_iter().enumerate() {
        let label = format!("{name} ray {ray_index}");
        let time = ray.time;
        let guess = initial_guess(&scene, ray.source, ray.receiver, ray.path);
        // Gauss-Newton and Newton take full steps, with no line search or trust region: from
        // eigenray's guess, which can be far from the ray, they may diverge (eigenray's damped
        // Newton does not). BFGS and L-BFGS have line searches on the convex T and must converge.
        let from_guess = solve_all(
            &format!("{label} from eigenray's guess"),
            &problem,
            &guess,
            &ray.points,
            time,
            true,
        );
        let start = perturbed(&s_ours);
        let from_perturbed = solve_all(
            &format!("{label} perturbed"),
            &problem,
            &start,
            &ray.points,
            time,
            false,
        );
        println!(
            "{label}: eigenray {} iterations; from eigenray's guess: {}; perturbed: {}",
            ray.iterations,
            show(&from_guess),
            show(&from_perturbed)
        );
    }
}

#[test]
fn refraction_flat_interface_agrees() {
    cross_check(REFRACTION, "refraction");
}

#[test]
fn reflection_flat_mirror_agrees() {
    cross_check(REFLECTION, "reflection");
}

#[test]
fn three_layer_stack_agrees() {
    cross_check(LAYERS, "layers");
}

#[test]
fn two_reflections_between_non_parallel_mirrors_agree() {
    cross_check(TWO_MIRRORS, "two mirrors");
}

#[test]
fn tilted_interface_refraction_agrees() {
    cross_check(TILTED, "tilted");
}

/// Every solver from many random starts 0.1–0.3 (per parameter, either side) from every ray:
/// the Newton methods must converge to `TOL`; BFGS and L-BFGS to `QUASI_NEWTON_ACCURACY`.
#[test]
fn random_starts_agree() {
    const STARTS: usize = 40;
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut uniform = move || {
        // 64-bit LCG (Knuth's MMIX constants), top 53 bits.
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut below_tol = [0usize; 4];
    let mut runs = 0;
    for (json, name) in SCENES {
        let scene = Scene::from_json(json).unwrap();
        for (ray_index, (ray, problem, s_ours)) in solved_rays(&scene).into_iter().enumerate() {
            for start in 0..STARTS {
                let s0: Vec<f64> = s_ours
                    .iter()
                    .map(|v| {
                        let shift = 0.1 + 0.2 * uniform();
                        if uniform() < 0.5 {
                            v - shift
                        } else {
                            v + shift
                        }
                    })
                    .collect();
                runs += 1;
                let label = format!("{name} ray {ray_index} start {start} {s0:?}");
                let solvers = [
                    ("Gauss-Newton", solve_gauss_newton as Solve, NEWTON_ACCURACY),
                    ("Newton", solve_newton, NEWTON_ACCURACY),
                    ("BFGS", solve_bfgs, QUASI_NEWTON_ACCURACY),
                    ("L-BFGS", solve_lbfgs, QUASI_NEWTON_ACCURACY),
                ];
                for (i, (solver, solve, accuracy)) in solvers.into_iter().enumerate() {
                    let out = solve(&problem, &s0, MAX_ITERS, TOL).unwrap();
                    let d = max_point_difference(&problem.points(&out.s), &ray.points);
                    let time = ray.time;
                    assert!(
                        out.residual <= accuracy.residual,
                        "{label}: {solver}: {out:?}"
                    );
                    assert!(
                        d <= accuracy.points,
                        "{label}: {solver}: points differ by {d:e}"
                    );
                    assert!(
                        (out.time - time).abs() <= 1e-12 * time,
                        "{label}: {solver}: {out:?}"
                    );
                    below_tol[i] += usize::from(out.converged);
                }
            }
        }
    }
    println!("runs {runs}; reached TOL: Gauss-Newton, Newton, BFGS, L-BFGS {below_tol:?}");
    assert_eq!(below_tol[0], runs);
    assert_eq!(below_tol[1], runs);
}

/// The analytic Hessian (argmin's `Hessian` and `Jacobian`) against a central difference of
/// argmin's `Gradient`, away from the solution (where the legs are not yet Snell's).
#[test]
fn hessian_matches_central_difference_of_gradient() {
    let scene = Scene::from_json(LAYERS).unwrap();
    let problem = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
    let path = ArgminPath::new(problem);
    // Points at x = 1.3, 2.1, 3.4 on the three interfaces (each starts at x = -30).
    let s = DVector::from_vec(vec![31.3, 32.1, 33.4]);
    let hessian = path.hessian(&s).unwrap();
    assert_eq!(hessian, path.jacobian(&s).unwrap());
    assert_eq!(hessian, hessian.transpose());
    let k = s.len();
    let h = 1e-5;
    let scale = hessian.amax();
    for j in 0..k {
        let mut plus = s.clone();
        let mut minus = s.clone();
        plus[j] += h;
        minus[j] -= h;
        let column = (path.gradient(&plus).unwrap() - path.gradient(&minus).unwrap()) / (2.0 * h);
        for i in 0..k {
            let (analytic, numeric) = (hessian[(i, j)], column[i]);
            assert!(
                (analytic - numeric).abs() <= 1e-6 * analytic.abs().max(1e-3 * scale),
                "H[{i}][{j}]: analytic {analytic}, central difference {numeric}"
            );
        }
    }
    // Tridiagonal: the corner entries are exactly zero, analytically and numerically.
    assert_eq!(hessian[(0, 2)], 0.0);

    // And the gradient against a central difference of the cost.
    let g = path.gradient(&s).unwrap();
    for j in 0..k {
        let mut plus = s.clone();
        let mut minus = s.clone();
        plus[j] += h;
        minus[j] -= h;
        let numeric = (path.cost(&plus).unwrap() - path.cost(&minus).unwrap()) / (2.0 * h);
        assert!(
            (g[j] - numeric).abs() <= 1e-7 * g.amax(),
            "g[{j}]: analytic {}, central difference {numeric}",
            g[j]
        );
    }
}

/// The argmin traits return exactly the path problem's values.
#[test]
fn traits_match_path_problem() {
    let scene = Scene::from_json(TWO_MIRRORS).unwrap();
    let problem = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[1]).unwrap();
    let s = [12.0, 15.0];
    let path = ArgminPath::from(problem.clone());
    let v = DVector::from_column_slice(&s);
    assert_eq!(path.cost(&v).unwrap(), problem.time(&s));
    assert_eq!(
        path.gradient(&v).unwrap().as_slice(),
        problem.gradient(&s).as_slice()
    );
    assert_eq!(path.apply(&v).unwrap(), path.gradient(&v).unwrap());
    let dense = problem.hessian(&s).to_dense();
    let h = path.hessian(&v).unwrap();
    for i in 0..2 {
        for j in 0..2 {
            assert_eq!(h[(i, j)], dense[i][j]);
        }
    }
    let w = problem.slowness();
    let r = problem.gradient(&s);
    let expected = (r[0].abs() / (w[0] + w[1])).max(r[1].abs() / (w[1] + w[2]));
    assert_eq!(path.relative_residual(&s), expected);
    assert!(path.relative_residual(&s[..1]).is_nan());
    assert_eq!(path.problem().len(), 2);
    assert_eq!(path.into_inner().len(), 2);
}

/// Bad inputs give errors, never panics.
#[test]
fn bad_inputs_are_errors() {
    let scene = Scene::from_json(LAYERS).unwrap();
    let problem = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
    let path = ArgminPath::new(problem.clone());
    assert!(path.cost(&DVector::from_vec(vec![1.0, 2.0])).is_err());
    assert!(
        path.gradient(&DVector::from_vec(vec![1.0, 2.0, 3.0, 4.0]))
            .is_err()
    );
    assert!(
        path.hessian(&DVector::from_vec(vec![1.0, f64::NAN, 3.0]))
            .is_err()
    );
    assert!(
        path.apply(&DVector::from_vec(vec![f64::INFINITY, 2.0, 3.0]))
            .is_err()
    );
    assert!(path.jacobian(&DVector::from_vec(vec![])).is_err());
    let good = [30.0, 31.0, 32.0];
    for solve in [solve_gauss_newton, solve_newton, solve_bfgs, solve_lbfgs] {
        assert!(solve(&problem, &good[..2], 10, TOL).is_err());
        assert!(solve(&problem, &[30.0, f64::NAN, 32.0], 10, TOL).is_err());
        assert!(solve(&problem, &good, 10, 0.0).is_err());
        assert!(solve(&problem, &good, 10, -1.0).is_err());
        assert!(solve(&problem, &good, 10, f64::NAN).is_err());
        let out = solve(&problem, &good, 0, TOL).unwrap();
        assert_eq!(out.iterations, 0);
        assert!(!out.converged);
        assert_eq!(out.s, good);
    }
}

/// The direct ray has no unknowns: every solver returns it at once.
#[test]
fn direct_ray_has_nothing_to_solve() {
    let scene = Scene::from_json(
        r#"{
        "media": { "air": { "speed": 2.0 } },
        "sources": [[0, 0]], "receivers": [[3, 4]],
        "paths": [{ "steps": [], "media": ["air"] }]
    }"#,
    )
    .unwrap();
    let problem = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
    for solve in [solve_gauss_newton, solve_newton, solve_bfgs, solve_lbfgs] {
        let out = solve(&problem, &[], 10, TOL).unwrap();
        assert!(out.s.is_empty());
        assert_eq!(out.time, 2.5);
        assert_eq!(out.iterations, 0);
        assert!(out.converged);
    }
}
