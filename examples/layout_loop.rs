//! A layout tool's loop: a reflector panel over a stage, a listener moved from seat to seat,
//! and for each seat the panel's tilt that brings its reflection soonest after the direct
//! sound. The tool keeps the tracer in its own struct (the tracer owns its scene), and moves
//! the receiver and one vertex of the panel with the tracer's updates instead of building the
//! scene again: each update is validated as the scene file would be, and only what depends on
//! it is prepared again.
//!
//! Run with `cargo run --release --example layout_loop`.

use eigenray::{
    InterfaceSpec, MediumSpec, PathSpec, Point, Scene, Status, StepSpec, Tracer, Workspace,
};

/// What the layout tool keeps between edits.
struct Layout {
    tracer: Tracer,
    /// Index of the panel among the scene's interfaces.
    panel: usize,
    /// Scratch for solving rays: nothing is allocated once it has grown.
    ws: Workspace,
}

impl Layout {
    fn new() -> Result<Layout, Box<dyn std::error::Error>> {
        let scene = Scene::builder()
            .medium("air", MediumSpec::speed(343.0))
            .interface("panel", InterfaceSpec::open([[2.0, 6.0], [6.0, 6.5]]))
            .source([1.0, 1.5])
            .receiver([8.0, 1.2])
            .path(PathSpec::direct().named("direct").media(["air"]))
            .path(
                PathSpec::new([StepSpec::reflect("panel")])
                    .named("panel")
                    .media(["air", "air"]),
            )
            .build()?;
        let tracer = Tracer::new(scene)?;
        let panel = tracer
            .scene()
            .interface_index("panel")
            .ok_or("the scene has a panel")?;
        Ok(Layout {
            tracer,
            panel,
            ws: Workspace::new(),
        })
    }

    /// The delay of the panel's reflection after the direct sound at receiver 0, in seconds
    /// (`None` when the panel sends no reflection there).
    fn delay(&mut self) -> Option<f64> {
        let direct = self.tracer.solve_indexed_from(0, 0, 0, None, &mut self.ws);
        let panel = self.tracer.solve_indexed_from(0, 0, 1, None, &mut self.ws);
        (direct.status == Status::Converged && panel.status == Status::Converged)
            .then_some(panel.time - direct.time)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut layout = Layout::new()?;
    let tilts = [-1.0, -0.5, 0.0, 0.5, 1.0, 1.5];
    println!(
        "seat x   best panel end y   delay (ms)   reflections found (of {})",
        tilts.len()
    );
    for seat in 0..6 {
        let x = 6.0 + 1.5 * seat as f64;
        layout.tracer.set_receiver(0, Point::new(x, 1.2))?;
        let mut best: Option<(f64, f64)> = None;
        let mut found = 0;
        for tilt in tilts {
            // Move the panel's far end up or down: the panel tilts about its near end.
            let end = Point::new(6.0, 6.5 + tilt);
            let points = [Point::new(2.0, 6.0), end];
            layout.tracer.set_interface_points(layout.panel, &points)?;
            if let Some(delay) = layout.delay() {
                found += 1;
                if best.is_none_or(|(_, d)| delay < d) {
                    best = Some((end.y, delay));
                }
            }
        }
        match best {
            Some((y, delay)) => println!("{x:6.1}   {y:16.1}   {:10.2}   {found}", 1e3 * delay),
            None => println!("{x:6.1}   {:>16}   {:>10}   0", "-", "-"),
        }
    }

    // A refused edit names the key, as the scene file's would, and changes nothing.
    let flat = [Point::new(2.0, 6.0), Point::new(2.0, 6.0)];
    if let Err(e) = layout.tracer.set_interface_points(layout.panel, &flat) {
        println!("refused: {e}");
    }
    for ray in layout.tracer.trace_all() {
        println!("{}", ray.describe(layout.tracer.scene()));
    }
    Ok(())
}
