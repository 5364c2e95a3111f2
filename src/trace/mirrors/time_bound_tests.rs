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

/// Random cases of an image, a wall's part and one to four receivers: the bound through the
/// part ([`Bounds::late_through`]) never exceeds the least `|image − x| + |x − r|` sampled
/// over 2,001 points `x` of the part and the receivers `r` (each sample is the length of a
/// way from the image through the part to a receiver, so at least the true minimum over
/// the receivers' box); and with one receiver (a box of one point, whose dense samples come
/// within 1e-6 of the minimum) it prunes where the reach is 1e-4 short of that minimum.
///
/// Mutants caught: a bound above the shortest way (a wrong tangent, a wrong side of the
/// bracket kept, the box distance of the far end); a bound that never prunes.
#[test]
fn the_bound_through_a_part_never_exceeds_the_shortest_way() {
    let mut rng = crate::demo::SplitMix64(39);
    let coord = |rng: &mut crate::demo::SplitMix64| 20.0 * rng.next_f64() - 10.0;
    let delta = 1e-12;
    let mut pruned = 0;
    for case in 0..2000 {
        let image = Point::new(coord(&mut rng), coord(&mut rng));
        let a = Point::new(coord(&mut rng), coord(&mut rng));
        let b = if case % 7 == 0 {
            a
        } else {
            Point::new(coord(&mut rng), coord(&mut rng))
        };
        let count = 1 + (rng.next_u64() % 4) as usize;
        let receivers: Vec<Point> = (0..count)
            .map(|_| Point::new(coord(&mut rng), coord(&mut rng)))
            .collect();
        let shortest = (0..=2000)
            .map(|i| a + (b - a) * (i as f64 / 2000.0))
            .flat_map(|x| {
                receivers
                    .iter()
                    .map(move |&r| image.distance(x) + x.distance(r))
            })
            .fold(f64::INFINITY, f64::min);
        let bounds = |reach: f64| Bounds {
            delta,
            receivers: Aabb::around(&receivers),
            reach,
            through: true,
            degenerate: true,
        };
        let margin = 4.0 * delta;
        // Late exactly when the bound exceeds `reach` + margin: never at the sampled minimum.
        assert!(
            !bounds(shortest - margin).late_through(image, a, b),
            "case {case}: {image:?} {a:?} {b:?} {receivers:?}: {shortest}"
        );
        if count == 1 {
            assert!(
                bounds(shortest - 1e-4).late_through(image, a, b),
                "case {case}: {image:?} {a:?} {b:?} {receivers:?}: {shortest}"
            );
            pruned += 1;
        }
    }
    assert!(pruned > 300, "{pruned}");
}

/// One arrival of a tree, its points and time as bits.
#[derive(Debug, PartialEq)]
struct Arrival {
    receiver: usize,
    walls: Vec<usize>,
    points: Vec<(u64, u64)>,
    time: u64,
}

/// A tree's arrivals, in the order found, and the beams it visited.
struct Walked {
    arrivals: Vec<Arrival>,
    beams: u64,
}

/// Every arrival of `walls`' tree from `source` to `receivers` by `max_time` (speed 343),
/// with or without the bound through the wall's part: each arrival's receiver, walls,
/// points and time as bits, and the beams visited.
fn tree(
    scene: &Scene,
    walls: &MirrorWalls,
    source: Point,
    receivers: &[Point],
    max_time: f64,
    through: bool,
) -> Walked {
    tree_pruned(scene, walls, source, receivers, max_time, [through, true])
}

/// [`tree`] with the bound through the wall's part (`prune[0]`) and the pruning of
/// degenerate windows (`prune[1]`) each on or off.
fn tree_pruned(
    scene: &Scene,
    walls: &MirrorWalls,
    source: Point,
    receivers: &[Point],
    max_time: f64,
    prune: [bool; 2],
) -> Walked {
    let search = MirrorSearch {
        scene,
        source,
        receivers,
        max_steps: crate::scene::MAX_SEARCH_STEPS,
        max_time,
        slowness: 1.0 / 343.0,
        obstructed: false,
        max_beams: u64::MAX,
        max_work: u64::MAX,
        max_depth: crate::scene::MAX_SEARCH_STEPS,
    };
    let mut bounds = walls.bounds(&search, search.max_steps);
    bounds.through = prune[0];
    bounds.degenerate = prune[1];
    let mut out = Vec::new();
    let stats = walls.walk(
        &search,
        &bounds,
        &mut MirrorScratch::default(),
        &mut |p: MirrorPath<'_>| {
            out.push(Arrival {
                receiver: p.receiver,
                walls: p.walls.to_vec(),
                points: p
                    .points
                    .iter()
                    .map(|q| (q.x.to_bits(), q.y.to_bits()))
                    .collect(),
                time: p.time.to_bits(),
            });
            true
        },
        &mut |_| true,
    );
    assert!(!stats.stopped);
    Walked {
        arrivals: out,
        beams: stats.beams,
    }
}

/// The comb room (`examples/scenes/comb_room.json`, its two listeners and the nine of
/// `tests/search.rs`), an L-shaped room and the 6 × 4 m room of
/// `benches/scenes/room_response.json` (ten listeners): the same arrivals, in the same
/// order, to the bit, with and without the bound through the wall's part (which only prunes
/// subtrees whose every path is later than `max_time`), and on the comb room strictly fewer
/// beams.
///
/// Mutant caught: a bound through the part that prunes a subtree holding an arrival.
#[test]
fn the_bound_through_a_part_keeps_every_arrival() {
    let comb = Scene::from_json(include_str!("../../../examples/scenes/comb_room.json")).unwrap();
    let room =
        Scene::from_json(include_str!("../../../benches/scenes/room_response.json")).unwrap();
    let l_shape = Scene::from_json(
        r#"{
        "media": { "air": { "speed": 343.0 } }, "background": "air",
        "interfaces": { "l": { "points": [[0, 0], [4, 0], [4, 1.5], [1.5, 1.5], [1.5, 3],
            [0, 3]], "closed": true } },
        "sources": [[0.5, 0.5]], "receivers": [[3.5, 1]], "paths": [{ "steps": [] }]
    }"#,
    )
    .unwrap();
    let nine = [
        [2.5, 4.5],
        [0.5, 4.5],
        [0.5, 2.5],
        [2.5, 2.5],
        [2.5, 0.5],
        [1.5, 1.5],
        [0.25, 1.25],
        [2.75, 3.75],
        [1.25, 1.75],
    ]
    .map(|[x, y]| Point::new(x, y));
    let cases: [(&Scene, Vec<Point>, f64, bool); 5] = [
        (&comb, comb.receivers().to_vec(), 0.08, true),
        (&comb, nine.to_vec(), 0.06, true),
        (
            &l_shape,
            vec![Point::new(3.5, 1.0), Point::new(0.7, 2.6)],
            0.1,
            false,
        ),
        (&room, room.receivers().to_vec(), 0.1, false),
        (&room, room.receivers()[..1].to_vec(), 0.15, false),
    ];
    for (i, (scene, receivers, max_time, fewer)) in cases.into_iter().enumerate() {
        let all: Vec<usize> = (0..scene.interfaces().len()).collect();
        let walls = MirrorWalls::new(scene, &all);
        let source = scene.sources()[0];
        let with = tree(scene, &walls, source, &receivers, max_time, true);
        let without = tree(scene, &walls, source, &receivers, max_time, false);
        let (beams, all_beams) = (with.beams, without.beams);
        assert!(!with.arrivals.is_empty(), "case {i}");
        assert_eq!(with.arrivals, without.arrivals, "case {i}");
        assert!(beams <= all_beams, "case {i}: {beams} > {all_beams}");
        if fewer {
            assert!(beams < all_beams, "case {i}: {beams} ≥ {all_beams}");
        }
    }
}

/// The distance from the nearest of `arrival`'s reflection points to an end of a wall of
/// `walls` that is no free end (a corner, where a reflection is no path).
fn corner_distance(walls: &MirrorWalls, arrival: &Arrival) -> f64 {
    let points = &arrival.points[1..arrival.points.len() - 1];
    let corners = walls.walls.iter().flat_map(|w| {
        [(w.p, w.open[0]), (w.q, w.open[1])]
            .into_iter()
            .filter(|&(_, open)| !open)
            .map(|(c, _)| c)
    });
    let corners: Vec<Point> = corners.collect();
    points
        .iter()
        .map(|&(x, y)| Point::new(f64::from_bits(x), f64::from_bits(y)))
        .flat_map(|p| corners.iter().map(move |&c| p.distance(c)))
        .fold(f64::INFINITY, f64::min)
}

/// Every arrival of the tree of `scene`'s walls from its first source to `receivers` by
/// `max_time`, with and without the pruning of degenerate windows (the tight beam): the
/// arrivals with the pruning are those without it, in the same order, to the bit, but for
/// the paths that reflect at a corner (a point within 1e-12 of the room's size of a wall's
/// end that is no free end: no reflection by the contract, which the tree without the
/// pruning lists where the round-off of its images puts such a point just inside its wall);
/// the beams with the pruning (never more), and without, and how many corner paths the
/// pruning left out.
fn degenerate_agree(
    scene: &Scene,
    receivers: &[Point],
    max_time: f64,
    what: &str,
) -> (u64, u64, usize) {
    let all: Vec<usize> = (0..scene.interfaces().len()).collect();
    let walls = MirrorWalls::new(scene, &all);
    let source = scene.sources()[0];
    let with = tree_pruned(scene, &walls, source, receivers, max_time, [true, true]);
    let without = tree_pruned(scene, &walls, source, receivers, max_time, [true, false]);
    let mut kept = with.arrivals.iter().peekable();
    let mut corners = 0;
    for a in &without.arrivals {
        if kept.peek() == Some(&a) {
            kept.next();
            continue;
        }
        let d = corner_distance(&walls, a);
        assert!(
            d <= 1e-12 * walls.extent,
            "{what}: an arrival {d:e} from the nearest corner left out: {a:?}"
        );
        corners += 1;
    }
    assert_eq!(
        kept.next(),
        None,
        "{what}: an arrival of the pruned tree alone"
    );
    assert!(
        with.beams <= without.beams,
        "{what}: {} > {}",
        with.beams,
        without.beams
    );
    (with.beams, without.beams, corners)
}

/// The comb room with the nine listeners of `tests/search.rs` to 0.1 s and with its own two
/// to 0.11 s: the same arrivals, to the bit, with and without the pruning of degenerate
/// windows, from over ten times fewer beams (its beams' edges run exactly through its
/// corners).
///
/// Mutant caught: a degenerate test that prunes a window holding rays (a margin-free clip
/// that cuts too much), or one that prunes nothing.
#[test]
fn pruning_degenerate_windows_keeps_the_comb_arrivals() {
    let comb = Scene::from_json(include_str!("../../../examples/scenes/comb_room.json")).unwrap();
    let nine = [
        [2.5, 4.5],
        [0.5, 4.5],
        [0.5, 2.5],
        [2.5, 2.5],
        [2.5, 0.5],
        [1.5, 1.5],
        [0.25, 1.25],
        [2.75, 3.75],
        [1.25, 1.75],
    ]
    .map(|[x, y]| Point::new(x, y));
    for (receivers, max_time) in [(nine.to_vec(), 0.1), (comb.receivers().to_vec(), 0.11)] {
        let (with, without, _) = degenerate_agree(&comb, &receivers, max_time, "comb");
        assert!(10 * with < without, "{with} beams against {without}");
    }
}

/// A random room of right angles on a grid of unit cells (an orthogonal polygon: a random
/// height for each of 3 to 6 columns, above a base row), its walls one interface each, the
/// source and receivers on the eighth grid strictly inside and off the walls' lines (an
/// image on a wall's line has a beam of the whole plane): every image is then exact, and
/// beams' edges run exactly through corners.
fn grid_room(rng: &mut crate::demo::SplitMix64) -> super::tests::Room {
    let columns = 3 + (rng.next_u64() % 4) as usize;
    let heights: Vec<f64> = (0..columns)
        .map(|_| (2 + rng.next_u64() % 4) as f64)
        .collect();
    // The outline: along the base, then down the columns' tops from the right.
    let mut corners = vec![Point::new(0.0, 0.0), Point::new(columns as f64, 0.0)];
    for i in (0..columns).rev() {
        let h = heights[i];
        let (x0, x1) = (i as f64, i as f64 + 1.0);
        if corners.last().unwrap().y != h {
            corners.push(Point::new(x1, h));
        }
        corners.push(Point::new(x0, h));
        if i > 0 && heights[i - 1] == h {
            corners.pop();
        }
    }
    let inside = |p: Point| {
        let i = p.x.floor() as usize;
        p.x > 0.0 && p.x < columns as f64 && p.y > 0.0 && p.y < heights[i.min(columns - 1)]
    };
    let point = |rng: &mut crate::demo::SplitMix64| loop {
        let p = Point::new(
            (rng.next_u64() % (4 * columns as u64)) as f64 / 4.0
                + 0.125 * (rng.next_u64() % 2) as f64,
            (rng.next_u64() % 24) as f64 / 4.0,
        );
        if inside(p) && p.x.fract() != 0.0 && p.y.fract() != 0.0 {
            return p;
        }
    };
    let sources = vec![point(rng)];
    let receivers = (0..4).map(|_| point(rng)).collect();
    super::tests::Room {
        corners,
        sources,
        receivers,
    }
}

/// Random rooms: 40 rooms of right angles on a grid (exact arithmetic, beams through
/// corners), and 40 of the random convex and non-convex rooms of the complete search's
/// tests (turned, shifted, their corners jittered: round-off everywhere), each with its
/// source and four receivers, to a random `max_time`: the same arrivals, to the bit, with
/// and without the pruning of degenerate windows, and in the grid rooms fewer beams.
///
/// Mutant caught: a degenerate test that prunes a window holding an arrival.
#[test]
fn pruning_degenerate_windows_keeps_random_rooms_arrivals() {
    let mut rng = crate::demo::SplitMix64(4239);
    let (mut with, mut without) = (0, 0);
    for case in 0..40 {
        let room = grid_room(&mut rng);
        let scene = super::tests::room_scene(&room, &[]);
        let max_time = (12.0 + 12.0 * rng.next_f64()) / 343.0;
        let what = format!("grid room {case}: {:?}", room.corners);
        let (w, wo, _) = degenerate_agree(&scene, &room.receivers, max_time, &what);
        with += w;
        without += wo;
    }
    assert!(with < without, "{with} beams against {without}");
    for case in 0..40 {
        let room = super::tests::random_room(case % 4, 1, 4, &mut rng);
        let scene = super::tests::room_scene(&room, &[]);
        let max_time = (15.0 + 15.0 * rng.next_f64()) / 343.0;
        let what = format!("random room {case}: {:?}", room.corners);
        let (w, wo, corners) = degenerate_agree(&scene, &room.receivers, max_time, &what);
        assert!(w <= wo);
        // Corners off the grid: no path through one.
        assert_eq!(corners, 0, "{what}");
    }
}

/// The comb room extruded in `benches/scenes/comb_room_extruded.json`, its plan: the tree of
/// its nine listeners (two of them outside the room, in the notch) to a plan length of 60 m
/// takes under 100,000 beams (the margins' slivers, clipped without the tight beam of each
/// level, took 1,018,067, and ten times more at each 20 m), for 6,108 arrivals.
///
/// Mutant caught: a tight beam that is only the margins' beam (the slivers below a sliver
/// kept).
#[test]
fn the_tight_beam_keeps_the_comb_tree_small() {
    let comb = Scene::from_json(include_str!("../../../examples/scenes/comb_room.json")).unwrap();
    let nine = [
        [2.5, 4.5],
        [0.5, 4.5],
        [1.5, 0.5],
        [2.5, 2.5],
        [0.5, 2.5],
        [2.5, 0.7],
        [0.3, 3.7],
        [2.7, 3.3],
        [1.4, 0.3],
    ]
    .map(|[x, y]| Point::new(x, y));
    let all: Vec<usize> = (0..comb.interfaces().len()).collect();
    let walls = MirrorWalls::new(&comb, &all);
    let source = Point::new(0.5, 0.5);
    let walked = tree_pruned(&comb, &walls, source, &nine, 60.0 / 343.0, [true, true]);
    assert_eq!(walked.arrivals.len(), 6108);
    assert!(walked.beams < 100_000, "{} beams", walked.beams);
}

/// Every node of `walls`' tree from `source` (its children clipped without occlusion and
/// without a time bound), to `depth` reflections: each wall that
/// [`MirrorWalls::behind`] skips below a node is one that [`MirrorWalls::child`] finds no
/// child through; the count of those skips, and of the tries.
fn behind_skips(scene: &Scene, walls: &MirrorWalls, source: Point, depth: usize) -> (u64, u64) {
    let receivers = [source];
    let search = MirrorSearch {
        scene,
        source,
        receivers: &receivers,
        max_steps: depth,
        max_time: f64::INFINITY,
        slowness: 1.0 / 343.0,
        obstructed: false,
        max_beams: u64::MAX,
        max_work: u64::MAX,
        max_depth: crate::scene::MAX_SEARCH_STEPS,
    };
    let bounds = walls.bounds(&search, depth);
    let root = Node {
        wall: usize::MAX,
        image: source,
        beam: None,
        next: 0,
    };
    let (mut skips, mut tries, mut work) = (0, 0, 0);
    let mut level = vec![root];
    for _ in 0..depth {
        let mut next = Vec::new();
        for node in &level {
            for w in (0..walls.count()).filter(|&w| w != node.wall) {
                tries += 1;
                let child = walls.child(node, w, &bounds, None, &mut work);
                if let Some(beam) = &node.beam
                    && walls.behind(node.wall, w, beam.side, bounds.delta)
                {
                    skips += 1;
                    assert!(child.is_none(), "wall {w} behind wall {}", node.wall);
                }
                next.extend(child);
            }
        }
        level = next;
    }
    (skips, tries)
}

/// The walls behind a node's wall, skipped before its children are clipped: in the comb
/// room, 40 grid rooms and 40 random rooms (convex and not), every wall skipped below a
/// node of the tree (to 4 reflections, 3 in the random rooms) has no child there (the test
/// is the first clip's, on the same numbers), and walls are skipped in the comb and in the
/// rooms that are not convex.
///
/// Mutants caught: the side of the beam's rays taken the other way (a wall in front of the
/// node's wall skipped), the heights of the pair looked up the other way round.
#[test]
fn walls_behind_a_node_have_no_child() {
    let comb = Scene::from_json(include_str!("../../../examples/scenes/comb_room.json")).unwrap();
    let all: Vec<usize> = (0..comb.interfaces().len()).collect();
    let walls = MirrorWalls::new(&comb, &all);
    let (skips, tries) = behind_skips(&comb, &walls, Point::new(0.5, 0.5), 4);
    assert!(skips * 10 > tries, "{skips} skips of {tries} tries");
    let mut rng = crate::demo::SplitMix64(4242);
    let mut skipped = 0;
    for case in 0..80 {
        let room = if case < 40 {
            grid_room(&mut rng)
        } else {
            super::tests::random_room(case % 4, 1, 1, &mut rng)
        };
        let scene = super::tests::room_scene(&room, &[]);
        let all: Vec<usize> = (0..scene.interfaces().len()).collect();
        let walls = MirrorWalls::new(&scene, &all);
        let depth = if case < 40 { 4 } else { 3 };
        skipped += behind_skips(&scene, &walls, room.sources[0], depth).0;
    }
    assert!(skipped > 0);
}

/// [`thin`] decides as [`subtends`] does: at random segments, at segments subtending the
/// threshold to within 1e-15 to 1e-6 of it (on both sides), and at degenerate ones (a zero
/// end, a zero angle, huge and tiny coordinates).
///
/// Mutant caught: the band's two answers swapped.
#[test]
fn thin_is_the_angle_below_the_threshold() {
    let mut rng = crate::demo::SplitMix64(60);
    let mut near = 0;
    for round in 0..200_000 {
        let scale = [1e-150, 1e-3, 1.0, 1e3, 1e150][round % 5];
        let r = |rng: &mut crate::demo::SplitMix64| (2.0 * rng.next_f64() - 1.0) * scale;
        let x = Point::new(r(&mut rng), r(&mut rng));
        let a = Point::new(r(&mut rng), r(&mut rng));
        let b = match round % 4 {
            // An angle of THIN (1 + e) at `x`, e down to 1e-15.
            0 | 1 => {
                let e = (2.0 * rng.next_f64() - 1.0) * 10f64.powi(-6 - (round % 10) as i32);
                let angle = (THIN * (1.0 + e)).asin();
                let (s, c) = angle.sin_cos();
                let u = a - x;
                near += 1;
                x + Vec2::new(c * u.x - s * u.y, s * u.x + c * u.y) * (0.5 + rng.next_f64())
            }
            2 => [x, a, a + (a - x) * rng.next_f64()][round % 3],
            _ => Point::new(r(&mut rng), r(&mut rng)),
        };
        assert_eq!(
            thin(x, a, b),
            subtends(x, a, b) < THIN,
            "{x:?} {a:?} {b:?}: {:e}",
            subtends(x, a, b) / THIN - 1.0
        );
    }
    assert!(near > 0);
}

/// Whether the crossing test among pair `(a, b)`'s listed segments and the whole scene's
/// test agree on the leg from `wall a` at `u` to `wall b` at `v` (the leg's line given by
/// two other points of it, so that it differs from the ends by round-off); `None` where
/// the leg is too short for the lists, else whether the whole test found a crossing.
fn lists_agree(
    scene: &Scene,
    walls: &MirrorWalls,
    a: usize,
    b: usize,
    u: f64,
    v: f64,
) -> Option<bool> {
    let (wa, wb) = (&walls.walls[a], &walls.walls[b]);
    let (p, q) = (wa.at(u), wb.at(v));
    if (q - p).length() <= walls.crossers.shortest || p == q {
        return None;
    }
    let d = q - p;
    let line = [p - d * 0.37, q + d * 1.3];
    let own = [wa.own, wb.own];
    let whole = scene.first_crossing_on_line(p, q, line, END_MARGIN, own);
    let listed = walls.crossers.of(a, b).expect("lists kept");
    let among = scene.first_crossing_on_line_among(p, q, line, END_MARGIN, listed, own);
    assert_eq!(
        whole.is_some(),
        among.is_some(),
        "walls {a} → {b} at {u}, {v}: {p:?} → {q:?}: whole {whole:?}, listed {among:?}"
    );
    Some(whole.is_some())
}

/// The segments listed for a pair of walls are every segment a leg between them can be
/// found to cross: in the comb, 40 rooms of right angles on a grid (legs exactly through
/// corners) and 40 random rooms (round-off everywhere), legs from random points of each
/// wall to random points of every other and from points within 1e-9 and 1e-12 of the
/// walls' ends (legs along a wall, and from corner to corner), the test among the pair's
/// list finds a crossing exactly where the whole scene's does; and the lists leave
/// segments out.
///
/// Mutant caught: a pair's list without the segments near the walls' hull (the comb's
/// legs between its arms cross the notch).
#[test]
fn listed_crossers_find_every_crossing() {
    let comb = Scene::from_json(include_str!("../../../examples/scenes/comb_room.json")).unwrap();
    let mut rng = crate::demo::SplitMix64(4243);
    let mut scenes = vec![comb];
    for case in 0..80 {
        let room = if case < 40 {
            grid_room(&mut rng)
        } else {
            super::tests::random_room(case % 4, 1, 1, &mut rng)
        };
        scenes.push(super::tests::room_scene(&room, &[]));
    }
    let (mut crossing, mut legs, mut listed, mut possible) = (0u64, 0u64, 0usize, 0usize);
    for scene in &scenes {
        let all: Vec<usize> = (0..scene.interfaces().len()).collect();
        let walls = MirrorWalls::new(scene, &all);
        let n = walls.count();
        for a in 0..n {
            for b in (0..n).filter(|&b| b != a) {
                listed += walls.crossers.of(a, b).unwrap().len();
                possible += scene.segments().len() - 2;
                let mut fractions: Vec<(f64, f64)> =
                    (0..60).map(|_| (rng.next_f64(), rng.next_f64())).collect();
                for &e in &[1e-9, 1e-12, 0.0] {
                    fractions.extend([(e, 0.5), (1.0 - e, 0.5), (0.5, e), (0.5, 1.0 - e)]);
                    fractions.extend([(e, e), (1.0 - e, 1.0 - e), (e, 1.0 - e), (1.0 - e, e)]);
                }
                for (u, v) in fractions {
                    if let Some(found) = lists_agree(scene, &walls, a, b, u, v) {
                        legs += 1;
                        crossing += u64::from(found);
                    }
                }
            }
        }
    }
    assert!(
        crossing > 1000 && crossing < legs,
        "{crossing} crossings of {legs} legs"
    );
    assert!(listed * 10 < possible * 9, "{listed} listed of {possible}");
}
