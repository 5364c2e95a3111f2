//! `PathProblem` derivatives against central finite differences of its own time and gradient.

use eigenray::{Scene, problem::PathProblem};
use serde_json::json;

use crate::common::*;

/// Finite-difference step (arclength); points sit at least 0.3 segment lengths ≥ 0.3 from a
/// vertex, so `s ± 2h` stays on the same segment.
const H: f64 = 1e-3;

/// Fourth-order central difference of `f` at `s` along coordinate `j`.
fn diff(f: &dyn Fn(&[f64]) -> f64, s: &[f64], j: usize) -> f64 {
    let at = |d: f64| {
        let mut x = s.to_vec();
        x[j] += d;
        f(&x)
    };
    (at(-2.0 * H) - 8.0 * at(-H) + 8.0 * at(H) - at(2.0 * H)) / (12.0 * H)
}

/// A scene with several shapes and paths (all with leg media, any slownesses: the
/// derivatives do not care whether a step is physical).
fn scene_for_jacobians() -> Scene {
    scene(&json!({
        "media": {
            "a": { "speed": 1.0 }, "b": { "speed": 0.6 }, "c": { "speed": 0.6896551724137931 }, "d": { "speed": 2.2 }
        },
        "interfaces": {
            "flat": { "points": [[-5.0, 0.0], [5.0, 0.0]] },
            "tilted": { "points": [[-3.0, -2.5], [3.0, -1.3]] },
            "bent": { "points": [[-3.0, 0.6], [-1.0, 0.9], [1.0, 0.4], [3.0, 1.0]] },
            "ceiling": { "points": [[-3.0, 3.5], [0.0, 4.0], [3.0, 3.2]] },
            "hexagon": {
                "points": [[5.0, -1.0], [6.0, -1.2], [7.0, -0.5], [7.0, 0.5], [6.0, 1.1], [5.0, 0.9]],
                "closed": true
            }
        },
        "sources": [[-2.0, 1.8]], "receivers": [[2.2, 2.1]],
        "paths": [
            { "name": "refract", "steps": [{ "refract": "flat" }], "media": ["a", "b"] },
            { "name": "reflect", "steps": [{ "reflect": "tilted" }], "media": ["c", "c"] },
            { "name": "two", "steps": [{ "refract": "bent" }, { "reflect": "ceiling" }], "media": ["a", "d", "d"] },
            { "name": "four", "steps": [
                { "refract": "bent" }, { "reflect": "tilted" }, { "refract": "bent" }, { "reflect": "ceiling" }
            ], "media": ["a", "b", "b", "c", "c"] },
            { "name": "lens", "steps": [
                { "refract": "hexagon" }, { "refract": "hexagon" }, { "reflect": "flat" },
                { "refract": "bent" }, { "reflect": "ceiling" }
            ], "media": ["a", "c", "a", "a", "d", "d"] }
        ]
    }))
}

/// Parameters inside segments: `(interface, segment, fraction)` per step.
fn parameters(sc: &Scene, path: usize, rng: &mut Rng) -> Vec<f64> {
    sc.paths()[path]
        .steps
        .iter()
        .map(|step| {
            let line = &sc.interfaces()[step.interface].polyline;
            let j = (rng.uniform(0.0, line.num_segments() as f64) as usize)
                .min(line.num_segments() - 1);
            line.start(j) + rng.uniform(0.3, 0.7) * line.segment_length(j)
        })
        .collect()
}

#[test]
fn gradient_and_hessian_match_finite_differences() {
    let sc = scene_for_jacobians();
    let mut rng = Rng::new(0x00AC_0B1A);
    let (mut max_g, mut max_h) = (0.0f64, 0.0f64);
    let mut zeros_checked = 0;
    for path in 0..sc.paths().len() {
        for trial in 0..6 {
            // Move the end points too, so that the derivatives are tested away from one geometry.
            let s0 = [-2.0 + rng.uniform(-0.5, 0.5), 1.8 + rng.uniform(-0.2, 0.2)];
            let r0 = [2.2 + rng.uniform(-0.5, 0.5), 2.1 + rng.uniform(-0.2, 0.2)];
            let problem =
                PathProblem::new(&sc, path, s0.into(), r0.into()).expect("path has media");
            let k = problem.len();
            let s = parameters(&sc, path, &mut rng);
            let case = format!("path {path} trial {trial}, s = {s:?}");
            let w = problem.slowness().to_vec();

            let g = problem.gradient(&s);
            assert_eq!(g.len(), k, "{case}");
            let time = |x: &[f64]| problem.time(x);
            for i in 0..k {
                let fd = diff(&time, &s, i);
                let scale = g[i].abs().max(w[i] + w[i + 1]);
                let err = (fd - g[i]).abs() / scale;
                assert!(
                    err <= 1e-7,
                    "{case}: dT/ds{i} analytic {}, finite differences {fd}",
                    g[i]
                );
                max_g = max_g.max(err);
            }

            let hess = problem.hessian(&s);
            assert_eq!(
                (hess.diag.len(), hess.off.len()),
                (k, k.saturating_sub(1)),
                "{case}"
            );
            let dense = hess.to_dense();
            let hscale = dense.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(hscale > 0.0, "{case}: zero Hessian");
            for (i, row) in dense.iter().enumerate() {
                for (j, &h) in row.iter().enumerate() {
                    let gi = |x: &[f64]| problem.gradient(x)[i];
                    let fd = diff(&gi, &s, j);
                    if i.abs_diff(j) >= 2 {
                        assert!(
                            fd.abs() <= 1e-12 * hscale,
                            "{case}: H[{i}][{j}] by finite differences {fd}, not 0"
                        );
                        assert_eq!(h, 0.0, "{case}");
                        zeros_checked += 1;
                        continue;
                    }
                    let err = (fd - dense[i][j]).abs() / hscale;
                    assert!(
                        err <= 1e-6,
                        "{case}: H[{i}][{j}] analytic {}, finite differences {fd}",
                        dense[i][j]
                    );
                    max_h = max_h.max(err);
                }
            }
        }
    }
    assert!(zeros_checked > 0);
    println!(
        "jacobian: max relative gradient error {max_g:.2e}, max Hessian error / max |H| {max_h:.2e}"
    );
}
