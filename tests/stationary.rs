//! Every stationary path of a sequence (`Tracer::stationary_paths`) against a brute-force
//! reference written here from scratch: every assignment of segments and vertices of small
//! random scenes, each minimised on its own (dense Newton on plain numbers), classified by
//! the contract's rules, and deduplicated. Then the issue's named cases.

use eigenray::{
    Arrival, Point, Reason, Scene, Status, Tracer, Workspace,
    trace::{Kink, StationaryError},
};

#[path = "support/rng.rs"]
mod rng;
use rng::SplitMix64;

type P = [f64; 2];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: P) -> f64 {
    a[0].hypot(a[1])
}
fn unit(a: P) -> P {
    let l = norm(a);
    [a[0] / l, a[1] / l]
}

/// An interface of a test scene.
#[derive(Clone, Debug)]
struct Line {
    points: Vec<P>,
    closed: bool,
}

impl Line {
    fn segments(&self) -> usize {
        self.points.len() - usize::from(!self.closed)
    }
    fn segment(&self, j: usize) -> (P, P) {
        (self.points[j], self.points[(j + 1) % self.points.len()])
    }
    /// The segment before vertex `j` (its start), if `j` is a vertex between two segments.
    fn before(&self, j: usize) -> Option<usize> {
        match j {
            0 if self.closed => Some(self.segments() - 1),
            0 => None,
            j => Some(j - 1),
        }
    }
}

/// A test case: interfaces, leg slownesses, steps `(reflect, interface)`, the ends.
#[derive(Clone, Debug)]
struct Case {
    lines: Vec<Line>,
    slowness: Vec<f64>,
    steps: Vec<(bool, usize)>,
    source: P,
    receiver: P,
}

impl Case {
    fn json(&self) -> String {
        let interfaces: Vec<String> = self
            .lines
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let pts: Vec<String> = l
                    .points
                    .iter()
                    .map(|p| format!("[{:e}, {:e}]", p[0], p[1]))
                    .collect();
                format!(
                    r#""i{i}": {{ "points": [{}], "closed": {} }}"#,
                    pts.join(", "),
                    l.closed
                )
            })
            .collect();
        let media: Vec<String> = self
            .slowness
            .iter()
            .enumerate()
            .map(|(i, w)| format!(r#""m{i}": {{ "index": {w:e} }}"#))
            .collect();
        let steps = steps_json(&self.steps);
        let leg_media: Vec<String> = (0..self.slowness.len())
            .map(|i| format!(r#""m{i}""#))
            .collect();
        format!(
            r#"{{ "media": {{ {} }}, "interfaces": {{ {} }},
                 "sources": [[{:e}, {:e}]], "receivers": [[{:e}, {:e}]],
                 "paths": [{{ "steps": [{}], "media": [{}] }}] }}"#,
            media.join(", "),
            interfaces.join(", "),
            self.source[0],
            self.source[1],
            self.receiver[0],
            self.receiver[1],
            steps,
            leg_media.join(", ")
        )
    }
}

/// Steps `(reflect, interface)` in the scene format, off interfaces named `i0`, `i1`, ….
fn steps_json(steps: &[(bool, usize)]) -> String {
    let each: Vec<String> = steps
        .iter()
        .map(|&(reflect, i)| {
            let kind = if reflect { "reflect" } else { "refract" };
            format!(r#"{{ "{kind}": "i{i}" }}"#)
        })
        .collect();
    each.join(", ")
}

/// A path of the reference.
#[derive(Clone, Debug)]
struct RefPath {
    status: Status,
    time: f64,
    points: Vec<P>,
    kink: Option<Kink>,
}

/// What the reference makes of a case.
enum Reference {
    Paths(Vec<RefPath>),
    /// Some candidate sits within round-off of a decision (a side, a crossing, a minimiser
    /// that did not settle): the case says nothing.
    Ambiguous(&'static str),
}

/// One interaction of an assignment: on the line of segment `seg`, or held on its first
/// vertex.
#[derive(Clone, Copy, Debug)]
struct Choice {
    seg: usize,
    held: bool,
}

/// Minimises `T` over the free points of `choice` (fractions along their segments' lines):
/// dense Newton with backtracking on `T`. Where a leg between two interactions vanishes on
/// the way, `T` has a kink there: the minimum of `T` with that kink smoothed away
/// (`|v| → √(|v|² + ε²)` on the legs between interactions, ε shrinking by 100 each time) is
/// followed down to ε = 1e-10 of the path's length; if its leg stays, the plain solve runs
/// again from there, else the minimum is the collapse (no path). Returns the fractions, or
/// why not.
fn minimise(case: &Case, choice: &[Choice]) -> Result<Vec<f64>, &'static str> {
    match minimise_from(case, choice, None, 0.0) {
        Err("vanished") => {}
        other => return other,
    }
    let total = (norm(sub(case.receiver, case.source)) + 1.0) * 4.0;
    let mut t = None;
    let mut eps = 1e-2 * total;
    while eps >= 1e-10 * total {
        t = Some(minimise_from(case, choice, t.as_deref(), eps)?);
        eps *= 1e-2;
    }
    minimise_from(case, choice, t.as_deref(), 0.0)
}

/// [`minimise`] from `start` (else the middle of each segment), with the legs between
/// interactions smoothed by `eps`.
fn minimise_from(
    case: &Case,
    choice: &[Choice],
    start: Option<&[f64]>,
    eps: f64,
) -> Result<Vec<f64>, &'static str> {
    let k = choice.len();
    let w = &case.slowness;
    let seg = |i: usize| case.lines[case.steps[i].1].segment(choice[i].seg);
    let point = |t: &[f64], i: usize| -> P {
        let (a, b) = seg(i);
        [a[0] + t[i] * (b[0] - a[0]), a[1] + t[i] * (b[1] - a[1])]
    };
    let all = |t: &[f64]| -> Vec<P> {
        let mut v = vec![case.source];
        v.extend((0..k).map(|i| point(t, i)));
        v.push(case.receiver);
        v
    };
    // A leg's length, smoothed between interactions.
    let length = |l: usize, d: P| {
        if l == 0 || l == k || eps == 0.0 {
            norm(d)
        } else {
            (dot(d, d) + eps * eps).sqrt()
        }
    };
    let time = |t: &[f64]| -> f64 {
        let x = all(t);
        (0..=k).map(|l| w[l] * length(l, sub(x[l + 1], x[l]))).sum()
    };
    let mut t: Vec<f64> = match start {
        Some(s) => s.to_vec(),
        None => (0..k)
            .map(|i| {
                if choice[i].held {
                    0.0
                } else {
                    0.5 + 0.1 * i as f64
                }
            })
            .collect(),
    };
    let free: Vec<usize> = (0..k).filter(|&i| !choice[i].held).collect();
    // A solve that does not settle approaches a minimum where `T` is not differentiable (a
    // leg between two interactions vanishing) or not strict (a leg along its interface's
    // line): no stationary path there. Anything else is a close call.
    let degenerate = |t: &[f64], why: &'static str| {
        let x = all(t);
        let len: Vec<f64> = (0..=k).map(|l| norm(sub(x[l + 1], x[l]))).collect();
        let total: f64 = len.iter().sum();
        let along = (0..k).any(|i| {
            let (a, b) = seg(i);
            let tan = unit(sub(b, a));
            [i, i + 1]
                .iter()
                .any(|&l| cross(unit(sub(x[l + 1], x[l])), tan).abs() <= 1e-6)
        });
        if (1..k).any(|l| len[l] <= 1e-6 * total) || along {
            Err("vanished")
        } else {
            Err(why)
        }
    };
    for _ in 0..200 {
        let x = all(&t);
        let legs: Vec<P> = (0..=k).map(|l| sub(x[l + 1], x[l])).collect();
        let len: Vec<f64> = (0..=k).map(|l| length(l, legs[l])).collect();
        let total: f64 = len.iter().sum();
        if len.iter().any(|&l| l <= 1e-9 * total) {
            return Err("vanished");
        }
        // ∂|v|/∂v (a unit vector unless smoothed).
        let u: Vec<P> = (0..=k)
            .map(|l| [legs[l][0] / len[l], legs[l][1] / len[l]])
            .collect();
        let d: Vec<P> = (0..k)
            .map(|i| {
                let (a, b) = seg(i);
                sub(b, a)
            })
            .collect();
        // Gradient and Hessian over the free fractions.
        let n = free.len();
        if n == 0 {
            return Ok(t);
        }
        let mut grad = vec![0.0; n];
        let mut hess = vec![vec![0.0; n]; n];
        let mut worst = 0.0f64;
        for (a, &i) in free.iter().enumerate() {
            grad[a] = w[i] * dot(u[i], d[i]) - w[i + 1] * dot(u[i + 1], d[i]);
            worst = worst.max(grad[a].abs() / (norm(d[i]) * (w[i] + w[i + 1])));
        }
        if worst <= 1e-14 || (eps > 0.0 && worst <= 1e-12) {
            return Ok(t);
        }
        // Leg `l` joins point l−1 and point l: Hessian of w|x_l − x_{l−1}|. How leg `l` moves
        // with point `i`: +dᵢ at its far end, −dᵢ at its near end.
        let moves = |i: usize, l: usize| {
            if i == l {
                1.0
            } else if i + 1 == l {
                -1.0
            } else {
                0.0
            }
        };
        for l in 0..=k {
            let p = |v: P, q: P| (dot(v, q) - dot(v, u[l]) * dot(q, u[l])) * w[l] / len[l];
            for (a, &i) in free.iter().enumerate() {
                for (b, &j) in free.iter().enumerate() {
                    // ∂x_l/∂t_i = d_i when i == l, ∂x_{l−1}/∂t_i = d_i when i == l − 1.
                    let (si, sj) = (moves(i, l), moves(j, l));
                    if si != 0.0 && sj != 0.0 {
                        hess[a][b] += si * sj * p(d[i], d[j]);
                    }
                }
            }
        }
        // Gaussian elimination with partial pivoting, slightly damped.
        let trace: f64 = (0..n).map(|a| hess[a][a]).sum();
        let mut m: Vec<Vec<f64>> = (0..n)
            .map(|a| {
                let mut row = hess[a].clone();
                row[a] += 1e-15 * trace;
                row.push(-grad[a]);
                row
            })
            .collect();
        for c in 0..n {
            let piv = (c..n)
                .max_by(|&x, &y| m[x][c].abs().total_cmp(&m[y][c].abs()))
                .unwrap();
            m.swap(c, piv);
            let pivot_row = m[c].clone();
            for row in &mut m[c + 1..] {
                let f = row[c] / pivot_row[c];
                for (x, p) in row[c..].iter_mut().zip(&pivot_row[c..]) {
                    *x -= f * p;
                }
            }
        }
        let mut step = vec![0.0; n];
        for r in (0..n).rev() {
            let mut v = m[r][n];
            for cc in r + 1..n {
                v -= m[r][cc] * step[cc];
            }
            step[r] = v / m[r][r];
        }
        if step.iter().any(|s| !s.is_finite()) {
            return degenerate(&t, "singular");
        }
        let small = free
            .iter()
            .enumerate()
            .all(|(a, &i)| (step[a] * norm(d[i])).abs() <= 1e-15 * total);
        if small {
            return if worst <= 1e-9 {
                Ok(t)
            } else {
                degenerate(&t, "stalled")
            };
        }
        // Backtracking on T.
        let t0 = time(&t);
        let slope: f64 = (0..n).map(|a| grad[a] * step[a]).sum();
        let mut alpha = 1.0f64;
        for (a, &i) in free.iter().enumerate() {
            let reach = 4.0 * len[i].max(len[i + 1]) / norm(d[i]);
            if step[a].abs() * alpha > reach {
                alpha = reach / step[a].abs();
            }
        }
        let mut moved = false;
        while alpha > 1e-14 {
            let mut trial = t.clone();
            for (a, &i) in free.iter().enumerate() {
                trial[i] += alpha * step[a];
            }
            let t1 = time(&trial);
            // Descent; or, where `T` no longer resolves the step (within its round-off), the
            // full Newton step near the minimum.
            let flat = alpha == 1.0 && (t1 - t0).abs() <= 8.0 * f64::EPSILON * t0;
            if (t1 <= t0 + 1e-4 * alpha * slope && t1 < t0) || flat {
                t = trial;
                moved = true;
                break;
            }
            alpha *= 0.5;
        }
        if !moved {
            return if worst <= 1e-9 {
                Ok(t)
            } else {
                degenerate(&t, "stalled")
            };
        }
    }
    degenerate(&t, "iterations")
}

/// Whether segments `p–q` (a leg) and `a–b` cross strictly inside the leg: `Err` when it is
/// too close to call.
fn crosses(p: P, q: P, a: P, b: P) -> Result<bool, &'static str> {
    let (r, s) = (sub(q, p), sub(b, a));
    let den = cross(r, s);
    if den.abs() <= 1e-14 * norm(r) * norm(s) {
        return Ok(false);
    }
    let lam = cross(sub(a, p), s) / den;
    let mu = cross(sub(a, p), r) / den;
    let inside_leg = lam > 1e-10 && lam < 1.0 - 1e-10;
    let near_leg_end = (lam > 1e-13 && lam < 1e-7) || (lam < 1.0 - 1e-13 && lam > 1.0 - 1e-7);
    let near_seg_end = mu.abs() < 1e-9 || (mu - 1.0).abs() < 1e-9;
    let on_seg = (0.0..=1.0).contains(&mu);
    if (near_leg_end && on_seg) || (near_seg_end && (1e-13..1.0 - 1e-13).contains(&lam)) {
        return Err("crossing too close to call");
    }
    Ok(inside_leg && on_seg)
}

/// Every stationary path of `case`, by brute force.
fn reference(case: &Case) -> Reference {
    let k = case.steps.len();
    let lines: Vec<&Line> = case.steps.iter().map(|s| &case.lines[s.1]).collect();
    // Every choice per point: each segment's line, and each vertex between two segments.
    let options: Vec<Vec<Choice>> = lines
        .iter()
        .map(|l| {
            (0..l.segments())
                .flat_map(|j| {
                    let mut v = vec![Choice {
                        seg: j,
                        held: false,
                    }];
                    if l.before(j).is_some() {
                        v.push(Choice { seg: j, held: true });
                    }
                    v
                })
                .collect()
        })
        .collect();
    let mut found: Vec<RefPath> = Vec::new();
    let mut index = vec![0usize; k];
    loop {
        let choice: Vec<Choice> = (0..k).map(|i| options[i][index[i]]).collect();
        match candidate(case, &lines, &choice) {
            Ok(Some(p)) => found.push(p),
            Ok(None) => {}
            Err(why) => return Reference::Ambiguous(why),
        }
        // Next assignment (odometer).
        let mut i = 0;
        loop {
            if i == k {
                found.sort_by(|a, b| a.time.total_cmp(&b.time));
                return Reference::Paths(dedup(found));
            }
            index[i] += 1;
            if index[i] < options[i].len() {
                break;
            }
            index[i] = 0;
            i += 1;
        }
    }
}

/// Drops repeats (the same points), keeping a vertex path over an interior one.
fn dedup(found: Vec<RefPath>) -> Vec<RefPath> {
    let mut kept: Vec<RefPath> = Vec::new();
    for p in found {
        let same = |q: &RefPath| {
            (q.time - p.time).abs() <= 1e-9 * p.time
                && q.points
                    .iter()
                    .zip(&p.points)
                    .all(|(a, b)| norm(sub(*a, *b)) <= 1e-9)
        };
        match kept.iter_mut().find(|q| same(q)) {
            Some(q) => {
                if p.status == Status::Vertex {
                    *q = p;
                }
            }
            None => kept.push(p),
        }
    }
    kept
}

/// The stationary path of one assignment, classified, if it has one.
fn candidate(
    case: &Case,
    lines: &[&Line],
    choice: &[Choice],
) -> Result<Option<RefPath>, &'static str> {
    let k = choice.len();
    let w = &case.slowness;
    let t = match minimise(case, choice) {
        Ok(t) => t,
        Err("vanished") => return Ok(None),
        Err(why) => return Err(why),
    };
    // Free points strictly inside their segments (close calls are ambiguous).
    for i in 0..k {
        if !choice[i].held {
            if (t[i] - 0.0).abs() < 1e-9 || (t[i] - 1.0).abs() < 1e-9 {
                return Err("minimiser at a segment's end");
            }
            if !(t[i] > 0.0 && t[i] < 1.0) {
                return Ok(None);
            }
        }
    }
    let mut x = vec![case.source];
    for i in 0..k {
        let (a, b) = lines[i].segment(choice[i].seg);
        x.push([a[0] + t[i] * (b[0] - a[0]), a[1] + t[i] * (b[1] - a[1])]);
    }
    x.push(case.receiver);
    let u: Vec<P> = (0..=k).map(|l| unit(sub(x[l + 1], x[l]))).collect();
    // Kinks at held points.
    let mut kink = None;
    for i in 0..k {
        if !choice[i].held {
            continue;
        }
        let j = choice[i].seg;
        let tangent = |s: usize| {
            let (a, b) = lines[i].segment(s);
            unit(sub(b, a))
        };
        let v = [
            w[i] * u[i][0] - w[i + 1] * u[i + 1][0],
            w[i] * u[i][1] - w[i + 1] * u[i + 1][1],
        ];
        let (before, after) = (
            dot(v, tangent(lines[i].before(j).unwrap())),
            dot(v, tangent(j)),
        );
        if before.abs() < 1e-9 || after.abs() < 1e-9 {
            return Err("one-sided derivative near zero");
        }
        let this = if before < 0.0 && after > 0.0 {
            Kink::Minimum
        } else if before > 0.0 && after < 0.0 {
            Kink::Maximum
        } else {
            return Ok(None);
        };
        kink = Some(match kink {
            None => this,
            Some(k) if k == this => this,
            Some(_) => Kink::Mixed,
        });
    }
    // Sides: a reflection's legs on one side, a refraction's on opposite sides. At a vertex
    // `v` between `p` (before) and `q` (after), the left side near `v` is the sector of
    // directions counter-clockwise from `q − v` to `p − v`, the right side the rest.
    for i in 0..k {
        let angle = |d: P| d[1].atan2(d[0]);
        let ccw = |from: f64, to: f64| (to - from).rem_euclid(std::f64::consts::TAU);
        let side = |leg: P| -> Result<f64, &'static str> {
            let (a, b) = lines[i].segment(choice[i].seg);
            if !choice[i].held {
                let t = unit(sub(b, a));
                let c = cross(t, unit(leg));
                return if c.abs() < 1e-8 {
                    Err("a leg along its interface")
                } else {
                    Ok(c.signum())
                };
            }
            let (p, _) = lines[i].segment(lines[i].before(choice[i].seg).unwrap());
            let (v, q) = (a, b);
            let (start, end) = (angle(sub(q, v)), angle(sub(p, v)));
            let (width, at) = (ccw(start, end), ccw(start, angle(leg)));
            // Along a segment next to the vertex (to round-off): on neither side.
            let gap = [0.0, width, std::f64::consts::TAU]
                .iter()
                .map(|b| (at - b).abs())
                .fold(f64::INFINITY, f64::min);
            if gap < 1e-12 {
                Ok(0.0)
            } else if gap < 1e-8 {
                Err("a leg along its interface")
            } else if at < width {
                Ok(1.0)
            } else {
                Ok(-1.0)
            }
        };
        let a = side(sub(x[i], x[i + 1]))?;
        let b = side(sub(x[i + 2], x[i + 1]))?;
        let reflect = case.steps[i].0;
        if a == 0.0 || b == 0.0 || (a == b) != reflect {
            return Ok(None);
        }
    }
    // Obstruction: a leg crossing any segment but those of its own end points.
    let mut obstructed = false;
    for l in 0..=k {
        for (f, line) in case.lines.iter().enumerate() {
            for j in 0..line.segments() {
                let own = |i: Option<usize>| {
                    i.is_some_and(|i: usize| i < k && case.steps[i].1 == f && choice[i].seg == j)
                };
                if own(l.checked_sub(1)) || own(Some(l)) {
                    continue;
                }
                let (a, b) = line.segment(j);
                obstructed |= crosses(x[l], x[l + 1], a, b)?;
            }
        }
    }
    let time = (0..=k).map(|l| w[l] * norm(sub(x[l + 1], x[l]))).sum();
    let status = if obstructed {
        Status::Obstructed
    } else if kink.is_some() {
        Status::Vertex
    } else {
        Status::Converged
    };
    Ok(Some(RefPath {
        status,
        time,
        points: x,
        kink: if status == Status::Vertex { kink } else { None },
    }))
}

/// The engine's arrivals for `case`.
fn engine(case: &Case) -> Vec<Arrival> {
    let scene = Scene::from_json(&case.json()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut out = Vec::new();
    let search = tracer
        .stationary_paths(
            Point::new(case.source[0], case.source[1]),
            Point::new(case.receiver[0], case.receiver[1]),
            0,
            &eigenray::options::Run::new(),
            &mut out,
        )
        .unwrap();
    // Every random case is small: a search that stops short would hide missing paths.
    assert!(search.complete, "incomplete search: {case:?}");
    out
}

/// A random interface: wavy or concave open polylines, closed lenses (convex or not).
fn random_line(rng: &mut SplitMix64, max_segments: usize) -> Line {
    let mut r = || rng.next_f64();
    let kind = (r() * 3.0) as usize;
    let m = 1 + (r() * max_segments as f64) as usize;
    match kind {
        0 => {
            // Wavy.
            let (y0, a, f, ph) = (r() * 2.0 - 1.0, 0.2 + 0.5 * r(), 0.5 + 2.0 * r(), 6.0 * r());
            let points = (0..=m)
                .map(|i| {
                    let x = -3.0 + 6.0 * i as f64 / m as f64 + 0.1 * (r() - 0.5);
                    [x, y0 + a * (f * x + ph).sin()]
                })
                .collect();
            Line {
                points,
                closed: false,
            }
        }
        1 => {
            // Concave (a bowl) or convex (a dome).
            let (y0, c) = (r() * 2.0 - 1.0, (r() - 0.5) * 0.6);
            let points = (0..=m)
                .map(|i| {
                    let x = -3.0 + 6.0 * i as f64 / m as f64;
                    [x, y0 + c * x * x]
                })
                .collect();
            Line {
                points,
                closed: false,
            }
        }
        _ => {
            // A lens: a polygon of 3..=max vertices, jittered radially.
            let n =
                (3 + (r() * (max_segments.max(3) - 2) as f64) as usize).min(max_segments.max(3));
            let (cx, cy, rad, ph) = (r() * 2.0 - 1.0, r() * 2.0 - 1.0, 0.4 + 0.8 * r(), r());
            let points = (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * (i as f64 + ph) / n as f64;
                    let rr = rad * (0.7 + 0.6 * r());
                    [cx + rr * a.cos(), cy + rr * a.sin()]
                })
                .collect();
            Line {
                points,
                closed: true,
            }
        }
    }
}

/// Whether two polylines cross or come close (the scene would be invalid or touchy).
fn too_close(a: &Line, b: &Line) -> bool {
    for i in 0..a.segments() {
        for j in 0..b.segments() {
            let (p, q) = a.segment(i);
            let (c, d) = b.segment(j);
            let hit = crosses(p, q, c, d).unwrap_or(true);
            let near = [p, q]
                .iter()
                .any(|&x| [c, d].iter().any(|&y| norm(sub(x, y)) < 0.05));
            if hit || near {
                return true;
            }
        }
    }
    false
}

fn random_case(rng: &mut SplitMix64) -> Case {
    loop {
        let k = 1 + (rng.next_f64() * 3.0) as usize;
        let max_segments = match k {
            1 => 12,
            2 => 8,
            _ => 4,
        };
        let n_lines = 1 + (rng.next_f64() * 2.0) as usize;
        let lines: Vec<Line> = (0..n_lines)
            .map(|_| random_line(rng, max_segments))
            .collect();
        if n_lines == 2 && too_close(&lines[0], &lines[1]) {
            continue;
        }
        let steps = (0..k)
            .map(|_| {
                (
                    rng.next_f64() < 0.5,
                    (rng.next_f64() * n_lines as f64) as usize,
                )
            })
            .collect();
        let slowness = (0..=k)
            .map(|_| [1.0, 1.5, 0.7][(rng.next_f64() * 3.0) as usize])
            .collect();
        let mut end = || [rng.next_f64() * 8.0 - 4.0, rng.next_f64() * 8.0 - 4.0];
        let (source, receiver) = (end(), end());
        return Case {
            lines,
            slowness,
            steps,
            source,
            receiver,
        };
    }
}

fn compare(case: &Case, want: &[RefPath], got: &[Arrival]) -> Result<(), String> {
    let show = || {
        let w: Vec<_> = want
            .iter()
            .map(|p| (p.status, p.time, p.kink, p.points.clone()))
            .collect();
        let g: Vec<_> = got
            .iter()
            .map(|a| {
                (
                    a.status,
                    a.time,
                    a.kink,
                    a.points.clone(),
                    a.segments.clone(),
                )
            })
            .collect();
        format!("{case:?}\nreference {w:?}\nengine    {g:?}")
    };
    if want.len() != got.len() {
        return Err(format!("{} vs {} paths\n{}", want.len(), got.len(), show()));
    }
    // Points within 1e-8 of the path's extent (the reference solves to 1e-12 in the residual).
    for (p, a) in want.iter().zip(got) {
        let extent = p
            .points
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum::<f64>();
        let same_points = p.points.len() == a.points.len()
            && p.points.iter().zip(&a.points).all(|(q, r)| {
                (q[0] - r.x).abs() <= 1e-8 * extent && (q[1] - r.y).abs() <= 1e-8 * extent
            });
        let ok = (p.time - a.time).abs() <= 1e-10 * p.time
            && p.status == a.status
            && p.kink == a.kink
            && a.time.is_finite()
            && same_points;
        if !ok {
            return Err(show());
        }
    }
    Ok(())
}

/// Hundreds of random scenes: reflections, refractions, converted legs (any given media),
/// closed lenses, concave, convex and wavy polylines, one to three steps, up to 12 segments:
/// the engine lists exactly the reference's paths (times to 1e-10, statuses, kinks).
#[test]
fn every_stationary_path_of_random_scenes_matches_brute_force() {
    let mut rng = SplitMix64(18);
    let (mut compared, mut paths, mut ambiguous) = (0, 0, 0);
    let mut by_status = std::collections::BTreeMap::new();
    let mut skipped = std::collections::BTreeMap::new();
    // Triples (each case is one source, receiver and path) by their number of paths.
    let mut by_count = std::collections::BTreeMap::new();
    let mut failures = Vec::new();
    while compared < 500 {
        let case = random_case(&mut rng);
        let want = match reference(&case) {
            Reference::Paths(p) => p,
            Reference::Ambiguous(why) => {
                *skipped.entry(why).or_insert(0) += 1;
                ambiguous += 1;
                continue;
            }
        };
        let got = engine(&case);
        if let Err(e) = compare(&case, &want, &got) {
            failures.push(e);
        }
        compared += 1;
        paths += want.len();
        *by_count.entry(want.len()).or_insert(0) += 1;
        for p in &want {
            *by_status.entry(p.status.as_str()).or_insert(0) += 1;
        }
    }
    println!(
        "{compared} scenes, {paths} paths ({by_status:?}), {ambiguous} ambiguous skipped ({skipped:?})"
    );
    let counts: Vec<String> = by_count.iter().map(|(n, t)| format!("{n}: {t}")).collect();
    println!("triples by their number of paths: {}", counts.join(", "));
    assert_no_failures(&failures);
    // Triples without a path, with one and with several, so that the comparison checks
    // proofs of no path and complete lists alike.
    let several: usize = by_count.range(2..).map(|(_, t)| t).sum();
    assert!(
        by_count.get(&0).copied().unwrap_or(0) >= 20
            && by_count.get(&1).copied().unwrap_or(0) >= 20
            && several >= 20,
        "{by_count:?}"
    );
    // The scenes exercise every kind of path.
    for s in ["converged", "vertex", "obstructed"] {
        assert!(
            by_status.get(s).copied().unwrap_or(0) >= 10,
            "{by_status:?}"
        );
    }
    // Close calls (a leg along its interface, a minimiser on a segment's end, a reference
    // solve that does not settle next to a collapse) are skipped, not compared: few.
    assert!(ambiguous * 4 < compared, "{ambiguous} ambiguous");
}

/// Prints the first few failures of a randomised test, then fails if there are any.
fn assert_no_failures(failures: &[String]) {
    for f in failures.iter().take(3) {
        println!("{f}\n");
    }
    assert!(failures.is_empty(), "{} failures", failures.len());
}

/// The reference's paths of `case` (which must not be a close call) against the engine's:
/// the same set, times to 1e-12. Returns the engine's arrivals.
fn agree(case: &Case) -> Vec<Arrival> {
    let Reference::Paths(want) = reference(case) else {
        panic!("a named case is a close call");
    };
    let got = engine(case);
    compare(case, &want, &got).unwrap();
    for (p, a) in want.iter().zip(&got) {
        assert!(
            (p.time - a.time).abs() <= 1e-12 * p.time,
            "{} vs {}",
            p.time,
            a.time
        );
    }
    got
}

/// A glass lens: a regular hexagon of circumradius 0.4 about the origin with vertices at
/// 30° + k·60° (flat faces left and right), index 1.5 in air; source (−2, 0.3); path `refract
/// lens, refract lens`.
fn lens_case(receiver: P) -> Case {
    let points = (0..6)
        .map(|k| {
            let a = (30.0 + 60.0 * k as f64).to_radians();
            [0.4 * a.cos(), 0.4 * a.sin()]
        })
        .collect();
    Case {
        lines: vec![Line {
            points,
            closed: true,
        }],
        slowness: vec![1.0, 1.5, 1.0],
        steps: vec![(false, 0), (false, 0)],
        source: [-2.0, 0.3],
        receiver,
    }
}

fn converged_times(arrivals: &[Arrival]) -> Vec<f64> {
    arrivals
        .iter()
        .filter(|a| a.status == Status::Converged)
        .map(|a| a.time)
        .collect()
}

/// Issue 18's lens (our hexagon: the issue does not give its vertices): where the default
/// mode's two steps start on one crossing of the line from source to receiver, the sequence
/// has stationary paths through two faces; the search lists them (and the vertex paths
/// beside them) as the brute force does.
#[test]
fn lens_paths_through_two_faces() {
    for (receiver, first) in [([1.0, 0.0], 3.3626), ([0.6, 0.0], 2.9219)] {
        let arrivals = agree(&lens_case(receiver));
        let times = converged_times(&arrivals);
        assert!(!times.is_empty(), "{arrivals:?}");
        assert!((times[0] - first).abs() < 1e-4, "{times:?}");
        assert!(arrivals.iter().all(|a| a.media == [0, 1, 2]));
        // Points inside their segments, legs on the right sides: the first leaves the
        // source, enters the glass, leaves it on the other face.
        let a = arrivals
            .iter()
            .find(|a| a.status == Status::Converged)
            .unwrap();
        assert_ne!(a.segments[0], a.segments[1]);
    }
}

/// Through the same lens to a receiver close behind it, three converged paths (one through
/// each pair of faces that can focus there), ordered by time, each once.
#[test]
fn lens_receiver_with_three_paths() {
    let arrivals = agree(&lens_case([0.6, 0.0]));
    let times = converged_times(&arrivals);
    assert_eq!(times.len(), 3, "{arrivals:?}");
    let expected = [2.92185859079608, 2.9653375886435818, 3.0274201722087346];
    for (t, e) in times.iter().zip(expected) {
        assert!((t - e).abs() <= 1e-12 * e, "{times:?}");
    }
    assert!(arrivals.windows(2).all(|w| w[0].time <= w[1].time));
}

/// A converted reflection (slowness 1 down, 1.6 up) off a bent polyline whose only
/// stationary path has a leg through a screen: listed once, as `obstructed`, not dropped.
#[test]
fn converted_reflection_whose_only_path_is_obstructed() {
    let case = Case {
        lines: vec![
            Line {
                points: vec![[-3.0, 0.0], [0.5, -0.3], [3.0, 0.2]],
                closed: false,
            },
            Line {
                points: vec![[1.4, 1.0], [2.1, 0.9]],
                closed: false,
            },
        ],
        slowness: vec![1.0, 1.6],
        steps: vec![(true, 0)],
        source: [-1.5, 2.0],
        receiver: [2.0, 2.0],
    };
    let arrivals = agree(&case);
    assert_eq!(arrivals.len(), 1, "{arrivals:?}");
    assert_eq!(arrivals[0].status, Status::Obstructed);
}

/// A roof seen from above: no slope reflects, the ridge is a minimum-type kink; a valley seen
/// from above: a specular point on each slope and a maximum-type kink in its bottom.
#[test]
fn kinks_of_roofs_and_valleys() {
    let roof = Case {
        lines: vec![Line {
            points: vec![[-3.0, 0.0], [0.0, 0.5], [3.0, 0.0]],
            closed: false,
        }],
        slowness: vec![1.0, 1.0],
        steps: vec![(true, 0)],
        source: [-0.5, 2.0],
        receiver: [0.5, 2.0],
    };
    let kinds = |c: &Case| -> Vec<_> { agree(c).iter().map(|a| (a.status, a.kink)).collect() };
    assert_eq!(kinds(&roof), [(Status::Vertex, Some(Kink::Minimum))]);
    let valley = Case {
        lines: vec![Line {
            points: vec![[-3.0, 0.0], [0.0, -2.0], [3.0, 0.0]],
            closed: false,
        }],
        ..roof
    };
    assert_eq!(
        kinds(&valley),
        [
            (Status::Converged, None),
            (Status::Converged, None),
            (Status::Vertex, Some(Kink::Maximum))
        ]
    );
}

/// The direct ray (no steps): one path, `converged`, or `obstructed` behind a screen.
#[test]
fn direct_ray_is_one_path() {
    let mut case = Case {
        lines: vec![Line {
            points: vec![[-1.0, 1.0], [1.0, 1.2]],
            closed: false,
        }],
        slowness: vec![1.25],
        steps: vec![],
        source: [0.0, 0.0],
        receiver: [3.0, 4.0],
    };
    let arrivals = agree(&case);
    assert_eq!(arrivals.len(), 1);
    assert_eq!(arrivals[0].status, Status::Obstructed);
    assert!((arrivals[0].time - 6.25).abs() < 1e-12);
    case.receiver = [3.0, -4.0];
    let arrivals = agree(&case);
    assert_eq!(arrivals[0].status, Status::Converged);
}

/// A path index out of range and a path longer than the search takes are refused, and the
/// caller's list is emptied first, whatever the answer.
#[test]
fn bad_paths_are_refused() {
    let wall = r#""interfaces": { "wall": { "points": [[-1, 0], [1, 0]] } },
                  "sources": [[0, 1]], "receivers": [[0.5, 1]]"#;
    let scene = Scene::from_json(&format!(
        r#"{{ "media": {{ "a": {{ "speed": 1.0 }} }}, {wall},
             "paths": [{{ "steps": [{{ "reflect": "wall" }}], "media": ["a", "a"] }}] }}"#
    ))
    .unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let (s, r) = (scene.sources()[0], scene.receivers()[0]);
    let stale = || {
        let mut out = Vec::new();
        tracer
            .stationary_paths(s, r, 0, &eigenray::options::Run::new(), &mut out)
            .unwrap();
        assert_eq!(out.len(), 1);
        out
    };
    let mut out = stale();
    assert_eq!(
        tracer.stationary_paths(s, r, 1, &eigenray::options::Run::new(), &mut out),
        Err(StationaryError::NoSuchPath { path: 1 })
    );
    assert!(out.is_empty());
    // More steps than the search takes (each assignment tries every choice of held
    // vertices): refused, not run for hours.
    let steps = vec![serde_json::json!({ "reflect": "wall" }); 13];
    let long = Scene::from_json(
        &serde_json::json!({
            "media": { "a": { "speed": 1.0 } },
            "interfaces": { "wall": { "points": [[-1, 0], [1, 0]] } },
            "sources": [[0, 1]], "receivers": [[0.5, 1]],
            "paths": [{ "steps": steps, "media": vec!["a"; 14] }]
        })
        .to_string(),
    )
    .unwrap();
    let mut out = stale();
    assert_eq!(
        Tracer::new(&long).unwrap().stationary_paths(
            s,
            r,
            0,
            &eigenray::options::Run::new(),
            &mut out
        ),
        Err(StationaryError::TooManySteps { path: 0, steps: 13 })
    );
    assert!(out.is_empty());
}

/// The default mode on the random scenes: every `no_path` it gives is `no_path` for the brute
/// force (no stationary path of any status), every sequence with a path gets one of the
/// reference's paths (time and status), and nothing ends `not_converged`.
#[test]
fn default_mode_no_path_is_a_proof() {
    let mut rng = SplitMix64(1818);
    let (mut compared, mut proofs, mut searched) = (0, 0, 0);
    let mut failures = Vec::new();
    while compared < 1000 {
        let case = random_case(&mut rng);
        let Reference::Paths(want) = reference(&case) else {
            continue;
        };
        compared += 1;
        let scene = Scene::from_json(&case.json()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let ray = tracer.trace(0, 0, 0, &mut Workspace::new());
        if ray.reason == Some(Reason::NoStationaryPath) {
            searched += 1;
        }
        let ok = match ray.status {
            Status::NoPath => {
                proofs += 1;
                want.is_empty()
            }
            Status::NotConverged => false,
            // The solver holds points on vertices by a weaker test than the kink definition:
            // its `vertex` answers are not checked here.
            Status::Vertex => true,
            _ => want
                .iter()
                .any(|p| p.status == ray.status && (p.time - ray.time).abs() <= 1e-10 * p.time),
        };
        if !ok {
            failures.push(format!(
                "{case:?}\nreference {:?}\ndefault {:?} {} {:?}",
                want.iter().map(|p| (p.status, p.time)).collect::<Vec<_>>(),
                ray.status,
                ray.time,
                ray.reason
            ));
        }
    }
    println!("{compared} scenes: {proofs} no_path ({searched} by the complete search)");
    assert_no_failures(&failures);
    assert!(proofs >= 100 && searched >= 50, "{proofs} {searched}");
}

/// A random scene whose media come from the regions: a closed lens (glass, claimed by an
/// `at` point at its centre) in air (the background), with an open reflector beside it, and
/// up to three steps off or through them.
struct LookupCase {
    lens: Line,
    centre: P,
    reflector: Line,
    steps: Vec<(bool, usize)>,
    source: P,
    receiver: P,
}

const AIR: f64 = 1.0;
const GLASS: f64 = 1.5;

impl LookupCase {
    fn random(rng: &mut SplitMix64) -> LookupCase {
        loop {
            let mut r = || rng.next_f64();
            let n = 3 + (r() * 5.0) as usize;
            let (cx, cy, rad, ph) = (r() - 0.5, r() - 0.5, 0.8 + 0.6 * r(), r());
            let points: Vec<P> = (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * (i as f64 + ph) / n as f64;
                    let rr = rad * (0.6 + 0.6 * r());
                    [cx + rr * a.cos(), cy + rr * a.sin()]
                })
                .collect();
            let lens = Line {
                points,
                closed: true,
            };
            let y = -2.6 + 0.4 * r();
            let reflector = Line {
                points: vec![
                    [-3.0, y + 0.3 * r()],
                    [0.0, y - 0.3 * r()],
                    [3.0, y + 0.3 * r()],
                ],
                closed: false,
            };
            if too_close(&lens, &reflector) {
                continue;
            }
            let k = 1 + (r() * 3.0) as usize;
            // Half of them through the lens (in and out), the rest any mix.
            let steps = if r() < 0.5 {
                vec![(false, 0), (false, 0)]
            } else {
                (0..k)
                    .map(|_| if r() < 0.2 { (true, 1) } else { (r() < 0.3, 0) })
                    .collect()
            };
            let mut end = || loop {
                let p = [r() * 8.0 - 4.0, r() * 4.0 - 1.5];
                if norm(sub(p, [cx, cy])) > 1.8 {
                    return p;
                }
            };
            let (source, receiver) = (end(), end());
            return LookupCase {
                lens,
                centre: [cx, cy],
                reflector,
                steps,
                source,
                receiver,
            };
        }
    }

    fn json(&self) -> String {
        let pts = |l: &Line| {
            l.points
                .iter()
                .map(|p| format!("[{:e}, {:e}]", p[0], p[1]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let steps = steps_json(&self.steps);
        format!(
            r#"{{ "media": {{ "air": {{ "index": {AIR:e} }},
                             "glass": {{ "index": {GLASS:e}, "at": [{:e}, {:e}] }} }},
                 "background": "air",
                 "interfaces": {{ "i0": {{ "points": [{}], "closed": true }},
                                  "i1": {{ "points": [{}] }} }},
                 "sources": [[{:e}, {:e}]], "receivers": [[{:e}, {:e}]],
                 "paths": [{{ "steps": [{}] }}] }}"#,
            self.centre[0],
            self.centre[1],
            pts(&self.lens),
            pts(&self.reflector),
            self.source[0],
            self.source[1],
            self.receiver[0],
            self.receiver[1],
            steps
        )
    }

    /// Whether `p` lies inside the lens (crossing number).
    fn inside(&self, p: P) -> bool {
        let mut inside = false;
        for j in 0..self.lens.segments() {
            let (a, b) = self.lens.segment(j);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > p[0] {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// The brute force: every sequence of leg slownesses (air or glass) that changes medium at
    /// each refraction through the lens and nowhere else, each searched by the reference,
    /// keeping the paths whose legs lie in the media they were solved with (a leg's midpoint
    /// inside the lens exactly when its medium is glass). Paths that reach
    /// interfaces only from one side have unobstructed legs in one region each, so only
    /// `converged` and `vertex` paths are compared.
    fn reference(&self) -> Option<Vec<RefPath>> {
        let k = self.steps.len();
        let mut found = Vec::new();
        for code in 0..(1usize << (k + 1)) {
            let glass = |leg: usize| code >> leg & 1 == 1;
            // A refraction at the lens crosses into the other medium, a reflection keeps it.
            let follows = (0..k).all(|i| {
                let refracts = !self.steps[i].0 && self.steps[i].1 == 0;
                (glass(i) != glass(i + 1)) == refracts
            });
            if !follows {
                continue;
            }
            let case = Case {
                lines: vec![self.lens.clone(), self.reflector.clone()],
                slowness: (0..=k)
                    .map(|l| if glass(l) { GLASS } else { AIR })
                    .collect(),
                steps: self.steps.clone(),
                source: self.source,
                receiver: self.receiver,
            };
            let Reference::Paths(paths) = reference(&case) else {
                return None;
            };
            for p in paths {
                let legs_agree = (0..=k).all(|l| {
                    let (a, b) = (p.points[l], p.points[l + 1]);
                    self.inside([0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]) == glass(l)
                });
                if legs_agree && p.status == Status::Converged {
                    found.push(p);
                }
            }
        }
        found.sort_by(|a, b| a.time.total_cmp(&b.time));
        Some(found)
    }
}

/// Paths without `media` on random lens scenes: the engine's arrivals (media from the
/// regions) are the brute force's over every sequence of media, kept where each leg lies in
/// its medium; the default mode's answer is one of them, or `no_path` where there is none.
#[test]
fn media_from_regions_match_brute_force() {
    let mut rng = SplitMix64(77);
    let (mut compared, mut paths, mut through) = (0, 0, 0);
    let mut by_count = std::collections::BTreeMap::new();
    let mut failures = Vec::new();
    while compared < 1000 {
        let case = LookupCase::random(&mut rng);
        let Some(want) = case.reference() else {
            continue;
        };
        compared += 1;
        let scene = Scene::from_json(&case.json()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut got = Vec::new();
        let (s, r) = (scene.sources()[0], scene.receivers()[0]);
        let search = tracer
            .stationary_paths(s, r, 0, &eigenray::options::Run::new(), &mut got)
            .unwrap();
        assert!(search.complete);
        got.retain(|a| a.status == Status::Converged);
        let same = want.len() == got.len()
            && want
                .iter()
                .zip(&got)
                .all(|(p, a)| p.status == a.status && (p.time - a.time).abs() <= 1e-10 * p.time);
        paths += want.len();
        *by_count.entry(want.len()).or_insert(0) += 1;
        through += got.iter().filter(|a| a.media.contains(&1)).count();
        let ray = tracer.trace(0, 0, 0, &mut Workspace::new());
        let default_ok = match ray.status {
            Status::NoPath => want.is_empty(),
            Status::NotConverged => false,
            // Stationary paths of the kinds not compared here.
            Status::Obstructed | Status::Vertex => true,
            _ => want
                .iter()
                .any(|p| (p.time - ray.time).abs() <= 1e-10 * p.time),
        };
        if !same || !default_ok {
            failures.push(format!(
                "{}\nreference {:?}\nengine {:?}\ndefault {:?} {}",
                case.json(),
                want.iter().map(|p| (p.status, p.time)).collect::<Vec<_>>(),
                got.iter()
                    .map(|a| (a.status, a.time, a.media.clone()))
                    .collect::<Vec<_>>(),
                ray.status,
                ray.time
            ));
        }
    }
    println!("{compared} scenes, {paths} paths, {through} through glass");
    let counts: Vec<String> = by_count.iter().map(|(n, t)| format!("{n}: {t}")).collect();
    println!(
        "triples by their number of converged paths: {}",
        counts.join(", ")
    );
    assert_no_failures(&failures);
    assert!(paths >= 60 && through >= 40, "{paths} {through}");
}

/// The search's cost grows with log M: one reflection off a digitised sea floor of 1,000 and
/// of 100,000 segments visits a few dozen tuples per ray and solves about one assignment.
#[test]
fn sea_floor_search_visits_few_tuples() {
    let mut tuples = Vec::new();
    for m in [1_000, 100_000] {
        let scene = Scene::from_spec(&eigenray::demo::sea_floor(m, 20)).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut out = Vec::new();
        let (mut visited, mut solves) = (0, 0);
        for &receiver in scene.receivers() {
            let search = tracer
                .stationary_paths(
                    scene.sources()[0],
                    receiver,
                    0,
                    &eigenray::options::Run::new(),
                    &mut out,
                )
                .unwrap();
            assert!(search.complete);
            assert_eq!(out.len(), 1, "{out:?}");
            assert!(matches!(out[0].status, Status::Converged | Status::Vertex));
            visited += search.tuples;
            solves += search.solves;
        }
        assert!(solves <= 2 * 20, "{solves} solves");
        tuples.push(visited as f64 / 20.0);
    }
    // About two tuples more per level of the hierarchy (7 more levels), not 100 times more.
    assert!(
        tuples[0] < 40.0 && tuples[1] < tuples[0] + 30.0,
        "{tuples:?}"
    );
}

/// Two refractions through one closed interface (a digitised round lens of 1,000 and of
/// 20,000 segments): the legs between two points of the same interface are bounded by the
/// tangents between them, so the search stays small (without that bound every pair of
/// neighbouring segments was solved: hundreds of thousands of solves).
#[test]
fn round_lens_search_stays_small() {
    let mut costs = Vec::new();
    for m in [1_000, 20_000] {
        let points = (0..m)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / m as f64;
                [0.5 * a.cos(), 0.5 * a.sin()]
            })
            .collect();
        let case = Case {
            lines: vec![Line {
                points,
                closed: true,
            }],
            ..lens_case([1.0, 0.0])
        };
        let scene = Scene::from_json(&case.json()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut out = Vec::new();
        let search = tracer
            .stationary_paths(
                Point::new(-2.0, 0.3),
                Point::new(1.0, 0.0),
                0,
                &eigenray::options::Run::new(),
                &mut out,
            )
            .unwrap();
        assert!(search.complete && !out.is_empty(), "{out:?}");
        // Every arrival passes through the glass: its first leg enters near the source side.
        assert!(
            out.iter()
                .all(|a| a.points[1].x < 0.0 && a.points[2].x > 0.0)
        );
        costs.push((search.tuples, search.solves));
    }
    assert!(
        costs.iter().all(|&(t, s)| t < 10_000 && s < 500),
        "{costs:?}"
    );
}
