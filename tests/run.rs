//! Every long call honours its `Run`: a stop requested before the call does no work and says
//! so, a stop requested during the call ends it, a budget of `N` units lets at most `N`
//! through (and what was done equals the unbounded call's own results), and `max_time` keeps
//! exactly the arrivals of an unbounded search up to that time, one test per long call: the
//! batch, every stationary path (all triples, and one triple), the search's beam tree and its
//! walk over sequences, and each response (the echoes of a scene, an impulse response, a
//! pressure). The ground truth is the same call without limits, and counts.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use eigenray::amplitude::Complex64;
use eigenray::batch::{BatchScratch, BatchSink, RaySlot};
use eigenray::options::{Progress, Run};
use eigenray::response::{Echo, ImpulseResponses, echoes_of_scene, pressure_into};
use eigenray::scene::ImpulseResponseOptions;
use eigenray::scene::ImpulseResponseSpec;
use eigenray::search::{SearchArrival, SearchReport};
use eigenray::{BatchOptions, Point, RayRecord, Reason, Scene, Status, Tracer};
use serde_json::{Value, json};

/// Beams a search's tree asks its run for at a time.
const BEAM_BLOCK: u64 = 1 << 14;

/// The comb-shaped room of pyroomacoustics issue #383 as one closed polyline in air, one
/// source, nine listeners, with `search`: its beam tree grows far faster than its arrivals.
fn comb_room(search: Value) -> Scene {
    let corners = [
        [0.0, 0.0],
        [0.0, 5.0],
        [1.0, 5.0],
        [1.0, 2.0],
        [2.0, 2.0],
        [2.0, 5.0],
        [3.0, 5.0],
        [3.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 0.0],
    ];
    let doc = json!({
        "media": { "air": { "speed": 343.0, "at": [0.5, 0.5] } },
        "interfaces": { "room": { "points": corners, "closed": true } },
        "sources": [[0.5, 0.5]],
        "receivers": [[2.5, 4.5], [0.5, 4.5], [0.5, 2.5], [2.5, 2.5], [2.5, 0.5], [1.5, 1.5],
                      [0.25, 1.25], [2.75, 3.75], [1.25, 1.75]],
        "search": search,
    });
    Scene::from_json(&doc.to_string()).unwrap()
}

/// Air over water under a bent surface, a flat bottom: the walk over sequences with
/// refractions (and the tree for the reflections), with `search`.
fn air_water(search: Value) -> Scene {
    let doc = json!({
        "domain": [[-20, -10], [20, 10]],
        "media": { "air": { "speed": 343.0, "at": [0.0, 5.0] },
                   "water": { "speed": 1500.0, "at": [0.0, -5.0] } },
        "interfaces": {
            "surface": { "points": [[-20, 0], [-5, 0.5], [5, -0.5], [20, 0]] },
            "bottom": { "points": [[-20, -10], [20, -10]] }
        },
        "sources": [[0.0, 5.0], [-3.0, 2.0]],
        "receivers": [[8.0, 3.0], [6.0, -4.0], [-7.0, -8.0], [2.0, 1.0]],
        "search": search
    });
    Scene::from_json(&doc.to_string()).unwrap()
}

/// A run that counts its work without bounding it (a budget it cannot reach).
fn counting() -> Run {
    Run::new().budget(u64::MAX - 1)
}

/// A run that asks itself to stop the first time it lets work through.
fn stopping_at_first_work() -> Run {
    let run = Run::new();
    let handle = run.clone();
    run.on_progress(move |p: Progress| {
        if p.work > 0 {
            handle.request_stop();
        }
    })
}

/// Whether two arrivals are the same, bit for bit (all but `complete`).
fn same(a: &SearchArrival, b: &SearchArrival) -> bool {
    (
        a.source,
        a.receiver,
        &a.steps,
        a.arrival.status,
        a.arrival.segments.as_slice(),
    ) == (
        b.source,
        b.receiver,
        &b.steps,
        b.arrival.status,
        b.arrival.segments.as_slice(),
    ) && a.arrival.time.to_bits() == b.arrival.time.to_bits()
        && a.arrival.points.len() == b.arrival.points.len()
        && a.arrival
            .points
            .iter()
            .zip(&b.arrival.points)
            .all(|(p, q)| p.x.to_bits() == q.x.to_bits() && p.y.to_bits() == q.y.to_bits())
}

/// Every arrival of `short` is one of `full`'s, bit for bit, and a pair that says it is
/// complete has all of `full`'s arrivals of that pair.
fn assert_part_of(short: &SearchReport, full: &SearchReport) {
    for a in &short.arrivals {
        assert!(full.arrivals.iter().any(|b| same(a, b)), "{a:?}");
    }
    for a in full.arrivals.iter() {
        let pair = |x: &SearchArrival| (x.source, x.receiver) == (a.source, a.receiver);
        let complete = short
            .arrivals
            .iter()
            .filter(|x| pair(x))
            .all(|x| x.complete)
            && short.arrivals.iter().any(pair);
        if complete {
            assert!(short.arrivals.iter().any(|b| same(a, b)), "{a:?} missing");
        }
    }
}

/// The arrivals of `report` up to time `t`, with `complete` as the report says.
fn up_to(report: &SearchReport, t: f64) -> Vec<SearchArrival> {
    report
        .arrivals
        .iter()
        .filter(|a| a.arrival.time <= t)
        .cloned()
        .collect()
}

fn assert_same_list(a: &[SearchArrival], b: &[SearchArrival]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert!(same(x, y) && x.complete == y.complete, "{x:?}\n{y:?}");
    }
}

/// A sink that records each ray's record, and counts the writes.
struct Records<'a>(&'a mut [Option<RayRecord>]);

impl BatchSink for Records<'_> {
    fn blocks(&self) -> usize {
        self.0.len()
    }
    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.0.split_at_mut(blocks);
        (Records(a), Records(b))
    }
    fn write(&mut self, at: RaySlot, record: &RayRecord, _: &[Point], _: &[usize]) {
        assert!(self.0[at.block].is_none(), "a ray written twice");
        self.0[at.block] = Some(*record);
    }
}

/// The records of every ray of a one-path scene's batch with `run`, in ray order.
fn batch_records(tracer: &Tracer, opts: &BatchOptions, run: &Run) -> Vec<RayRecord> {
    let mut out = vec![None; tracer.scene().num_rays()];
    let mut scratch = BatchScratch::default();
    tracer
        .trace_batch_to(opts, run, Records(&mut out), &mut scratch)
        .unwrap();
    out.into_iter()
        .map(|r| r.expect("every ray is written once"))
        .collect()
}

fn not_solved(r: &RayRecord) -> bool {
    r.status == Status::NotConverged && r.reason == Some(Reason::SearchLimit)
}

fn same_record(a: &RayRecord, b: &RayRecord) -> bool {
    (a.status, a.iterations, a.reason) == (b.status, b.iterations, b.reason)
        && a.time.to_bits() == b.time.to_bits()
        && a.residual.to_bits() == b.residual.to_bits()
}

/// The batch: a stop before it solves nothing (every ray written, `not_converged` at a
/// limit, no work spent); a stop during it ends it after the first unit; a budget of `N` rays
/// solves at most `N`, each exactly as the unbounded batch does, and the rest are marked.
#[test]
fn the_batch_honours_its_run() {
    let scene = Scene::from_spec(&eigenray::demo::air_water(1000, 7)).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let opts = BatchOptions {
        chunk: 16,
        ..BatchOptions::default()
    };
    let full = batch_records(&tracer, &opts, &Run::new());
    assert!(full.iter().all(|r| r.status == Status::Converged));

    let run = counting();
    run.request_stop();
    let none = batch_records(&tracer, &opts, &run);
    assert!(none.iter().all(not_solved));
    assert_eq!((run.spent(), run.items()), (0, 0));

    let run = stopping_at_first_work();
    let first = batch_records(&tracer, &opts, &run);
    let solved = first.iter().filter(|r| !not_solved(r)).count();
    // One unit per worker thread may have been let through before the stop was seen.
    assert!(
        (16..=16 * rayon::current_num_threads()).contains(&solved),
        "{solved}"
    );

    for budget in [0, 15, 16, 100, 999] {
        let run = Run::new().budget(budget);
        let part = batch_records(&tracer, &opts, &run);
        let solved: Vec<usize> = (0..part.len()).filter(|&i| !not_solved(&part[i])).collect();
        assert!(solved.len() as u64 <= budget, "{} > {budget}", solved.len());
        // Whole units only: 62 of 16 rays and the last of 1000 % 16 = 8, which the scheduler
        // may take first.
        assert!([0, 8].contains(&(solved.len() % 16)), "{}", solved.len());
        assert_eq!(run.spent(), solved.len() as u64);
        assert!(run.stopped() && !run.stop_requested());
        for &i in &solved {
            assert!(same_record(&part[i], &full[i]), "ray {i}");
        }
    }
    // A budget it does not reach: the whole batch, as without one.
    let run = Run::new().budget(1000);
    let all = batch_records(&tracer, &opts, &run);
    assert!(all.iter().zip(&full).all(|(a, b)| same_record(a, b)) && !run.stopped());
}

/// A valley mirror seen by many receivers, every stationary path of each.
fn valley() -> Scene {
    let receivers: Vec<[f64; 2]> = (0..40).map(|i| [-4.0 + 0.2 * i as f64, 2.0]).collect();
    let doc = json!({
        "media": { "air": { "speed": 1.0 } },
        "interfaces": { "valley": { "points": [[-3, 0], [-1, -1.5], [0, -2], [1, -1.2], [3, 0]] } },
        "sources": [[-0.5, 2], [0.7, 3]],
        "receivers": receivers,
        "paths": [
            { "steps": [{ "reflect": "valley" }], "media": ["air", "air"] },
            { "steps": [{ "reflect": "valley" }, { "reflect": "valley" }], "media": ["air", "air", "air"] }
        ],
        "solver": { "stationary": "all" }
    });
    Scene::from_json(&doc.to_string()).unwrap()
}

/// Every stationary path of every triple, and of one: a stop before searches nothing (every
/// triple empty and not complete); a budget of `N` units spends at most `N`, every triple it
/// completes equals the unbounded one, and the triples it leaves short say so.
#[test]
fn every_stationary_path_honours_its_run() {
    let scene = valley();
    let tracer = Tracer::new(&scene).unwrap();
    let run = counting();
    let full = tracer.trace_stationary(&run).unwrap();
    let total = run.spent();
    assert!(full.complete() && total > 1000, "{total}");
    assert_eq!(run.items(), scene.num_rays() as u64);

    let run = counting();
    run.request_stop();
    let none = tracer.trace_stationary(&run).unwrap();
    assert!(
        none.triples
            .iter()
            .all(|t| t.arrivals.is_empty() && !t.complete)
    );
    assert_eq!(run.spent(), 0);

    for budget in [1, total / 3, total - 1] {
        let run = Run::new().budget(budget);
        let part = tracer.trace_stationary(&run).unwrap();
        assert!(run.spent() <= budget && run.stopped());
        assert!(part.triples.iter().any(|t| !t.complete));
        for (p, f) in part.triples.iter().zip(&full.triples) {
            if p.complete {
                assert_eq!(p.arrivals, f.arrivals);
            }
        }
    }
    let run = Run::new().budget(total);
    assert_eq!(tracer.trace_stationary(&run).unwrap(), full);

    // One triple.
    let (s, r) = (scene.sources()[0], scene.receivers()[22]);
    let mut out = Vec::new();
    let run = counting();
    let one = tracer.stationary_paths(s, r, 0, &run, &mut out).unwrap();
    let (each, arrivals) = (run.spent(), out.clone());
    assert!(one.complete, "{one:?}");
    assert!(!arrivals.is_empty() && each >= 2, "{each}");
    let run = Run::new();
    run.request_stop();
    let stopped = tracer.stationary_paths(s, r, 0, &run, &mut out).unwrap();
    assert!(!stopped.complete && out.is_empty());
    let run = Run::new().budget(each / 2);
    let short = tracer.stationary_paths(s, r, 0, &run, &mut out).unwrap();
    assert!(!short.complete && run.spent() <= each / 2);
    let run = Run::new().budget(each);
    let whole = tracer.stationary_paths(s, r, 0, &run, &mut out).unwrap();
    assert!(whole.complete && out == arrivals);
}

/// The search's beam tree (a room, reflections only): a stop before lists nothing and every
/// pair says `complete: false`; a stop during it ends it within the block of beams it was
/// given; a budget of `N` beams visits at most `N`, and lists a part of the unbounded
/// search's arrivals (all of a pair's where it says it is complete); `max_time` lists exactly
/// the unbounded search's arrivals up to that time, one arriving at it exactly included.
#[test]
fn the_beam_tree_honours_its_run() {
    // Deep enough for several blocks of beams.
    let (steps, tracer, full) = (12..40)
        .step_by(2)
        .map(|k| {
            let tracer = Tracer::new(comb_room(json!({ "max_steps": k }))).unwrap();
            let full = tracer.search(&Run::new()).unwrap();
            (k, tracer, full)
        })
        .find(|(_, _, full)| full.beams > 4 * BEAM_BLOCK)
        .unwrap();
    assert_eq!(full.incomplete_pairs, 0);
    assert_eq!(full.work, 0, "no walk");

    let run = Run::new();
    run.request_stop();
    let none = tracer.search(&run).unwrap();
    assert!(none.arrivals.is_empty() && none.beams == 0);
    assert_eq!(none.incomplete_pairs, 9);

    let run = stopping_at_first_work();
    let first = tracer.search(&run).unwrap();
    assert!(first.beams <= BEAM_BLOCK && first.incomplete_pairs == 9);
    assert_part_of(&first, &full);

    for budget in [BEAM_BLOCK - 1, BEAM_BLOCK, 3 * BEAM_BLOCK + 5] {
        let run = Run::new().budget(budget);
        let part = tracer.search(&run).unwrap();
        assert!(
            part.beams <= budget && run.spent() <= budget,
            "{}",
            part.beams
        );
        assert!(part.incomplete_pairs == 9 && part.arrivals.len() < full.arrivals.len());
        assert!(part.arrivals.iter().all(|a| !a.complete));
        assert_part_of(&part, &full);
    }

    // `max_time` at the time of an arrival of the unbounded search, within its steps.
    let t = full.arrivals[full.arrivals.len() / 2].arrival.time;
    let timed = comb_room(json!({ "max_steps": steps, "max_time": t }));
    let by_time = Tracer::new(&timed).unwrap().search(&Run::new()).unwrap();
    assert!(by_time.arrivals.iter().any(|a| a.arrival.time == t));
    assert_same_list(&by_time.arrivals, &up_to(&full, t));
    assert!(by_time.beams < full.beams);
}

/// The search's walk over sequences with refractions: a stop before lists nothing; a budget
/// of `N` units spends at most `N` and lists a part of the unbounded search's arrivals;
/// `max_time` lists exactly the unbounded search's arrivals up to that time.
#[test]
fn the_walk_honours_its_run() {
    let scene = air_water(json!({ "max_steps": 3 }));
    let tracer = Tracer::new(&scene).unwrap();
    let run = counting();
    let full = tracer.search(&run).unwrap();
    let total = run.spent();
    assert_eq!(full.incomplete_pairs, 0);
    assert!(
        full.work > 100 && total >= full.work,
        "{} {total}",
        full.work
    );
    let refracted = |a: &SearchArrival| {
        a.steps
            .iter()
            .any(|s| s.kind == eigenray::scene::StepKind::Refract)
    };
    assert!(full.arrivals.iter().filter(|a| refracted(a)).count() > 4);

    let run = Run::new();
    run.request_stop();
    let none = tracer.search(&run).unwrap();
    assert!(none.arrivals.is_empty() && none.work == 0 && none.incomplete_pairs == 8);

    for budget in [1, total / 4, total - 1] {
        let run = Run::new().budget(budget);
        let part = tracer.search(&run).unwrap();
        assert!(run.spent() <= budget);
        assert!(part.incomplete_pairs > 0);
        assert_part_of(&part, &full);
    }

    let t = full
        .arrivals
        .iter()
        .filter(|a| refracted(a))
        .map(|a| a.arrival.time)
        .nth(2)
        .unwrap();
    let timed = air_water(json!({ "max_steps": 3, "max_time": t }));
    let by_time = Tracer::new(&timed).unwrap().search(&Run::new()).unwrap();
    assert!(
        by_time
            .arrivals
            .iter()
            .any(|a| a.arrival.time == t && refracted(a))
    );
    assert_same_list(&by_time.arrivals, &up_to(&full, t));
    assert!(by_time.work < full.work);
}

/// Echoes with amplitudes one a sample apart, at receiver `i % 2`.
fn echoes(n: usize) -> Vec<Echo> {
    (0..n)
        .map(|i| Echo {
            source: 0,
            receiver: i % 2,
            time: 0.001 * (i + 3) as f64 + 1e-4,
            amplitude: Complex64::new(1.0 / (i + 1) as f64, 0.5),
            order: i,
            diffractions: 0,
            vertical_reflections: 0,
        })
        .collect()
}

/// An impulse response and a pressure: a stop before renders or sums nothing; a budget lets
/// through exactly the echoes whose units fit, and the result equals rendering (or summing)
/// those echoes alone without limits.
#[test]
fn the_responses_honour_their_run() {
    let spec = ImpulseResponseSpec::new(1000.0, 0.05);
    let options = ImpulseResponseOptions::of_spec("impulse_response", &spec).unwrap();
    let ir = ImpulseResponses::new(&options, 1, 2);
    let taps = ir.pulse().taps() as u64;
    let all = echoes(10);

    let run = Run::new();
    run.request_stop();
    let silent = ir.render(all.iter().copied(), &run).unwrap();
    assert!(silent.iter().all(|&v| v == 0.0));
    for n in [0, 1, 4, 9] {
        let run = Run::new().budget(n * taps + taps - 1);
        let part = ir.render(all.iter().copied(), &run).unwrap();
        let want = ir
            .render(all[..n as usize].iter().copied(), &Run::new())
            .unwrap();
        assert_eq!(part, want, "{n} echoes");
        assert_eq!((run.spent(), run.items()), (n * taps, n));
        assert_ne!(part, ir.render(all.iter().copied(), &Run::new()).unwrap());
    }

    let mut p = vec![Complex64::new(0.0, 0.0); 2];
    let run = Run::new();
    run.request_stop();
    pressure_into(all.iter().copied(), 50.0, 1, &run, &mut p);
    assert!(p.iter().all(|v| v.norm() == 0.0));
    for n in [1, 5] {
        let run = Run::new().budget(n);
        pressure_into(all.iter().copied(), 50.0, 1, &run, &mut p);
        let mut want = vec![Complex64::new(0.0, 0.0); 2];
        pressure_into(
            all[..n as usize].iter().copied(),
            50.0,
            1,
            &Run::new(),
            &mut want,
        );
        assert_eq!(p, want);
    }
}

/// The echoes of a scene (a batch and a search, with amplitudes): a stop before finds none; a
/// budget bounds the work of both; `max_time` keeps the search's echoes up to that time.
#[test]
fn the_echoes_of_a_scene_honour_their_run() {
    let mut doc: Value =
        serde_json::from_str(&comb_room(json!({ "max_steps": 6 })).to_json()).unwrap();
    doc["amplitudes"] = json!({ "source": "point" });
    doc["paths"] = json!([{ "steps": [] }]);
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let run = counting();
    let full = echoes_of_scene(&tracer, &run).unwrap();
    let total = run.spent();
    assert!(full.len() > 100 && total > 0);

    let run = Run::new();
    run.request_stop();
    assert!(echoes_of_scene(&tracer, &run).unwrap().is_empty());

    let run = Run::new().budget(total / 2);
    let part = echoes_of_scene(&tracer, &run).unwrap();
    assert!(run.spent() <= total / 2 && part.len() < full.len());
    for e in &part {
        assert!(full.contains(e), "{e:?}");
    }

    let t = full[full.len() / 2].time;
    doc["search"] = json!({ "max_steps": 6, "max_time": t });
    let timed = Tracer::new(Scene::from_json(&doc.to_string()).unwrap()).unwrap();
    let by_time = echoes_of_scene(&timed, &Run::new()).unwrap();
    // The paths' echoes first, then the search's.
    let mut paths_only = doc.clone();
    paths_only.as_object_mut().unwrap().remove("search");
    let paths_only = Tracer::new(Scene::from_json(&paths_only.to_string()).unwrap()).unwrap();
    let rays = echoes_of_scene(&paths_only, &Run::new()).unwrap().len();
    assert!(rays > 0);
    let want: Vec<Echo> = full
        .iter()
        .enumerate()
        .filter(|(i, e)| *i < rays || e.time <= t)
        .map(|(_, e)| *e)
        .collect();
    assert_eq!(by_time, want);
}

/// A stop requested by the progress callback's first report, counted in items, ends a
/// stationary call too; and a run's items count what was begun.
#[test]
fn a_run_counts_what_it_lets_through() {
    let heard = Arc::new(AtomicU64::new(0));
    let counter = heard.clone();
    let run = Run::new().on_progress(move |p: Progress| {
        counter.fetch_add(p.items, Ordering::Relaxed);
    });
    let scene = valley();
    let tracer = Tracer::new(&scene).unwrap();
    tracer.trace_stationary(&run).unwrap();
    assert_eq!(heard.load(Ordering::Relaxed), scene.num_rays() as u64);
    assert_eq!(run.items(), scene.num_rays() as u64);
}
