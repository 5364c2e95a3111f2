//! eigenray's automatic search ([`Tracer::search`]) on pyroomacoustics' two rooms
//! (`fixtures/pyroomacoustics/{hexagon,l_shape}.json`: every wall its own interface, every
//! wall sequence to order 4), or on the scene files given, timed in-process on one thread.
//!
//! `cargo run --release --example search_rooms -- [REPETITIONS] [--arrivals] [SCENE.json ...]`
//! prints one JSON line per room: the median time of `Tracer::search` with the tracer built
//! once before the timing (`search_ms`), and of `Tracer::new` followed by `Tracer::search`
//! (`new_and_search_ms`), over `REPETITIONS` calls each (default 500) after a warm-up; with
//! `--arrivals`, also every arrival (source, receiver, walls, time). `benches/search_rooms.py`
//! runs it in alternation with pyroomacoustics' `image_source_model` on the same rooms and
//! checks the arrivals against exact ones; `benches/comb_room.py` runs it on the comb-shaped
//! room against the order and `max_time`.

use std::hint::black_box;
use std::time::Instant;

use eigenray::{Scene, Tracer};

/// The rooms, by name.
const ROOMS: [&str; 2] = ["hexagon", "l_shape"];

/// The median of `times`.
fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Median wall time in milliseconds of `repetitions` calls of `f`, after a tenth as many.
fn time_ms(repetitions: usize, mut f: impl FnMut()) -> f64 {
    for _ in 0..repetitions.div_ceil(10) {
        f();
    }
    let times = (0..repetitions)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    median(times)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repetitions: usize = args
        .iter()
        .find_map(|a| a.parse().ok())
        .unwrap_or(500)
        .max(1);
    let arrivals = args.iter().any(|a| a == "--arrivals");
    let files: Vec<String> = args
        .iter()
        .filter(|a| a.ends_with(".json"))
        .cloned()
        .collect();
    let rooms: Vec<(String, String)> = if files.is_empty() {
        ROOMS
            .iter()
            .map(|name| {
                let path = format!(
                    "{}/fixtures/pyroomacoustics/{name}.json",
                    env!("CARGO_MANIFEST_DIR")
                );
                (name.to_string(), path)
            })
            .collect()
    } else {
        files.iter().map(|f| (f.clone(), f.clone())).collect()
    };
    // One thread: the search's parallel loops run on a pool of one.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    pool.install(|| {
        for (name, path) in &rooms {
            let text = std::fs::read_to_string(path).expect("the room's scene");
            let scene = Scene::from_json(&text).expect("a valid scene");
            let tracer = Tracer::new(&scene).expect("a tracer");
            let found = tracer
                .search(&eigenray::options::Run::new())
                .expect("the scene's search")
                .arrivals;
            let search_ms = time_ms(repetitions, || {
                black_box(
                    tracer
                        .search(&eigenray::options::Run::new())
                        .expect("the scene's search")
                        .arrivals,
                );
            });
            let new_and_search_ms = time_ms(repetitions, || {
                let tracer = Tracer::new(black_box(&scene)).expect("a tracer");
                black_box(
                    tracer
                        .search(&eigenray::options::Run::new())
                        .expect("the scene's search")
                        .arrivals,
                );
            });
            let mut line = format!(
                "{{\"room\": \"{name}\", \"sources\": {}, \"receivers\": {}, \"arrivals\": {}, \
                 \"search_ms\": {search_ms}, \"new_and_search_ms\": {new_and_search_ms}",
                scene.sources().len(),
                scene.receivers().len(),
                found.len(),
            );
            if arrivals {
                let list: Vec<String> = found
                    .iter()
                    .map(|a| {
                        let walls: Vec<&str> = a
                            .steps
                            .iter()
                            .map(|s| scene.interfaces()[s.interface].name.as_str())
                            .collect();
                        format!(
                            "[{}, {}, {:?}, \"{}\", {:?}, {:?}]",
                            a.source,
                            a.receiver,
                            walls,
                            a.arrival.status,
                            a.arrival.time,
                            a.arrival.segments
                        )
                    })
                    .collect();
                line += &format!(", \"list\": [{}]", list.join(", "));
            }
            println!("{line}}}");
        }
    });
}
