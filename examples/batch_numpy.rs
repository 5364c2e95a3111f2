//! A large batch into NumPy: 100,000 receivers under a water surface, traced in parallel into
//! flat arrays and written as a `.npy` file beside the name tables that give its codes and
//! indices their names.
//!
//! Run with `cargo run --release --example batch_numpy [DIR]` (default: the system's temporary
//! directory); it prints the Python that reads the two files.

use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;

use eigenray::{BatchOptions, Format, Scene, Tracer, output::write_names, write};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args_os()
        .nth(1)
        .map_or_else(std::env::temp_dir, PathBuf::from);
    let scene = Scene::from_spec(&eigenray::demo::air_water(100_000, 1))?;
    let tracer = Tracer::new(&scene)?;

    let start = std::time::Instant::now();
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let solved = start.elapsed();

    let rays = dir.join("rays.npy");
    let names = dir.join("rays.names.json");
    write(
        &scene,
        &batch,
        Format::Npy,
        BufWriter::new(File::create(&rays)?),
    )?;
    write_names(&scene, BufWriter::new(File::create(&names)?))?;
    println!(
        "{} rays solved in {:.1} ms; wrote {} and {}",
        batch.len(),
        solved.as_secs_f64() * 1e3,
        rays.display(),
        names.display()
    );
    println!(
        "\nimport json, numpy as np\n\
         rays = np.load({rays:?})\n\
         names = json.load(open({names:?}))\n\
         ok = rays[rays['status'] == names['status'].index('converged')]\n\
         print(len(ok), ok['time'].min(), ok['time'].max())\n\
         print([names['media'][m] for m in ok['media'][0]])   # ['air', 'water']\n\
         hits = ok['points'][:, 1]                             # the refraction points (x, y)",
        rays = rays.display().to_string(),
        names = names.display().to_string(),
    );
    Ok(())
}
