//! Stability tests: extreme contrasts, scales, angles, chain lengths and polyline sizes, each against an exact reference.

mod cases;

/// Runs the case `name` and fails with every broken check and a reproduction.
fn check(name: &str) {
    let case = cases::by_name(name);
    let out = cases::run(&case);
    println!("{}", cases::TABLE_HEADER);
    println!("{}", out.row(name));
    if !out.failures.is_empty() {
        let json = case.json.to_string();
        let scene = if json.len() <= 4000 {
            json
        } else {
            format!(
                "({} bytes; `cargo run --release --example stability -- --dump {name}`)",
                json.len()
            )
        };
        panic!(
            "{name}: {}\n  - {}\nray: {:?}\nscene: {scene}",
            case.what,
            out.failures.join("\n  - "),
            out.ray
        );
    }
}

/// One test per case of [`cases::CASES`], and a check that none is left out.
macro_rules! stability_tests {
    ($($test:ident => $name:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check($name);
            }
        )*

        #[test]
        fn every_case_has_a_test() {
            let tested = [$($name),*];
            for (name, _) in cases::CASES {
                assert!(tested.contains(name), "case {name} has no test");
            }
            assert_eq!(tested.len(), cases::CASES.len(), "a test names no case");
        }
    };
}

stability_tests! {
    contrast_1e_minus_6_below => "contrast_1e-6_below",
    contrast_1e6_below => "contrast_1e6_below",
    alternating_1e3_stack => "alternating_1e3_stack",
    alternating_1e6_stack => "alternating_1e6_stack",
    alternating_1e3_beyond_end => "alternating_1e3_beyond_end",
    alternating_1e3_grazing => "alternating_1e3_grazing",
    scale_1 => "scale_1",
    scale_1e_minus_6 => "scale_1e-6",
    scale_1e6 => "scale_1e6",
    translate_1e7 => "translate_1e7",
    grazing_reflection => "grazing_reflection",
    grazing_transmitted_critical => "grazing_transmitted_critical",
    grazing_incident_critical => "grazing_incident_critical",
    source_1e_minus_9_above_refraction => "source_1e-9_above_refraction",
    source_1e_minus_9_above_long_interface => "source_1e-9_above_long_interface",
    source_1e_minus_9_above_stack => "source_1e-9_above_stack",
    source_1e_minus_9_above_mirror => "source_1e-9_above_mirror",
    receiver_1e_minus_9_below_refraction => "receiver_1e-9_below_refraction",
    receiver_1e_minus_9_above_mirror => "receiver_1e-9_above_mirror",
    normal_incidence_refraction => "normal_incidence_refraction",
    normal_incidence_reflection => "normal_incidence_reflection",
    normal_incidence_stack => "normal_incidence_stack",
    receiver_on_refracting_interface => "receiver_on_refracting_interface",
    receiver_on_mirror => "receiver_on_mirror",
    stack_200_down_and_up => "stack_200_down_and_up",
    stack_200_alternating_1e3 => "stack_200_alternating_1e3",
    seafloor_100k_near => "seafloor_100k_near",
    seafloor_100k_far => "seafloor_100k_far",
    vertex_convex_roof => "vertex_convex_roof",
    vertex_minus_1e_minus_9 => "vertex_minus_1e-9",
    vertex_plus_1e_minus_9 => "vertex_plus_1e-9",
    concave_parabola_at_maximum => "concave_parabola_at_maximum",
    concave_parabola_flank => "concave_parabola_flank",
    concave_circular_trough => "concave_circular_trough",
    lens_crossed_twice => "lens_crossed_twice",
    reflection_inside_polygon => "reflection_inside_polygon",
    poor_guess_long_mirror => "poor_guess_long_mirror",
    poor_guess_refraction => "poor_guess_refraction",
    poor_guess_waveguide => "poor_guess_waveguide",
}

#[test]
fn eigenvalues_of_a_known_tridiagonal() {
    // The second-difference matrix tridiag(−1, 2, −1) of order n has eigenvalues
    // 2 − 2 cos(jπ/(n+1)).
    let n = 50;
    let (lo, hi, small) = cases::eigen_extremes(&vec![2.0; n], &vec![-1.0; n - 1]);
    let pi = std::f64::consts::PI;
    let want_lo = 2.0 - 2.0 * (pi / (n + 1) as f64).cos();
    let want_hi = 2.0 - 2.0 * (n as f64 * pi / (n + 1) as f64).cos();
    assert!(cases::rel_err(lo, want_lo) < 1e-12, "{lo} vs {want_lo}");
    assert!(cases::rel_err(hi, want_hi) < 1e-12, "{hi} vs {want_hi}");
    assert_eq!(small, lo.abs());
    // Graded: eigenvalues 1e-20 and 1 are both found to relative precision.
    let (lo, hi, _) = cases::eigen_extremes(&[1e-20, 1.0], &[0.0]);
    assert!(cases::rel_err(lo, 1e-20) < 1e-12 && cases::rel_err(hi, 1.0) < 1e-12);
    // Indefinite: the one nearest zero.
    let (_, _, small) = cases::eigen_extremes(&[-3.0, 0.5, 7.0], &[0.0, 0.0]);
    assert!(cases::rel_err(small, 0.5) < 1e-12);
}
