//! The extreme cases of the stability suite: scenes, exact references and the checks.
//!
//! Shared by the `stability` tests and `examples/stability.rs`. Every case is one ray (source 0, receiver 0, path 0) of one scene, built here as JSON, with
//! the answer computed here without the library: Snell's law by bisection on one flat
//! interface, the ray-parameter solution for flat layer stacks (a 1-D root on `p`), the image
//! method for flat mirror segments, and, for bent and digitised curves, the full list of
//! stationary reflection paths (a specular point strictly inside a segment, by the image
//! method, or a kink of `T` at a vertex whose one-sided derivatives bracket zero).
//!
//! Tolerances. A converged time must match its reference to `1e-12` relative, or to the
//! bound the conditioning allows if that is larger: a point whose residual vector is `r`
//! sits `δ = H⁻¹ r` from the stationary point, where `T` differs by `½ rᵀ H⁻¹ r ≤ ½ ‖r‖² /
//! λmin(H)` (second order, as `T` is stationary). An interaction point must lie within
//! `‖r‖ / λmin(H)` of its reference (first order), with `‖r‖` taken from the ray's relative
//! residual plus the round-off of evaluating it (`16 ε` of the slownesses), plus `64 ε` of
//! the scene's size for the coordinates themselves.

use std::time::{Duration, Instant};

use eigenray::{Ray, Reason, Scene, Status, Tracer, Workspace, problem::PathProblem, write};
use serde_json::{Map, Value, json};

#[path = "../support/rng.rs"]
mod rng;
use rng::SplitMix64;

#[path = "../support/reference.rs"]
mod reference;
use reference::snell_reference as snell;
pub use reference::{
    P, add, bisect, cross, dist, dot, intersect, lerp, norm, path_time, reflect, rel_err, scale,
    sub, unit,
};

/// Whether `v` is not within `tol` (NaN is not within anything).
fn exceeds(v: f64, tol: f64) -> bool {
    !matches!(
        v.partial_cmp(&tol),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    )
}

/// Flat layers: the legs' vertical extents `h` and slownesses `w`. The ray parameter `p`
/// (horizontal slowness, `sin θⱼ = p / wⱼ`) with `Σ hⱼ tan θⱼ = x`, by bisection on
/// `[0, min w)`, and the horizontal extent of every leg, `h p / √(w² − p²)` (the root
/// written as `√((w − p)(w + p))`, which keeps its precision as `p → w`).
fn ray_parameter(legs: &[(f64, f64)], x: f64) -> (f64, Vec<f64>) {
    assert!(x >= 0.0);
    let wmin = legs.iter().map(|l| l.1).fold(f64::INFINITY, f64::min);
    let dx = |p: f64, (h, w): (f64, f64)| {
        let c = ((w - p) * (w + p)).sqrt();
        if c > 0.0 { h * p / c } else { f64::INFINITY }
    };
    let total = |p: f64| legs.iter().map(|&l| dx(p, l)).sum::<f64>() - x;
    let p = bisect(0.0, wmin, total);
    (p, legs.iter().map(|&l| dx(p, l)).collect())
}

/// The ray-parameter path through flat layers from `s` to `r`: legs `(height, speed)`, the
/// interaction heights `ys`. Returns the interaction points and the time in its intercept
/// form `T = p X + Σ hⱼ √(wⱼ² − p²)`, which is stationary in `p` (its derivative is
/// `X − Σ dxⱼ = 0`): the error of the bisected `p` enters only to second order, also where
/// the legs' extents are extremely sensitive to `p` (near-grazing legs). The time summed
/// along the reference points would not be: their last leg takes up the error of `Σ dxⱼ`.
fn layered_path(s: P, r: P, legs: &[(f64, f64)], ys: &[f64]) -> (Vec<P>, f64) {
    assert_eq!(legs.len(), ys.len() + 1);
    // The slownesses as the library derives them from the speeds.
    let hw: Vec<(f64, f64)> = legs.iter().map(|&(h, v)| (h, 1.0 / v)).collect();
    let offset = r[0] - s[0];
    let (p, dx) = ray_parameter(&hw, offset.abs());
    let mut pts = Vec::with_capacity(ys.len());
    let mut x = s[0];
    for (d, &y) in dx.iter().zip(ys) {
        x += d * offset.signum();
        pts.push([x, y]);
    }
    let tau: f64 = hw
        .iter()
        .map(|&(h, w)| h * ((w - p) * (w + p)).sqrt())
        .sum();
    let t = p * offset.abs() + tau;
    // A check on the reference: the time along its points agrees to second order in their
    // error (loosely where the legs graze, as explained above).
    let mut all = vec![s];
    all.extend_from_slice(&pts);
    all.push(r);
    let w: Vec<f64> = hw.iter().map(|l| l.1).collect();
    let along = path_time(&all, &w);
    assert!(
        rel_err(along, t) < 1e-8,
        "intercept time {t}, along the points {along}"
    );
    (pts, t)
}

/// One stationary path a case accepts: its status, time and interaction points.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// `converged` or `vertex`.
    pub status: Status,
    /// Reference travel time.
    pub time: f64,
    /// Reference interaction points.
    pub points: Vec<P>,
    /// Distance allowed between a reported interaction point and the reference; `None`: the
    /// conditioning bound of the module doc.
    pub point_tol: Option<f64>,
}

impl Candidate {
    fn converged(time: f64, points: Vec<P>) -> Candidate {
        Candidate {
            status: Status::Converged,
            time,
            points,
            point_tol: None,
        }
    }
}

/// What a case must give.
#[derive(Clone, Debug)]
pub enum Expect {
    /// Exactly this path.
    Path(Candidate),
    /// Any one of these stationary paths (a curve with several).
    OneOf(Vec<Candidate>),
    /// No path, for one of the given reasons.
    NoPath(Vec<Reason>),
}

/// Another scene whose time, times `factor`, this case's time must equal (a scaled or
/// translated copy).
pub struct Twin {
    /// The other scene (same source, receiver and path indices).
    pub json: Value,
    /// Time of this case = `factor` × time of the twin.
    pub factor: f64,
}

/// One extreme case.
pub struct Case {
    /// Short name (also the test's name).
    pub name: &'static str,
    /// What is extreme about it, and the reference used.
    pub what: String,
    /// The scene: one source, one receiver, one path.
    pub json: Value,
    /// The answer.
    pub expect: Expect,
    /// Iterations allowed: the bound on the solve's work (no case is held to a wall time;
    /// the table's column of milliseconds is for reading only).
    pub max_iterations: usize,
    /// An optional scaled or translated copy to compare with.
    pub twin: Option<Twin>,
}

/// Iterations allowed when a case does not say otherwise: Newton with a line search from the
/// documented initial guess converges quadratically; 30 is generous for every case here.
pub const ITERATIONS: usize = 30;
/// Relative time tolerance where the conditioning allows it.
pub const TIME_TOL: f64 = 1e-12;

/// Extreme eigenvalues of the symmetric tridiagonal matrix (`diag`, `off`) by Sturm-sequence
/// bisection: `(smallest, largest, smallest in magnitude)`.
pub fn eigen_extremes(diag: &[f64], off: &[f64]) -> (f64, f64, f64) {
    let n = diag.len();
    assert!(n > 0 && off.len() + 1 == n);
    // Number of eigenvalues below x (the negative pivots of LDLᵀ of H − x I).
    let below = |x: f64| {
        let mut count = 0;
        let mut d = 1.0;
        for i in 0..n {
            let b2 = if i > 0 { off[i - 1] * off[i - 1] } else { 0.0 };
            d = (diag[i] - x) - if i > 0 { b2 / d } else { 0.0 };
            if d == 0.0 {
                d = -f64::EPSILON * (diag[i].abs() + x.abs()).max(f64::MIN_POSITIVE);
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..n {
        let r = if i > 0 { off[i - 1].abs() } else { 0.0 } + off.get(i).map_or(0.0, |o| o.abs());
        lo = lo.min(diag[i] - r);
        hi = hi.max(diag[i] + r);
    }
    let pad = 1e-300 + (hi - lo).abs() * 1e-15;
    let (lo, hi) = (lo - pad, hi + pad);
    // The j-th smallest eigenvalue (0-based): the smallest x with below(x) > j.
    let nth = |j: usize| {
        let (mut a, mut b) = (lo, hi);
        for _ in 0..2200 {
            // Geometric midpoints where the bracket is positive: relative precision for
            // eigenvalues tiny against the largest.
            let mid = if a > 0.0 && b > 0.0 {
                a.sqrt() * b.sqrt()
            } else if a < 0.0 && b < 0.0 {
                -((-a).sqrt() * (-b).sqrt())
            } else {
                0.5 * (a + b)
            };
            if mid <= a || mid >= b {
                break;
            }
            if below(mid) > j {
                b = mid;
            } else {
                a = mid;
            }
            if (b - a) <= 1e-15 * a.abs().max(b.abs()) {
                break;
            }
        }
        0.5 * (a + b)
    };
    let neg = below(0.0);
    let small = if neg == 0 {
        nth(0).abs()
    } else if neg == n {
        nth(n - 1).abs()
    } else {
        nth(neg - 1).abs().min(nth(neg).abs())
    };
    (nth(0), nth(n - 1), small)
}

/// What one case gave, and every check that failed.
pub struct Outcome {
    /// The ray.
    pub ray: Ray,
    /// Relative time error against the matched reference (when there is one).
    pub time_err: Option<f64>,
    /// The relative time tolerance applied: `1e-12`, or the conditioning bound if larger.
    pub time_tol: Option<f64>,
    /// Largest distance of an interaction point from its reference (when there is one).
    pub point_err: Option<f64>,
    /// The 2-norm condition of the Hessian at the solution (converged rays).
    pub condition: Option<f64>,
    /// Wall time of scene validation, tracer set-up and the solve: printed in the table, never
    /// checked.
    pub elapsed: Duration,
    /// Every failed check, in words.
    pub failures: Vec<String>,
}

impl Outcome {
    /// One Markdown table row: case, status, iterations, residual, time error and tolerance,
    /// point error, condition, wall time, verdict.
    pub fn row(&self, name: &str) -> String {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1e}"));
        let verdict = if self.failures.is_empty() {
            "ok"
        } else {
            "**FAIL**"
        };
        format!(
            "| {name} | {} | {} | {:.1e} | {} | {} | {} | {} | {:.1} | {verdict} |",
            self.ray.status,
            self.ray.iterations,
            self.ray.residual,
            opt(self.time_err),
            opt(self.time_tol),
            opt(self.point_err),
            opt(self.condition),
            self.elapsed.as_secs_f64() * 1e3,
        )
    }
}

/// The table header matching [`Outcome::row`].
pub const TABLE_HEADER: &str = "| case | status | iterations | residual | rel. time error | time tol. | point error | cond(H) | ms | check |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |";

/// A scene from a JSON value.
pub fn scene(v: &Value) -> Scene {
    Scene::from_json(&v.to_string()).unwrap_or_else(|e| panic!("invalid stability scene: {e}"))
}

/// Every number of a JSON document is finite and nothing is `null`.
fn json_numbers_ok(v: &Value, at: &str, bad: &mut Vec<String>) {
    match v {
        Value::Null => bad.push(format!("{at} is null")),
        Value::Number(n) => {
            if !n.as_f64().is_some_and(f64::is_finite) {
                bad.push(format!("{at} = {n} is not finite"));
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                json_numbers_ok(x, &format!("{at}[{i}]"), bad);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                json_numbers_ok(x, &format!("{at}.{k}"), bad);
            }
        }
        Value::Bool(_) | Value::String(_) => {}
    }
}

/// Solves one ray of `v` (source 0, receiver 0, path 0); the ray, its parameters and the
/// scene.
fn solve(v: &Value) -> (Scene, Ray, Vec<f64>) {
    let sc = scene(v);
    let tracer = Tracer::new(&sc).expect("tracer");
    let mut ws = Workspace::new();
    let ray = tracer.trace(0, 0, 0, &mut ws);
    let params = ws.parameters().to_vec();
    (sc, ray, params)
}

/// Runs a case and checks everything it promises.
pub fn run(case: &Case) -> Outcome {
    let start = Instant::now();
    let (sc, ray, params) = solve(&case.json);
    let elapsed = start.elapsed();
    let mut fail = Vec::new();
    let k = sc.paths()[0].steps.len();

    // No NaN or infinity anywhere: the ray …
    if ray.status.has_time() && !ray.time.is_finite() {
        fail.push(format!("time {:?} is not finite", ray.time));
    }
    if ray
        .points
        .iter()
        .any(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        fail.push(format!("a point is not finite: {:?}", ray.points));
    }
    if !ray.residual.is_finite() {
        fail.push(format!("residual {} is not finite", ray.residual));
    }
    // … and its JSON.
    let mut buf = Vec::new();
    write(
        &sc,
        std::slice::from_ref(&ray),
        eigenray::Format::Json,
        &mut buf,
    )
    .expect("write to a Vec");
    match serde_json::from_slice::<Value>(&buf) {
        Ok(doc) => {
            let mut bad = Vec::new();
            json_numbers_ok(&doc, "", &mut bad);
            fail.extend(bad.into_iter().map(|b| format!("JSON output: {b}")));
            let jt = doc["rays"][0]["time"].as_f64();
            if jt != ray.status.has_time().then_some(ray.time) {
                fail.push(format!("JSON time {jt:?} != ray time {:?}", ray.time));
            }
            if doc["rays"][0]["status"].as_str() != Some(ray.status.as_str()) {
                fail.push("JSON status differs from the ray's".to_string());
            }
        }
        Err(e) => fail.push(format!("JSON output does not parse: {e}")),
    }
    if ray.iterations > case.max_iterations {
        fail.push(format!(
            "{} iterations, more than the {} allowed",
            ray.iterations, case.max_iterations
        ));
    }

    let s = sc.sources()[0];
    let r = sc.receivers()[0];
    let (sp, rp) = ([s.x, s.y], [r.x, r.y]);
    let slowness: Vec<f64> = ray.media.iter().map(|&m| sc.media()[m].slowness).collect();
    let pts: Vec<P> = ray.points.iter().map(|p| [p.x, p.y]).collect();
    let bbox = sc.bbox();
    // The scene's size, and the magnitude of its coordinates (their rounding).
    let size = (bbox.max.x - bbox.min.x)
        .hypot(bbox.max.y - bbox.min.y)
        .max(dist(sp, rp))
        .max(bbox.min.x.abs().max(bbox.max.x.abs()))
        .max(bbox.min.y.abs().max(bbox.max.y.abs()));

    // The Hessian at the solution: its condition, and the bounds it allows.
    let mut condition = None;
    let mut lambda_min = None;
    if ray.status == Status::Converged && k > 0 && slowness.len() == k + 1 {
        let problem = PathProblem::with_slowness(&sc, 0, slowness.clone(), s, r);
        let h = problem.hessian(&params);
        let (lo, hi, small) = eigen_extremes(&h.diag, &h.off);
        let big = lo.abs().max(hi.abs());
        condition = Some(big / small);
        lambda_min = Some(small);
    }
    // ‖r‖₂ from the relative residual and the round-off of evaluating it.
    let wmax = slowness.windows(2).map(|w| w[0] + w[1]).fold(0.0, f64::max);
    let r_norm = (k as f64).sqrt() * (ray.residual.max(0.0) + 16.0 * f64::EPSILON) * wmax;

    if ray.status.has_time() {
        if pts.len() != k + 2 {
            fail.push(format!("{} points for {k} steps", pts.len()));
        } else {
            if pts[0] != sp || pts[k + 1] != rp {
                fail.push(format!(
                    "end points {:?}, {:?} are not the source {sp:?} and receiver {rp:?}",
                    pts[0],
                    pts[k + 1]
                ));
            }
            if slowness.len() == k + 1 {
                let own = path_time(&pts, &slowness);
                let t = ray.time;
                if exceeds(rel_err(t, own), TIME_TOL) {
                    fail.push(format!(
                        "time {t} is not Σ slowness × leg length over its points, {own}"
                    ));
                }
            } else {
                fail.push(format!("{} leg media for {k} steps", slowness.len()));
            }
        }
    }

    // Against the reference.
    let mut time_err = None;
    let mut time_tol = None;
    let mut point_err = None;
    let candidates: &[Candidate] = match &case.expect {
        Expect::Path(c) => std::slice::from_ref(c),
        Expect::OneOf(cs) => cs,
        Expect::NoPath(reasons) => {
            if ray.status != Status::NoPath {
                fail.push(format!(
                    "status {}, expected no_path ({reasons:?})",
                    ray.status
                ));
            } else if !ray.reason.is_some_and(|r| reasons.contains(&r)) {
                fail.push(format!(
                    "no_path for the reason {:?}, expected one of {reasons:?}",
                    ray.reason
                ));
            }
            if !ray.time.is_nan() || !ray.points.is_empty() {
                fail.push("a no_path ray has a time or points".to_string());
            }
            &[]
        }
    };
    if !candidates.is_empty() {
        let time = ray.time;
        let point_bound = |c: &Candidate| {
            c.point_tol.unwrap_or_else(|| {
                lambda_min.map_or(f64::INFINITY, |l| r_norm / l) + 64.0 * f64::EPSILON * size
            })
        };
        let gap = |c: &Candidate| {
            if c.points.len() != k || pts.len() != k + 2 {
                return f64::INFINITY;
            }
            c.points
                .iter()
                .zip(&pts[1..=k])
                .map(|(a, b)| dist(*a, *b))
                .fold(0.0, f64::max)
        };
        let best = candidates
            .iter()
            .filter(|c| c.status == ray.status)
            .min_by(|a, b| gap(a).total_cmp(&gap(b)));
        match best {
            None => fail.push(format!(
                "status {} ({:?}), expected {}",
                ray.status,
                ray.reason,
                candidates
                    .iter()
                    .map(|c| c.status.as_str())
                    .collect::<Vec<_>>()
                    .join(" or ")
            )),
            Some(c) => {
                let g = gap(c);
                point_err = Some(g);
                let bound = point_bound(c);
                if exceeds(g, bound) {
                    fail.push(format!(
                        "interaction points {:?} are {g:.3e} from the reference {:?} (bound {bound:.3e})",
                        &pts.get(1..=k),
                        c.points
                    ));
                }
                let err = rel_err(time, c.time);
                // Second-order bound of the module doc.
                let tol = match lambda_min {
                    Some(l) if c.status == Status::Converged => {
                        TIME_TOL.max(0.5 * r_norm * r_norm / l / c.time.abs())
                    }
                    _ => TIME_TOL,
                };
                if exceeds(err, tol) {
                    fail.push(format!(
                        "time {time:e}, reference {:e}: relative error {err:.3e} > {tol:.1e}",
                        c.time
                    ));
                }
                time_err = Some(err);
                time_tol = Some(tol);
            }
        }
    }

    if let Some(twin) = &case.twin {
        let (_, tray, _) = solve(&twin.json);
        let time = |r: &Ray| r.status.has_time().then_some(r.time);
        match (time(&ray), time(&tray)) {
            (Some(a), Some(b)) if !b.is_finite() => {
                fail.push(format!("the twin's time {b} is not finite (here {a})"));
            }
            (Some(a), Some(b)) => {
                let err = rel_err(a, twin.factor * b);
                if exceeds(err, TIME_TOL) {
                    fail.push(format!(
                        "time {a:e} vs {:e} × the twin's {b:e}: relative error {err:.3e}",
                        twin.factor
                    ));
                }
            }
            _ => fail.push(format!(
                "no time to compare: {} here, {} in the twin",
                ray.status, tray.status
            )),
        }
    }

    Outcome {
        ray,
        time_err,
        time_tol,
        point_err,
        condition,
        elapsed,
        failures: fail,
    }
}

// ---------------------------------------------------------------------------------------
// Scene building.

/// A scene of one path: `media` name → speed, interfaces name → (points, closed), the path's
/// steps (`"reflect"`/`"refract"`, interface) and leg media.
fn one_path(
    media: &[(&str, f64)],
    interfaces: Vec<(String, Vec<P>, bool)>,
    s: P,
    r: P,
    steps: &[(&str, String)],
    legs: &[&str],
) -> Value {
    let media: Map<String, Value> = media
        .iter()
        .map(|(n, v)| (n.to_string(), json!({ "speed": v })))
        .collect();
    let interfaces: Map<String, Value> = interfaces
        .into_iter()
        .map(|(n, p, c)| (n, json!({ "points": p, "closed": c })))
        .collect();
    let steps: Vec<Value> = steps
        .iter()
        .map(|(kind, name)| json!({ *kind: name }))
        .collect();
    json!({
        "media": media, "interfaces": interfaces,
        "sources": [s], "receivers": [r],
        "paths": [{ "name": "case", "steps": steps, "media": legs }]
    })
}

/// One refraction through the flat interface `y = 0`, `x ∈ [−half, half]`: speed `v1` above,
/// `v2` below; reference by bisection.
fn flat_refraction(v1: f64, v2: f64, s: P, r: P, half: f64) -> (Value, Candidate) {
    assert!(s[1] > 0.0 && r[1] < 0.0);
    let v = one_path(
        &[("above", v1), ("below", v2)],
        vec![("surface".into(), vec![[-half, 0.0], [half, 0.0]], false)],
        s,
        r,
        &[("refract", "surface".into())],
        &["above", "below"],
    );
    let (x, t) = snell(1.0 / v1, s[0], s[1], 1.0 / v2, r[0], -r[1]);
    (v, Candidate::converged(t, vec![[x, 0.0]]))
}

/// One reflection off the flat mirror `y = 0`, `x ∈ [−half, half]`, speed `v`; reference by
/// the image method.
fn flat_reflection(v: f64, s: P, r: P, lo: f64, hi: f64) -> (Value, Candidate) {
    assert!(s[1] > 0.0 && r[1] > 0.0);
    let json = one_path(
        &[("m", v)],
        vec![("mirror".into(), vec![[lo, 0.0], [hi, 0.0]], false)],
        s,
        r,
        &[("reflect", "mirror".into())],
        &["m", "m"],
    );
    let image = [s[0], -s[1]];
    let (_, u) = intersect(image, r, [lo, 0.0], [hi, 0.0]);
    let x = lo + u * (hi - lo);
    (
        json,
        Candidate::converged(dist(image, r) / v, vec![[x, 0.0]]),
    )
}

/// Horizontal interfaces at heights `ys` (named `i0`, `i1`, …) over `x ∈ [−half, half]`, a
/// medium `L{j}` of speed `speeds[j]` per layer.
struct Stack {
    ys: Vec<f64>,
    speeds: Vec<f64>,
    half: f64,
}

impl Stack {
    /// Down through every interface from `s` to `r`: the scene and the ray-parameter reference.
    fn down(&self, s: P, r: P) -> (Value, Candidate) {
        let n = self.ys.len();
        let steps: Vec<(&str, String)> = (0..n).map(|j| ("refract", format!("i{j}"))).collect();
        let legs: Vec<usize> = (0..=n).collect();
        let mut heights = vec![s[1] - self.ys[0]];
        heights.extend(self.ys.windows(2).map(|w| w[0] - w[1]));
        heights.push(self.ys[n - 1] - r[1]);
        self.build(s, r, &steps, &legs, &heights, &self.ys)
    }

    /// Down through all but the last interface, reflected off the last, back up to `r`.
    fn down_up(&self, s: P, r: P) -> (Value, Candidate) {
        let n = self.ys.len();
        let mut steps: Vec<(&str, String)> =
            (0..n - 1).map(|j| ("refract", format!("i{j}"))).collect();
        steps.push(("reflect", format!("i{}", n - 1)));
        steps.extend((0..n - 1).rev().map(|j| ("refract", format!("i{j}"))));
        let mut legs: Vec<usize> = (0..n).collect();
        legs.extend((0..n).rev());
        let mut down = vec![s[1] - self.ys[0]];
        down.extend(self.ys.windows(2).map(|w| w[0] - w[1]));
        let mut heights = down.clone();
        heights.extend(down[1..].iter().rev());
        heights.push(r[1] - self.ys[0]);
        let mut ys = self.ys.clone();
        ys.extend(self.ys[..n - 1].iter().rev());
        self.build(s, r, &steps, &legs, &heights, &ys)
    }

    fn build(
        &self,
        s: P,
        r: P,
        steps: &[(&str, String)],
        legs: &[usize],
        heights: &[f64],
        ys: &[f64],
    ) -> (Value, Candidate) {
        assert!(heights.iter().all(|&h| h > 0.0), "{heights:?}");
        let names: Vec<String> = (0..self.speeds.len()).map(|j| format!("L{j}")).collect();
        let media: Vec<(&str, f64)> = names
            .iter()
            .zip(&self.speeds)
            .map(|(n, &v)| (n.as_str(), v))
            .collect();
        let interfaces = self
            .ys
            .iter()
            .enumerate()
            .map(|(j, &y)| {
                (
                    format!("i{j}"),
                    vec![[-self.half, y], [self.half, y]],
                    false,
                )
            })
            .collect();
        let leg_names: Vec<&str> = legs.iter().map(|&j| names[j].as_str()).collect();
        let json = one_path(&media, interfaces, s, r, steps, &leg_names);
        let lv: Vec<(f64, f64)> = heights
            .iter()
            .zip(legs)
            .map(|(&h, &j)| (h, self.speeds[j]))
            .collect();
        let (pts, t) = layered_path(s, r, &lv, ys);
        (json, Candidate::converged(t, pts))
    }
}

/// Alternating speeds `1, c, 1, c, …` in `n + 1` layers of thickness 1 below `y = 0`.
fn alternating(n: usize, c: f64, half: f64) -> Stack {
    Stack {
        ys: (0..n).map(|j| -(j as f64)).collect(),
        speeds: (0..=n).map(|j| if j % 2 == 0 { 1.0 } else { c }).collect(),
        half,
    }
}

// ---------------------------------------------------------------------------------------
// Stationary reflections off a polyline, enumerated independently.

/// Whether segment `a–b` crosses the leg `p–q` strictly inside the leg (away from its ends
/// by more than `1e-10` of its length) and inside the segment.
fn crosses(p: P, q: P, a: P, b: P) -> bool {
    let d = sub(q, p);
    let (d1, d2) = (cross(d, sub(a, p)), cross(d, sub(b, p)));
    if d1 * d2 >= 0.0 {
        return false;
    }
    let e = sub(b, a);
    let (d3, d4) = (cross(e, sub(p, a)), cross(e, sub(q, a)));
    if d3 * d4 >= 0.0 {
        return false;
    }
    let t = d3 / (d3 - d4);
    t > 1e-10 && t < 1.0 - 1e-10
}

/// Every stationary reflection path off polyline `pts` (open, or `closed`) from `s` to `r`
/// in one medium of slowness `w` whose legs cross no segment: specular points strictly inside
/// a segment with both ends strictly on one side of it (the image method), and vertices where
/// `T` has a kink with one-sided derivatives of opposite signs and both ends on one side of
/// the corner (status `vertex`).
pub fn reflection_paths(pts: &[P], closed: bool, s: P, r: P, w: f64) -> Vec<Candidate> {
    let n = pts.len();
    let nseg = if closed { n } else { n - 1 };
    let seg = |j: usize| (pts[j], pts[(j + 1) % n]);
    let clear = |q: P| {
        (0..nseg).all(|j| {
            let (a, b) = seg(j);
            !crosses(s, q, a, b) && !crosses(q, r, a, b)
        })
    };
    let mut out = Vec::new();
    let mut hits = Vec::new();
    for j in 0..nseg {
        let (a, b) = seg(j);
        let e = sub(b, a);
        let (cs, cr) = (cross(e, sub(s, a)), cross(e, sub(r, a)));
        if cs * cr <= 0.0 {
            continue;
        }
        let (_, u) = intersect(reflect(s, a, b), r, a, b);
        if u > 0.0 && u < 1.0 {
            hits.push((j, u));
        }
    }
    for (j, u) in hits {
        let (a, b) = seg(j);
        let q = lerp(a, b, u);
        if clear(q) {
            out.push(Candidate {
                status: Status::Converged,
                time: w * dist(reflect(s, a, b), r),
                points: vec![q],
                point_tol: None,
            });
        }
    }
    let first = if closed { 0 } else { 1 };
    let last = if closed { n } else { n - 1 };
    for i in first..last {
        let v = pts[i];
        let (prev, next) = (pts[(i + n - 1) % n], pts[(i + 1) % n]);
        let (tb, ta) = (unit(sub(v, prev)), unit(sub(next, v)));
        let g = sub(unit(sub(v, s)), unit(sub(r, v)));
        let (rm, rp) = (dot(g, tb), dot(g, ta));
        if rm * rp >= 0.0 {
            continue;
        }
        let nrm = add([-tb[1], tb[0]], [-ta[1], ta[0]]);
        let (a, b) = (dot(nrm, sub(s, v)), dot(nrm, sub(r, v)));
        if a * b <= 0.0 || !clear(v) {
            continue;
        }
        out.push(Candidate {
            status: Status::Vertex,
            time: w * (dist(s, v) + dist(v, r)),
            points: vec![v],
            point_tol: Some(64.0 * f64::EPSILON * (norm(v) + dist(s, r))),
        });
    }
    out
}

/// One reflection off the polyline `pts`, speed `v`: the scene and every stationary path.
fn polyline_reflection(pts: &[P], closed: bool, s: P, r: P, v: f64) -> (Value, Vec<Candidate>) {
    let json = one_path(
        &[("m", v)],
        vec![("curve".into(), pts.to_vec(), closed)],
        s,
        r,
        &[("reflect", "curve".into())],
        &["m", "m"],
    );
    (json, reflection_paths(pts, closed, s, r, 1.0 / v))
}

// ---------------------------------------------------------------------------------------
// The cases.

fn case(name: &'static str, what: impl Into<String>, json: Value, expect: Expect) -> Case {
    Case {
        name,
        what: what.into(),
        json,
        expect,
        max_iterations: ITERATIONS,
        twin: None,
    }
}

fn contrast_slow_below() -> Case {
    let (v, c) = flat_refraction(1.0, 1e-6, [-0.375, 1.25], [2.5, -0.75], 100.0);
    case(
        "contrast_1e-6_below",
        "speed 1 above, 1e-6 below one flat interface (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn contrast_fast_below() -> Case {
    let (v, c) = flat_refraction(1.0, 1e6, [-0.375, 1.25], [2.5, -0.75], 100.0);
    case(
        "contrast_1e6_below",
        "speed 1 above, 1e6 below one flat interface (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn alternating_1e3() -> Case {
    let st = alternating(8, 1e3, 1000.0);
    let (v, c) = st.down([0.0, 1.0], [50.0, -8.0]);
    case(
        "alternating_1e3_stack",
        "8 interfaces, speeds 1, 1e3, 1, … alternating, offset 50 (ray parameter)",
        v,
        Expect::Path(c),
    )
}

fn alternating_1e6() -> Case {
    let st = alternating(4, 1e6, 100.0);
    let (v, c) = st.down([0.0, 1.0], [3.0, -4.0]);
    case(
        "alternating_1e6_stack",
        "4 interfaces, speeds 1, 1e6, 1, 1e6, 1, offset 3 (ray parameter)",
        v,
        Expect::Path(c),
    )
}

fn alternating_beyond_end() -> Case {
    // The same kind of stack on interfaces only 40 long: the ray-parameter path crosses the
    // lower interfaces beyond x = 20, so no transmitted path through them exists (T is
    // convex in the parameters of a flat stack: its one stationary point is outside).
    let st = alternating(8, 1e3, 20.0);
    let (v, c) = st.down([0.0, 1.0], [50.0, -8.0]);
    let outside: Vec<Reason> = (0..c.points.len())
        .filter(|&i| c.points[i][0] > 20.0)
        .map(|step| Reason::LeavesEnd { step })
        .collect();
    assert!(!outside.is_empty(), "reference {:?} inside", c.points);
    // The start leaves an end; then the complete search proves it.
    let reasons = [Reason::NoStationaryPath];
    case(
        "alternating_1e3_beyond_end",
        format!(
            "as alternating_1e3_stack on interfaces x ∈ [−20, 20]: the ray-parameter path meets interfaces {:?} at x = {:.3?}, beyond their ends (no_path: the start leaves one of those ends, and the complete search finds no path)",
            outside,
            c.points.iter().map(|p| p[0]).collect::<Vec<_>>()
        ),
        v,
        Expect::NoPath(reasons.to_vec()),
    )
}

fn alternating_grazing() -> Case {
    // Offset 2.5e4 over two fast layers of thickness 1: the fast legs run 8e-5 rad from the
    // interfaces; the slow legs meet them 5e-12 rad inside the critical angle asin(1e-3).
    let st = alternating(4, 1e3, 5e4);
    let (v, c) = st.down([0.0, 1.0], [2.5e4, -4.0]);
    let fast_leg = sub(c.points[1], c.points[0]);
    let graze = (fast_leg[1] / fast_leg[0]).abs().atan();
    assert!(graze < 1e-4, "grazing angle {graze}");
    case(
        "alternating_1e3_grazing",
        format!(
            "speeds 1, 1e3, 1, 1e3, 1, offset 2.5e4: fast legs {graze:.1e} rad from the interfaces, slow ones at the critical angle (ray parameter)"
        ),
        v,
        Expect::Path(c),
    )
}

/// The base scene of the scaling cases: a three-interface stack, refracted down, reflected
/// off the bottom, refracted up; coordinates multiples of 1/64.
fn scaled_scene(factor: f64, shift: P) -> (Value, Candidate) {
    let st = Stack {
        ys: vec![0.0, -1.25, -3.0],
        speeds: vec![1.0, 2.5, 0.75],
        half: 20.0,
    };
    let (v, c) = st.down_up([-2.5, 1.5], [3.75, 0.625]);
    let map = |p: &Value| -> Value {
        let x = p[0].as_f64().expect("x") * factor + shift[0];
        let y = p[1].as_f64().expect("y") * factor + shift[1];
        json!([x, y])
    };
    let mut out = v.clone();
    for key in ["sources", "receivers"] {
        out[key] = Value::Array(v[key].as_array().expect("list").iter().map(map).collect());
    }
    let ifs = out["interfaces"].as_object_mut().expect("interfaces");
    for i in ifs.values_mut() {
        let p: Vec<Value> = i["points"]
            .as_array()
            .expect("points")
            .iter()
            .map(map)
            .collect();
        i["points"] = Value::Array(p);
    }
    let cand = Candidate::converged(
        c.time * factor,
        c.points
            .iter()
            .map(|p| add(scale(*p, factor), shift))
            .collect(),
    );
    (out, cand)
}

fn scaled(name: &'static str, factor: f64, shift: P) -> Case {
    let (v, c) = scaled_scene(factor, shift);
    let (base, _) = scaled_scene(1.0, [0.0, 0.0]);
    let mut k = case(
        name,
        format!(
            "5-step stack down-reflect-up, scaled by {factor:e} and moved by {shift:?} (ray parameter × {factor:e}; and the unscaled solve × {factor:e})"
        ),
        v,
        Expect::Path(c),
    );
    k.twin = Some(Twin { json: base, factor });
    k
}

fn scale_unit() -> Case {
    let (v, c) = scaled_scene(1.0, [0.0, 0.0]);
    case(
        "scale_1",
        "5-step stack down-reflect-up, the unscaled base of the scaling cases (ray parameter)",
        v,
        Expect::Path(c),
    )
}

fn scale_small() -> Case {
    scaled("scale_1e-6", 1e-6, [0.0, 0.0])
}

fn scale_large() -> Case {
    scaled("scale_1e6", 1e6, [0.0, 0.0])
}

fn translated() -> Case {
    let mut c = scaled("translate_1e7", 1.0, [1e7, -1e7]);
    c.what = "5-step stack down-reflect-up moved by (1e7, −1e7), exactly (coordinates are multiples of 1/64): the same time as the unmoved solve and the ray-parameter reference".into();
    c
}

fn grazing_reflection() -> Case {
    let (v, c) = flat_reflection(1.0, [0.0, 0.004], [100.0, 0.006], -100.0, 200.0);
    case(
        "grazing_reflection",
        "flat mirror, heights 0.004 and 0.006 over offset 100: legs 1e-4 rad from the mirror (image method)",
        v,
        Expect::Path(c),
    )
}

fn grazing_transmitted() -> Case {
    // Speed 1 above, 2 below: the transmitted leg leaves 5e-5 rad from the interface, the
    // incident one arrives 2.9e-5 rad inside the critical angle of 30°.
    let g: f64 = 5e-5;
    let sin1 = (std::f64::consts::FRAC_PI_2 - g).sin() / 2.0;
    let xc = sin1 / (1.0 - sin1 * sin1).sqrt();
    let r = [xc + 1e-3 / g.tan(), -1e-3];
    let (v, c) = flat_refraction(1.0, 2.0, [0.0, 1.0], r, 100.0);
    case(
        "grazing_transmitted_critical",
        "speed 1 → 2, receiver 1e-3 below and 20 away: transmitted leg 5e-5 rad from the interface, incidence at the critical angle (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn grazing_incident() -> Case {
    // The reverse: a grazing source leg in the fast medium, the refracted leg at the critical
    // angle in the slow one.
    let one = one_path(
        &[("fast", 2.0), ("slow", 1.0)],
        vec![("surface".into(), vec![[-100.0, 0.0], [100.0, 0.0]], false)],
        [-20.0, 1e-3],
        [0.0, -1.0],
        &[("refract", "surface".into())],
        &["fast", "slow"],
    );
    let (x, t) = snell(0.5, -20.0, 1e-3, 1.0, 0.0, 1.0);
    case(
        "grazing_incident_critical",
        "speed 2 → 1, source 1e-3 above and 20 away: incident leg 5e-5 rad from the interface, refracted at the critical angle (Snell by bisection)",
        one,
        Expect::Path(Candidate::converged(t, vec![[x, 0.0]])),
    )
}

fn source_near_refraction() -> Case {
    let (v, c) = flat_refraction(1.0, 1.0 / 1.5, [0.0, 1e-9], [1.0, -1.0], 10.0);
    case(
        "source_1e-9_above_refraction",
        "source 1e-9 above the interface it refracts through (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn source_near_long_interface() -> Case {
    let (v, c) = flat_refraction(1.0, 1.0 / 1.5, [0.0, 1e-9], [1.0, -1.0], 1e6);
    case(
        "source_1e-9_above_long_interface",
        "source 1e-9 above an interface 2e6 long (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn source_near_stack() -> Case {
    // Ten layers of speeds 1 … 3.25; the source 1e-9 above the first interface, the receiver
    // 4 to the side below the last.
    let st = Stack {
        ys: (0..10).map(|j| -0.5 * j as f64).collect(),
        speeds: (0..=10).map(|j| 1.0 + 0.25 * j as f64).collect(),
        half: 10.0,
    };
    let (v, c) = st.down([0.25, 1e-9], [4.25, -6.0]);
    case(
        "source_1e-9_above_stack",
        "10 flat layers, the source 1e-9 above the first interface it meets (ray parameter)",
        v,
        Expect::Path(c),
    )
}

fn source_near_mirror() -> Case {
    let (v, c) = flat_reflection(1.0, [0.0, 1e-9], [1.0, 1.0], -10.0, 10.0);
    case(
        "source_1e-9_above_mirror",
        "source 1e-9 above the mirror (image method)",
        v,
        Expect::Path(c),
    )
}

fn receiver_near_refraction() -> Case {
    let (v, c) = flat_refraction(1.0, 1.0 / 1.5, [0.0, 1.0], [1.0, -1e-9], 10.0);
    case(
        "receiver_1e-9_below_refraction",
        "receiver 1e-9 below the interface it is refracted through (Snell by bisection)",
        v,
        Expect::Path(c),
    )
}

fn receiver_near_mirror() -> Case {
    let (v, c) = flat_reflection(1.0, [0.0, 1.0], [1.0, 1e-9], -10.0, 10.0);
    case(
        "receiver_1e-9_above_mirror",
        "receiver 1e-9 above the mirror (image method)",
        v,
        Expect::Path(c),
    )
}

fn normal_refraction() -> Case {
    // Interface along (4, 3)/5 through the origin; source and receiver on its normal
    // (−3, 4)/5, at distances 1.25 and 2.5: the path is straight through the origin.
    let v = one_path(
        &[("a", 1.0), ("b", 0.625)],
        vec![("tilted".into(), vec![[-8.0, -6.0], [8.0, 6.0]], false)],
        [-0.75, 1.0],
        [1.5, -2.0],
        &[("refract", "tilted".into())],
        &["a", "b"],
    );
    case(
        "normal_incidence_refraction",
        "tilted interface, source and receiver on one normal (T = 1.25/1 + 2.5/0.625)",
        v,
        Expect::Path(Candidate::converged(1.25 + 2.5 / 0.625, vec![[0.0, 0.0]])),
    )
}

fn normal_reflection() -> Case {
    let (v, c) = flat_reflection(1.0, [0.5, 1.0], [0.5, 2.0], -4.0, 4.0);
    assert_eq!((c.time, c.points[0]), (3.0, [0.5, 0.0]));
    case(
        "normal_incidence_reflection",
        "source and receiver on one normal of a mirror, the receiver above the source (T = 3)",
        v,
        Expect::Path(c),
    )
}

fn normal_stack() -> Case {
    let st = Stack {
        ys: (0..10).map(|j| -0.5 * j as f64).collect(),
        speeds: (0..=10).map(|j| 1.0 + 0.25 * j as f64).collect(),
        half: 10.0,
    };
    let (v, c) = st.down([0.25, 1.0], [0.25, -6.0]);
    let want: f64 = 1.0 + (1..10).map(|j| 0.5 / (1.0 + 0.25 * j as f64)).sum::<f64>() + 1.5 / 3.5;
    assert!(rel_err(c.time, want) < 1e-15, "{} vs {want}", c.time);
    case(
        "normal_incidence_stack",
        "10 flat layers, receiver straight below the source (T = Σ h / v)",
        v,
        Expect::Path(c),
    )
}

fn receiver_on_refracting_interface() -> Case {
    // T(x) = |S − X| / 1 + 1.5 |X − R| along y = 0 has a kink minimum at X = R (the one-sided
    // derivatives are sin θ ∓ 1.5 = 0.707 ∓ 1.5): the ray would end where it meets the
    // interface, the interaction point the receiver: the direct path, listed once, as such.
    let s = [0.0, 1.0];
    let r = [1.0, 0.0];
    let v = one_path(
        &[("air", 1.0), ("glass", 1.0 / 1.5)],
        vec![("surface".into(), vec![[-4.0, 0.0], [4.0, 0.0]], false)],
        s,
        r,
        &[("refract", "surface".into())],
        &["air", "glass"],
    );
    case(
        "receiver_on_refracting_interface",
        "receiver exactly on the interface it is refracted through: the interaction point would be the receiver (a zero-length last leg), which is the direct path, not a refraction: no path of this sequence, saying why",
        v,
        Expect::NoPath(vec![Reason::AtEnd { step: 0 }]),
    )
}

fn receiver_on_mirror() -> Case {
    let s = [0.0, 1.0];
    let r = [1.0, 0.0];
    let v = one_path(
        &[("m", 1.0)],
        vec![("mirror".into(), vec![[-4.0, 0.0], [4.0, 0.0]], false)],
        s,
        r,
        &[("reflect", "mirror".into())],
        &["m", "m"],
    );
    case(
        "receiver_on_mirror",
        "receiver exactly on the mirror: the reflection point would be the receiver (the image method's point), which is the direct path: no path of this sequence, saying why",
        v,
        Expect::NoPath(vec![Reason::AtEnd { step: 0 }]),
    )
}

/// `n` flat layers with random thicknesses in [0.2, 1.5] and speeds in [0.5, 3], a mirror
/// below them.
fn random_stack(n: usize, seed: u64) -> Stack {
    let mut rng = SplitMix64(seed);
    let mut y = 0.0;
    let mut ys = vec![y];
    for _ in 0..n {
        y -= 0.2 + 1.3 * rng.next_f64();
        ys.push(y);
    }
    let speeds = (0..=n).map(|_| 0.5 + 2.5 * rng.next_f64()).collect();
    Stack {
        ys,
        speeds,
        half: 1000.0,
    }
}

fn long_chain() -> Case {
    let st = random_stack(200, 0x5AB1_0200);
    let (v, c) = st.down_up([0.0, 1.0], [150.0, 0.5]);
    case(
        "stack_200_down_and_up",
        "200 random flat layers down, a bottom mirror, the same 200 up: 401 steps (two-way ray parameter)",
        v,
        Expect::Path(c),
    )
}

fn long_chain_alternating() -> Case {
    let mut st = alternating(201, 1e3, 1e4);
    st.speeds.truncate(201);
    let (v, c) = st.down_up([0.0, 1.0], [400.0, 0.5]);
    case(
        "stack_200_alternating_1e3",
        "200 layers of speeds 1, 1e3, 1, … down, a mirror, back up: 401 steps (two-way ray parameter)",
        v,
        Expect::Path(c),
    )
}

/// The digitised sea floor: `y = −10 + 0.5 sin(x/7) + 0.2 sin(x/2.3)` at `x = −500 + i/100`.
fn sea_floor() -> Vec<P> {
    (0..=100_000)
        .map(|i| {
            let x = -500.0 + i as f64 / 100.0;
            [x, -10.0 + 0.5 * (x / 7.0).sin() + 0.2 * (x / 2.3).sin()]
        })
        .collect()
}

/// Newton steps allowed on the digitised sea floor (it takes 3 or 4).
const FLOOR_ITERATIONS: usize = 8;

fn floor_case(name: &'static str, s: P, r: P) -> Case {
    let pts = sea_floor();
    let (v, cands) = polyline_reflection(&pts, false, s, r, 1500.0);
    assert!(!cands.is_empty(), "no stationary path off the floor");
    let mut c = case(
        name,
        format!(
            "reflection off a 100,000-segment digitised sea floor, source {s:?}, receiver {r:?}, speed 1500: one of its {} stationary paths (image method on each segment, kinks at vertices)",
            cands.len()
        ),
        v,
        Expect::OneOf(cands),
    );
    // Each Newton step is O(log M) (the nearest segments from the hierarchy): the solve's work
    // is bounded by its steps, 3 to 4 from the documented start (docs/method.md's table).
    c.max_iterations = FLOOR_ITERATIONS;
    c
}

fn floor_near() -> Case {
    floor_case("seafloor_100k_near", [-20.0, 5.0], [35.0, 2.0])
}

fn floor_far() -> Case {
    floor_case("seafloor_100k_far", [-300.0, 20.0], [250.0, 1.0])
}

/// The mirror `(−10, 0) – (0, 0) – (10, −5)`, convex at the origin seen from above.
const ROOF: [P; 3] = [[-10.0, 0.0], [0.0, 0.0], [10.0, -5.0]];

fn roof_case(name: &'static str, what: &str, s: P, r: P, want: Status) -> Case {
    let (v, cands) = polyline_reflection(&ROOF, false, s, r, 1.0);
    assert!(
        cands.len() == 1 && cands[0].status == want,
        "{name}: stationary paths {cands:?}"
    );
    case(
        name,
        format!("{what}; the only stationary path"),
        v,
        Expect::Path(cands[0].clone()),
    )
}

fn vertex_roof() -> Case {
    roof_case(
        "vertex_convex_roof",
        "roof (−10, 0)–(0, 0)–(10, −5), source (−1, 1), receiver (2, 1): T has a kink minimum at the vertex",
        [-1.0, 1.0],
        [2.0, 1.0],
        Status::Vertex,
    )
}

fn near_vertex_left() -> Case {
    // Image method on the left segment (y = 0), heights 2 and 0.5: the specular point is at
    // x = −1 + (1.25 − 1.25e-9) · 2 / 2.5 = −1e-9. The initial guess (below the chord's
    // midpoint) is at x = −0.375.
    let s = [-1.0, 2.0];
    let r = [0.25 - 1.25e-9, 0.5];
    let c = roof_case(
        "vertex_minus_1e-9",
        "roof, specular point on the left segment 1e-9 before the vertex",
        s,
        r,
        Status::Converged,
    );
    if let Expect::Path(p) = &c.expect {
        assert!((p.points[0][0] + 1e-9).abs() < 1e-14, "{p:?}");
    }
    c
}

fn near_vertex_right() -> Case {
    // The same in the frame of the right segment (tangent t, normal n): the specular point
    // is 1e-9 past the vertex along it.
    let t = unit(sub(ROOF[2], ROOF[1]));
    let n = [-t[1], t[0]];
    let at = |u: f64, h: f64| add(scale(t, u), scale(n, h));
    let s = at(-1.0, 2.0);
    let r = at(0.25 + 1.25e-9, 0.5);
    let c = roof_case(
        "vertex_plus_1e-9",
        "roof, specular point on the right segment 1e-9 past the vertex",
        s,
        r,
        Status::Converged,
    );
    if let Expect::Path(p) = &c.expect {
        let u = dot(p.points[0], t);
        assert!((u - 1e-9).abs() < 1e-14, "{p:?} at {u}");
    }
    c
}

/// The parabola `y = x² / 4` on `x ∈ [−6, 6]`, 1200 segments.
fn parabola() -> Vec<P> {
    (0..=1200)
        .map(|i| {
            let x = -6.0 + i as f64 / 100.0;
            [x, 0.25 * x * x]
        })
        .collect()
}

/// The documented initial guess for one step: the point of `pts` nearest the chord's
/// midpoint (brute force over the segments).
fn nearest_to_midpoint(pts: &[P], s: P, r: P) -> P {
    let q = lerp(s, r, 0.5);
    pts.windows(2)
        .map(|w| {
            let d = sub(w[1], w[0]);
            let t = (dot(sub(q, w[0]), d) / dot(d, d)).clamp(0.0, 1.0);
            lerp(w[0], w[1], t)
        })
        .min_by(|a, b| dist(*a, q).total_cmp(&dist(*b, q)))
        .expect("a segment")
}

/// Stationary points grouped where they lie within 0.5 of each other: `"x̄ (n)"` each.
fn clusters(xs: &[f64]) -> String {
    let mut xs = xs.to_vec();
    xs.sort_by(f64::total_cmp);
    let mut groups: Vec<Vec<f64>> = Vec::new();
    for x in xs {
        match groups.last_mut() {
            Some(g) if x - g[g.len() - 1] < 0.5 => g.push(x),
            _ => groups.push(vec![x]),
        }
    }
    groups
        .iter()
        .map(|g| {
            format!(
                "{:.3} ({})",
                g.iter().sum::<f64>() / g.len() as f64,
                g.len()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// A reflection off the concave digitised curve `pts` (open) with several stationary paths.
fn concave_case(name: &'static str, curve: &str, pts: &[P], s: P, r: P, note: &str) -> Case {
    let (v, cands) = polyline_reflection(pts, false, s, r, 1.0);
    // Several stationary paths: specular or kink points in at least two places apart.
    let xs: Vec<f64> = cands.iter().map(|c| c.points[0][0]).collect();
    let spread = xs.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - xs.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(spread > 1.0, "{name}: stationary points {xs:?}");
    let guess = nearest_to_midpoint(pts, s, r);
    case(
        name,
        format!(
            "concave {curve}, source {s:?}, receiver {r:?}: {} stationary paths, near x = {}; the initial guess is at x = {:.3}{note}",
            cands.len(),
            clusters(&xs),
            guess[0]
        ),
        v,
        Expect::OneOf(cands),
    )
}

fn concave_symmetric() -> Case {
    // The initial guess is the bottom, x = 0: on the slope of T that descends to the minimum
    // near x = 2.02, right of the maximum near x = −0.2.
    concave_case(
        "concave_parabola_at_maximum",
        "digitised parabola y = x²/4 (1200 segments)",
        &parabola(),
        [-2.0, 1.5],
        [2.0, 1.2],
        ", right of the maximum of T, on its descent to the right-hand minimum",
    )
}

fn concave_between() -> Case {
    concave_case(
        "concave_parabola_flank",
        "digitised parabola y = x²/4 (1200 segments)",
        &parabola(),
        [-2.5, 3.0],
        [3.5, 3.2],
        ", on a flank between the maximum and a minimum",
    )
}

fn concave_arc() -> Case {
    // The lower half of the circle of radius 5 about the origin, 1000 segments; source and
    // receiver inside, off the centre: minima and maxima of T around the arc.
    let pts: Vec<P> = (0..=1000)
        .map(|i| {
            let phi = std::f64::consts::PI * (1.0 + i as f64 / 1000.0);
            [5.0 * phi.cos(), 5.0 * phi.sin()]
        })
        .collect();
    concave_case(
        "concave_circular_trough",
        "digitised half circle of radius 5 (1000 segments)",
        &pts,
        [-2.5, -0.3],
        [2.0, -1.2],
        ", between the left minimum and the maximum",
    )
}

fn lens() -> Case {
    // A rectangular lens of index 1.5 ([−5, 5] × [−1, 1], one closed interface) crossed top to
    // bottom: flat layers of thicknesses 3, 2, 2.5.
    let (s, r) = ([0.3125, 4.0], [1.75, -3.5]);
    let v = one_path(
        &[("air", 1.0), ("glass", 1.0 / 1.5)],
        vec![(
            "lens".into(),
            vec![[-5.0, -1.0], [5.0, -1.0], [5.0, 1.0], [-5.0, 1.0]],
            true,
        )],
        s,
        r,
        &[("refract", "lens".into()), ("refract", "lens".into())],
        &["air", "glass", "air"],
    );
    let (pts, t) = layered_path(
        s,
        r,
        &[(3.0, 1.0), (2.0, 1.0 / 1.5), (2.5, 1.0)],
        &[1.0, -1.0],
    );
    case(
        "lens_crossed_twice",
        "rectangular closed lens of index 1.5 refracted into and out of (ray parameter)",
        v,
        Expect::Path(Candidate::converged(t, pts)),
    )
}

fn inside_polygon() -> Case {
    let poly: Vec<P> = vec![
        [-3.0, -2.0],
        [2.0, -2.5],
        [4.0, 0.0],
        [2.5, 2.5],
        [-1.0, 3.0],
        [-3.5, 1.0],
    ];
    for i in 0..poly.len() {
        let (a, b, c) = (poly[i], poly[(i + 1) % 6], poly[(i + 2) % 6]);
        assert!(cross(sub(b, a), sub(c, b)) > 0.0, "not convex at {b:?}");
    }
    let (s, r) = ([-1.0, 0.5], [1.5, -0.25]);
    let (v, cands) = polyline_reflection(&poly, true, s, r, 1.0);
    assert!(cands.len() >= 2, "{cands:?}");
    case(
        "reflection_inside_polygon",
        format!(
            "source and receiver inside a convex hexagon, one reflection off it (one closed interface): one of its {} stationary paths (image method per wall)",
            cands.len()
        ),
        v,
        Expect::OneOf(cands),
    )
}

fn poor_guess_mirror() -> Case {
    // The initial guess is the mirror point nearest the chord's midpoint, x = 0; the image
    // method puts the reflection at x = 490.1.
    let (v, c) = flat_reflection(1.0, [-500.0, 100.0], [500.0, 1.0], -1000.0, 1000.0);
    case(
        "poor_guess_long_mirror",
        format!(
            "long mirror, source (−500, 100), receiver (500, 1): guess x = 0, reflection at x = {:.3} (image method)",
            c.points[0][0]
        ),
        v,
        Expect::Path(c),
    )
}

fn poor_guess_refraction() -> Case {
    // The chord crosses y = 0 at x = −294; Snell puts the crossing near x = 290.
    let (v, c) = flat_refraction(10.0, 1.0, [-300.0, 1.0], [300.0, -100.0], 1000.0);
    case(
        "poor_guess_refraction",
        format!(
            "speed 10 above, 1 below; the chord crosses at x = −294, the ray at x = {:.3} (Snell by bisection)",
            c.points[0][0]
        ),
        v,
        Expect::Path(c),
    )
}

fn poor_guess_waveguide() -> Case {
    // Seven bounces between y = 0 and y = 1 over an offset of 100 (image method: unfold the
    // guide).
    let (s, r) = ([-50.0, 0.25], [50.0, 0.75]);
    let names = ["bottom", "top"];
    let steps: Vec<(&str, String)> = (0..7)
        .map(|i| ("reflect", names[i % 2].to_string()))
        .collect();
    let v = one_path(
        &[("m", 1.0)],
        vec![
            ("bottom".into(), vec![[-100.0, 0.0], [100.0, 0.0]], false),
            ("top".into(), vec![[-100.0, 1.0], [100.0, 1.0]], false),
        ],
        s,
        r,
        &steps,
        &["m"; 8],
    );
    // Unfolded (each mirror reflected in turn): bounce i + 1 is where the straight line
    // crosses y = −i, and the receiver, 0.75 above the bottom after the seventh bounce (off
    // the bottom at unfolded y = −6), is at unfolded y = −6.75.
    let unfolded_r = [r[0], -6.75];
    let total = dist(s, unfolded_r);
    let mut pts = Vec::new();
    for i in 0..7 {
        // The unfolded line crosses y = −i (i = 0 … 6).
        let t = (s[1] + i as f64) / (s[1] - unfolded_r[1]);
        pts.push([s[0] + t * (r[0] - s[0]), if i % 2 == 0 { 0.0 } else { 1.0 }]);
    }
    case(
        "poor_guess_waveguide",
        "seven alternating bounces between two parallel mirrors over offset 100 (image method, unfolded)",
        v,
        Expect::Path(Candidate::converged(total, pts)),
    )
}

/// Builds one case.
pub type Builder = fn() -> Case;

/// Every case, by name, in table order: one source of truth for the tests and the example.
pub const CASES: &[(&str, Builder)] = &[
    ("contrast_1e-6_below", contrast_slow_below),
    ("contrast_1e6_below", contrast_fast_below),
    ("alternating_1e3_stack", alternating_1e3),
    ("alternating_1e6_stack", alternating_1e6),
    ("alternating_1e3_beyond_end", alternating_beyond_end),
    ("alternating_1e3_grazing", alternating_grazing),
    ("scale_1", scale_unit),
    ("scale_1e-6", scale_small),
    ("scale_1e6", scale_large),
    ("translate_1e7", translated),
    ("grazing_reflection", grazing_reflection),
    ("grazing_transmitted_critical", grazing_transmitted),
    ("grazing_incident_critical", grazing_incident),
    ("source_1e-9_above_refraction", source_near_refraction),
    (
        "source_1e-9_above_long_interface",
        source_near_long_interface,
    ),
    ("source_1e-9_above_stack", source_near_stack),
    ("source_1e-9_above_mirror", source_near_mirror),
    ("receiver_1e-9_below_refraction", receiver_near_refraction),
    ("receiver_1e-9_above_mirror", receiver_near_mirror),
    ("normal_incidence_refraction", normal_refraction),
    ("normal_incidence_reflection", normal_reflection),
    ("normal_incidence_stack", normal_stack),
    (
        "receiver_on_refracting_interface",
        receiver_on_refracting_interface,
    ),
    ("receiver_on_mirror", receiver_on_mirror),
    ("stack_200_down_and_up", long_chain),
    ("stack_200_alternating_1e3", long_chain_alternating),
    ("seafloor_100k_near", floor_near),
    ("seafloor_100k_far", floor_far),
    ("vertex_convex_roof", vertex_roof),
    ("vertex_minus_1e-9", near_vertex_left),
    ("vertex_plus_1e-9", near_vertex_right),
    ("concave_parabola_at_maximum", concave_symmetric),
    ("concave_parabola_flank", concave_between),
    ("concave_circular_trough", concave_arc),
    ("lens_crossed_twice", lens),
    ("reflection_inside_polygon", inside_polygon),
    ("poor_guess_long_mirror", poor_guess_mirror),
    ("poor_guess_refraction", poor_guess_refraction),
    ("poor_guess_waveguide", poor_guess_waveguide),
];

/// The case called `name`.
pub fn by_name(name: &str) -> Case {
    let (_, build) = CASES
        .iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no case {name}"));
    let c = build();
    assert_eq!(c.name, name, "case registered under another name");
    c
}
