//! A hand-written SVG picture of a scene and its rays: axes with coordinates, the rays (one per
//! triple, every stationary path of each, and a search's arrivals) coloured by travel time
//! (viridis, with a colour bar), by path or by step sequence (with a legend), labelled
//! interfaces and media. Big batches are drawn as a sample, and the picture says so. This file
//! puts the picture together and draws the scene; its parts are in the files beside it.

mod axes;
mod caption;
pub mod charts;
mod colour;
mod colouring;
mod curves;
mod entries;
mod key;
mod labels;
mod layout;
mod legend;
mod marks;
mod markup;

use std::fmt::Write as _;

use rayon::prelude::*;

use eigenray::{Point, RaySet, Scene, SearchArrival};

pub use axes::{Axes, AxisSpec};
pub use colour::Colouring;
pub use markup::thousands;

use colour::{RayColours, time_range};
use entries::{Entries, Item};
use layout::{Frame, LEFT, TOP, View};
use legend::{Legend, path_label, sequence_label};
use marks::ShownReceivers;
use markup::esc;

/// At most this many rays are drawn: beyond it an evenly spread sample, and the caption says so.
pub const MAX_RAYS: usize = 2_000;

/// An SVG picture of `scene`, its `rays` and a search's `arrivals`: the axes with coordinates,
/// the domain box (dashed), the interfaces (closed ones closed) labelled at their middle, each
/// drawn ray (every stationary path of a ray in `"stationary": "all"`, each arrival) as a
/// polyline coloured as `colouring` says (obstructed ones dashed, vertex ones dotted), sources
/// as stars, receivers as dots, the media labelled, a colour bar (travel time, with its range)
/// or a legend (paths or step sequences), and `title`. The y axis points up. Past [`MAX_RAYS`]
/// entries a sample is drawn; past [`layout::MAX_ASPECT`] one axis is stretched; the caption says both.
pub fn scene_svg(
    scene: &Scene,
    rays: RaySet<'_>,
    arrivals: &[SearchArrival],
    title: &str,
    colouring: Colouring,
) -> String {
    scene_svg_with_axes(scene, rays, arrivals, title, colouring, &Axes::default())
}

/// [`scene_svg`] with the axes named, and numbered, as `axes` says.
pub fn scene_svg_with_axes(
    scene: &Scene,
    rays: RaySet<'_>,
    arrivals: &[SearchArrival],
    title: &str,
    colouring: Colouring,
    axes: &Axes,
) -> String {
    let entries = Entries::new(scene, rays, arrivals);
    let mut drawn = entries.drawn();
    // (In parallel: a profile's ray is searched again per pair.)
    drawn
        .items
        .par_iter_mut()
        .for_each(|item| item.curve = curves::sampled(scene, item));
    let rays = &drawn.items;
    // Paths or sequences drawn, for the legend.
    let legend = Legend::new(scene, rays, colouring);
    let frame = Frame::new(scene, rays, &legend, colouring);
    let colours = RayColours {
        colouring,
        legend: &legend,
        range: time_range(rays),
    };
    let receivers = ShownReceivers::of(scene, rays);

    let mut s = String::with_capacity(8192 + rays.len() * 96);
    write_canvas(&mut s, &frame, title);
    caption::write_title_and_captions(
        &mut s,
        title,
        &caption::drawn_caption(&entries, &drawn, colouring),
        &caption::marks_caption(&receivers, frame.stretch),
    );
    axes::draw_axes(&mut s, &frame, axes);
    draw_domain(&mut s, scene, &frame.view);
    draw_rays(&mut s, scene, &frame.view, rays, &colours);
    draw_interfaces(&mut s, scene, &frame.view);
    labels::draw_labels(&mut s, scene, &frame.view, rays);
    marks::draw_receivers(&mut s, scene, &frame.view, &receivers);
    marks::draw_sources(&mut s, scene, &frame.view);
    key::draw_key(
        &mut s,
        LEFT + frame.area_w + 26.0,
        TOP,
        frame.area_h,
        colouring,
        colours.range,
        &legend,
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// Opens the SVG document of `frame`'s size, titled `title`, on white, with the plot's box.
fn write_canvas(s: &mut String, frame: &Frame, title: &str) {
    let (width, height) = (frame.width, frame.height);
    let (plot_w, plot_h) = (frame.plot_w, frame.plot_h);
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
    );
    let _ = writeln!(s, "<title>{}</title>", esc(title));
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r##"<rect x="{:.2}" y="{:.2}" width="{plot_w:.2}" height="{plot_h:.2}" fill="#fafafa" stroke="#bbb"/>"##,
        frame.view.left(),
        frame.view.top()
    );
}

/// Draws the scene's domain box, dashed (nothing without a domain).
fn draw_domain(s: &mut String, scene: &Scene, view: &View) {
    if let Some(d) = scene.domain() {
        let (x0, y0) = view.px(Point::new(d.min.x, d.max.y));
        let (x1, y1) = view.px(Point::new(d.max.x, d.min.y));
        let _ = writeln!(
            s,
            r##"<rect x="{x0:.2}" y="{y0:.2}" width="{:.2}" height="{:.2}" fill="none" stroke="#999" stroke-width="1" stroke-dasharray="6 4"><title>domain</title></rect>"##,
            x1 - x0,
            y1 - y0
        );
    }
}

/// Draws the drawn items as polylines in their `colours` (curved legs, through a gradient
/// or a profile medium, sampled on the ray), thinner the more there are, each titled with its source, receiver, path (or sequence), status and time.
fn draw_rays(s: &mut String, scene: &Scene, view: &View, rays: &[Item], colours: &RayColours) {
    let stroke = match rays.len() {
        0..=50 => 1.6,
        51..=600 => 0.9,
        _ => 0.6,
    };
    let _ = writeln!(
        s,
        r#"<g class="rays" fill="none" stroke-width="{stroke}" stroke-opacity="0.85" stroke-linejoin="round" stroke-linecap="round">"#
    );
    for (k, r) in rays.iter().enumerate() {
        let t = r.time;
        let dash = colours.dash(k, r);
        let what = match r.path {
            Some(p) => path_label(scene, p),
            None => format!("search arrival, {}", sequence_label(scene, &r.steps)),
        };
        let arrival = match r.arrival {
            Some(a) => format!(", arrival {a}"),
            None => String::new(),
        };
        // Curved legs (a gradient or a profile medium): sampled on the ray, to the
        // micro-pixel.
        let points = match &r.curve {
            Some(sampled) => view.points_fine(sampled),
            None => view.points(&r.points),
        };
        let _ = writeln!(
            s,
            r#"<polyline points="{}" stroke="{}"{dash}><title>source {}, receiver {}, {}: {}{arrival}, time {t}</title></polyline>"#,
            points,
            colours.of(k, r),
            r.source,
            r.receiver,
            esc(&what),
            r.status
        );
    }
    let _ = writeln!(s, "</g>");
}

/// Draws the interfaces (closed ones as polygons), over the rays that end on them.
fn draw_interfaces(s: &mut String, scene: &Scene, view: &View) {
    let _ = writeln!(
        s,
        r##"<g class="interfaces" fill="none" stroke="#333" stroke-width="2" stroke-linejoin="round">"##
    );
    for i in scene.interfaces() {
        let tag = if i.polyline.is_closed() {
            "polygon"
        } else {
            "polyline"
        };
        let _ = writeln!(
            s,
            r#"<{tag} points="{}"><title>{}</title></{tag}>"#,
            view.points(i.polyline.vertices()),
            esc(&i.name)
        );
    }
    let _ = writeln!(s, "</g>");
}

#[cfg(test)]
mod tests {
    use super::labels::{boxes_overlap, text_box};
    use super::legend::MAX_LEGEND_LINES;
    use super::*;
    use eigenray::scene::{Step, StepKind};
    use eigenray::{BatchOptions, Point, Status, Tracer};

    fn picture(json: &str, colouring: Colouring) -> String {
        let scene = Scene::from_json(json).expect("valid scene");
        let batch = Tracer::new(&scene)
            .expect("tracer")
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap();
        scene_svg(&scene, RaySet::Batch(&batch), &[], "test", colouring)
    }

    /// Parses the picture as XML and returns its elements' (name, class) pairs and texts.
    fn parse(svg: &str) -> (Vec<(String, String)>, Vec<String>) {
        let doc = roxmltree::Document::parse(svg).expect("well-formed XML");
        let mut elements = Vec::new();
        let mut texts = Vec::new();
        for n in doc.descendants() {
            if n.is_element() {
                elements.push((
                    n.tag_name().name().to_string(),
                    n.attribute("class").unwrap_or("").to_string(),
                ));
                for a in n.attributes() {
                    assert!(
                        !a.value().contains("NaN") && !a.value().contains("inf"),
                        "{}={}",
                        a.name(),
                        a.value()
                    );
                }
                if n.tag_name().name() == "text" {
                    texts.push(n.text().unwrap_or("").to_string());
                }
            }
        }
        (elements, texts)
    }

    const ROOM: &str = r#"{
        "media": { "air": { "speed": 343 } },
        "interfaces": {
            "north": { "points": [[0, 4], [6, 4]] }, "east": { "points": [[6, 0], [6, 4]] },
            "south": { "points": [[0, 0], [6, 0]] }, "west": { "points": [[0, 0], [0, 4]] }
        },
        "sources": [[1.5, 1.2]], "receivers": [[4.5, 2.5], [3, 3]],
        "paths": [
            { "name": "direct", "steps": [], "media": ["air"] },
            { "name": "north", "steps": [{ "reflect": "north" }], "media": ["air", "air"] },
            { "name": "west", "steps": [{ "reflect": "west" }], "media": ["air", "air"] }
        ]
    }"#;

    #[test]
    fn a_room_by_path_has_axes_labels_and_a_legend() {
        let svg = picture(ROOM, Colouring::Path);
        let (elements, texts) = parse(&svg);
        let has = |class: &str| elements.iter().any(|(_, c)| c == class);
        assert!(has("axes") && has("legend") && has("rays") && has("labels"));
        assert!(!has("colour-bar"));
        for want in [
            "direct (2)",
            "north (2)",
            "west (2)",
            "0",
            "6",
            "4",
            "x",
            "y",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        // Every interface labelled once (each text drawn twice: outline and fill); the medium
        // too, from its legs.
        for name in ["north", "east", "south", "west", "air"] {
            assert_eq!(texts.iter().filter(|t| *t == name).count(), 2, "{name}");
        }
        assert!(!svg.contains("paint-order"));
        assert!(texts.iter().any(|t| t.starts_with("6 of 6 rays drawn")));
    }

    #[test]
    fn the_west_label_sits_beside_the_west_wall_middle() {
        let svg = picture(ROOM, Colouring::Time);
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let west = doc
            .descendants()
            .find(|n| n.has_tag_name("text") && n.text() == Some("west"))
            .expect("west label");
        let y: f64 = west.attribute("y").unwrap().parse().unwrap();
        // The wall runs from y = 0 to 4; the corners are at the plot's pixel rows of the
        // north and south walls' labels' lines. The label is within the middle half.
        let rows: Vec<f64> = doc
            .descendants()
            .filter(|n| n.has_tag_name("polyline"))
            .filter(|n| n.children().any(|c| c.text() == Some("west")))
            .flat_map(|n| {
                n.attribute("points")
                    .unwrap()
                    .split(' ')
                    .map(|p| p.split(',').nth(1).unwrap().parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .collect();
        let (lo, hi) = (rows[0].min(rows[1]), rows[0].max(rows[1]));
        let quarter = 0.25 * (hi - lo);
        assert!(
            y > lo + quarter && y < hi - quarter + 12.0,
            "{y} in {lo}..{hi}"
        );
    }

    #[test]
    fn a_big_batch_is_drawn_as_a_sample_and_says_so() {
        let scene = Scene::from_spec(&eigenray::demo::air_water(20_000, 1)).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap();
        let svg = scene_svg(&scene, RaySet::Batch(&batch), &[], "demo", Colouring::Time);
        let (elements, texts) = parse(&svg);
        let drawn = elements.iter().filter(|(n, _)| n == "polyline").count() - 1;
        assert!(drawn <= MAX_RAYS, "{drawn}");
        let caption = format!(
            "{} of 20,000 rays drawn (a sample spread over all rays)",
            thousands(drawn)
        );
        assert!(
            texts.iter().any(|t| t.starts_with(&caption)),
            "{caption} not in {texts:?}"
        );
        assert!(
            texts
                .iter()
                .any(|t| t.contains("of 20,000 receivers shown"))
        );
        assert!(svg.len() < 1_500_000, "{} bytes", svg.len());
        // Air and water are labelled from their legs.
        for name in ["air", "water", "surface", "travel time", "(length ÷ speed)"] {
            assert!(texts.iter().any(|t| t == name), "{name}");
        }
    }

    #[test]
    fn the_caption_counts_rays_without_a_time() {
        let svg = picture(
            r#"{
            "media": { "air": { "speed": 1 } },
            "interfaces": { "floor": { "points": [[-1, 0], [1, 0]] } },
            "sources": [[0, 1]], "receivers": [[0.5, 1], [5, 1]],
            "paths": [{ "steps": [{ "reflect": "floor" }], "media": ["air", "air"] }]
        }"#,
            Colouring::Time,
        );
        let (_, texts) = parse(&svg);
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with("1 of 2 rays drawn (1 has no time)")),
            "{texts:?}"
        );
    }

    #[test]
    fn a_sample_holds_every_path() {
        let json = r#"{
            "media": { "air": { "speed": 1 } },
            "interfaces": { "floor": { "points": [[-100, 0], [100, 0]] } },
            "sources": [[0, 1]], "receivers": RECEIVERS,
            "paths": [{ "steps": [], "media": ["air"] },
                      { "steps": [{ "reflect": "floor" }], "media": ["air", "air"] }]
        }"#;
        let receivers: Vec<[f64; 2]> = (0..3000).map(|k| [k as f64 * 0.01, 2.0]).collect();
        let json = json.replace("RECEIVERS", &serde_json::to_string(&receivers).unwrap());
        let svg = picture(&json, Colouring::Path);
        let (_, texts) = parse(&svg);
        assert!(texts.iter().any(|t| t.starts_with("path 0 (")), "{texts:?}");
        assert!(texts.iter().any(|t| t.starts_with("path 1 (")), "{texts:?}");
    }

    /// An interface's label keeps clear of a medium's name beside its `at` point (here the
    /// bedrock's middle, where its label would go, lies just above the rock's `at` point).
    #[test]
    fn interface_labels_keep_clear_of_medium_names() {
        let svg = picture(
            r#"{
            "media": { "water": { "speed": 1500, "at": [500, -5] },
                       "rock": { "speed": 2500, "at": [500, -46] } },
            "domain": [[0, -50], [1000, 0]],
            "interfaces": { "bedrock": { "points": [[0, -40], [500, -42], [1000, -39]] } },
            "sources": [[10, -2]], "receivers": [[600, -10]],
            "paths": [{ "steps": [{ "reflect": "bedrock" }] }]
        }"#,
            Colouring::Time,
        );
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let label = |name: &str, size: f64| {
            let n = doc
                .descendants()
                .find(|n| n.tag_name().name() == "text" && n.text() == Some(name))
                .unwrap();
            let at = |a: &str| n.attribute(a).unwrap().parse::<f64>().unwrap();
            text_box(at("x"), at("y"), name.chars().count(), size)
        };
        let (bedrock, rock) = (label("bedrock", 12.0), label("rock", 13.0));
        assert!(!boxes_overlap(bedrock, rock), "{bedrock:?} and {rock:?}");
    }

    #[test]
    fn a_wide_shallow_scene_is_stretched_and_says_so() {
        let svg = picture(
            r#"{
            "media": { "air": { "speed": 1 }, "rock": { "speed": 2 } },
            "interfaces": { "bed": { "points": [[0, -1], [1000, -1]] } },
            "sources": [[0, 0]], "receivers": [[1000, 0]],
            "paths": [{ "steps": [{ "reflect": "bed" }], "media": ["air", "air"] }]
        }"#,
            Colouring::Time,
        );
        let (_, texts) = parse(&svg);
        assert!(
            texts.iter().any(|t| t.contains("vertical scale stretched")),
            "{texts:?}"
        );
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let root = doc.root_element();
        let h: f64 = root.attribute("height").unwrap().parse().unwrap();
        let w: f64 = root.attribute("width").unwrap().parse().unwrap();
        assert!(h > 0.35 * w, "{w} × {h}");
        // The scales differ by the factor the caption gives: the bed is 1000 wide and 1 below
        // the source, which stands at its left end.
        let caption = texts.iter().find(|t| t.contains("stretched ×")).unwrap();
        let factor: f64 = caption.rsplit('×').next().unwrap().parse().unwrap();
        let bed = doc
            .descendants()
            .find(|n| {
                n.is_element()
                    && n.parent().and_then(|p| p.attribute("class")) == Some("interfaces")
            })
            .unwrap();
        let xy: Vec<f64> = bed
            .attribute("points")
            .unwrap()
            .split([' ', ','])
            .map(|v| v.parse().unwrap())
            .collect();
        let source = doc
            .descendants()
            .find(|n| {
                n.is_element() && n.parent().and_then(|p| p.attribute("class")) == Some("sources")
            })
            .unwrap();
        let star: Vec<f64> = source
            .attribute("points")
            .unwrap()
            .split([' ', ','])
            .map(|v| v.parse().unwrap())
            .collect();
        // The star's centre: the mean of its ten corners.
        let cy = star.iter().skip(1).step_by(2).sum::<f64>() / 10.0;
        let per_unit_x = (xy[2] - xy[0]) / 1000.0;
        let per_unit_y = xy[1] - cy;
        let ratio = per_unit_y / per_unit_x;
        assert!(
            (ratio / factor - 1.0).abs() < 2e-3,
            "{ratio} against ×{factor}"
        );
    }

    #[test]
    fn tiny_scenes_and_odd_names_stay_well_formed() {
        // The smallest scale a scene may have (scenes below 1e-100 are refused; the axes of
        // still smaller extents are tested above).
        let svg = picture(
            r#"{
            "media": { "a\ufffeb": { "speed": 1 } },
            "interfaces": { "i\uffff<&>": { "points": [[-1e-99, 0], [1e-99, 0]] } },
            "sources": [[0, 1e-100]], "receivers": [[5e-100, 1e-100]],
            "paths": [{ "name": "p\u0001", "steps": [{ "reflect": "i\uffff<&>" }], "media": ["a\ufffeb", "a\ufffeb"] }]
        }"#,
            Colouring::Path,
        );
        let (elements, _) = parse(&svg);
        assert!(elements.iter().any(|(_, c)| c == "axes"));
        assert!(!svg.contains("inf") && !svg.contains("NaN"));
    }

    /// A search arrival built by hand: `steps` off the scene's interfaces, through `points`.
    fn search_arrival(
        scene: &Scene,
        steps: &[(StepKind, &str)],
        status: Status,
        time: f64,
        points: &[[f64; 2]],
    ) -> SearchArrival {
        let air = scene.medium_index("air").unwrap();
        SearchArrival {
            source: 0,
            receiver: 0,
            steps: steps
                .iter()
                .map(|&(kind, name)| Step {
                    kind,
                    interface: scene.interface_index(name).unwrap(),
                })
                .collect(),
            arrival: eigenray::Arrival {
                status,
                time,
                points: points.iter().map(|p| Point::new(p[0], p[1])).collect(),
                parameters: vec![0.0; steps.len()],
                segments: vec![0; steps.len()],
                media: vec![air; steps.len() + 1],
                iterations: 1,
                reason: None,
                kink: None,
                residual: 0.0,
                amplitude: None,
                turns: None,
                caustics: None,
                launch_angle: None,
            },
            complete: true,
            heights: Vec::new(),
        }
    }

    #[test]
    fn search_arrivals_are_drawn_with_their_sequences_in_the_legend() {
        let scene = Scene::from_json(ROOM).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap();
        let arrivals = [
            search_arrival(
                &scene,
                &[],
                Status::Converged,
                0.01,
                &[[1.5, 1.2], [4.5, 2.5]],
            ),
            search_arrival(
                &scene,
                &[(StepKind::Reflect, "north"), (StepKind::Reflect, "east")],
                Status::Converged,
                0.03,
                &[[1.5, 1.2], [5.0, 4.0], [6.0, 3.5], [4.5, 2.5]],
            ),
            search_arrival(
                &scene,
                &[(StepKind::Reflect, "north"), (StepKind::Reflect, "east")],
                Status::Obstructed,
                0.05,
                &[[1.5, 1.2], [2.0, 4.0], [6.0, 1.0], [4.5, 2.5]],
            ),
        ];
        // By sequence: paths and arrivals of one sequence share a line.
        let svg = scene_svg(
            &scene,
            RaySet::Batch(&batch),
            &arrivals,
            "t",
            Colouring::Sequence,
        );
        let (elements, texts) = parse(&svg);
        assert!(elements.iter().any(|(_, c)| c == "legend"));
        for want in [
            "sequence (paths drawn)",
            "direct (3)",
            "reflect north (2)",
            "reflect west (2)",
            "reflect north → reflect east (2)",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with("9 of 9 rays and search arrivals drawn")),
            "{texts:?}"
        );
        // By path: the paths by name, then the arrivals' sequences.
        let svg = scene_svg(
            &scene,
            RaySet::Batch(&batch),
            &arrivals,
            "t",
            Colouring::Path,
        );
        let (_, texts) = parse(&svg);
        for want in [
            "direct (2)",
            "north (2)",
            "west (2)",
            "direct (1)",
            "reflect north → reflect east (2)",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        // By time: the colour bar spans the arrivals' times too.
        let svg = scene_svg(
            &scene,
            RaySet::Batch(&batch),
            &arrivals,
            "t",
            Colouring::Time,
        );
        let (_, texts) = parse(&svg);
        assert!(texts.iter().any(|t| t == "0.05000"), "{texts:?}");
        assert!(svg.contains("search arrival, reflect north → reflect east: obstructed"));
    }

    #[test]
    fn a_long_legend_stops_at_its_limit_and_counts_the_rest() {
        let scene = Scene::from_json(ROOM).unwrap();
        let walls = ["north", "east", "south", "west"];
        // 4³ = 64 sequences of three reflections, one arrival each.
        let mut arrivals = Vec::new();
        for a in walls {
            for b in walls {
                for c in walls {
                    arrivals.push(search_arrival(
                        &scene,
                        &[
                            (StepKind::Reflect, a),
                            (StepKind::Reflect, b),
                            (StepKind::Reflect, c),
                        ],
                        Status::Converged,
                        0.02,
                        &[[1.5, 1.2], [3.0, 4.0], [6.0, 2.0], [3.0, 0.0], [4.5, 2.5]],
                    ));
                }
            }
        }
        let svg = scene_svg(
            &scene,
            RaySet::Rays(&[]),
            &arrivals,
            "t",
            Colouring::Sequence,
        );
        let (_, texts) = parse(&svg);
        let lines = texts.iter().filter(|t| t.starts_with("reflect ")).count();
        assert_eq!(lines, MAX_LEGEND_LINES);
        assert!(
            texts.iter().any(|t| t
                == &format!(
                    "… {} more ({})",
                    64 - MAX_LEGEND_LINES,
                    64 - MAX_LEGEND_LINES
                )),
            "{texts:?}"
        );
    }

    /// Long sequences (a waveguide's ten bounces) wrap in the legend, and every row of text
    /// ends inside the canvas: the legend is not cut off at the right edge.
    #[test]
    fn a_legend_of_long_sequences_stays_inside_the_canvas() {
        let scene = Scene::from_json(ROOM).unwrap();
        let mut arrivals = Vec::new();
        // Sixteen steps that repeat no block from their start, and shorter ones that do.
        let irregular = [
            "north", "east", "south", "west", "west", "south", "north", "east", "north", "north",
            "east", "south", "south", "west", "east", "north",
        ];
        for n in [1usize, 4, 10, 16] {
            let steps: Vec<(StepKind, &str)> = if n == 16 {
                irregular.iter().map(|&w| (StepKind::Reflect, w)).collect()
            } else {
                (0..n)
                    .map(|k| {
                        (
                            StepKind::Reflect,
                            if k % 2 == 0 { "north" } else { "south" },
                        )
                    })
                    .collect()
            };
            arrivals.push(search_arrival(
                &scene,
                &steps,
                Status::Converged,
                0.02,
                &[[1.5, 1.2], [4.5, 2.5]],
            ));
        }
        let svg = scene_svg(
            &scene,
            RaySet::Rays(&[]),
            &arrivals,
            "t",
            Colouring::Sequence,
        );
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let width: f64 = doc
            .root_element()
            .attribute("width")
            .unwrap()
            .parse()
            .unwrap();
        let legend = doc
            .descendants()
            .find(|n| n.attribute("class") == Some("legend"))
            .unwrap();
        let rows: Vec<(f64, String)> = legend
            .children()
            .filter(|n| n.has_tag_name("text"))
            .map(|n| {
                let x: f64 = n.attribute("x").unwrap().parse().unwrap();
                (x, n.text().unwrap().to_string())
            })
            .collect();
        // The 16 steps' line wraps onto several rows, each continued with an arrow.
        assert!(
            rows.iter().filter(|r| r.1.starts_with("→ ")).count() >= 3,
            "{rows:?}"
        );
        for (x, text) in &rows {
            // DejaVu Sans at 12 px: no character is wider than 7.4 px on average over a row.
            let right = x + super::legend::LEGEND_CHAR_W * text.chars().count() as f64;
            assert!(
                right <= width,
                "{text:?} ends at {right}, the canvas at {width}"
            );
        }
        // Every step of every sequence is there, in order, once the rows are joined; a
        // repeated block once, with its count.
        let joined: String = rows
            .iter()
            .map(|r| r.1.as_str())
            .collect::<Vec<_>>()
            .join(" ");
        let irregular: Vec<String> = irregular.iter().map(|w| format!("reflect {w}")).collect();
        assert!(joined.contains(&irregular.join(" → ")), "{joined}");
        assert!(
            joined.contains("(reflect north → reflect south) ×5 (1)"),
            "{joined}"
        );
    }
}
