//! The tree's time bound against the exact distances of one image: a node, or a receiver,
//! is pruned exactly when every path through it is later than `max_time` by more than the
//! bound's margin (four beam margins).

use super::*;

/// A floor `y = 0` from x = −10 to 10, source (0, 1): its image in the floor is (0, −1),
/// exactly 5 from (3, 3) and √13 / 2 from (1, 0.5), and the floor itself 1 from it.
const FAR: Point = Point::new(3.0, 3.0);
const NEAR: Point = Point::new(1.0, 0.5);

/// What the tree of the floor, one reflection deep, does with `max_time` (speed 1), and
/// the margin of its bound.
fn floor_tree(receivers: &[Point], max_time: f64) -> (MirrorStats, f64) {
    let doc = r#"{
        "media": { "air": { "speed": 1.0 } }, "background": "air",
        "interfaces": { "floor": { "points": [[-10, 0], [10, 0]] } },
        "sources": [[0, 1]], "receivers": [[3, 3]],
        "paths": [{ "steps": [] }]
    }"#;
    let scene = Scene::from_json(doc).unwrap();
    let walls = MirrorWalls::new(&scene, &[0]);
    let search = MirrorSearch {
        scene: &scene,
        source: Point::new(0.0, 1.0),
        receivers,
        max_steps: 1,
        max_time,
        slowness: 1.0,
        obstructed: false,
        max_beams: u64::MAX,
        max_work: u64::MAX,
        max_depth: crate::scene::MAX_SEARCH_STEPS,
    };
    let margin = 4.0 * walls.bounds(&search, 1).delta;
    let stats = walls.arrivals(
        &search,
        &mut MirrorScratch::default(),
        &mut |_| true,
        &mut |_| true,
    );
    (stats, margin)
}

/// With one receiver, 5 from the floor's image: `max_time` 5 less a little more than the
/// margin prunes the floor's node (no beam visited); a little less than the margin visits
/// it. The margin is far below the times (round-off is some 1e-15 here), far above the
/// round-off of the distances.
///
/// Mutant caught: the late bound of a node (`Bounds::late`) made looser by a multiple of its
/// margin (or tighter).
#[test]
fn a_node_is_pruned_exactly_beyond_its_margin() {
    let (_, margin) = floor_tree(&[FAR], 5.0);
    assert!(margin > 1e-12 && margin < 1e-8, "{margin:e}");
    let (late, m) = floor_tree(&[FAR], 5.0 - 1.05 * margin);
    assert_eq!(m, margin, "the margin does not depend on max_time here");
    // The direct ray alone.
    assert_eq!((late.beams, late.leaves), (0, 1), "{late:?}");
    let (kept, _) = floor_tree(&[FAR], 5.0 - 0.95 * margin);
    assert_eq!((kept.beams, kept.leaves), (1, 2), "{kept:?}");
}

/// With a second receiver near the image, the floor's node is visited (the receivers' box
/// lies within reach); the far receiver is then left out exactly where every path to it is
/// later than `max_time` by more than the margin, and validated within it.
///
/// Mutant caught: the bound of a receiver at a node (`Validation::node`) made looser by a
/// multiple of its margin (or tighter).
#[test]
fn a_receiver_is_left_out_exactly_beyond_the_margin() {
    let receivers = [NEAR, FAR];
    let (_, margin) = floor_tree(&receivers, 5.0);
    let (late, _) = floor_tree(&receivers, 5.0 - 1.05 * margin);
    // The direct ray to each receiver, and the floor's path to the near one.
    assert_eq!((late.beams, late.leaves), (1, 3), "{late:?}");
    let (kept, _) = floor_tree(&receivers, 5.0 - 0.95 * margin);
    assert_eq!((kept.beams, kept.leaves), (1, 4), "{kept:?}");
}
