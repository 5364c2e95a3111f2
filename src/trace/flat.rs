//! One refraction at a flat interface (an open polyline of one segment) with the leg media
//! given: the classic ray (air over water, a flat sea floor, a lens face), solved in the
//! segment's frame without the general bookkeeping.
//!
//! With `x` the point's distance along the segment from its start, and the source and
//! receiver at `(xₛ, zₛ)` and `(xᵣ, zᵣ)` in the segment's frame (along it, across it),
//!
//! ```text
//! T(x)   = w₀ ℓ₀ + w₁ ℓ₁,         ℓ₀ = √(zₛ² + (x − xₛ)²),  ℓ₁ = √(zᵣ² + (xᵣ − x)²)
//! r(x)   = T′(x)  = w₀ (x − xₛ)/ℓ₀ − w₁ (xᵣ − x)/ℓ₁         (Snell's law: r = 0)
//! r′(x)  = T″(x)  = w₀ zₛ²/ℓ₀³ + w₁ zᵣ²/ℓ₁³  > 0
//! ```
//!
//! Snell's law squared, `Q(a) = w₀² a² ℓ₁² − w₁² b² ℓ₀² = 0` with `a = x − xₛ` and
//! `b = xᵣ − x`, is a quartic in `a`: its value and its first two derivatives need no square
//! root and no division. From the paraxial start (the crossing of the straight line moved as
//! for small angles) a fixed count of Halley's steps on it ([`QUARTIC_STEPS`], one division
//! each) brings the common ray to within a few ulps; a loop of known length is one the
//! processor predicts, so that one ray's steps overlap with the next ray's. Then Newton's
//! steps on `r` itself, with the general solve's tests of convergence (computed without
//! division), finish the ray and say when it is done: usually at once, after one evaluation.
//!
//! The quartic has other roots (where the sines have opposite signs) and a grazing ray's
//! paraxial start can be far from the root, so the steps on `r` keep a bracket: the root
//! lies between the feet of the source and the receiver and on the segment, `r` increases
//! (`T` is convex), and each evaluation narrows the bracket by its sign. A step that would
//! leave the bracket bisects it instead (after checking the residual's sign at a segment end
//! that is not yet known to lie beyond the root).
//!
//! The solve gives up (`None`) on anything but the clean case: the source and receiver
//! clearly on opposite sides, the root strictly inside the segment, convergence within the
//! iteration limit. The caller then solves the ray with the general code from the same
//! start. Where the kernel converges, so does the general solve, to the same status (tested
//! on the benchmark and demo scenes and a scene with obstructed and pathless rays).

use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::{coord, finite, max_num, min_num};
use crate::scene::SolverOptions;

/// A refraction at an open interface of one segment, with its two slownesses.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FlatRefraction {
    /// The segment's start and unit tangent, and its length.
    origin: Point,
    t: Vec2,
    len: f64,
    /// Slownesses before and after the interface.
    w: [f64; 2],
    /// The scene's tolerance, its square root, and the steps allowed.
    tol: f64,
    sqrt_tol: f64,
    /// Steps in all that the iteration limit allows.
    steps: usize,
}

/// A segment's start, unit tangent and length.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SegmentFrame {
    pub start: Point,
    pub tangent: Vec2,
    pub length: f64,
}

/// A converged [`FlatRefraction::solve`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct FlatSolution {
    /// The point's parameter (its distance from the segment's start).
    pub s: f64,
    /// The two legs' lengths.
    pub len: [f64; 2],
    /// Travel time.
    pub time: f64,
    /// Relative residual `|r| / (w₀ + w₁)`.
    pub residual: f64,
    /// Steps taken.
    pub iterations: usize,
}

/// Halley's steps on Snell's law squared from the paraxial start (see the module): two leave
/// the common ray within a few ulps (`demo_rays_take_two_steps` checks them on
/// `demo::air_water`), and a fixed count lets the processor overlap one ray's steps with the
/// next ray's.
const QUARTIC_STEPS: usize = 2;

/// Steps on the travel time's own residual after those, before the kernel hands a ray to
/// the general solve (grazing rays, whose bracket is bisected a few times, take up to 15 over
/// the random rays of the tests).
const MAX_STEPS: usize = 30;

impl FlatRefraction {
    /// The kernel for a refraction at `line` between slownesses `w` with the solver settings
    /// `opts`, if `line` is one open segment.
    pub(crate) fn of(line: &Polyline, w: [f64; 2], opts: SolverOptions) -> Option<FlatRefraction> {
        if line.is_closed() || line.num_segments() != 1 {
            return None;
        }
        let origin = line.segment(0).start;
        let len = line.length();
        let kernel =
            len > 0.0 && len.is_finite() && SLOWNESS.contains(&w[0]) && SLOWNESS.contains(&w[1]);
        (kernel && opts.max_iterations >= QUARTIC_STEPS).then_some(FlatRefraction {
            origin,
            t: line.tangent(0),
            len,
            w,
            tol: opts.tolerance,
            sqrt_tol: opts.tolerance.sqrt(),
            steps: opts.max_iterations.min(QUARTIC_STEPS + MAX_STEPS),
        })
    }

    /// The refraction point of the ray from `source` to `receiver`, converged as the solver
    /// settings ask (the tests of the general solve: the relative residual within the
    /// tolerance and the next step within its square root of the path's length, or the step
    /// at the round-off floor), or `None` when the ray is not the clean case (see the module).
    #[inline(always)]
    pub(crate) fn solve(&self, source: Point, receiver: Point) -> Option<FlatSolution> {
        let t = self.t;
        let (ds, dr) = (source - self.origin, receiver - self.origin);
        let (xs, zs) = (ds.dot(t), t.cross(ds));
        let (xr, zr) = (dr.dot(t), t.cross(dr));
        let dx = xr - xs;
        // Clearly on opposite sides: no leg near the interface's line, where the general
        // solve's vanishing legs and kinks take over. The quartic's terms are fourth powers
        // of these lengths times slownesses squared, and Halley's step squares its slope (the
        // sixth power): within these bounds (and those of the slownesses, `SLOWNESS`) nothing
        // overflows or underflows.
        let scale = zs.abs() + zr.abs() + dx.abs();
        let clear = CLEAR * scale + 16.0 * f64::EPSILON * coord(source, receiver);
        if !(zs * zr < 0.0 && zs.abs() > clear && zr.abs() > clear && scale > 1e-30 && scale < 1e30)
        {
            return None;
        }
        let [w0, w1] = self.w;
        // The paraxial start (`paraxial_one`): the crossing of S → R at fraction
        // `c = zₛ / (zₛ − zᵣ)` moved to `τ = (c/w₀) / (c/w₀ + (1 − c)/w₁)`, which is
        // `zₛ w₁ / (zₛ w₁ − zᵣ w₀)`: one division where that form takes three in a row; and
        // `a = τ Δx` with the product in the numerator, beside the denominator.
        let (zw, dw) = (zs * w1, zs * w1 - zr * w0);
        let start = zw * dx / dw;
        // Halley's steps on Q(a) = w₀² a² ℓ₁² − w₁² b² ℓ₀² in a = x − xₛ (b = Δx − a). With
        // P = w₀² zᵣ², R = w₁² zₛ² and D = w₀² − w₁², Q = P a² − R b² + D a² b², and
        // Q′ = 2 q₁, Q″ = 2 q₂ with q₁ = P a + R b + D ab (b − a), q₂ = P − R + D (a² + b² − 4ab):
        //   a ← a − Q q₁ / (2 q₁² − Q q₂ / 2).
        // (Written for a short chain of dependent operations: the steps are the ray's latency.
        // Where the ray is the normal, a = b = 0, the step is zero over zero: the NaN fails the
        // bracket below, which takes the paraxial start, there the root.)
        let (zs2, zr2) = (zs * zs, zr * zr);
        let (p, q) = (w0 * w0, w1 * w1);
        let (big_p, big_r, big_d) = (p * zr2, q * zs2, p - q);
        let (twice_p, twice_r, twice_d) = (2.0 * big_p, 2.0 * big_r, 2.0 * big_d);
        let (half_pr, half_d) = (0.5 * (big_p - big_r), 0.5 * big_d);
        let mut a = start;
        for _ in 0..QUARTIC_STEPS {
            let b = dx - a;
            let (aa, bb, ab) = (a * a, b * b, a * b);
            let value = (big_p * aa - big_r * bb) + big_d * (aa * bb);
            let skew = ab * (b - a);
            let q1 = (big_p * a + big_r * b) + big_d * skew;
            let q1_twice = (twice_p * a + twice_r * b) + twice_d * skew;
            let q2_half = half_pr + half_d * ((aa + bb) - 4.0 * ab);
            a -= value * q1 / (q1_twice * q1 - value * q2_half);
        }
        // The root lies between the source's and the receiver's feet (the sines of Snell's
        // law have one sign) and on the segment: a bracket that the residual's sign narrows
        // (`r` increases: T is convex). The ends of the segment are not known to bracket it
        // until the residual there says so (`sure`); the feet are.
        let (mut lo, mut hi) = if xs < xr { (xs, xr) } else { (xr, xs) };
        let mut sure = [lo >= 0.0, hi <= self.len];
        (lo, hi) = (max_num(lo, 0.0), min_num(hi, self.len));
        // (Both finite: a NaN or infinite coordinate failed the test of sides above.)
        if lo > hi {
            return None;
        }
        let mut x = xs + a;
        if !(x >= lo && x <= hi) {
            // The quartic's steps left the bracket (another root of the squared law, or a
            // grazing ray's start far from the root, or the NaN of the normal ray): the paraxial
            // start, or the middle.
            x = xs + start;
            if !(x >= lo && x <= hi) {
                x = 0.5 * (lo + hi);
            }
        }
        let mut iterations = QUARTIC_STEPS;
        loop {
            if !(x > 0.0 && x < self.len) {
                return None;
            }
            // The residual and Hessian times ℓ₀ℓ₁ and (ℓ₀ℓ₁)³: the convergence tests below
            // then need no division (a division is a fifth of a step's latency).
            let (l0, l1, r, h) = self.residual(x, xs, zs2, xr, zr2);
            let (l0l1, total) = (l0 * l1, l0 + l1);
            // |step| = |r| (ℓ₀ℓ₁)² / h, the relative residual |r| / (ℓ₀ℓ₁ (w₀ + w₁)).
            let moved = r.abs() * (l0l1 * l0l1);
            // (The bounds on the scale and the slownesses keep both finite and h positive: the
            // legs are no longer than the scale, and no shorter than the clearance.)
            debug_assert!(finite(moved) && finite(h) && h > 0.0, "{moved} {h}");
            if moved <= 4.0 * f64::EPSILON * (x.abs() + total) * h
                || (r.abs() <= self.tol * (w0 + w1) * l0l1 && moved <= self.sqrt_tol * total * h)
            {
                return Some(FlatSolution {
                    s: x,
                    len: [l0, l1],
                    time: w0 * l0 + w1 * l1,
                    residual: r.abs() / (l0l1 * (w0 + w1)),
                    iterations,
                });
            }
            if iterations >= self.steps {
                return None;
            }
            iterations += 1;
            if r < 0.0 {
                (lo, sure[0]) = (x, true);
            } else {
                (hi, sure[1]) = (x, true);
            }
            let next = x - r * l0l1 * (l0l1 / h);
            if next > lo && next < hi {
                x = next;
                continue;
            }
            // Newton's step leaves the bracket: bisect it, once the end it heads for is known
            // to be beyond the root (else the root may be beyond the end: no clean case).
            let end = usize::from(next >= hi);
            if !sure[end] {
                let at = if end == 0 { 0.0 } else { self.len };
                let (.., r_end, _) = self.residual(at, xs, zs2, xr, zr2);
                if (r_end < 0.0) != (end == 0) {
                    return None;
                }
                sure[end] = true;
            }
            x = 0.5 * (lo + hi);
        }
    }

    /// The legs' lengths, and the residual and Hessian times ℓ₀ℓ₁ and (ℓ₀ℓ₁)³, at `x`.
    #[inline(always)]
    fn residual(&self, x: f64, xs: f64, zs2: f64, xr: f64, zr2: f64) -> (f64, f64, f64, f64) {
        let [w0, w1] = self.w;
        let (a, b) = (x - xs, xr - x);
        let (l0, l1) = ((zs2 + a * a).sqrt(), (zr2 + b * b).sqrt());
        let r = w0 * a * l1 - w1 * b * l0;
        let h = w0 * zs2 * (l1 * l1 * l1) + w1 * zr2 * (l0 * l0 * l0);
        (l0, l1, r, h)
    }
}

impl FlatRefraction {
    /// The point at parameter `s`: `origin + s t` (not `Polyline::point_on`, which measures
    /// from the nearer end: the kernel's parameter is measured from the start, and the point
    /// is as exact as it is).
    #[inline(always)]
    pub(crate) fn point(&self, s: f64) -> Point {
        self.origin + self.t * s
    }

    /// The interface's one segment as the kernel holds it: the start, unit tangent and length
    /// of [`Polyline::segment`], [`Polyline::tangent`] and [`Polyline::segment_length`], bit
    /// for bit.
    #[inline(always)]
    pub(crate) fn frame(&self) -> SegmentFrame {
        SegmentFrame {
            start: self.origin,
            tangent: self.t,
            length: self.len,
        }
    }

    /// The interface's normal ([`Polyline::normal`]).
    #[inline(always)]
    pub(crate) fn normal(&self) -> Vec2 {
        self.t.perp()
    }
}

/// How far, relative to the ray's extent, the source and the receiver must lie from the
/// interface's line for the kernel (see [`FlatRefraction::solve`]). Above the classification's
/// `SIDE_MARGIN`: a ray the kernel solves always has its legs on the two sides (each leg's sine
/// with the line is at least this, as no leg is longer than the extent), so its status skips
/// the side test.
pub(crate) const CLEAR: f64 = 1e-9;
const _: () = assert!(super::classify::SIDE_MARGIN < CLEAR);

/// The slownesses the kernel takes (see [`FlatRefraction::solve`]).
const SLOWNESS: std::ops::RangeInclusive<f64> = 1e-15..=1e15;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::scene::{Scene, SolverOptions};
    use crate::trace::{Kernels, Status, Tracer};
    use crate::{Ray, Workspace};

    /// `T′(x)` of the ray from `s` to `r` refracting at `x` along the segment `o + x t`.
    /// (Relative to `o`: the coordinates are as far as 3e6 from the origin.)
    fn residual(o: Point, t: Vec2, w: [f64; 2], s: Point, r: Point, x: f64) -> f64 {
        let p = t * x;
        let (u0, u1) = (p - (s - o), (r - o) - p);
        w[0] * u0.dot(t) / u0.length() - w[1] * u1.dot(t) / u1.length()
    }

    /// The root of `T′` in `[0, len]` by bisection (`T′` increases: `T` is convex), to the
    /// last bit: an independent solution. `None` when it is not inside.
    fn bisection(o: Point, t: Vec2, len: f64, w: [f64; 2], s: Point, r: Point) -> Option<f64> {
        let f = |x| residual(o, t, w, s, r, x);
        let (mut lo, mut hi) = (0.0, len);
        if !(f(lo) < 0.0 && f(hi) > 0.0) {
            return None;
        }
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                return Some(mid);
            }
            if f(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }

    /// A random interface (anywhere, any direction, some 3e6 from the origin), random
    /// slownesses (either way round, up to a contrast of 25) and a source and a receiver on
    /// its two sides at random heights (1e-3 to 10 lengths).
    fn random_ray(rng: &mut SplitMix64) -> (Polyline, [f64; 2], Point, Point) {
        let mut u = || rng.next_f64();
        let far = if u() < 0.2 { 3e6 } else { 0.0 };
        let o = Point::new(far + 2e3 * (u() - 0.5), 2e3 * (u() - 0.5));
        let angle = std::f64::consts::TAU * u();
        let t = Vec2::new(angle.cos(), angle.sin());
        let len = 1.0 + 99.0 * u();
        let line = Polyline::new(vec![o, o + t * len], false).unwrap();
        let w = [0.2 + 4.8 * u(), 0.2 + 4.8 * u()];
        let height = |v: f64| len * 10f64.powf(-3.0 + 4.0 * v);
        let (hs, hr) = (height(u()), height(u()));
        let s = o + t * (len * (1.4 * u() - 0.2)) + t.perp() * hs;
        let r = o + t * (len * (1.4 * u() - 0.2)) - t.perp() * hr;
        (line, w, s, r)
    }

    #[test]
    fn the_kernel_solves_snells_law() {
        let opts = SolverOptions::default();
        let mut rng = SplitMix64(41);
        let (mut inside, mut solved, mut most) = (0, 0, 0);
        for i in 0..20_000 {
            let (line, w, s, r) = random_ray(&mut rng);
            let flat = FlatRefraction::of(&line, w, opts).unwrap();
            let (o, t, len) = (line.segment(0).start, line.tangent(0), line.length());
            let root = bisection(o, t, len, w, s, r);
            let clear = root.is_some_and(|x| x > 1e-3 * len && x < len * 0.999);
            inside += usize::from(clear);
            let Some(sol) = flat.solve(s, r) else {
                assert!(
                    !clear,
                    "ray {i}: root {root:?} inside, not solved by the kernel"
                );
                continue;
            };
            solved += 1;
            most = most.max(sol.iterations);
            // A solution is the one root, inside the segment, at the tolerance.
            let x = root.unwrap_or_else(|| panic!("ray {i}: solved without a root inside"));
            assert!(sol.s > 0.0 && sol.s < len, "ray {i}");
            assert!(
                (sol.s - x).abs() <= 1e-9 * (len + (s - r).length()),
                "ray {i}: {} vs bisection {x}",
                sol.s
            );
            // (Within the residual's own round-off: sines of ulps of the coordinates over the
            // legs' lengths.)
            let rel = residual(o, t, w, s, r, sol.s).abs() / (w[0] + w[1]);
            let reach = (s - o).length() + (r - o).length();
            let floor = 8.0 * f64::EPSILON * reach / sol.len[0].min(sol.len[1]);
            assert!(
                rel <= 1e-12 + floor,
                "ray {i}: Snell residual {rel} (round-off {floor:e}, lengths {:?}, reach {reach})",
                sol.len
            );
            // (Converged: at the tolerance, or with the step below round-off.)
            assert!(sol.residual <= opts.tolerance + floor, "ray {i}");
            let p = t * sol.s;
            let time = w[0] * (p - (s - o)).length() + w[1] * ((r - o) - p).length();
            // Round-off: of the coordinates relative to the segment's start (a short ray at
            // the far end of a long interface has lengths of a few ulps of those).
            let ulps = 8.0 * f64::EPSILON * (w[0] + w[1]) * ((s - o).length() + (r - o).length());
            assert!(
                (sol.time - time).abs() <= 1e-15 * time + ulps,
                "ray {i}: {} vs {time}",
                sol.time
            );
            let exact = t * x;
            let best = w[0] * (exact - (s - o)).length() + w[1] * ((r - o) - exact).length();
            assert!((sol.time - best).abs() <= 1e-15 * best + ulps, "ray {i}");
        }
        // The kernel takes the common case itself (at least every ray whose root lies clearly
        // inside: its ends are never closer to the line than 1e-3 of its length), and leaves
        // no ray without a root inside to the caller unsolved by mistake.
        assert!(inside > 15_000, "{inside}");
        assert!(solved >= inside, "{solved} solved, {inside} clearly inside");
        // (The most steps, as `MAX_STEPS` documents: grazing rays bisect their bracket a few
        // times.)
        assert!(most <= QUARTIC_STEPS + 15, "{most} steps");
    }

    /// At the edges of the scales and slownesses the kernel takes (`SLOWNESS`, and 1e-30 to
    /// 1e30 for the ray's extent), every power it forms stays finite (a debug build checks it
    /// at every step) and what it returns obeys Snell's law.
    #[test]
    fn the_kernel_stays_finite_at_its_bounds() {
        let opts = SolverOptions::default();
        let mut rng = SplitMix64(7);
        let mut solved = 0;
        for scale in [2e-30, 1e-15, 1.0, 1e15, 3e29] {
            for w in [
                [1e-15, 1e-15],
                [1e-15, 1e15],
                [1e15, 1e-15],
                [1e15, 1e15],
                [1.0, 1e15],
            ] {
                let line = Polyline::new(
                    vec![Point::new(0.0, 0.0), Point::new(0.1 * scale, 0.0)],
                    false,
                )
                .unwrap();
                let flat = FlatRefraction::of(&line, w, opts).unwrap();
                for _ in 0..200 {
                    let mut u = || rng.next_f64();
                    let s = Point::new(0.1 * scale * u(), 0.1 * scale * (0.01 + u()));
                    let r = Point::new(0.1 * scale * u(), -0.1 * scale * (0.01 + u()));
                    let Some(sol) = flat.solve(s, r) else {
                        continue;
                    };
                    solved += 1;
                    let (o, t) = (line.segment(0).start, line.tangent(0));
                    assert!(sol.s > 0.0 && sol.s < 0.1 * scale, "{scale:e} {w:?}");
                    assert!(sol.time.is_finite() && sol.time > 0.0, "{scale:e} {w:?}");
                    let rel = residual(o, t, w, s, r, sol.s).abs() / (w[0] + w[1]);
                    assert!(rel <= 1e-12, "{scale:e} {w:?}: Snell residual {rel:e}");
                }
            }
        }
        assert!(solved > 2_000, "{solved}");
    }

    /// The rays of `demo::air_water` converge after the two Halley steps alone, all but a few
    /// per thousand, to a relative residual of 1e-12 checked apart from the kernel.
    #[test]
    fn demo_rays_take_two_steps() {
        let scene = Scene::from_spec(&crate::demo::air_water(3000, 5)).unwrap();
        let line = &scene.interfaces()[0].polyline;
        let m = scene.paths()[0].media.as_deref().unwrap();
        let w = [scene.media()[m[0]].slowness, scene.media()[m[1]].slowness];
        let flat = FlatRefraction::of(line, w, scene.solver()).unwrap();
        let (o, t) = (line.segment(0).start, line.tangent(0));
        let source = scene.sources()[0];
        let mut more = 0;
        for &r in scene.receivers() {
            let sol = flat.solve(source, r).unwrap();
            let rel = residual(o, t, w, source, r, sol.s).abs() / (w[0] + w[1]);
            assert!(rel <= 1e-12, "{r:?}: {rel:e}");
            more += usize::from(sol.iterations > QUARTIC_STEPS);
        }
        assert!(
            more * 1000 <= 3 * scene.receivers().len(),
            "{more} rays took more steps"
        );
    }

    #[test]
    fn the_kernel_hands_over_what_it_does_not_solve() {
        let opts = SolverOptions::default();
        let line = Polyline::new(vec![Point::new(-1.0, 0.0), Point::new(2.0, 0.0)], false).unwrap();
        let flat = FlatRefraction::of(&line, [1.0, 1.333], opts).unwrap();
        let s = Point::new(0.0, 1.0);
        // Straight below: the normal itself, converged at once (a zero slope of the quartic).
        let sol = flat.solve(s, Point::new(0.0, -1.0)).unwrap();
        assert_eq!(sol.s, 1.0);
        assert_eq!(sol.time, 1.0 + 1.333);
        // On the line, on the same side, beyond the end, or with a NaN: the general solve's.
        for r in [
            Point::new(0.5, 0.0),
            Point::new(0.5, 1e-12),
            Point::new(0.5, 0.3),
            Point::new(40.0, -0.1),
            Point::new(f64::NAN, -1.0),
        ] {
            assert!(flat.solve(s, r).is_none(), "{r:?}");
        }
        // Beyond the scales and slownesses whose powers stay finite: the general solve's.
        let s_far = Point::new(0.0, 1e31);
        assert!(flat.solve(s_far, Point::new(0.5, -1e31)).is_none());
        assert!(
            flat.solve(Point::new(0.0, 1e-31), Point::new(0.5, -1e-31))
                .is_none()
        );
        assert!(FlatRefraction::of(&line, [1e-16, 1.0], opts).is_none());
        assert!(FlatRefraction::of(&line, [1.0, 2e15], opts).is_none());
        assert!(FlatRefraction::of(&line, [1e-15, 1e15], opts).is_some());
        // A closed polyline or one of two segments has no kernel.
        let two = Polyline::new(
            vec![
                Point::new(-1.0, 0.0),
                Point::new(0.5, 0.0),
                Point::new(2.0, 0.0),
            ],
            false,
        )
        .unwrap();
        assert!(FlatRefraction::of(&two, [1.0, 1.333], opts).is_none());
        // An iteration limit below the kernel's fixed steps leaves the rays to the general
        // solve; one at them allows only rays solved by those.
        let tight = |max_iterations| SolverOptions {
            max_iterations,
            ..opts
        };
        assert!(FlatRefraction::of(&line, [1.0, 1.333], tight(QUARTIC_STEPS - 1)).is_none());
        let grazing = Point::new(1.9, -0.05);
        let free = FlatRefraction::of(&line, [1.0, 1.333], opts).unwrap();
        assert!(free.solve(s, grazing).unwrap().iterations > QUARTIC_STEPS);
        let flat = FlatRefraction::of(&line, [1.0, 1.333], tight(QUARTIC_STEPS)).unwrap();
        assert!(flat.solve(s, grazing).is_none());
        let sol = flat.solve(s, Point::new(0.1, -0.5)).unwrap();
        assert_eq!(sol.iterations, QUARTIC_STEPS);
    }

    /// Every ray of `scene` with the kernel and without it (the one-interaction code's Newton
    /// steps, those of the general solve): the same statuses and reasons, times within 1e-12,
    /// points within 1e-9 of the scene's size. Returns how many the kernel solved.
    fn kernel_agrees(scene: &Scene) -> usize {
        let tracer = Tracer::new(scene).unwrap();
        let mut ws = Workspace::new();
        let mut rays: [Vec<Ray>; 2] = Default::default();
        for (kernels, out) in [Kernels::All, Kernels::BitExact].into_iter().zip(&mut rays) {
            let tracer = Tracer::new(scene).unwrap().with_kernels(kernels);
            for s in 0..scene.sources().len() {
                for r in 0..scene.receivers().len() {
                    for p in 0..scene.paths().len() {
                        out.push(tracer.trace(s, r, p, &mut ws));
                    }
                }
            }
        }
        let size = scene
            .receivers()
            .iter()
            .chain(scene.sources())
            .fold(1.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        let mut kernel = 0;
        for (i, (a, b)) in rays[0].iter().zip(&rays[1]).enumerate() {
            assert_eq!((a.status, a.reason), (b.status, b.reason), "ray {i}");
            assert_eq!(a.media, b.media, "ray {i}");
            if a.status.has_time() {
                let (ta, tb) = (a.time, b.time);
                assert!((ta - tb).abs() <= 1e-12 * tb, "ray {i}: {ta} vs {tb}");
                for (pa, pb) in a.points.iter().zip(&b.points) {
                    assert!((*pa - *pb).length() <= 1e-9 * size, "ray {i}");
                }
            }
            let (src, rcv) = (scene.sources()[a.source], scene.receivers()[a.receiver]);
            let flat = tracer.plan_of(a.path).flat();
            kernel += flat.and_then(|f| f.solve(src, rcv)).is_some() as usize;
        }
        kernel
    }

    #[test]
    fn the_kernel_agrees_with_the_general_solve() {
        let root = env!("CARGO_MANIFEST_DIR");
        let text = std::fs::read_to_string(format!("{root}/fixtures/bench/seed500.json")).unwrap();
        let seed = Scene::from_json(&text).unwrap();
        assert!(kernel_agrees(&seed) > 400);
        let demo = Scene::from_spec(&crate::demo::air_water(400, 9)).unwrap();
        assert!(kernel_agrees(&demo) > 300);
        // Receivers beyond the interface's end (no path) and beside a wall across the water
        // that some legs cross (obstructed): the statuses of the general solve.
        let scene = Scene::from_json(
            r#"{
            "media": { "air": { "index": 1.0 }, "glass": { "index": 1.5 } },
            "interfaces": {
                "face": { "points": [[0, 0], [4, 0]] },
                "wall": { "points": [[3, -0.2], [3, -3]] }
            },
            "sources": [[0.5, 1.0], [3.5, 2.0]],
            "receivers": [[1, -1], [2.5, -0.5], [3.5, -1], [6, -1], [-2, -0.1], [3.9, -2.5]],
            "paths": [{ "steps": [{ "refract": "face" }], "media": ["air", "glass"] }]
        }"#,
        )
        .unwrap();
        kernel_agrees(&scene);
        let tracer = Tracer::new(&scene).unwrap();
        let statuses: Vec<Status> = tracer.trace_all().iter().map(|r| r.status).collect();
        assert!(statuses.contains(&Status::Obstructed), "{statuses:?}");
        assert!(statuses.contains(&Status::NoPath), "{statuses:?}");
        assert!(statuses.contains(&Status::Converged), "{statuses:?}");
    }
}
