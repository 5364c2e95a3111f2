//! Spreading against ray-tube widths from neighbouring rays, worked out here: the in-plane
//! width from the take-off angles of paths re-solved to receivers moved across the last leg,
//! the out-of-plane width from rays shot slightly out of the plane (traced here in 3-D through
//! the extruded interfaces), and the recursion of widths through flat interfaces; on
//! refracting stacks, undulating interfaces, a lens, a refraction–reflection–refraction path,
//! a polygon room and a layered axisymmetric waveguide (BELLHOP's geometry).

use std::f64::consts::PI;

use eigenray::amplitude::{Complex64, NoAmplitude};
use eigenray::scene::{AmplitudesSpec, SourceModel};
use eigenray::scene::{Step, StepKind};
use eigenray::{Point, Scene, SceneSpec, Status, Tracer, Vec2, Workspace};

fn unit(v: Vec2) -> Vec2 {
    v * (1.0 / v.length())
}

/// One solved ray: what the widths are measured from.
struct Solved {
    path: usize,
    steps: Vec<Step>,
    points: Vec<Point>,
    media: Vec<usize>,
    parameters: Vec<f64>,
    spreading: f64,
    value: Complex64,
}

/// Every converged ray of `scene` with its amplitude.
fn solved(scene: &Scene) -> Vec<Solved> {
    let tracer = Tracer::new(scene).unwrap();
    let mut ws = Workspace::new();
    let mut out = Vec::new();
    for s in 0..scene.sources().len() {
        for r in 0..scene.receivers().len() {
            for p in 0..scene.paths().len() {
                let rec = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                if rec.status != Status::Converged {
                    continue;
                }
                let a = tracer.amplitude(p, &rec, &ws).expect("amplitude");
                // A converted reflection has its spreading, but no value.
                let converted = matches!(a.reason, Some(NoAmplitude::ConvertedReflection { .. }));
                assert!(a.has_value() || converted, "{:?}", a.reason);
                assert!(a.spreading > 0.0);
                out.push(Solved {
                    path: p,
                    steps: scene.paths()[p].steps.clone(),
                    points: ws.points().to_vec(),
                    media: ws.media().to_vec(),
                    parameters: ws.parameters().to_vec(),
                    spreading: a.spreading,
                    value: a.value,
                });
            }
        }
    }
    out
}

/// The unit tangent of interface `interface` at `p` (on it).
fn tangent_at(scene: &Scene, interface: usize, p: Point) -> Vec2 {
    let line = &scene.interfaces()[interface].polyline;
    line.tangent(line.nearest(p).seg)
}

/// The in-plane width per unit take-off angle, `|Δx⊥ / Δφ₀|`, from the paths re-solved to
/// the receiver moved by `±ε` and `±2ε` across the last leg (central differences, with
/// Richardson's extrapolation of the two).
fn in_plane_width(tracer: &Tracer, ray: &Solved) -> f64 {
    let n = ray.points.len();
    let across = unit(ray.points[n - 1] - ray.points[n - 2]).perp();
    let length: f64 = ray.points.windows(2).map(|w| w[0].distance(w[1])).sum();
    let eps = 1e-4 * length;
    let mut ws = Workspace::new();
    let source = ray.points[0];
    let mut take_off = |r: Point| {
        let rec = tracer.solve_from(source, r, ray.path, &ray.parameters, &mut ws);
        assert_eq!(rec.status, Status::Converged);
        unit(ws.points()[1] - source)
    };
    let receiver = ray.points[n - 1];
    let mut turn = |h: f64| {
        let (a, b) = (
            take_off(receiver + across * h),
            take_off(receiver - across * h),
        );
        a.cross(b).asin().abs() / (2.0 * h)
    };
    let (one, two) = (turn(eps), turn(2.0 * eps));
    3.0 / (4.0 * one - two)
}

/// The out-of-plane width per unit angle of a point source in a scene uniform along `z`:
/// the ray leaving at the angle `ψ` out of the plane, traced in 3-D through the planes of the
/// solved path's segments (Snell's law and the mirror law in 3-D), where it meets the plane
/// through the receiver across the last leg: `z / ψ`.
fn out_of_plane_width(scene: &Scene, ray: &Solved) -> f64 {
    let psi: f64 = 1e-6;
    let w = |j: usize| scene.media()[ray.media[j]].slowness;
    let u0 = unit(ray.points[1] - ray.points[0]);
    let (mut x, mut z) = (ray.points[0], 0.0);
    let (mut d, mut dz) = (u0 * psi.cos(), psi.sin());
    for (i, step) in ray.steps.iter().enumerate() {
        let at = ray.points[i + 1];
        let n = tangent_at(scene, step.interface, at).perp();
        let lambda = (at - x).dot(n) / d.dot(n);
        x = x + d * lambda;
        z += dz * lambda;
        let dn = d.dot(n);
        // The tangential slowness (in the plane and along z) is conserved; the normal one
        // keeps its side (refraction) or turns back (reflection, also into another medium).
        let (s1, s2) = (w(i), w(i + 1));
        let (pt, pz) = ((d - n * dn) * s1, dz * s1);
        let side = match step.kind {
            StepKind::Refract => dn.signum(),
            StepKind::Reflect => -dn.signum(),
            StepKind::Diffract { .. } => unreachable!("no diffraction in these scenes"),
        };
        let pn = side * (s2 * s2 - pt.dot(pt) - pz * pz).sqrt();
        d = (pt + n * pn) * (1.0 / s2);
        dz = pz / s2;
    }
    let k = ray.points.len() - 1;
    let last = unit(ray.points[k] - ray.points[k - 1]);
    let lambda = (ray.points[k] - x).dot(last) / d.dot(last);
    (z + dz * lambda) / psi
}

/// `Π cos θ₂ / cos θ₁` over the interactions of the solved path that change the medium
/// (refractions, converted reflections).
fn cos_ratio(scene: &Scene, ray: &Solved) -> f64 {
    let mut ratio = 1.0;
    for (i, step) in ray.steps.iter().enumerate() {
        if ray.media[i] != ray.media[i + 1] {
            let n = tangent_at(scene, step.interface, ray.points[i + 1]).perp();
            let u1 = unit(ray.points[i + 1] - ray.points[i]);
            let u2 = unit(ray.points[i + 2] - ray.points[i + 1]);
            ratio *= u2.dot(n).abs() / u1.dot(n).abs();
        }
    }
    ratio
}

/// The in-plane width by the recursion through flat interfaces: `(w, dθ) = (0, 1)` at the
/// source; a leg of length `L` adds `L dθ` to `w`; a refraction multiplies `w` by
/// `cos θ₂ / cos θ₁` and `dθ` by `(w₁ cos θ₁)/(w₂ cos θ₂)` (slownesses `wⱼ`; so does a
/// converted reflection); a reflection keeps both.
fn recursion_width(scene: &Scene, ray: &Solved) -> f64 {
    let slow = |j: usize| scene.media()[ray.media[j]].slowness;
    let (mut w, mut dtheta) = (ray.points[0].distance(ray.points[1]), 1.0);
    for (i, step) in ray.steps.iter().enumerate() {
        if ray.media[i] != ray.media[i + 1] {
            let n = tangent_at(scene, step.interface, ray.points[i + 1]).perp();
            let c1 = unit(ray.points[i + 1] - ray.points[i]).dot(n).abs();
            let c2 = unit(ray.points[i + 2] - ray.points[i + 1]).dot(n).abs();
            w *= c2 / c1;
            dtheta *= (slow(i) * c1) / (slow(i + 1) * c2);
        }
        w += ray.points[i + 1].distance(ray.points[i + 2]) * dtheta;
    }
    w
}

/// `s₀ Σ Lⱼ / sⱼ`: the out-of-plane width of a point source.
fn reduced_length(scene: &Scene, ray: &Solved) -> f64 {
    let slow = |j: usize| scene.media()[ray.media[j]].slowness;
    let sum: f64 = ray
        .points
        .windows(2)
        .enumerate()
        .map(|(j, w)| w[0].distance(w[1]) / slow(j))
        .sum();
    slow(0) * sum
}

/// The largest relative error of each check over the converged rays of a point-source
/// scene: the spreading against the finite-difference widths, and the amplitude's in-plane
/// width against the recursion.
struct Errors {
    finite_differences: f64,
    recursion: f64,
    rays: usize,
}

fn check_point_scene(scene: &Scene) -> Errors {
    let tracer = Tracer::new(scene).unwrap();
    let mut e = Errors {
        finite_differences: 0.0,
        recursion: 0.0,
        rays: 0,
    };
    for ray in solved(scene) {
        let ratio = cos_ratio(scene, &ray);
        let (w, y) = (
            in_plane_width(&tracer, &ray),
            out_of_plane_width(scene, &ray),
        );
        let want = ratio.sqrt() / (4.0 * PI * (w * y).sqrt());
        e.finite_differences = e
            .finite_differences
            .max(((ray.spreading - want) / want).abs());
        // The in-plane width the amplitude used, against the recursion.
        let y_closed = reduced_length(scene, &ray);
        assert!(((y - y_closed) / y_closed).abs() < 1e-9, "{y} {y_closed}");
        let w_amp = ratio / (16.0 * PI * PI * y_closed * ray.spreading * ray.spreading);
        let w_rec = recursion_width(scene, &ray);
        e.recursion = e.recursion.max(((w_amp - w_rec) / w_rec).abs());
        e.rays += 1;
    }
    e
}

fn with_amplitudes(mut spec: SceneSpec, source: SourceModel) -> Scene {
    spec.amplitudes = Some(AmplitudesSpec::new(source));
    Scene::from_spec(&spec).unwrap()
}

fn report(case: &str, e: &Errors) {
    eprintln!(
        "{case} ({} rays): finite differences {:.3e}, recursion {:.3e}",
        e.rays, e.finite_differences, e.recursion
    );
    assert!(e.rays > 0, "{case}: no rays");
    assert!(
        e.finite_differences < 1e-9,
        "{case}: {:e}",
        e.finite_differences
    );
    assert!(e.recursion < 1e-9, "{case}: {:e}", e.recursion);
}

#[test]
fn refracting_stacks_flat_dipping_and_undulating() {
    let flat = with_amplitudes(eigenray::demo::layer_stack(10, 9), SourceModel::Point);
    report("10 flat layers", &check_point_scene(&flat));
    let dipping = with_amplitudes(eigenray::demo::dipping_stack(8, 9), SourceModel::Point);
    report("8 dipping layers", &check_point_scene(&dipping));
    let undulating = with_amplitudes(
        eigenray::demo::undulating_stack(3, 40, 15),
        SourceModel::Point,
    );
    report("3 undulating layers", &check_point_scene(&undulating));
}

#[test]
fn a_lens_and_a_refraction_reflection_refraction_path() {
    let lens = Scene::from_json(
        r#"{ "media": { "air": { "speed": 1 }, "glass": { "speed": 0.6, "at": [0, 0] } },
             "background": "air",
             "interfaces": { "lens": { "points": [[-0.5, -1], [0.5, -1.2], [0.8, 0], [0.4, 1.1], [-0.6, 0.9]], "closed": true } },
             "sources": [[-4, 0.3]], "receivers": [[3, -0.4], [3.5, 0.6], [2.5, 0.1]],
             "paths": [{ "steps": [{ "refract": "lens" }, { "refract": "lens" }] }],
             "amplitudes": { "source": "point" } }"#,
    )
    .unwrap();
    report("a lens", &check_point_scene(&lens));
    let bounce = Scene::from_json(
        r#"{ "media": { "air": { "speed": 1 }, "water": { "speed": 0.7 } },
             "interfaces": { "surface": { "points": [[-50, 0], [50, 0]] },
                             "bottom": { "points": [[-50, -3], [50, -6]] } },
             "sources": [[0, 2]], "receivers": [[3, 1.5], [6, 0.7], [9, 2.5], [-4, 1]],
             "paths": [{ "steps": [{ "refract": "surface" }, { "reflect": "bottom" }, { "refract": "surface" }],
                         "media": ["air", "water", "water", "air"] }],
             "amplitudes": { "source": "point" } }"#,
    )
    .unwrap();
    report(
        "refract, reflect off a tilted bottom, refract",
        &check_point_scene(&bounce),
    );
}

#[test]
fn converted_reflections_have_their_spreading_but_no_value() {
    // A reflection off a tilted floor into a slower wave (media given, as a converted P-to-S
    // wave), and one off a second floor back into the first medium.
    let converted = Scene::from_json(
        r#"{ "media": { "p": { "speed": 1.7 }, "s": { "speed": 1.0 } },
             "interfaces": { "floor": { "points": [[-50, -3], [50, -5]] },
                             "deep": { "points": [[-50, -9], [50, -8]] } },
             "sources": [[0, 2]], "receivers": [[3, 1.5], [6, -1], [-5, 0.5]],
             "paths": [{ "steps": [{ "reflect": "floor" }], "media": ["p", "s"] },
                       { "steps": [{ "refract": "floor" }, { "reflect": "deep" }, { "refract": "floor" }],
                         "media": ["p", "s", "p", "s"] }],
             "amplitudes": { "source": "point" } }"#,
    )
    .unwrap();
    let tracer = Tracer::new(&converted).unwrap();
    for ray in tracer.trace_all() {
        let a = ray.amplitude.unwrap();
        assert!(matches!(
            a.reason,
            Some(NoAmplitude::ConvertedReflection { .. })
        ));
        assert!(a.value.re.is_nan() && a.coefficient.re.is_nan() && a.spreading > 0.0);
    }
    report("converted reflections", &check_point_scene(&converted));
}

#[test]
fn a_polygon_room() {
    let text = std::fs::read_to_string(format!(
        "{}/fixtures/bench/room2d.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut spec = SceneSpec::from_json(&text).unwrap();
    spec.receivers.points_mut().truncate(6);
    let room = with_amplitudes(spec, SourceModel::Point);
    let e = check_point_scene(&room);
    report("a hexagonal room, reflections of orders 0 to 2", &e);
}

/// The waveguide: a pressure-release surface, three interfaces between layers of water and a
/// bottom reflecting against a faster sediment (`"media"`), the source on the axis.
fn waveguide(source: &str) -> Scene {
    let receivers: Vec<String> = (0..24)
        .map(|i| format!("[{}, -15]", 150.0 + 160.0 * i as f64))
        .collect();
    let down = r#"{ "refract": "l1" }, { "refract": "l2" }, { "refract": "l3" }"#;
    let up = r#"{ "refract": "l3" }, { "refract": "l2" }, { "refract": "l1" }"#;
    let bottom = r#"{ "reflect": "bottom" }"#;
    let surface = r#"{ "reflect": "surface" }"#;
    Scene::from_json(&format!(
        r#"{{ "media": {{ "w1": {{ "speed": 1500, "at": [10, -10] }}, "w2": {{ "speed": 1490, "at": [10, -30] }},
                         "w3": {{ "speed": 1510, "at": [10, -60] }}, "w4": {{ "speed": 1530, "at": [10, -90] }},
                         "sediment": {{ "speed": 1700, "density": 1.9, "attenuation": 0.002, "at": [10, -200] }} }},
             "domain": [[-10, -400], [20000, 10]],
             "interfaces": {{
                 "surface": {{ "points": [[-10, 0], [20000, 0]], "reflection": "pressure-release" }},
                 "l1": {{ "points": [[-10, -20], [20000, -20]] }},
                 "l2": {{ "points": [[-10, -45], [20000, -45]] }},
                 "l3": {{ "points": [[-10, -70], [20000, -70]] }},
                 "bottom": {{ "points": [[-10, -100], [20000, -100]], "reflection": "media" }} }},
             "sources": [[0, -10]], "receivers": [{}],
             "paths": [
                 {{ "steps": [] }},
                 {{ "steps": [{surface}] }},
                 {{ "steps": [{down}, {bottom}, {up}] }},
                 {{ "steps": [{surface}, {down}, {bottom}, {up}] }},
                 {{ "steps": [{down}, {bottom}, {up}, {surface}, {down}, {bottom}, {up}] }}
             ],
             "amplitudes": {{ "source": "{source}", "frequency": 50 }} }}"#,
        receivers.join(", ")
    ))
    .unwrap()
}

/// The plane-wave pressure coefficients between fluids `(c, ρ)` at incidence cosine `cos1`:
/// `(R, T)` with `cos θ₂` from Snell's law (imaginary beyond the critical angle).
fn fluid(m1: (f64, f64), m2: (f64, f64), cos1: f64) -> (Complex64, Complex64) {
    let q = (m2.0 / m1.0).powi(2) * (1.0 - cos1 * cos1);
    let cos2 = if q <= 1.0 {
        Complex64::new((1.0 - q).sqrt(), 0.0)
    } else {
        Complex64::new(0.0, (q - 1.0).sqrt())
    };
    let (z1, z2) = (m1.0 * m1.1, m2.0 * m2.1);
    let den = cos2 * z1 + z2 * cos1;
    (
        (z2 * cos1 - cos2 * z1) / den,
        Complex64::new(2.0 * z2 * cos1, 0.0) / den,
    )
}

#[test]
fn a_layered_axisymmetric_waveguide_against_ray_tube_areas() {
    let scene = waveguide("axisymmetric");
    let point = waveguide("point");
    let tracer = Tracer::new(&scene).unwrap();
    let fluid_of = |m: usize| {
        let name = &scene.media()[m].name;
        let speed = 1.0 / scene.media()[m].slowness;
        (speed, if name == "sediment" { 1.9 } else { 1.0 })
    };
    let sediment = scene.medium_index("sediment").unwrap();
    let (mut worst, mut worst_models, mut rays): (f64, f64, usize) = (0.0, 0.0, 0);
    let point_rays = solved(&point);
    for (ray, other) in solved(&scene).iter().zip(&point_rays) {
        // The tube's area per unit solid angle: the in-plane width from re-solved paths times
        // the ring x_R dψ, over the cone sin θ₀ dθ₀ dψ of take-off directions about the axis.
        let w = in_plane_width(&tracer, ray);
        let x_r = ray.points.last().unwrap().x;
        let sin0 = unit(ray.points[1] - ray.points[0]).x.abs();
        let spreading = cos_ratio(&scene, ray).sqrt() / (4.0 * PI) * (sin0 / (w * x_r)).sqrt();
        // The coefficients and the sediment's attenuation (none of its legs here).
        let mut coef = Complex64::new(1.0, 0.0);
        for (i, step) in ray.steps.iter().enumerate() {
            let n = Vec2::new(0.0, 1.0);
            let cos1 = unit(ray.points[i + 1] - ray.points[i]).dot(n).abs();
            let name = &scene.interfaces()[step.interface].name;
            coef *= match (step.kind, name.as_str()) {
                (StepKind::Reflect, "surface") => Complex64::new(-1.0, 0.0),
                (StepKind::Reflect, _) => fluid(fluid_of(ray.media[i]), fluid_of(sediment), cos1).0,
                (StepKind::Refract, _) => {
                    fluid(fluid_of(ray.media[i]), fluid_of(ray.media[i + 1]), cos1).1
                }
                (StepKind::Diffract { .. }, _) => unreachable!("no diffraction in this scene"),
            };
        }
        let want = coef * spreading;
        worst = worst.max(((ray.spreading - spreading) / spreading).abs());
        worst = worst.max((ray.value - want).norm() / want.norm());
        // Flat layers: the point source's out-of-plane width is the axisymmetric one.
        assert_eq!(ray.points, other.points);
        worst_models = worst_models.max(((ray.value - other.value).norm()) / ray.value.norm());
        rays += 1;
    }
    eprintln!(
        "axisymmetric waveguide ({rays} rays): ray-tube areas {worst:.3e}, point vs \
         axisymmetric {worst_models:.3e}"
    );
    assert!(rays >= 24 * 4, "{rays}");
    assert!(worst < 1e-7, "{worst:e}");
    assert!(worst_models < 1e-12, "{worst_models:e}");
}
