//! Amplitudes against closed forms written out here: the free field of a point, an
//! axisymmetric and a line source (the 2-D Green's function by its own asymptotic series),
//! image sources in rooms with absorbing walls, Lloyd's mirror, a plane fluid–fluid interface
//! (reflected and transmitted amplitudes, energy, the phase beyond the critical angle), the
//! Fresnel coefficients; the rays without a value (vertex, obstructed, converted), the
//! validation of the keys, and the same amplitudes from every way of tracing.

use std::f64::consts::PI;

use eigenray::amplitude::{Complex64, NoAmplitude};
use eigenray::{Amplitude, BatchOptions, Point, Scene, Status, Tracer, Workspace};

/// `|a − b| / |b|`.
fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// `|a − b| / |b|` of complex numbers.
fn crel(a: Complex64, b: Complex64) -> f64 {
    (a - b).norm() / b.norm()
}

/// Prints the largest relative error of a case (for the closing table) and checks it.
fn report(case: &str, worst: f64, bound: f64) {
    eprintln!("largest relative error, {case}: {worst:.3e}");
    assert!(worst <= bound, "{case}: {worst:e} > {bound:e}");
}

fn scene(json: &str) -> Scene {
    Scene::from_json(json).unwrap_or_else(|e| panic!("{e}"))
}

fn amplitude(ray: &eigenray::Ray) -> Amplitude {
    let a = ray.amplitude.expect("an amplitude");
    assert!(a.has_value(), "{:?}", a.reason);
    a
}

/// A homogeneous scene of speed 1500 with the source at `source`, receivers `receivers` and
/// the direct path, asking for `amplitudes`.
fn free_field(source: [f64; 2], receivers: &[[f64; 2]], amplitudes: &str) -> Scene {
    let receivers: Vec<String> = receivers
        .iter()
        .map(|r| format!("[{}, {}]", r[0], r[1]))
        .collect();
    scene(&format!(
        r#"{{ "media": {{ "w": {{ "speed": 1500 }} }},
             "sources": [[{}, {}]], "receivers": [{}],
             "paths": [{{ "steps": [], "media": ["w"] }}],
             "amplitudes": {amplitudes} }}"#,
        source[0],
        source[1],
        receivers.join(", ")
    ))
}

#[test]
fn the_free_field_of_a_point_source_is_one_over_four_pi_r() {
    let receivers: Vec<[f64; 2]> = (0..40)
        .map(|i| {
            let r = 0.5 * 1.37f64.powi(i);
            let a = 0.37 * i as f64;
            [r * a.cos().abs(), -50.0 + r * a.sin()]
        })
        .chain([[0.0, -150.0], [0.0, 10.0]])
        .collect();
    let mut worst: f64 = 0.0;
    for model in ["point", "axisymmetric"] {
        let s = free_field(
            [0.0, -50.0],
            &receivers,
            &format!(r#"{{"source": "{model}"}}"#),
        );
        for ray in Tracer::new(&s).unwrap().trace_all() {
            let a = amplitude(&ray);
            let r = ray.points[0].distance(ray.points[1]);
            let want = 1.0 / (4.0 * PI * r);
            worst = worst.max(rel(a.value.re, want)).max(rel(a.spreading, want));
            assert_eq!(a.value.im, 0.0);
            assert_eq!(a.coefficient, Complex64::new(1.0, 0.0));
            assert_eq!(a.attenuation_db, 0.0);
        }
    }
    report("free field, point and axisymmetric", worst, 1e-14);
}

/// `H₀⁽¹⁾(z)` by its Hankel asymptotic series (DLMF 10.17.5), summed until its terms stop
/// shrinking: accurate to round-off for `z` above about 20.
fn hankel0(z: f64) -> Complex64 {
    let mut sum = Complex64::new(0.0, 0.0);
    let mut a = 1.0; // a_m(0)
    let mut i_m = Complex64::new(1.0, 0.0);
    let mut last = f64::INFINITY;
    for m in 0..60 {
        let term = i_m * (a / z.powi(m));
        if term.norm() >= last {
            break;
        }
        last = term.norm();
        sum += term;
        let m1 = (m + 1) as f64;
        a *= -(2.0 * m1 - 1.0).powi(2) / (8.0 * m1);
        i_m *= Complex64::new(0.0, 1.0);
    }
    let phase = z - PI / 4.0;
    Complex64::new(phase.cos(), phase.sin()) * (2.0 / (PI * z)).sqrt() * sum
}

/// `J₀(z) = (1/π) ∫₀^π cos(z sin θ) dθ` by Simpson's rule.
fn bessel_j0(z: f64) -> f64 {
    let n = 20_000;
    let h = PI / n as f64;
    let f = |t: f64| (z * t.sin()).cos();
    let mut s = f(0.0) + f(PI);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0 / PI
}

#[test]
fn a_line_source_gives_the_far_field_of_the_2d_greens_function() {
    // The series itself, against J₀ by quadrature.
    for z in [25.0, 60.0, 300.0] {
        assert!((hankel0(z).re - bessel_j0(z)).abs() < 1e-12, "z = {z}");
    }
    let (f, c) = (250.0, 1500.0);
    let k = 2.0 * PI * f / c;
    let receivers: Vec<[f64; 2]> = (0..30)
        .map(|i| {
            let r = 20.0 * 1.2f64.powi(i);
            [r * (0.3 * i as f64).cos(), r * (0.3 * i as f64).sin()]
        })
        .collect();
    let s = free_field(
        [0.0, 0.0],
        &receivers,
        r#"{"source": "line", "frequency": 250}"#,
    );
    let (mut worst, mut worst_series): (f64, f64) = (0.0, 0.0);
    for ray in Tracer::new(&s).unwrap().trace_all() {
        let a = amplitude(&ray);
        let r = ray.points[1].distance(Point::new(0.0, 0.0));
        let kr = k * r;
        // The far field of (i/4) H₀⁽¹⁾(kR) without e^{ikR}: e^{iπ/4} / √(8π kR).
        let far = Complex64::new(0.5f64.sqrt(), 0.5f64.sqrt()) / (8.0 * PI * kr).sqrt();
        worst = worst.max(crel(a.value, far));
        assert!(rel(a.spreading, 1.0 / (8.0 * PI * kr).sqrt()) < 1e-14);
        // The whole Green's function differs by its first correction, i/(8kR), and less.
        let phase = Complex64::new(
            (ray.time * 2.0 * PI * f).cos(),
            (ray.time * 2.0 * PI * f).sin(),
        );
        let exact = Complex64::new(0.0, 0.25) * hankel0(kr);
        let off = crel(a.value * phase, exact);
        worst_series = worst_series.max(off * 8.0 * kr);
        assert!(
            off <= 1.0 / (8.0 * kr) * 1.01 && off >= 1.0 / (8.0 * kr) * 0.98,
            "kR {kr}"
        );
    }
    report("free field, line source (far field)", worst, 1e-14);
    eprintln!("line source: |ray − (i/4)H₀| · 8kR at most {worst_series:.4}");
}

/// `p` mirrored in the line through `a` and `b`.
fn mirror(p: Point, a: Point, b: Point) -> Point {
    let t = (b - a) * (1.0 / a.distance(b));
    let d = p - a;
    let along = t * d.dot(t);
    a + (along - (d - along))
}

/// A room of one interface per wall, each with its absorption, every arrival of up to three
/// reflections against `Π √(1 − αᵢ) / (4π L)` with `L` the distance from the image source
/// (the source mirrored in each wall's line in turn). Returns the largest relative error.
fn image_sources(walls: &[([f64; 2], [f64; 2], f64)], source: [f64; 2], receivers: &str) -> f64 {
    let interfaces: Vec<String> = walls
        .iter()
        .enumerate()
        .map(|(i, (a, b, alpha))| {
            format!(
                r#""w{i}": {{ "points": [[{}, {}], [{}, {}]], "reflection": {{ "absorption": {alpha} }} }}"#,
                a[0], a[1], b[0], b[1]
            )
        })
        .collect();
    let s = scene(&format!(
        r#"{{ "media": {{ "air": {{ "speed": 343 }} }}, "background": "air",
             "interfaces": {{ {} }},
             "sources": [[{}, {}]], "receivers": {receivers},
             "search": {{ "max_steps": 3, "refract": false }},
             "amplitudes": {{ "source": "point" }} }}"#,
        interfaces.join(", "),
        source[0],
        source[1]
    ));
    let arrivals = Tracer::new(&s)
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    assert!(arrivals.len() > 20);
    let mut worst: f64 = 0.0;
    for arr in &arrivals {
        let a = arr.arrival.amplitude.expect("amplitude");
        assert!(a.has_value(), "{:?}", a.reason);
        let mut image = Point::new(source[0], source[1]);
        let mut damping = 1.0;
        for step in &arr.steps {
            let (p, q, alpha) = walls[step.interface];
            image = mirror(image, Point::new(p[0], p[1]), Point::new(q[0], q[1]));
            damping *= (1.0 - alpha).sqrt();
        }
        let receiver = s.receivers()[arr.receiver];
        let l = image.distance(receiver);
        let want = damping / (4.0 * PI * l);
        worst = worst.max(rel(a.value.re, want));
        assert_eq!(a.value.im, 0.0);
        assert!(rel(arr.arrival.time, l / 343.0) < 1e-12);
    }
    worst
}

#[test]
fn image_sources_in_rooms_with_absorbing_walls() {
    // Interfaces are named in order, w0 … w9: their indices are their places in `walls`.
    let rectangle = [
        ([0.0, 0.0], [6.0, 0.0], 0.1),
        ([6.0, 0.0], [6.0, 4.0], 0.3),
        ([6.0, 4.0], [0.0, 4.0], 0.5),
        ([0.0, 4.0], [0.0, 0.0], 0.2),
    ];
    let a = image_sources(
        &rectangle,
        [1.2, 0.9],
        "[[4.5, 3.1], [2.0, 2.5], [5.1, 0.4]]",
    );
    let pentagon = [
        ([0.0, 0.0], [7.0, 0.0], 0.05),
        ([7.0, 0.0], [8.0, 5.0], 0.6),
        ([8.0, 5.0], [3.0, 7.0], 0.25),
        ([3.0, 7.0], [-1.0, 4.0], 0.9),
        ([-1.0, 4.0], [0.0, 0.0], 0.4),
    ];
    let b = image_sources(
        &pentagon,
        [2.0, 2.0],
        "[[5.0, 4.0], [1.0, 3.5], [6.5, 1.0]]",
    );
    report("image sources, two rooms", a.max(b), 1e-13);
}

#[test]
fn lloyds_mirror_over_range() {
    // A pressure-release sea surface, the source 30 m and the receivers 60 m deep.
    let (c, f) = (1500.0, 100.0);
    let k = 2.0 * PI * f / c;
    let receivers: Vec<String> = (0..400)
        .map(|i| format!("[{}, -60]", 20.0 + 12.5 * i as f64))
        .collect();
    let s = scene(&format!(
        r#"{{ "media": {{ "w": {{ "speed": {c} }} }},
             "interfaces": {{ "surface": {{ "points": [[-100, 0], [10000, 0]],
                                           "reflection": "pressure-release" }} }},
             "sources": [[0, -30]], "receivers": [{}],
             "paths": [{{ "steps": [], "media": ["w"] }},
                       {{ "steps": [{{ "reflect": "surface" }}], "media": ["w", "w"] }}],
             "amplitudes": {{ "source": "point", "frequency": {f} }} }}"#,
        receivers.join(", ")
    ));
    let rays = Tracer::new(&s).unwrap().trace_all();
    let (mut worst, mut worst_level): (f64, f64) = (0.0, 0.0);
    for pair in rays.chunks(2) {
        let rx = s.receivers()[pair[0].receiver];
        let sum: Complex64 = pair
            .iter()
            .map(|r| {
                let w = 2.0 * PI * f * r.time;
                amplitude(r).value * Complex64::new(w.cos(), w.sin())
            })
            .sum();
        let (r1, r2) = (
            rx.distance(Point::new(0.0, -30.0)),
            rx.distance(Point::new(0.0, 30.0)),
        );
        let e = |r: f64| Complex64::new((k * r).cos(), (k * r).sin()) / r;
        let exact = (e(r1) - e(r2)) / (4.0 * PI);
        let scale = (1.0 / r1 + 1.0 / r2) / (4.0 * PI);
        worst = worst.max((sum - exact).norm() / scale);
        if exact.norm() > 0.05 * scale {
            worst_level = worst_level.max(rel(sum.norm(), exact.norm()));
        }
    }
    report("Lloyd's mirror, coherent sum (of the scale)", worst, 1e-11);
    report(
        "Lloyd's mirror, |p| away from the nulls",
        worst_level,
        1e-10,
    );
}

/// Water over a faster sediment (a critical angle) for the plane-interface tests.
const WATER: (f64, f64) = (1500.0, 1000.0);
const SEDIMENT: (f64, f64) = (1700.0, 1800.0);

/// The plane-wave coefficients from medium 1 to medium 2 (speed, density) at incidence
/// `theta`: `(R, T, cos θ₂)` as the contract writes them.
fn fluid_coefficients(
    m1: (f64, f64),
    m2: (f64, f64),
    theta: f64,
) -> (Complex64, Complex64, Complex64) {
    let (z1, z2) = (m1.0 * m1.1, m2.0 * m2.1);
    let q = (m2.0 / m1.0 * theta.sin()).powi(2);
    let cos2 = if q <= 1.0 {
        Complex64::new((1.0 - q).sqrt(), 0.0)
    } else {
        Complex64::new(0.0, (q - 1.0).sqrt())
    };
    let cos1 = theta.cos();
    let den = z2 * cos1 + cos2 * z1;
    (
        (z2 * cos1 - cos2 * z1) / den,
        Complex64::new(2.0 * z2 * cos1, 0.0) / den,
        cos2,
    )
}

/// The interface scene: water above y = 0, sediment below, the source at (0, h₁).
fn interface_scene(h1: f64, receivers: &[[f64; 2]], model: &str) -> Scene {
    let receivers: Vec<String> = receivers
        .iter()
        .map(|r| format!("[{}, {}]", r[0], r[1]))
        .collect();
    scene(&format!(
        r#"{{ "media": {{ "water": {{ "speed": {}, "density": {}, "at": [0, 10] }},
                         "sediment": {{ "speed": {}, "density": {}, "at": [0, -10] }} }},
             "domain": [[-10000, -10000], [10000, 10000]],
             "interfaces": {{ "bottom": {{ "points": [[-10000, 0], [10000, 0]], "reflection": "media" }} }},
             "sources": [[0, {h1}]], "receivers": [{}],
             "paths": [{{ "steps": [{{ "reflect": "bottom" }}] }},
                       {{ "steps": [{{ "refract": "bottom" }}] }}],
             "amplitudes": {{ "source": "{model}" }} }}"#,
        WATER.0,
        WATER.1,
        SEDIMENT.0,
        SEDIMENT.1,
        receivers.join(", ")
    ))
}

/// The incidence `θ₁` of the ray from `(0, h₁)` through `y = 0` to `(x, −h₂)`, by bisection on
/// `h₁ tan θ₁ + h₂ tan θ₂ = x` with Snell's law.
fn transmitted_angle(h1: f64, h2: f64, x: f64) -> f64 {
    let ratio = SEDIMENT.0 / WATER.0;
    let reach = |t1: f64| {
        let s2: f64 = ratio * t1.sin();
        h1 * t1.tan() + h2 * s2 / (1.0 - s2 * s2).sqrt()
    };
    let (mut lo, mut hi) = (0.0, (1.0 / ratio).asin());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if reach(mid) < x { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

#[test]
fn a_plane_interface_against_the_two_half_space_closed_forms() {
    let (h1, h2) = (100.0, 80.0);
    // Reflected: incidences from 5° to 85° (the critical angle is 61.9°); transmitted:
    // offsets below the critical angle.
    let degrees: Vec<f64> = (1..=17).map(|i| 5.0 * i as f64).collect();
    let offsets: Vec<f64> = (1..=25).map(|i| 12.0 * i as f64 * 1.1f64.powi(i)).collect();
    let mut receivers: Vec<[f64; 2]> = degrees
        .iter()
        .map(|d| [2.0 * h1 * d.to_radians().tan(), h1])
        .collect();
    receivers.extend(offsets.iter().map(|&x| [x, -h2]));
    let mut worst: f64 = 0.0;
    for model in ["point", "axisymmetric"] {
        let s = interface_scene(h1, &receivers, model);
        let rays = Tracer::new(&s).unwrap().trace_all();
        for (i, d) in degrees.iter().enumerate() {
            let ray = &rays[2 * i];
            assert_eq!(ray.status, Status::Converged);
            let (r, _, _) = fluid_coefficients(WATER, SEDIMENT, d.to_radians());
            let l = 2.0 * h1 / d.to_radians().cos();
            worst = worst.max(crel(amplitude(ray).value, r / (4.0 * PI * l)));
        }
        for (j, &x) in offsets.iter().enumerate() {
            let ray = &rays[2 * (degrees.len() + j) + 1];
            assert_eq!(ray.status, Status::Converged);
            let t1 = transmitted_angle(h1, h2, x);
            let (_, t, cos2) = fluid_coefficients(WATER, SEDIMENT, t1);
            // dX/dθ₁ at fixed depths, dθ₂/dθ₁ = (c₂ cos θ₁)/(c₁ cos θ₂) by Snell's law.
            let c2 = cos2.re;
            let dx =
                h1 / t1.cos().powi(2) + h2 / (c2 * c2) * (SEDIMENT.0 * t1.cos()) / (WATER.0 * c2);
            let want = t / (4.0 * PI) * (t1.sin() / (t1.cos() * x * dx)).sqrt();
            worst = worst.max(crel(amplitude(ray).value, want));
        }
    }
    report("plane interface, reflected and transmitted", worst, 1e-11);
}

#[test]
fn plane_interface_energy_and_the_phase_beyond_the_critical_angle() {
    let (h1, h2) = (100.0, 80.0);
    let ratio = SEDIMENT.0 / WATER.0;
    let below: Vec<f64> = (1..=12).map(|i| (5.0 * i as f64).to_radians()).collect();
    let mut receivers = Vec::new();
    for &t1 in &below {
        let s2 = ratio * t1.sin();
        let x = h1 * t1.tan();
        receivers.push([2.0 * x, h1]);
        receivers.push([x + h2 * s2 / (1.0 - s2 * s2).sqrt(), -h2]);
    }
    let s = interface_scene(h1, &receivers, "point");
    let rays = Tracer::new(&s).unwrap().trace_all();
    let (z1, z2) = (WATER.0 * WATER.1, SEDIMENT.0 * SEDIMENT.1);
    let mut worst: f64 = 0.0;
    for (i, &t1) in below.iter().enumerate() {
        let r = amplitude(&rays[4 * i]).coefficient;
        let tray = &rays[4 * i + 3];
        let t = amplitude(tray).coefficient;
        let cos2 =
            (tray.points[2] - tray.points[1]).y.abs() / tray.points[1].distance(tray.points[2]);
        let energy = r.norm_sqr() + (z1 * cos2) / (z2 * t1.cos()) * t.norm_sqr();
        worst = worst.max((energy - 1.0).abs());
    }
    report(
        "plane interface, energy below the critical angle",
        worst,
        1e-12,
    );
    // Beyond it: |R| = 1 with the phase −2 atan(Z₁ b / (Z₂ cos θ₁)).
    let beyond: Vec<f64> = (0..10)
        .map(|i| (63.0 + 2.5 * i as f64).to_radians())
        .collect();
    let receivers: Vec<[f64; 2]> = beyond.iter().map(|t| [2.0 * h1 * t.tan(), h1]).collect();
    let s = interface_scene(h1, &receivers, "point");
    let rays = Tracer::new(&s).unwrap().trace_all();
    let mut worst_phase: f64 = 0.0;
    for (i, &t1) in beyond.iter().enumerate() {
        let r = amplitude(&rays[2 * i]).coefficient;
        assert!((r.norm() - 1.0).abs() < 1e-14, "{}", r.norm());
        let b = ((ratio * t1.sin()).powi(2) - 1.0).sqrt();
        let phase = -2.0 * (z1 * b / (z2 * t1.cos())).atan();
        worst_phase = worst_phase.max((r.arg() - phase).abs() / phase.abs());
    }
    report(
        "plane interface, phase beyond the critical angle",
        worst_phase,
        1e-11,
    );
}

#[test]
fn fresnel_coefficients_of_index_media() {
    // Air over glass: r and t of s and p against their formulas, the energy they carry, and
    // Brewster's angle, which zeroes r_p.
    let (n1, n2) = (1.0, 1.5);
    // Reflection against glass needs the region across: glass fills y < 0.
    let make = |pol: &str, receivers: &str| {
        scene(&format!(
            r#"{{ "media": {{ "air": {{ "index": {n1}, "at": [0, 50] }}, "glass": {{ "index": {n2}, "at": [0, -50] }} }},
                 "interfaces": {{ "face": {{ "points": [[-100, 0], [100, 0]], "reflection": "media" }} }},
                 "domain": [[-100, -100], [100, 100]],
                 "sources": [[0, 1]], "receivers": {receivers},
                 "paths": [{{ "steps": [{{ "reflect": "face" }}] }}, {{ "steps": [{{ "refract": "face" }}] }}],
                 "amplitudes": {{ "source": "point", "polarization": "{pol}" }} }}"#
        ))
    };
    let mut worst: f64 = 0.0;
    for pol in ["s", "p"] {
        for t1 in (1..=8).map(|i| (10.0 * i as f64).to_radians()) {
            let x = t1.tan();
            let sin2: f64 = n1 / n2 * t1.sin();
            let xt = x + sin2 / (1.0 - sin2 * sin2).sqrt();
            let s = make(pol, &format!("[[{}, 1], [{xt}, -1]]", 2.0 * x));
            let rays = Tracer::new(&s).unwrap().trace_all();
            let (r, t) = (
                amplitude(&rays[0]).coefficient,
                amplitude(&rays[3]).coefficient,
            );
            let (c1, c2) = (t1.cos(), (1.0 - sin2 * sin2).sqrt());
            let (want_r, want_t) = if pol == "s" {
                (
                    (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2),
                    2.0 * n1 * c1 / (n1 * c1 + n2 * c2),
                )
            } else {
                (
                    (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2),
                    2.0 * n1 * c1 / (n2 * c1 + n1 * c2),
                )
            };
            worst = worst.max((r.re - want_r).abs()).max(rel(t.re, want_t));
            // Energy: |r|² + (n₂ cos θ₂)/(n₁ cos θ₁) |t|² = 1, for both polarizations.
            let energy = r.norm_sqr() + (n2 * c2) / (n1 * c1) * t.norm_sqr();
            worst = worst.max((energy - 1.0).abs());
        }
    }
    // Brewster's angle: no p reflection.
    let tb = (n2 / n1).atan();
    let s = make("p", &format!("[[{}, 1]]", 2.0 * tb.tan()));
    let rays = Tracer::new(&s).unwrap().trace_all();
    assert!(amplitude(&rays[0]).coefficient.norm() < 1e-14);
    report("Fresnel s and p", worst, 1e-11);
}

#[test]
fn attenuation_adds_decibels_along_the_legs() {
    let s = scene(
        r#"{ "media": { "a": { "speed": 1, "attenuation": 0.5 }, "b": { "speed": 2, "attenuation": 0.25 } },
             "interfaces": { "s": { "points": [[-50, 0], [50, 0]] } },
             "sources": [[0, 3]], "receivers": [[4, -5]],
             "paths": [{ "steps": [{ "refract": "s" }], "media": ["a", "b"] }],
             "amplitudes": { "source": "point" } }"#,
    );
    let ray = &Tracer::new(&s).unwrap().trace_all()[0];
    let a = amplitude(ray);
    let (l0, l1) = (
        ray.points[0].distance(ray.points[1]),
        ray.points[1].distance(ray.points[2]),
    );
    let db = 0.5 * l0 + 0.25 * l1;
    assert!(rel(a.attenuation_db, db) < 1e-14);
    let want = a.spreading * a.coefficient.re * 10f64.powf(-db / 20.0);
    assert!(rel(a.value.re, want) < 1e-14);
}

#[test]
fn paths_without_a_ray_theory_amplitude_say_why() {
    // A valley: two specular points and a vertex (edge-held) arrival; a converted reflection;
    // an obstructed direct ray.
    let s = scene(
        r#"{ "media": { "air": { "speed": 1 }, "rock": { "speed": 2 } },
             "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] },
                             "screen": { "points": [[0, 1.5], [0, 2.5]] },
                             "ceiling": { "points": [[-9, 5], [9, 5]] } },
             "sources": [[-0.5, 2]], "receivers": [[0.5, 2]],
             "paths": [{ "steps": [{ "reflect": "valley" }], "media": ["air", "air"] },
                       { "steps": [{ "reflect": "ceiling" }], "media": ["air", "rock"] },
                       { "steps": [], "media": ["air"] }],
             "solver": { "stationary": "all" },
             "amplitudes": { "source": "point" } }"#,
    );
    let tracer = Tracer::new(&s).unwrap();
    let rays = tracer
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
    let valley = &rays.triples[0].arrivals;
    assert_eq!(valley.len(), 3);
    for a in &valley[..2] {
        assert!(a.amplitude.unwrap().has_value());
    }
    let vertex = valley[2].amplitude.unwrap();
    assert_eq!(valley[2].status, Status::Vertex);
    assert_eq!(vertex.reason, Some(NoAmplitude::Vertex));
    assert!(vertex.value.re.is_nan() && vertex.spreading.is_nan());
    let converted = rays.triples[1].arrivals[0].amplitude.unwrap();
    assert_eq!(
        converted.reason,
        Some(NoAmplitude::ConvertedReflection { step: 0 })
    );
    assert!(converted.value.re.is_nan() && converted.coefficient.im.is_nan());
    assert!(converted.spreading > 0.0 && converted.attenuation_db == 0.0);
    let direct = &rays.triples[2].arrivals[0];
    assert_eq!(direct.status, Status::Obstructed);
    assert_eq!(
        direct.amplitude.unwrap().reason,
        Some(NoAmplitude::Obstructed)
    );
    // One by one: the same.
    let one = tracer.trace_all();
    assert_eq!(one[1].amplitude.unwrap().reason, converted.reason);
    // Without a time, no amplitude at all.
    let mut ws = Workspace::new();
    let rec = tracer.solve(Point::new(-0.5, 2.0), Point::new(50.0, 2.0), 0, &mut ws);
    assert!(!rec.status.has_time());
    assert_eq!(tracer.amplitude(0, &rec, &ws), None);
}

#[test]
fn every_way_of_tracing_gives_the_same_amplitudes() {
    let mut spec = eigenray::demo::dipping_stack(6, 60);
    spec.amplitudes = Some(eigenray::scene::AmplitudesSpec::new(
        eigenray::scene::SourceModel::Point,
    ));
    let s = Scene::from_spec(&spec).unwrap();
    let tracer = Tracer::new(&s).unwrap();
    let one = tracer.trace_all();
    let cold = tracer
        .trace_batch(
            &BatchOptions {
                warm_start: false,
                ..BatchOptions::default()
            },
            &eigenray::options::Run::new(),
        )
        .unwrap();
    for (i, ray) in one.iter().enumerate() {
        assert_eq!(cold.amplitude(i), ray.amplitude.as_ref(), "ray {i}");
        assert_eq!(cold.ray(i).amplitude, ray.amplitude);
    }
    // Warm starts end at other points of the tolerance ball: the same to its worth.
    let warm = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    for (i, ray) in one.iter().enumerate() {
        let (a, b) = (warm.amplitude(i).unwrap(), ray.amplitude.unwrap());
        assert!(crel(a.value, b.value) < 1e-10, "ray {i}");
    }
    // Every stationary path and a scene without amplitudes.
    let stationary = tracer
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
    for (t, ray) in stationary.triples.iter().zip(&one) {
        let a = t.arrivals[0].amplitude.unwrap();
        assert!(crel(a.value, ray.amplitude.unwrap().value) < 1e-10);
    }
    let plain = Scene::from_spec(&eigenray::demo::dipping_stack(6, 20)).unwrap();
    let tracer = Tracer::new(&plain).unwrap();
    assert!(tracer.trace_all().iter().all(|r| r.amplitude.is_none()));
    assert!(
        tracer
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap()
            .amplitude(0)
            .is_none()
    );
}

#[test]
fn amplitude_keys_are_validated_with_their_keys() {
    let base = |media: &str, interfaces: &str, extra: &str| {
        format!(
            r#"{{ "media": {{ {media} }}, "interfaces": {{ {interfaces} }},
                 "sources": [[1, 1]], "receivers": [[2, 1]],
                 "paths": [{{ "steps": [], "media": ["a"] }}] {extra} }}"#
        )
    };
    let wall = r#""wall": { "points": [[0, 0], [5, 0]] }"#;
    let cases = [
        (
            base(r#""a": { "speed": 1, "density": 0 }"#, wall, ""),
            "media.a.density",
        ),
        (
            base(r#""a": { "speed": 1, "density": -2 }"#, wall, ""),
            "media.a.density",
        ),
        (
            base(r#""a": { "speed": 1, "attenuation": -1 }"#, wall, ""),
            "media.a.attenuation",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                r#""wall": { "points": [[0, 0], [5, 0]], "reflection": { "absorption": 1.5 } }"#,
                "",
            ),
            "interfaces.wall.reflection.absorption",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                r#""wall": { "points": [[0, 0], [5, 0]], "reflection": { "coefficient": -2 } }"#,
                "",
            ),
            "interfaces.wall.reflection.coefficient",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                r#""wall": { "points": [[0, 0], [5, 0]], "reflection": "soft" }"#,
                "",
            ),
            "interfaces.wall.reflection",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                r#""wall": { "points": [[0, 0], [5, 0]], "reflection": "media" }"#,
                r#", "amplitudes": { "source": "point" }"#,
            ),
            "interfaces.wall.reflection",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "line" }"#,
            ),
            "amplitudes.frequency",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "line", "frequency": 0 }"#,
            ),
            "amplitudes.frequency",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "sphere" }"#,
            ),
            "amplitudes.source",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "point", "polarization": "q" }"#,
            ),
            "amplitudes.polarization",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "frequency": 1 }"#,
            ),
            "amplitudes.source",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "point", "loud": 1 }"#,
            ),
            "amplitudes",
        ),
        (
            base(
                r#""a": { "speed": 1 }, "b": { "index": 1.5 }"#,
                wall,
                r#", "amplitudes": { "source": "point" }"#,
            ),
            "media.b",
        ),
        (
            base(
                r#""a": { "speed": 1 }"#,
                wall,
                r#", "amplitudes": { "source": "axisymmetric" }"#,
            ),
            "sources[0]",
        ),
    ];
    for (text, key) in cases {
        let e = Scene::from_json(&text).expect_err(key);
        assert!(e.key.starts_with(key), "{key}: {e}");
    }
    // Without `amplitudes`, a `media` law needs no regions.
    assert!(
        Scene::from_json(&base(
            r#""a": { "speed": 1 }, "b": { "speed": 0.5 }"#,
            wall,
            ""
        ))
        .is_ok()
    );
    // An axisymmetric scene refuses a source moved off its axis.
    let mut s = scene(
        &base(
            r#""a": { "speed": 1 }"#,
            wall,
            r#", "amplitudes": { "source": "axisymmetric" }"#,
        )
        .replace("[[1, 1]]", "[[0, 1]]"),
    );
    let e = s.set_source(0, Point::new(0.5, 1.0)).unwrap_err();
    assert_eq!(e.key, "sources[0]");
    s.set_source(0, Point::new(0.0, 2.0)).unwrap();
}

#[test]
fn the_builder_writes_the_amplitude_keys() {
    use eigenray::scene::{AmplitudesSpec, Polarization, ReflectionSpec, SourceModel};
    use eigenray::{InterfaceSpec, MediumSpec, PathSpec, StepSpec};
    let built = Scene::builder()
        .medium(
            "w",
            MediumSpec::speed(1500.0).density(1000.0).attenuation(0.01),
        )
        .interface(
            "surface",
            InterfaceSpec::open([[-10.0, 0.0], [10.0, 0.0]])
                .reflection(ReflectionSpec::PressureRelease),
        )
        .interface(
            "wall",
            InterfaceSpec::open([[20.0, -10.0], [20.0, 10.0]])
                .reflection(ReflectionSpec::Absorption(0.3)),
        )
        .source([0.0, -5.0])
        .receiver([3.0, -4.0])
        .path(PathSpec::new([StepSpec::reflect("surface")]).media(["w", "w"]))
        .amplitudes(
            AmplitudesSpec::new(SourceModel::Line)
                .frequency(50.0)
                .polarization(Polarization::P),
        );
    let json = r#"{ "media": { "w": { "speed": 1500, "density": 1000, "attenuation": 0.01 } },
        "interfaces": { "surface": { "points": [[-10, 0], [10, 0]], "reflection": "pressure-release" },
                        "wall": { "points": [[20, -10], [20, 10]], "reflection": { "absorption": 0.3 } } },
        "sources": [[0, -5]], "receivers": [[3, -4]],
        "paths": [{ "steps": [{ "reflect": "surface" }], "media": ["w", "w"] }],
        "amplitudes": { "source": "line", "frequency": 50, "polarization": "p" } }"#;
    let read = eigenray::SceneSpec::from_json(json).unwrap();
    let text = |s: &eigenray::SceneSpec| serde_json::to_string(s).unwrap();
    assert_eq!(text(built.spec()), text(&read));
    let s = built.build().unwrap();
    let a = s.amplitudes().unwrap();
    assert_eq!(a.reflection[0], eigenray::scene::Reflection::Fixed(-1.0));
    assert_eq!(
        a.reflection[1],
        eigenray::scene::Reflection::Fixed((1.0f64 - 0.3).sqrt())
    );
    let ray = &Tracer::new(&s).unwrap().trace_all()[0];
    assert!(amplitude(ray).coefficient.re < 0.0);
}

/// A scene with every kind of entry: converged rays with amplitudes, a converted reflection
/// (spreading, no value), an obstructed ray (no value), rays without a time; and a search.
const OUTPUT_SCENE: &str = r#"{
    "media": { "air": { "speed": 343 }, "slow": { "speed": 200 } },
    "background": "air",
    "interfaces": { "floor": { "points": [[-10, 0], [10, 0]], "reflection": { "absorption": 0.19 } },
                    "screen": { "points": [[2, 0.5], [2, 3]] } },
    "sources": [[0, 1]], "receivers": [[1, 2], [4, 1]],
    "paths": [{ "steps": [], "media": ["air"] },
              { "steps": [{ "reflect": "floor" }], "media": ["air", "air"] },
              { "steps": [{ "reflect": "floor" }], "media": ["air", "slow"] },
              { "steps": [{ "reflect": "screen" }], "media": ["air", "air"] }],
    "search": { "max_steps": 1, "refract": false, "obstructed": true },
    "amplitudes": { "source": "point", "frequency": 1000 }
}"#;

#[test]
fn every_format_writes_the_amplitudes() {
    use eigenray::{Format, write};
    let s = scene(OUTPUT_SCENE);
    let tracer = Tracer::new(&s).unwrap();
    let rays = tracer.trace_all();
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let written = |doc: eigenray::Document<'_>, format| {
        let mut out = Vec::new();
        write(&s, doc, format, &mut out).unwrap();
        out
    };
    // JSON: the numbers of the rays, `null` and a reason where there is none.
    let json: serde_json::Value =
        serde_json::from_slice(&written((&rays).into(), Format::Json)).unwrap();
    assert_eq!(
        written((&batch).into(), Format::Json),
        written((&rays).into(), Format::Json)
    );
    let mut reasons = 0;
    for (entry, ray) in json["rays"].as_array().unwrap().iter().zip(&rays) {
        let Some(a) = ray.amplitude else {
            assert!(entry.get("amplitude").is_none() && entry.get("spreading").is_none());
            continue;
        };
        if a.has_value() {
            assert_eq!(entry["amplitude"][0].as_f64().unwrap(), a.value.re);
            assert_eq!(entry["amplitude"][1].as_f64().unwrap(), a.value.im);
            assert_eq!(entry["coefficient"][0].as_f64().unwrap(), a.coefficient.re);
            assert_eq!(entry["spreading"].as_f64().unwrap(), a.spreading);
            assert_eq!(entry["attenuation_db"].as_f64().unwrap(), a.attenuation_db);
            assert!(entry.get("amplitude_reason").is_none());
        } else {
            reasons += 1;
            assert!(entry["amplitude"].is_null() && entry["coefficient"].is_null());
            assert_eq!(entry["amplitude_reason"], a.reason.unwrap().to_string());
            assert_eq!(
                entry["spreading"].as_f64(),
                a.spreading.is_finite().then_some(a.spreading)
            );
        }
    }
    assert!(reasons >= 2, "{reasons}");
    // JSON Lines: the same objects, then the search's arrivals with theirs.
    let arrivals = tracer
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    let both = eigenray::Document::from(&rays).with_arrivals(&arrivals);
    let lines = String::from_utf8(written(both, Format::Jsonl)).unwrap();
    let marked: Vec<serde_json::Value> = lines
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .filter(|v: &serde_json::Value| v["kind"] == "arrival")
        .collect();
    assert_eq!(marked.len(), arrivals.len());
    for (v, a) in marked.iter().zip(&arrivals) {
        let amp = a.arrival.amplitude.unwrap();
        match amp.reason {
            None => assert_eq!(v["amplitude"][0].as_f64().unwrap(), amp.value.re),
            Some(r) => assert_eq!(v["amplitude_reason"], r.to_string()),
        }
    }
    // CSV: five more columns.
    let csv = String::from_utf8(written((&rays).into(), Format::Csv)).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(
        header.ends_with("reason,amplitude,spreading,coefficient,attenuation_db,amplitude_reason")
    );
    for (line, ray) in lines.zip(&rays) {
        let cols: Vec<&str> = line.rsplitn(6, ',').collect();
        let (amplitude, spreading) = (cols[4], cols[3]);
        match ray.amplitude {
            Some(a) if a.has_value() => {
                let parts: Vec<f64> = amplitude.split(' ').map(|v| v.parse().unwrap()).collect();
                assert_eq!(parts, [a.value.re, a.value.im]);
                assert_eq!(spreading.parse::<f64>().unwrap(), a.spreading);
            }
            Some(a) => assert_eq!(cols[0], a.reason.unwrap().to_string().as_str()),
            None => assert_eq!(&cols[..5], ["", "", "", "", ""]),
        }
    }
    let arrivals_csv = String::from_utf8(written((&arrivals).into(), Format::Csv)).unwrap();
    assert!(
        arrivals_csv
            .lines()
            .next()
            .unwrap()
            .ends_with("complete,amplitude,spreading,coefficient,attenuation_db,amplitude_reason")
    );
    // .npy: the fields after the others, NaN and a reason's code where there is no value.
    let npy = written((&batch).into(), Format::Npy);
    let len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
    let dict = std::str::from_utf8(&npy[10..10 + len]).unwrap();
    assert!(dict.contains("('amplitude', '<f8', (2,)), ('spreading', '<f8'), ('coefficient', '<f8', (2,)), ('attenuation_db', '<f8'), ('amplitude_reason', '|u1')"), "{dict}");
    let (p, l) = (3, 2);
    let size = 3 * 4 + 1 + 4 + 8 + 8 + 16 * p + 4 * l + 6 * 8 + 1;
    let data = &npy[10 + len..];
    assert_eq!(data.len(), rays.len() * size);
    let f64_at = |r: &[u8], at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap());
    for (r, ray) in data.chunks(size).zip(&rays) {
        let base = 33 + 16 * p + 4 * l;
        let code = r[size - 1];
        match ray.amplitude {
            Some(a) if a.has_value() => {
                assert_eq!(f64_at(r, base), a.value.re);
                assert_eq!(f64_at(r, base + 16), a.spreading);
                assert_eq!(code, 0);
            }
            Some(a) => {
                assert!(f64_at(r, base).is_nan());
                assert_eq!(code, a.reason.unwrap().code());
                assert_eq!(
                    NoAmplitude::CODES[usize::from(code) - 1].name(),
                    a.reason.unwrap().name()
                );
            }
            None => assert!(f64_at(r, base).is_nan() && code == 0),
        }
    }
    // The names table lists the reasons' codes.
    let mut names = Vec::new();
    eigenray::output::write_names(&s, &mut names).unwrap();
    let names: serde_json::Value = serde_json::from_slice(&names).unwrap();
    assert!(names["amplitude_reasons"][0].is_null());
    assert_eq!(names["amplitude_reasons"][1], "vertex");
    // A scene without amplitudes writes none of it.
    let plain = scene(&OUTPUT_SCENE.replace(
        r#""amplitudes": { "source": "point", "frequency": 1000 }"#,
        r#""description": "plain""#,
    ));
    let tracer = Tracer::new(&plain).unwrap();
    let mut out = Vec::new();
    write(&plain, &tracer.trace_all(), Format::Json, &mut out).unwrap();
    assert!(!String::from_utf8(out).unwrap().contains("amplitude"));
}
