//! Times `Tracer::trace_batch_into` on a scene file, for comparisons with other front ends
//! (the Python package's benchmark runs it beside its own calls).
//!
//! `cargo run --release --example batch_timing -- SCENE.json [REPETITIONS]` prints the median
//! wall-clock seconds of one batch over the repetitions (after one warm-up batch), with the
//! tracer and the batch's arrays built once.

use eigenray::{Batch, BatchOptions, Scene, Tracer};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: batch_timing SCENE.json [REPETITIONS]")?;
    let repetitions: usize = args.next().map_or(Ok(5), |r| r.parse())?;
    let scene = Scene::from_json(&std::fs::read_to_string(&path)?)?;
    let tracer = Tracer::new(&scene)?;
    let options = BatchOptions::default();
    let mut batch = Batch::default();
    let run = eigenray::options::Run::new();
    tracer.trace_batch_into(&options, &run, &mut batch)?;
    let mut seconds: Vec<f64> = (0..repetitions.max(1))
        .map(|_| {
            let start = Instant::now();
            tracer
                .trace_batch_into(&options, &run, &mut batch)
                .expect("allocated by the first batch");
            start.elapsed().as_secs_f64()
        })
        .collect();
    seconds.sort_by(f64::total_cmp);
    println!("{}", seconds[seconds.len() / 2]);
    Ok(())
}
