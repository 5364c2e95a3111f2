//! Error against run time: eigenray's Newton solver, argmin's solvers and gradient descent.
//!
//! `cargo run --release --features argmin --example report` solves the benchmark scenes of
//! `fixtures/bench/` (exact references beside them) and an 8-interaction layer stack (exact
//! reference computed here) with every method at several settings, and writes
//! `docs/report.md` and `docs/error_vs_time_SCENE.svg`.

#[path = "../benches/support/plot.rs"]
mod plot;
#[path = "../benches/support/timing.rs"]
mod timing;

#[cfg(not(feature = "argmin"))]
fn main() {
    eprintln!(
        "the report compares with argmin's solvers: run \
         `cargo run --release --features argmin --example report`"
    );
    std::process::exit(2);
}

#[cfg(feature = "argmin")]
fn main() -> std::io::Result<()> {
    report::run()
}

#[cfg(feature = "argmin")]
mod report {
    use std::fmt::Write as _;
    use std::hint::black_box;
    use std::io;

    use eigenray::argmin_bridge::{solve_bfgs, solve_gauss_newton, solve_lbfgs};
    use eigenray::{
        InitialGuess, Point, RayRecord, Scene, SolverOptions, Tracer, Workspace, demo,
        problem::PathProblem,
    };

    use super::plot::{Marker, Plot, Scale, Series};
    use super::timing::{Timing, cpu_model, fmt_seconds, load_average, time_per_call};

    /// Each timed run lasts at least this long (seconds).
    const MIN_RUN: f64 = 0.1;
    /// Errors below this are plotted at it (an error of exactly 0 has no logarithm).
    const ERROR_FLOOR: f64 = 1e-17;
    /// Errors above this (diverged) are plotted at it.
    const ERROR_CEILING: f64 = 10.0;

    /// An exact reference: per ray, `converged` or `no_path`, and the time (NaN if none).
    struct Reference {
        status: Vec<String>,
        time: Vec<f64>,
        method: String,
    }

    /// A figure of another tool from `fixtures/bench/README.md`.
    struct Other {
        what: &'static str,
        /// Legend entry in the plot.
        short: &'static str,
        setting: &'static str,
        /// Seconds per ray, when one number is given.
        seconds: Option<f64>,
        /// The error as printed there.
        error_text: &'static str,
        /// The error to plot (an upper bound when the text says `≤`).
        error: Option<f64>,
    }

    /// One benchmark scene with its reference.
    struct Case {
        key: &'static str,
        title: String,
        scene: Scene,
        reference: Reference,
        others: Vec<Other>,
        /// Errors of argmin and gradient descent count only rays the reference says exist.
        decides_existence: bool,
        /// The README's "fastest other tool" cells at max error ≤ 1e-6 and ≤ 1e-12, with
        /// their time per ray when there is one.
        readme: [(&'static str, Option<f64>); 2],
    }

    impl Case {
        /// Every (source, receiver, path) in ray order (source-major, then receiver, then path).
        fn rays(&self) -> Vec<(usize, usize, usize)> {
            let s = &self.scene;
            let mut v = Vec::with_capacity(s.num_rays());
            for a in 0..s.sources().len() {
                for b in 0..s.receivers().len() {
                    for p in 0..s.paths().len() {
                        v.push((a, b, p));
                    }
                }
            }
            v
        }
        /// The rays argmin and gradient descent run on: those the reference says exist when
        /// existence is part of the problem (they cannot decide it), else every ray. Indices
        /// into [`Case::rays`].
        fn oracle_rays(&self) -> Vec<usize> {
            (0..self.reference.status.len())
                .filter(|&i| !self.decides_existence || self.reference.status[i] == "converged")
                .collect()
        }
        fn converged_rays(&self) -> usize {
            self.reference
                .status
                .iter()
                .filter(|s| *s == "converged")
                .count()
        }
        fn interactions(&self) -> String {
            let mut ks: Vec<usize> = self.scene.paths().iter().map(|p| p.steps.len()).collect();
            ks.sort_unstable();
            ks.dedup();
            let ks: Vec<String> = ks.iter().map(|k| k.to_string()).collect();
            ks.join(", ")
        }
    }

    /// One measured setting of one method.
    struct Row {
        method: &'static str,
        setting: String,
        /// Short label for the plot.
        label: String,
        /// CPU time per ray (see [`Timing`]).
        seconds: f64,
        /// Wall-clock time per ray.
        wall: f64,
        iterations: f64,
        max_error: f64,
        /// Rays the reference says exist that got no finite time.
        failures: usize,
        /// Rays the reference says exist that are off by more than 1e-6 (or have no time).
        off: usize,
        agreement: String,
    }

    /// Max relative time error over the rays the reference says converge, and how many of
    /// them have no finite time.
    fn max_error(reference: &Reference, times: &[f64]) -> (f64, usize) {
        let (mut worst, mut failures) = (0.0f64, 0);
        for (t_ref, t) in existing(reference, times) {
            if t.is_finite() {
                worst = worst.max((t - t_ref).abs() / t_ref);
            } else {
                failures += 1;
            }
        }
        (worst, failures)
    }

    /// `(reference time, time)` of the rays the reference says exist.
    fn existing<'a>(
        reference: &'a Reference,
        times: &'a [f64],
    ) -> impl Iterator<Item = (f64, f64)> + 'a {
        reference
            .status
            .iter()
            .zip(&reference.time)
            .zip(times)
            .filter(|((s, _), _)| *s == "converged")
            .map(|((_, &r), &t)| (r, t))
    }

    /// How many of the rays the reference says exist are off by more than 1e-6 (or have no
    /// time).
    fn off_by_1e6(reference: &Reference, times: &[f64]) -> usize {
        existing(reference, times)
            .filter(|&(r, t)| {
                let e = (t - r).abs() / r;
                e.is_nan() || e > 1e-6
            })
            .count()
    }

    fn load(key: &str) -> (Scene, Reference) {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench");
        let text = std::fs::read_to_string(format!("{dir}/{key}.json")).expect("scene file");
        let scene = Scene::from_json(&text).expect("valid scene");
        let text = std::fs::read_to_string(format!("{dir}/{key}.ref.json")).expect("ref file");
        let v: serde_json::Value = serde_json::from_str(&text).expect("reference JSON");
        let status = v["status"]
            .as_array()
            .expect("status")
            .iter()
            .map(|s| s.as_str().expect("status string").to_string())
            .collect();
        let time = v["time"]
            .as_array()
            .expect("time")
            .iter()
            .map(|t| t.as_f64().unwrap_or(f64::NAN))
            .collect();
        let method = v["method"].as_str().unwrap_or("").to_string();
        (
            scene,
            Reference {
                status,
                time,
                method,
            },
        )
    }

    /// The exact travel time of a path refracting through horizontal two-point interfaces
    /// (a flat layer stack), from its ray parameter: `p` solves
    /// `X(p) = Σ hⱼ p / √(wⱼ² − p²) = |x_R − x_S|` (safeguarded Newton on a bracket, to
    /// round-off), and `T = p X + Σ hⱼ √(wⱼ² − p²)`, which is stationary in `p`, so an error
    /// `δp` changes `T` only by `O(δp²)`. `None` if some interface is not horizontal.
    pub(super) fn flat_layer_time(
        scene: &Scene,
        path: usize,
        source: Point,
        receiver: Point,
    ) -> Option<f64> {
        let spec = &scene.paths()[path];
        let media = spec.media.as_ref()?;
        let w: Vec<f64> = media.iter().map(|&m| scene.media()[m].slowness).collect();
        let mut ys = vec![source.y];
        for step in &spec.steps {
            let v = scene.interfaces()[step.interface].polyline.vertices();
            if v.iter().any(|p| p.y != v[0].y) {
                return None;
            }
            ys.push(v[0].y);
        }
        ys.push(receiver.y);
        let h: Vec<f64> = ys.windows(2).map(|y| (y[1] - y[0]).abs()).collect();
        let x = (receiver.x - source.x).abs();
        let wmin = w.iter().copied().fold(f64::INFINITY, f64::min);
        let offset = |p: f64| -> (f64, f64) {
            let (mut f, mut df) = (0.0, 0.0);
            for (hj, wj) in h.iter().zip(&w) {
                let c = wj * wj - p * p;
                f += hj * p / c.sqrt();
                df += hj * wj * wj / (c * c.sqrt());
            }
            (f, df)
        };
        let p = if x == 0.0 {
            0.0
        } else {
            let (mut lo, mut hi) = (0.0, wmin);
            let mut p = 0.5 * wmin;
            for _ in 0..200 {
                let (f, df) = offset(p);
                let r = f - x;
                if r > 0.0 {
                    hi = p;
                } else {
                    lo = p;
                }
                let mut next = p - r / df;
                if !(next > lo && next < hi) {
                    next = 0.5 * (lo + hi);
                }
                if next == p || hi - lo <= 2.0 * f64::EPSILON * hi {
                    break;
                }
                p = next;
            }
            p
        };
        let tau: f64 = h
            .iter()
            .zip(&w)
            .map(|(hj, wj)| hj * (wj * wj - p * p).sqrt())
            .sum();
        Some(p * x + tau)
    }

    /// `layer_stack(8, 500)` with its reference computed by [`flat_layer_time`].
    fn stack8() -> (Scene, Reference) {
        let scene = Scene::from_spec(&demo::layer_stack(8, 500)).expect("valid scene");
        let src = scene.sources()[0];
        let time: Vec<f64> = scene
            .receivers()
            .iter()
            .map(|&r| flat_layer_time(&scene, 0, src, r).expect("flat layers"))
            .collect();
        let status = vec!["converged".to_string(); time.len()];
        (
            scene,
            Reference {
                status,
                time,
                method: "flat layers: ray parameter p from X(p) = offset by safeguarded Newton \
                         in f64, T = pX + Σ h √(w² − p²) (stationary in p); computed by the report"
                    .to_string(),
            },
        )
    }

    /// Our default initial guess for every ray (the solver stopped after 0 iterations), and
    /// our converged parameters (empty where the ray has no time).
    fn starts(case: &Case) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let mut scene = case.scene.clone();
        let run = |max_iterations: usize, scene: &mut Scene| {
            scene
                .set_solver(SolverOptions {
                    tolerance: 1e-300,
                    max_iterations,
                    ..SolverOptions::default()
                })
                .expect("valid solver options");
            let tracer = Tracer::new(&*scene)
                .expect("tracer")
                .with_initial_guess(InitialGuess::Paraxial);
            let mut ws = Workspace::new();
            case.rays()
                .iter()
                .map(|&(s, r, p)| {
                    let sum = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                    if max_iterations == 0 || sum.status.has_time() {
                        ws.parameters().to_vec()
                    } else {
                        Vec::new()
                    }
                })
                .collect::<Vec<_>>()
        };
        let guess = run(0, &mut scene);
        let solved = run(100, &mut scene);
        (guess, solved)
    }

    fn problem<'a>(scene: &'a Scene, (s, r, p): (usize, usize, usize)) -> PathProblem<'a> {
        PathProblem::new(scene, p, scene.sources()[s], scene.receivers()[r])
            .expect("benchmark paths give their media")
    }

    /// A timing of `n` rays as a timing per ray.
    fn per(t: Timing, n: usize) -> Timing {
        Timing {
            cpu: t.cpu / n as f64,
            wall: t.wall / n as f64,
        }
    }

    /// eigenray's solver with the given options and start, one reused workspace, one thread.
    fn ours(case: &Case, options: SolverOptions, guess: InitialGuess) -> (Timing, Vec<RayRecord>) {
        let mut scene = case.scene.clone();
        scene.set_solver(options).expect("valid solver options");
        let tracer = Tracer::new(&scene)
            .expect("tracer")
            .with_initial_guess(guess);
        let rays = case.rays();
        let mut ws = Workspace::new();
        let mut out = vec![RayRecord::default(); rays.len()];
        let t = time_per_call(9, MIN_RUN, || {
            for (o, &(s, r, p)) in out.iter_mut().zip(&rays) {
                *o = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                if !o.status.has_time() {
                    // The last iterate's time: a fixed number of iterations may stop short.
                    o.time = ws.iterate_time();
                }
            }
            black_box(&out);
        });
        (per(t, rays.len()), out)
    }

    /// Times `solve` over the rays `subset` (indices into [`Case::rays`]): returns seconds per
    /// ray, and per ray of the case the time (NaN outside `subset`), iterations and the
    /// solver's own convergence flag.
    fn per_ray<F>(
        case: &Case,
        subset: &[usize],
        mut solve: F,
    ) -> (Timing, Vec<f64>, Vec<u64>, Vec<bool>)
    where
        F: FnMut(usize, (usize, usize, usize)) -> (f64, u64, bool),
    {
        let rays = case.rays();
        let n = rays.len();
        let mut times = vec![f64::NAN; n];
        let mut iters = vec![0; n];
        let mut conv = vec![false; n];
        let t = time_per_call(3, MIN_RUN, || {
            for &i in subset {
                let (t, it, c) = solve(i, rays[i]);
                times[i] = t;
                iters[i] = it;
                conv[i] = c;
            }
            black_box(&times);
        });
        (per(t, subset.len()), times, iters, conv)
    }

    /// Our rows: tolerances and fixed iteration counts.
    fn our_rows(case: &Case, rows: &mut Vec<Row>) {
        let n = case.reference.status.len();
        let mut push = |method, setting: String, label: String, opts, guess| {
            let (secs, out) = ours(case, opts, guess);
            let times: Vec<f64> = out.iter().map(|s| s.time).collect();
            let (err, failures) = max_error(&case.reference, &times);
            let off = off_by_1e6(&case.reference, &times);
            let agree = out
                .iter()
                .zip(&case.reference.status)
                .filter(|(s, r)| s.status.as_str() == r.as_str())
                .count();
            let iterations = out.iter().map(|s| s.iterations as f64).sum::<f64>() / n as f64;
            eprintln!(
                "  {method} {setting}: {} per ray, error {err:.2e}, {agree}/{n} statuses agree",
                fmt_seconds(secs.cpu)
            );
            rows.push(Row {
                method,
                setting,
                label,
                seconds: secs.cpu,
                wall: secs.wall,
                iterations,
                max_error: err,
                failures,
                off,
                agreement: format!("{agree}/{n}"),
            });
        };
        for e in [2, 4, 6, 8, 10, 12, 14] {
            let tol = 10f64.powi(-e);
            push(
                "eigenray Newton",
                format!("tolerance 1e-{e}"),
                format!("1e-{e}"),
                SolverOptions {
                    tolerance: tol,
                    max_iterations: 100,
                    ..SolverOptions::default()
                },
                InitialGuess::Paraxial,
            );
            push(
                "eigenray, default start",
                format!("tolerance 1e-{e}"),
                format!("1e-{e}"),
                SolverOptions {
                    tolerance: tol,
                    max_iterations: 100,
                    ..SolverOptions::default()
                },
                InitialGuess::RayParameter,
            );
        }
        for it in 0..=6 {
            push(
                "eigenray Newton, fixed iterations",
                if it == 0 {
                    "0 iterations (the initial guess)".to_string()
                } else {
                    format!("{it} iteration{}", if it == 1 { "" } else { "s" })
                },
                it.to_string(),
                SolverOptions {
                    tolerance: 1e-300,
                    max_iterations: it,
                    ..SolverOptions::default()
                },
                InitialGuess::Paraxial,
            );
        }
    }

    /// An argmin solver: `(problem, start, max_iters, tol)`.
    type ArgminSolve = fn(
        &PathProblem,
        &[f64],
        u64,
        f64,
    )
        -> Result<eigenray::argmin_bridge::ArgminOutcome, argmin::core::Error>;

    fn argmin_rows(case: &Case, guess: &[Vec<f64>], rows: &mut Vec<Row>) {
        let solvers: [(&'static str, ArgminSolve, &[u64]); 3] = [
            (
                "argmin Gauss-Newton",
                |p, s, i, t| solve_gauss_newton(p, s, i, t),
                &[1, 2, 3, 4, 6],
            ),
            (
                "argmin BFGS",
                |p, s, i, t| solve_bfgs(p, s, i, t),
                &[2, 5, 10, 20, 40],
            ),
            (
                "argmin L-BFGS",
                |p, s, i, t| solve_lbfgs(p, s, i, t),
                &[2, 5, 10, 20, 40],
            ),
        ];
        let n_conv = case.converged_rays();
        let subset = case.oracle_rays();
        for (name, solve, limits) in solvers {
            let settings = limits
                .iter()
                .map(|&i| {
                    (
                        i,
                        1e-300,
                        format!("{i} iteration{}", if i == 1 { "" } else { "s" }),
                        i.to_string(),
                    )
                })
                .chain([6, 10, 14].iter().map(|&e| {
                    (
                        200,
                        10f64.powi(-e),
                        format!("tolerance 1e-{e}, ≤ 200 iterations"),
                        String::new(),
                    )
                }));
            for (max_iters, tol, setting, label) in settings {
                let scene = &case.scene;
                let (secs, times, iters, conv) = per_ray(case, &subset, |i, ray| {
                    let problem = problem(scene, ray);
                    match solve(&problem, &guess[i], max_iters, tol) {
                        Ok(o) => (o.time, o.iterations, o.converged),
                        Err(_) => (f64::NAN, 0, false),
                    }
                });
                let (err, failures) = max_error(&case.reference, &times);
                let off = off_by_1e6(&case.reference, &times);
                let claimed = conv
                    .iter()
                    .zip(&case.reference.status)
                    .filter(|(c, r)| **c && *r == "converged")
                    .count();
                let iterations = iters.iter().map(|&i| i as f64).sum::<f64>() / iters.len() as f64;
                eprintln!(
                    "  {name} {setting}: {} per ray, error {err:.2e}",
                    fmt_seconds(secs.cpu)
                );
                rows.push(Row {
                    method: name,
                    setting,
                    label,
                    seconds: secs.cpu,
                    wall: secs.wall,
                    iterations,
                    max_error: err,
                    failures,
                    off,
                    agreement: if tol > 1e-100 {
                        format!("— (claims convergence on {claimed}/{n_conv})")
                    } else {
                        "—".to_string()
                    },
                });
            }
        }
    }

    /// Gershgorin bound on the largest eigenvalue of the Hessian at `s`.
    fn lambda_max(problem: &PathProblem, s: &[f64]) -> f64 {
        let h = problem.hessian(s);
        let k = h.diag.len();
        (0..k)
            .map(|i| {
                h.diag[i].abs()
                    + if i > 0 { h.off[i - 1].abs() } else { 0.0 }
                    + if i + 1 < k { h.off[i].abs() } else { 0.0 }
            })
            .fold(0.0, f64::max)
    }

    /// The learning rate of gradient descent for a scene: `1 / L`, with `L` the largest
    /// Gershgorin bound of the Hessian over the rays it runs on, at our start and at our
    /// solution.
    fn learning_rate(case: &Case, guess: &[Vec<f64>], solved: &[Vec<f64>]) -> f64 {
        let mut l: f64 = 0.0;
        let rays = case.rays();
        for i in case.oracle_rays() {
            let problem = problem(&case.scene, rays[i]);
            if problem.is_empty() {
                continue;
            }
            l = l.max(lambda_max(&problem, &guess[i]));
            if !solved[i].is_empty() {
                l = l.max(lambda_max(&problem, &solved[i]));
            }
        }
        1.0 / l
    }

    fn gd_rows(case: &Case, guess: &[Vec<f64>], eta: f64, rows: &mut Vec<Row>) {
        let subset = case.oracle_rays();
        for iterations in [10usize, 40, 75, 200, 1000, 1600] {
            let scene = &case.scene;
            let (secs, times, _, _) = per_ray(case, &subset, |i, ray| {
                let problem = problem(scene, ray);
                let mut s = guess[i].clone();
                for _ in 0..iterations {
                    let g = problem.gradient(&s);
                    for (si, gi) in s.iter_mut().zip(&g) {
                        *si -= eta * gi;
                    }
                }
                (problem.time(&s), iterations as u64, false)
            });
            let (err, failures) = max_error(&case.reference, &times);
            let off = off_by_1e6(&case.reference, &times);
            eprintln!(
                "  gradient descent {iterations}: {} per ray, error {err:.2e}",
                fmt_seconds(secs.cpu)
            );
            rows.push(Row {
                method: "gradient descent",
                setting: format!("{iterations} iterations, η = {eta:.3e}"),
                label: iterations.to_string(),
                seconds: secs.cpu,
                wall: secs.wall,
                iterations: iterations as f64,
                max_error: err,
                failures,
                off,
                agreement: "—".to_string(),
            });
        }
    }

    fn fmt_error(e: f64, failures: usize) -> String {
        let s = if e == 0.0 {
            "0".to_string()
        } else {
            format!("{e:.1e}")
        };
        if failures > 0 {
            format!("{s} ({failures} rays without a time)")
        } else {
            s
        }
    }

    const METHODS: [&str; 7] = [
        "eigenray Newton",
        "eigenray Newton, fixed iterations",
        "argmin Gauss-Newton",
        "argmin BFGS",
        "argmin L-BFGS",
        "gradient descent",
        "eigenray, default start",
    ];

    /// The fastest row of `method` with max error ≤ `bound` (and no failures).
    fn fastest<'a>(rows: &'a [Row], method: &str, bound: f64) -> Option<&'a Row> {
        rows.iter()
            .filter(|r| r.method == method && r.failures == 0 && r.max_error <= bound)
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
    }

    fn plot(case: &Case, rows: &[Row], eta: f64) -> String {
        let mut p = Plot::new(
            format!("Max relative time error against time per ray: {}", case.key),
            "time per ray (µs, one thread)",
            "max relative travel-time error",
            Scale::Log,
            Scale::Log,
        );
        p.subtitle = format!(
            "{}; labels: tolerance, iterations; errors of 0 drawn at {ERROR_FLOOR:.0e}; GD η = {eta:.2e}",
            case.title
        );
        let mut clamped = false;
        for (i, method) in METHODS.iter().enumerate() {
            let mut pts = Vec::new();
            let mut labels = Vec::new();
            let mut floor_labelled = false;
            for r in rows
                .iter()
                .filter(|r| r.method == *method && !r.label.is_empty() && r.failures == 0)
            {
                let e = r.max_error.clamp(ERROR_FLOOR, ERROR_CEILING);
                clamped |= r.max_error > ERROR_CEILING;
                pts.push((r.seconds * 1e6, e));
                // One label among the points at round-off, where they pile up.
                let at_floor = e <= 1e-15;
                labels.push(if at_floor && floor_labelled {
                    String::new()
                } else {
                    r.label.clone()
                });
                floor_labelled |= at_floor;
            }
            let mut s = Series::new(*method, pts, i);
            s.labels = labels;
            if *method == "eigenray Newton, fixed iterations" {
                s.dashed = true;
            }
            p.series.push(s);
        }
        for (j, o) in case.others.iter().enumerate() {
            if let (Some(t), Some(e)) = (o.seconds, o.error) {
                let mut s = Series::new(o.short, vec![(t * 1e6, e)], j);
                s.line = false;
                s.marker = Marker::Star;
                s.color = ["#999999", "#D4B000", "#7A3E9D", "#5C5C5C"][j % 4].to_string();
                p.series.push(s);
            }
        }
        p.hlines.push((f64::EPSILON, "f64 ε = 2.2e-16".to_string()));
        if clamped {
            p.hlines.push((
                ERROR_CEILING,
                format!("errors above {ERROR_CEILING} (diverged) drawn here"),
            ));
            p.y_range = Some((1e-17, ERROR_CEILING));
        }
        p.to_svg()
    }

    fn cases() -> Vec<Case> {
        let mut v = Vec::new();
        let (scene, reference) = load("seed500");
        v.push(Case {
            key: "seed500",
            title: "classic air-over-water refraction, 500 receivers".to_string(),
            scene,
            reference,
            others: vec![
                Other {
                    what: "numpy+autograd gradient descent, all receivers as one vector",
                    short: "numpy+autograd GD, 40 it. (≤ 1e-6)",
                    setting: "40 iterations",
                    seconds: Some(13e-6),
                    error_text: "≤ 1e-6",
                    error: Some(1e-6),
                },
                Other {
                    what: "numpy+autograd gradient descent, all receivers as one vector",
                    short: "numpy+autograd GD, 75 it. (≤ 1e-12)",
                    setting: "75 iterations",
                    seconds: Some(24e-6),
                    error_text: "≤ 1e-12",
                    error: Some(1e-12),
                },
                Other {
                    what: "scipy fmin_bfgs per ray",
                    short: "scipy fmin_bfgs",
                    setting: "defaults",
                    seconds: None,
                    error_text: "0.5–0.9 ms/ray (error not given)",
                    error: None,
                },
                Other {
                    what: "ttcrpy grid eikonal solver",
                    short: "ttcrpy eikonal (best error)",
                    setting: "finest grid",
                    seconds: Some(1.9e-3),
                    error_text: "never below 1.8e-4 (33 µs–1.9 ms/ray)",
                    error: Some(1.8e-4),
                },
            ],
            decides_existence: false,
            readme: [("13 µs/ray — numpy+autograd gradient descent, all receivers as one vector, 40 iterations", Some(13e-6)), ("24 µs/ray — the same, 75 iterations", Some(24e-6))],
        });
        let (scene, reference) = load("layers10");
        v.push(Case {
            key: "layers10",
            title: "10 flat layers, one path refracting through all 10, 1,000 receivers"
                .to_string(),
            scene,
            reference,
            others: vec![
                Other {
                    what: "gradient descent generalised to 10 unknowns",
                    short: "GD, 1,600 it. (≤ 1e-6)",
                    setting: "1,600 iterations",
                    seconds: Some(1.8e-3),
                    error_text: "≤ 1e-6",
                    error: Some(1e-6),
                },
                Other {
                    what: "scipy fmin_bfgs",
                    short: "scipy fmin_bfgs, gtol 1e-8 (≤ 1e-12)",
                    setting: "gtol 1e-8",
                    seconds: Some(7.5e-3),
                    error_text: "≤ 1e-12",
                    error: Some(1e-12),
                },
            ],
            decides_existence: false,
            readme: [
                (
                    "1.8 ms/ray — gradient descent generalised to 10 unknowns, 1,600 iterations",
                    Some(1.8e-3),
                ),
                ("7.5 ms/ray — scipy `fmin_bfgs`, gtol 1e-8", Some(7.5e-3)),
            ],
        });
        let (scene, reference) = load("room2d");
        v.push(Case {
            key: "room2d",
            title: "hexagonal room, direct + all reflection sequences up to order 2, 100 receivers"
                .to_string(),
            scene,
            reference,
            others: vec![
                Other {
                    what: "pyroomacoustics image sources (float32)",
                    short: "pyroomacoustics (float32)",
                    setting: "decides existence",
                    seconds: Some(1.04e-6),
                    error_text: "1.9e-7",
                    error: Some(1.9e-7),
                },
                Other {
                    what: "DiffeRT exhaustive path tracer (float32)",
                    short: "DiffeRT (float32)",
                    setting: "decides existence",
                    seconds: Some(2.7e-6),
                    error_text: "4.1e-7",
                    error: Some(4.1e-7),
                },
                Other {
                    what: "fpt-jax Fermat solver (BFGS)",
                    short: "fpt-jax Fermat solver (BFGS)",
                    setting: "adaptive stopping",
                    seconds: Some(14e-6),
                    error_text: "3e-16",
                    error: Some(3e-16),
                },
                Other {
                    what: "bare image method (infinite mirrors, no validity)",
                    short: "bare image method",
                    setting: "—",
                    seconds: Some(0.29e-6),
                    error_text: "exact times, does not decide existence",
                    error: None,
                },
            ],
            decides_existence: true,
            readme: [("1.04 µs/ray at 1.9e-7 — pyroomacoustics image sources (float32; decides which paths exist); 2.7 µs/ray at 4.1e-7 — DiffeRT (float32)", Some(1.04e-6)), ("none that also decides which paths exist; the bare image method (infinite mirrors, no validity) takes 0.29 µs/ray", None)],
        });
        let (scene, reference) = stack8();
        v.push(Case {
            key: "stack8",
            title: "8 flat layers (demo::layer_stack(8, 500)), one path refracting through all 8"
                .to_string(),
            scene,
            reference,
            others: Vec::new(),
            decides_existence: false,
            readme: [
                ("— (not in the README)", None),
                ("— (not in the README)", None),
            ],
        });
        v
    }

    pub(super) fn run() -> io::Result<()> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        std::fs::create_dir_all("docs")?;
        let load_avg = load_average();
        let mut wall_ratio = (f64::INFINITY, 0.0f64);
        // The f64 ray-parameter reference, checked against the 40-digit one.
        let (l10, l10_ref) = load("layers10");
        let mut worst: f64 = 0.0;
        for (i, &r) in l10.receivers().iter().enumerate() {
            let t = flat_layer_time(&l10, 0, l10.sources()[0], r).expect("flat");
            worst = worst.max((t - l10_ref.time[i]).abs() / l10_ref.time[i]);
        }
        eprintln!("f64 ray-parameter reference vs layers10.ref.json: {worst:.2e}");

        let mut summary = String::new();
        let _ = writeln!(
            summary,
            "## Summary: fastest setting of each method reaching a max error\n"
        );
        let _ = writeln!(
            summary,
            "| scene | method | fastest at ≤ 1e-6 | fastest at ≤ 1e-12 |"
        );
        let _ = writeln!(summary, "| --- | --- | --- | --- |");
        let mut body = String::new();
        let mut ratios: Vec<String> = Vec::new();

        for case in cases() {
            eprintln!("{}: {}", case.key, case.title);
            let (guess, solved) = starts(&case);
            let eta = learning_rate(&case, &guess, &solved);
            let mut rows = Vec::new();
            our_rows(&case, &mut rows);
            argmin_rows(&case, &guess, &mut rows);
            gd_rows(&case, &guess, eta, &mut rows);
            for r in &rows {
                let q = r.wall / r.seconds;
                wall_ratio = (wall_ratio.0.min(q), wall_ratio.1.max(q));
            }
            std::fs::write(
                format!("docs/error_vs_time_{}.svg", case.key),
                plot(&case, &rows, eta),
            )?;

            let n = case.scene.num_rays();
            let _ = writeln!(body, "## {} — {}\n", case.key, case.title);
            let _ = writeln!(
                body,
                "{n} rays ({} exist), {} interaction(s) per path. Reference: {}.{}\n",
                case.converged_rays(),
                case.interactions(),
                case.reference.method,
                if case.key == "stack8" {
                    format!(
                        " The same f64 computation reproduces the 40-digit reference of \
                         `layers10` to a max relative difference of {worst:.1e}"
                    )
                } else {
                    String::new()
                }
            );
            if case.decides_existence {
                let _ = writeln!(
                    body,
                    "Status agreement: eigenray's status equals the reference's (`converged` or \
                     `no_path`) — a ray that does not exist counts as correct only if eigenray \
                     also says `no_path`. eigenray's time per ray is over all {n} rays. argmin and \
                     gradient descent cannot decide existence: they run on the {} rays the \
                     reference says exist (an oracle they would not have) and are timed and \
                     judged on those only; on the other rays they would run to their iteration \
                     limit (on all {n} rays, BFGS at tolerance 1e-10 took some 430 µs per ray in a \
                     trial run).\n",
                    case.converged_rays()
                );
            }
            let _ = writeln!(
                body,
                "![error against time](error_vs_time_{}.svg)\n",
                case.key
            );
            let _ = writeln!(
                body,
                "| method | setting | time per ray | wall clock | iterations per ray | max rel. error | rays off by > 1e-6 | status agreement |"
            );
            let _ = writeln!(
                body,
                "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"
            );
            for r in &rows {
                let _ = writeln!(
                    body,
                    "| {} | {} | {} | {} | {:.2} | {} | {} | {} |",
                    r.method,
                    r.setting,
                    fmt_seconds(r.seconds),
                    fmt_seconds(r.wall),
                    r.iterations,
                    fmt_error(r.max_error, r.failures),
                    r.off,
                    r.agreement
                );
            }
            for o in &case.others {
                let _ = writeln!(
                    body,
                    "| *other tool:* {} | {} | {} | — | — | {} | — | — |",
                    o.what,
                    o.setting,
                    o.seconds
                        .map_or("see error column".to_string(), fmt_seconds),
                    o.error_text
                );
            }
            let _ = writeln!(body);

            for method in METHODS {
                let cell = |bound| {
                    fastest(&rows, method, bound).map_or("not reached".to_string(), |r| {
                        format!("{} ({})", fmt_seconds(r.seconds), r.setting)
                    })
                };
                let _ = writeln!(
                    summary,
                    "| {} | {method} | {} | {} |",
                    case.key,
                    cell(1e-6),
                    cell(1e-12)
                );
            }
            let _ = writeln!(
                summary,
                "| {} | *fastest other tool (benchmarks README)* | {} | {} |",
                case.key, case.readme[0].0, case.readme[1].0
            );
            // Ratios at max error ≤ 1e-12.
            let ours = fastest(&rows, METHODS[0], 1e-12);
            let argmin = METHODS[2..5]
                .iter()
                .filter_map(|m| fastest(&rows, m, 1e-12))
                .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
            if let Some(ours) = ours {
                let mut line = format!(
                    "- **{}**: eigenray's Newton solver reaches max error ≤ 1e-12 in {} per ray",
                    case.key,
                    fmt_seconds(ours.seconds)
                );
                if let Some(a) = argmin {
                    let _ = write!(
                        line,
                        "; {:.0}× less than the fastest argmin solver ({}, {}, {})",
                        a.seconds / ours.seconds,
                        a.method,
                        a.setting,
                        fmt_seconds(a.seconds)
                    );
                }
                if let Some(gd) = fastest(&rows, METHODS[5], 1e-12) {
                    let _ = write!(
                        line,
                        "; {:.0}× less than gradient descent ({})",
                        gd.seconds / ours.seconds,
                        gd.setting
                    );
                }
                if let Some(t) = case.readme[1].1 {
                    let _ = write!(
                        line,
                        "; {:.0}× less than the fastest other tool of the README",
                        t / ours.seconds
                    );
                }
                line.push('.');
                ratios.push(line);
            }
        }
        summary.push('\n');
        for line in &ratios {
            let _ = writeln!(summary, "{line}");
        }
        let mut md = String::new();
        let _ = writeln!(md, "# Error against run time\n");
        let _ = writeln!(
            md,
            "Generated by `cargo run --release --features argmin --example report` on a machine \
             with {cores} cores (`std::thread::available_parallelism`), {}. Every figure is \
             single-threaded. **Time per ray** is the CPU time of the measuring thread \
             (`/proc/thread-self/schedstat`): the median of at least 3 runs over all rays of \
             the scene (9 for eigenray's solver), each run at least {} ms, divided by the \
             number of rays. The machine was shared with other engineers' builds and tests \
             (load average {} on {cores} cores when the report started), so wall-clock time \
             also counted the time the thread waited for a core; it is given beside (median \
             over the same runs) and was {:.1}–{:.1}× the CPU time here. Expect ±10–20 % noise \
             all the same (caches shared with other processes). **Max error** is the largest \
             `|T − T_ref| / T_ref` over the rays the exact reference says exist.\n",
            cpu_model(),
            MIN_RUN * 1e3,
            load_avg,
            wall_ratio.0,
            wall_ratio.1
        );
        let _ = writeln!(
            md,
            "Methods, all but the last from the same start: eigenray's initial guess with the \
             paraxial refinement (`InitialGuess::Paraxial`; computed once beforehand and not \
             timed for argmin and gradient descent; it is the \"0 iterations\" row). eigenray's \
             default start refines paths of refractions further, to the flat-layer ray-parameter \
             solution, and starts reflections off flat mirrors at the image method's points: \
             through the flat layers of layers10 and stack8 and off the walls of room2d that is \
             the solution itself, and every solver would stop at once from it, so the solvers are \
             compared from the paraxial start and the default start has a line of its own.\n\n\
             - **eigenray Newton**: `Tracer::solve_indexed_from` with one reused `Workspace` (the \
             time includes the start and the classification), at tolerances 1e-2 … 1e-14 \
             (100 iterations at most), and with a fixed number of iterations (tolerance 1e-300, \
             `max_iterations` = n; the time of a ray that did not converge is its last iterate's, `Workspace::iterate_time` \
             all the same; the solver also stops when the full Newton step is below round-off). \
             On seed500 (one refraction at an interface of one segment) the rays go through the \
             flat-refraction kernel, from either start: two Halley steps on Snell's law squared \
             that always run (counted as iterations), then Newton steps on the residual only \
             where the tolerance asks for them, so every tolerance takes about the same time; \
             with fewer than 2 iterations allowed, or where the kernel has not converged within \
             the limit, the ray goes to the general solve (after the kernel's attempt, which is \
             timed too).\n\
             - **eigenray, default start**: the same at tolerances 1e-2 … 1e-14 with the default \
             `InitialGuess::RayParameter`: the whole default pipeline, start included. Through \
             the parallel flat layers of layers10 and stack8 (media given) it goes through the \
             stack kernel, which takes the general code's steps (the ray-parameter start, one \
             confirming evaluation) on data prepared once per path.\n\
             - **argmin** Gauss-Newton, BFGS and L-BFGS through `eigenray::argmin_bridge` \
             (`solve_gauss_newton`, `solve_bfgs`, `solve_lbfgs` on a `PathProblem` built per \
             ray), with an iteration limit and an unreachable tolerance, or with a tolerance and \
             at most 200 iterations; the iterations per ray are as argmin reports them. argmin \
             cannot decide whether a path exists (see `room2d`).\n\
             - **gradient descent**: `s ← s − η ∇T(s)` with `PathProblem::gradient`, a fixed \
             number of iterations and one learning rate per scene, `η = 1/L`, `L` the largest \
             Gershgorin bound of the Hessian over every ray at the start and at the solution \
             (the classic step for an `L`-smooth function). `PathProblem::gradient` allocates \
             its scratch space on every call, which is part of its cost here.\n\
             - **other tools**: the figures of `fixtures/bench/README.md` (one core, same \
             scenes), as reference lines.\n"
        );

        md.push_str(&summary);
        md.push('\n');
        md.push_str(&body);
        std::fs::write("docs/report.md", md)?;
        eprintln!("wrote docs/report.md and docs/error_vs_time_*.svg");
        Ok(())
    }
}
