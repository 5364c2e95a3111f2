//! The collect-then-sum response of a scene (what Python's `transmission_loss()` and
//! `impulse_response()` do at this commit): `response_reference SCENE tl|ir OUT.f64`.
use eigenray::response::{ImpulseResponses, echoes_of_scene, pressure_into, transmission_loss};
use eigenray::{Scene, Tracer};
use num_complex::Complex64;
use std::io::Write;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).unwrap();
    let scene = Scene::from_json(&text).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let echoes = echoes_of_scene(&tracer).unwrap();
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    let values: Vec<f64> = if args[2] == "tl" {
        let f = scene.amplitudes().unwrap().frequency.unwrap();
        let mut p = vec![Complex64::new(0.0, 0.0); s * r];
        pressure_into(echoes.iter().copied(), f, s, &mut p);
        p.iter().map(|&p| transmission_loss(p)).collect()
    } else {
        let ir = ImpulseResponses::new(scene.impulse_response().unwrap(), s, r);
        let mut out = vec![0.0; ir.len()];
        ir.render_into(echoes.iter().copied(), &mut out);
        out
    };
    eprintln!("{} echoes", echoes.len());
    let mut f = std::io::BufWriter::new(std::fs::File::create(&args[3]).unwrap());
    for v in values {
        f.write_all(&v.to_le_bytes()).unwrap();
    }
}
