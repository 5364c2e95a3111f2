use super::*;
use crate::leg::{Linear, Uniform};

/// A Munk-like profile: a sound channel around −1300 with a steep top.
fn munk() -> Profile {
    let knots: Vec<[f64; 2]> = (0..=25)
        .map(|i| {
            let z = 200.0 * f64::from(i);
            let e = 2.0 * (z - 1300.0) / 1300.0;
            [-z, 1500.0 * (1.0 + 0.00737 * (e - 1.0 + (-e).exp()))]
        })
        .collect();
    Profile::new(&knots)
}

/// The model of `branch` in `profile` from the origin.
fn model(profile: &Profile, first: f64, turns: u32, near: f64) -> ProfileLegModel<'_> {
    ProfileLegModel {
        profile,
        origin: Vec2::default(),
        branch: Branch { first, turns, near },
    }
}

/// Legs of several branches (direct up and down, one and two turns) in a Munk profile.
fn cases(profile: &Profile) -> Vec<(ProfileLegModel<'_>, Point, Point)> {
    let mut out = Vec::new();
    let pairs = [
        (Point::new(0.0, -1000.0), Point::new(3000.0, -1800.0), 1.0),
        (Point::new(0.0, -800.0), Point::new(-2500.0, -300.0), 1.0),
        (Point::new(0.0, -1300.0), Point::new(12000.0, -1100.0), 1.0),
        (
            Point::new(100.0, -1500.0),
            Point::new(30000.0, -1700.0),
            2.0,
        ),
        (Point::new(0.0, -1200.0), Point::new(70000.0, -1400.0), 2.0),
        (Point::new(0.0, -2000.0), Point::new(1000.0, -2100.0), 2.0),
        (Point::new(0.0, -50.0), Point::new(2000.0, -400.0), 2.0),
    ];
    for (a, b, _) in pairs {
        // Off the knots (where dc/dy jumps, the blocks are one-sided).
        let (a, b) = (a + Vec2::new(0.0, 7.3), b + Vec2::new(0.0, -3.1));
        for turns in 0..=2 {
            for first in [1.0, -1.0] {
                for ray in profile.arrivals(a.to_vec2(), b.to_vec2()).rays {
                    if ray.first == first && ray.turns == turns {
                        out.push((model(profile, first, turns, ray.p.abs()), a, b));
                    }
                }
            }
        }
    }
    out
}

/// The leg's slowness vectors are the gradient of its time (central differences), and its
/// Hessian blocks the derivatives of the slowness vectors, over direct and turning legs.
#[test]
fn derivatives_match_finite_differences() {
    let profile = munk();
    let all = cases(&profile);
    let count = |t: u32| all.iter().filter(|c| c.0.branch.turns == t).count();
    assert!(count(0) >= 4);
    assert!(all.iter().filter(|c| c.0.branch.turns == 1).count() >= 2);
    assert!(all.iter().filter(|c| c.0.branch.turns == 2).count() >= 1);
    let dirs = [
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.6, -0.8),
    ];
    for (m, a, b) in all {
        let leg = m.valid_leg(a, b).expect("the ray arrivals found");
        // (Central differences of 1 cm: their error is below 1e-7 of each value on these
        // legs, from 1 m down, and their rounding too.)
        let h = 1e-2;
        let at = |da: Vec2, db: Vec2| m.valid_leg(a + da, b + db).unwrap();
        for t in dirs {
            let fd_b = (at(Vec2::default(), t * h).time() - at(Vec2::default(), t * -h).time())
                / (2.0 * h);
            let fd_a = (at(t * h, Vec2::default()).time() - at(t * -h, Vec2::default()).time())
                / (2.0 * h);
            let scale = leg.arrival().length();
            assert!(
                (fd_b - leg.arrival().dot(t)).abs() < 1e-7 * scale,
                "{m:?} {fd_b}"
            );
            assert!(
                (fd_a + leg.departure().dot(t)).abs() < 1e-7 * scale,
                "{m:?} {fd_a}"
            );
            for t2 in dirs {
                let d_end = (at(Vec2::default(), t2 * h).arrival()
                    - at(Vec2::default(), t2 * -h).arrival())
                .dot(t)
                    / (2.0 * h);
                let d_start = -(at(t2 * h, Vec2::default()).departure()
                    - at(t2 * -h, Vec2::default()).departure())
                .dot(t)
                    / (2.0 * h);
                let cross = (at(t2 * h, Vec2::default()).arrival()
                    - at(t2 * -h, Vec2::default()).arrival())
                .dot(t)
                    / (2.0 * h);
                let tol = |x: f64| 1e-5 * x.abs().max(1e-9 / leg.len);
                if t == t2 {
                    let (e, s) = (leg.end_block(t), leg.start_block(t));
                    assert!((d_end - e).abs() < tol(e), "{m:?} end {t:?}: {d_end} {e}");
                    assert!(
                        (d_start - s).abs() < tol(s),
                        "{m:?} start {t:?}: {d_start} {s}"
                    );
                }
                let c = leg.coupling(t2, t);
                assert!((cross - c).abs() < tol(c), "{m:?} coupling: {cross} {c}");
            }
        }
    }
}

/// Two knots with one speed: every leg is the straight leg (time, slowness vectors, blocks).
#[test]
fn isovelocity_is_the_straight_leg() {
    let profile = Profile::new(&[[0.0, 1500.0], [-200.0, 1500.0]]);
    let straight = Uniform::new(1.0 / 1500.0);
    for (a, b) in [
        (Point::new(0.0, -10.0), Point::new(800.0, -150.0)),
        (Point::new(0.0, -190.0), Point::new(-300.0, -20.0)),
        (Point::new(5.0, -100.0), Point::new(5.0, -20.0)),
    ] {
        let first = if b.y > a.y { 1.0 } else { -1.0 };
        let leg = model(&profile, first, 0, f64::NAN).valid_leg(a, b).unwrap();
        let line = straight.valid_leg(a, b).unwrap();
        assert!((leg.time() - line.time()).abs() <= 1e-12 * line.time());
        assert!((leg.arrival() - line.arrival()).length() <= 1e-12 * line.slowness);
        assert!((leg.departure() - line.departure()).length() <= 1e-12 * line.slowness);
        if a.x == b.x {
            continue;
        }
        for t in [Vec2::new(1.0, 0.0), Vec2::new(0.8, 0.6)] {
            let t2 = Vec2::new(0.0, 1.0);
            let scale = line.slowness / line.len;
            assert!((leg.end_block(t) - line.end_block(t)).abs() <= 1e-9 * scale);
            assert!((leg.start_block(t) - line.start_block(t)).abs() <= 1e-9 * scale);
            assert!((leg.coupling(t, t2) - line.coupling(t, t2)).abs() <= 1e-9 * scale);
        }
    }
    // No ray of a branch that does not reach: a direct leg going away, a turn in a uniform
    // medium.
    let (a, b) = (Point::new(0.0, -10.0), Point::new(800.0, -150.0));
    assert!(model(&profile, 1.0, 0, f64::NAN).valid_leg(a, b).is_none());
    assert!(model(&profile, 1.0, 1, f64::NAN).valid_leg(a, b).is_none());
}

/// One linear layer: the `gradient` medium's arc (time to 1e-12, slowness vectors and
/// blocks to 1e-8), a turning arc included.
#[test]
fn one_layer_is_the_arc() {
    let profile = Profile::new(&[[0.0, 1500.0], [-5000.0, 1585.0]]);
    let linear = Linear {
        speed: 1500.0,
        gradient: Vec2::new(0.0, -0.017),
        least_speed: 1500.0,
    };
    for (a, b, first, turns) in [
        (Point::new(0.0, -100.0), Point::new(5000.0, -300.0), -1.0, 0),
        (
            Point::new(0.0, -100.0),
            Point::new(-3000.0, -2000.0),
            -1.0,
            0,
        ),
        (
            Point::new(0.0, -2000.0),
            Point::new(20000.0, -2000.0),
            -1.0,
            1,
        ),
        (Point::new(0.0, -300.0), Point::new(9000.0, -100.0), -1.0, 1),
    ] {
        let leg = model(&profile, first, turns, f64::NAN)
            .valid_leg(a, b)
            .unwrap();
        let arc = linear.valid_leg(a, b).unwrap();
        assert!(
            (leg.time() - arc.time()).abs() <= 1e-12 * arc.time(),
            "{a:?} {b:?}"
        );
        let w = arc.arrival().length();
        assert!((leg.arrival() - arc.arrival()).length() <= 1e-8 * w);
        assert!((leg.departure() - arc.departure()).length() <= 1e-8 * w);
        for t in [
            Vec2::new(1.0, 0.0),
            Vec2::new(0.6, 0.8),
            Vec2::new(0.0, 1.0),
        ] {
            let t2 = Vec2::new(0.8, -0.6);
            let e = arc.end_block(t);
            assert!((leg.end_block(t) - e).abs() <= 1e-7 * e.abs().max(w / arc.len));
            let s = arc.start_block(t);
            assert!((leg.start_block(t) - s).abs() <= 1e-7 * s.abs().max(w / arc.len));
            let c = arc.coupling(t, t2);
            assert!((leg.coupling(t, t2) - c).abs() <= 1e-7 * c.abs().max(w / arc.len));
        }
    }
}

/// Every ray `arrivals` finds between two points is its branch's leg (time to 1e-12), its
/// caustics and turns the same.
#[test]
fn legs_are_the_rays_of_arrivals() {
    let profile = munk();
    for (m, a, b) in cases(&profile) {
        let leg = m.valid_leg(a, b).unwrap();
        let found = profile.arrivals(a.to_vec2(), b.to_vec2());
        let ray = found
            .rays
            .iter()
            .find(|r| {
                r.first == m.branch.first && r.turns == m.branch.turns && r.p.abs() == m.branch.near
            })
            .unwrap();
        assert!((leg.time - ray.sums.t).abs() <= 1e-12 * ray.sums.t, "{m:?}");
        assert_eq!((leg.turns, leg.caustics), (ray.turns, ray.caustics));
    }
}
