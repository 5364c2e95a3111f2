//! Every stationary path of one reflection off a digitised sea floor: time per ray of
//! `Tracer::stationary_paths` against the number of segments `M`, and against the number of
//! arrivals on a corrugated floor.
//!
//! `cargo run --release --example stationary` prints two tables and writes their plots,
//! `docs/stationary_segments.svg` and `docs/stationary_arrivals.svg`:
//! - per `M` (10 to 10⁶, `demo::sea_floor(M, 1000)`: one reflection point per receiver), the
//!   time per ray, the arrivals per ray and the tuples and solves the search spent on each;
//! - per number of undulations `n` of a corrugated floor (the sea floor with ripples of
//!   wavelength `20 / n` km and 25 m amplitude added, digitised with 100,000 segments), the
//!   same: each ripple in sight adds two reflection points, so the arrivals per ray grow with
//!   `n`.
//!
//! One thread, its CPU time (the median of 5 runs); the hierarchy of the floor is built before
//! the timing. Issue 18's target: at
//! most 20 µs per ray at `M = 100,000`. `cargo run --release --example stationary -- M`
//! measures one size and writes nothing.

#[path = "../benches/support/plot.rs"]
mod plot;
#[path = "../benches/support/timing.rs"]
mod timing;

use eigenray::{Arrival, Scene, SceneSpec, Status, Tracer, demo};
use plot::{Plot, Scale, Series};
use timing::{load_average, time_per_call};

/// Receivers per scene of the `M` curve.
const RECEIVERS: usize = 1000;
/// Receivers per scene of the arrivals curve (more arrivals, more time per ray).
const CORRUGATED_RECEIVERS: usize = 200;
/// Segments of the corrugated floors.
const CORRUGATED_SEGMENTS: usize = 100_000;
/// Ripples across the corrugated floors of the arrivals curve.
const RIPPLES: [usize; 7] = [0, 10, 25, 50, 100, 200, 400];
/// Amplitude of the ripples (km).
const RIPPLE: f64 = 0.025;
/// Timed runs per scene (the median is kept), each of whole rounds over the receivers lasting
/// at least `MIN_RUN` seconds.
const RUNS: usize = 5;
/// See [`RUNS`].
const MIN_RUN: f64 = 0.1;

/// One measured scene.
struct Row {
    /// Time per ray (µs).
    micros: f64,
    arrivals: f64,
    converged: usize,
    vertex: usize,
    obstructed: usize,
    tuples: f64,
    solves: f64,
}

/// Times `Tracer::stationary_paths` on every receiver of `spec`'s scene (one source, one
/// path): the thread's CPU time per ray, the median of [`RUNS`] runs.
fn measure(spec: &SceneSpec) -> Row {
    let scene = Scene::from_spec(spec).expect("the demo scene");
    let tracer = Tracer::new(&scene).expect("no regions");
    let source = scene.sources()[0];
    let receivers = scene.receivers();
    let mut out: Vec<Arrival> = Vec::new();
    // Builds the hierarchy (once per interface), outside the timing.
    tracer
        .stationary_paths(
            source,
            receivers[0],
            0,
            &eigenray::options::Run::new(),
            &mut out,
        )
        .expect("media given");
    let (mut arrivals, mut converged, mut vertex, mut obstructed) = (0, 0, 0, 0);
    let (mut tuples, mut solves) = (0, 0);
    for &receiver in receivers {
        let search = tracer
            .stationary_paths(
                source,
                receiver,
                0,
                &eigenray::options::Run::new(),
                &mut out,
            )
            .expect("media given");
        assert!(search.complete);
        arrivals += out.len();
        let count = |s: Status| out.iter().filter(|a| a.status == s).count();
        converged += count(Status::Converged);
        vertex += count(Status::Vertex);
        obstructed += count(Status::Obstructed);
        tuples += search.tuples;
        solves += search.solves;
    }
    // The thread's CPU time of a round over the receivers, the median of RUNS runs.
    let timing = time_per_call(RUNS, MIN_RUN, || {
        for &receiver in receivers {
            tracer
                .stationary_paths(
                    source,
                    receiver,
                    0,
                    &eigenray::options::Run::new(),
                    &mut out,
                )
                .expect("media given");
        }
    });
    let n = receivers.len() as f64;
    Row {
        micros: timing.cpu / n * 1e6,
        arrivals: arrivals as f64 / n,
        converged,
        vertex,
        obstructed,
        tuples: tuples as f64 / n,
        solves: solves as f64 / n,
    }
}

/// The sea floor of `demo::sea_floor` with `undulations` ripples of amplitude [`RIPPLE`]
/// across its 20 km, digitised with `segments` segments.
fn corrugated_floor(undulations: usize, segments: usize, receivers: usize) -> SceneSpec {
    let mut spec = demo::sea_floor(segments, receivers);
    let floor = spec.interfaces.get_mut("floor").expect("the floor");
    let k = std::f64::consts::TAU * undulations as f64 / 20.0;
    for p in &mut floor.points {
        p[1] += RIPPLE * (k * (p[0] + 10.0)).sin();
    }
    spec.description = Some(format!(
        "the sea floor of demo::sea_floor with {undulations} ripples of {RIPPLE} km amplitude, \
         {segments} segments"
    ));
    spec
}

fn header(first: &str) {
    println!(
        "| {first} | µs per ray | arrivals per ray | converged | vertex | obstructed | tuples per ray | solves per ray |"
    );
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
}

fn print_row(first: &str, r: &Row) {
    println!(
        "| {first} | {:.2} | {:.2} | {} | {} | {} | {:.1} | {:.1} |",
        r.micros, r.arrivals, r.converged, r.vertex, r.obstructed, r.tuples, r.solves
    );
}

fn main() -> std::io::Result<()> {
    if let Some(m) = std::env::args().nth(1) {
        let m: usize = m.parse().expect("a number of segments");
        header("M");
        print_row(&m.to_string(), &measure(&demo::sea_floor(m, RECEIVERS)));
        return Ok(());
    }

    // 1. Time per ray against M.
    header("M");
    let mut by_m = Vec::new();
    for m in [10, 100, 1_000, 10_000, 100_000, 1_000_000] {
        let row = measure(&demo::sea_floor(m, RECEIVERS));
        print_row(&m.to_string(), &row);
        by_m.push((m as f64, row));
    }
    let mut p = Plot::new(
        "Every stationary path of one reflection: cost against segments",
        "segments of the digitised sea floor (M)",
        "per ray",
        Scale::Log,
        Scale::Log,
    );
    p.subtitle = format!(
        "demo::sea_floor(M, {RECEIVERS}), stationary: all; CPU time of one thread; one arrival per ray"
    );
    p.series.push(Series::new(
        "time per ray (µs)",
        by_m.iter().map(|(m, r)| (*m, r.micros)).collect(),
        0,
    ));
    p.series.push(Series::new(
        "tuples visited per ray",
        by_m.iter().map(|(m, r)| (*m, r.tuples)).collect(),
        1,
    ));
    p.hlines.push((20.0, "target at M = 10⁵: 20 µs".into()));
    std::fs::write("docs/stationary_segments.svg", p.to_svg())?;

    // 2. Time per ray against arrivals per ray.
    println!();
    header("ripples");
    let mut by_n = Vec::new();
    for n in RIPPLES {
        let row = measure(&corrugated_floor(
            n,
            CORRUGATED_SEGMENTS,
            CORRUGATED_RECEIVERS,
        ));
        print_row(&n.to_string(), &row);
        by_n.push(row);
    }
    let mut p = Plot::new(
        "Every stationary path of one reflection: cost against arrivals",
        "stationary paths per ray (mean over the receivers)",
        "per ray",
        Scale::Log,
        Scale::Log,
    );
    p.subtitle = format!(
        "sea floor with 0 to {} ripples of {} m, {CORRUGATED_SEGMENTS} segments, {CORRUGATED_RECEIVERS} receivers; CPU time of one thread",
        RIPPLES[RIPPLES.len() - 1],
        RIPPLE * 1e3
    );
    let mut time = Series::new(
        "time per ray (µs)",
        by_n.iter().map(|r| (r.arrivals, r.micros)).collect(),
        0,
    );
    // (The floors of 0 and 10 ripples give about one arrival each: one label for both.)
    time.labels = RIPPLES
        .iter()
        .map(|&n| match n {
            0 => "0 and 10 ripples".to_string(),
            10 => String::new(),
            n => format!("{n} ripples"),
        })
        .collect();
    p.series.push(time);
    p.series.push(Series::new(
        "tuples visited per ray",
        by_n.iter().map(|r| (r.arrivals, r.tuples)).collect(),
        1,
    ));
    // A guide: cost proportional to the arrivals, through the middle point.
    let mid = &by_n[by_n.len() / 2];
    let per = mid.micros / mid.arrivals;
    let x_max = by_n.iter().map(|r| r.arrivals).fold(1.0, f64::max);
    let mut guide = Series::new(
        format!("proportional to the arrivals ({per:.1} µs each)"),
        vec![(1.0, per), (x_max, per * x_max)],
        7,
    );
    guide.dashed = true;
    guide.marker = plot::Marker::Ring;
    p.series.push(guide);
    std::fs::write("docs/stationary_arrivals.svg", p.to_svg())?;
    eprintln!(
        "wrote docs/stationary_segments.svg, docs/stationary_arrivals.svg (load average {})",
        load_average()
    );
    Ok(())
}
