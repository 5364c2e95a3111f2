//! A hand-written SVG picture of a scene and its rays: axes with coordinates, the rays (one per
//! triple, every stationary path of each, and a search's arrivals) coloured by travel time
//! (viridis, with a colour bar), by path or by step sequence (with a legend), labelled
//! interfaces and media. Big batches are drawn as a sample, and the picture says so.

use std::fmt::Write as _;

use eigenray::geometry::Aabb;
use eigenray::scene_parts::{Step, StepKind};
use eigenray::{Point, RaySet, Scene, SearchArrival, Status};

/// Viridis (matplotlib's perceptually uniform colormap) at 0, 1/8, …, 1; linear in between.
const VIRIDIS: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

/// Colours of paths (Tableau's 10, then their lighter companions), repeated beyond 20 paths.
const PATH_COLOURS: [&str; 20] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac", "#a0cbe8", "#ffbe7d", "#ff9d9a", "#86bcb6", "#8cd17d", "#f1ce63",
    "#d4a6c8", "#fabfd2", "#d7b5a6", "#79706e",
];

/// At most this many rays are drawn: beyond it an evenly spread sample, and the caption says so.
pub const MAX_RAYS: usize = 2_000;
/// At most this many receivers are drawn (beyond it, those of the drawn rays).
const MAX_RECEIVERS: usize = 2_000;

/// Largest plot, in pixels.
const PLOT_MAX_W: f64 = 820.0;
const PLOT_MAX_H: f64 = 620.0;
/// A plot is never flatter (or narrower) than this: beyond it one axis is stretched, and the
/// caption gives the factor.
const MAX_ASPECT: f64 = 3.0;
/// Smallest plot area (the colour bar and the title need room even for a small scene).
const AREA_MIN_W: f64 = 460.0;
const AREA_MIN_H: f64 = 300.0;
/// Room left of the plot for the y axis's labels.
const LEFT: f64 = 78.0;
/// Room for the title and the caption.
const TOP: f64 = 66.0;
/// Room below the plot for the x axis's labels.
const BOTTOM: f64 = 48.0;
/// Room right of the plot for the colour bar and its labels.
const BAR_AREA: f64 = 170.0;
/// Height of one line of the path legend.
const LEGEND_LINE: f64 = 17.0;
/// At most this many lines of a legend are drawn; a last line counts the rest.
const MAX_LEGEND_LINES: usize = 40;

/// What gives a ray its colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Colouring {
    /// Travel time, on viridis, with a colour bar.
    #[default]
    Time,
    /// The path, with a legend of path names (a search arrival, which has no path: its step
    /// sequence).
    Path,
    /// The step sequence: one colour per distinct sequence of steps, with a legend listing the
    /// sequences (`reflect w0 → refract surface`).
    Sequence,
}

/// Viridis at `t ∈ [0, 1]` (clamped; NaN is 0) as `#rrggbb`.
pub fn viridis(t: f64) -> String {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let c = |k: usize| (f64::from(a[k]) + f * (f64::from(b[k]) - f64::from(a[k]))).round() as u8;
    format!("#{:02x}{:02x}{:02x}", c(0), c(1), c(2))
}

/// World → pixel map, y up. Positions are taken relative to the centre and divided by the half
/// extents (never multiplied by a scale), so that tiny or huge scenes stay finite.
struct View {
    /// World centre.
    c: Point,
    /// World half extents shown.
    hw: f64,
    hh: f64,
    /// Pixel centre and half sizes of the plot.
    pc: (f64, f64),
    half: (f64, f64),
}

impl View {
    fn px(&self, p: Point) -> (f64, f64) {
        (
            self.pc.0 + (p.x - self.c.x) / self.hw * self.half.0,
            self.pc.1 - (p.y - self.c.y) / self.hh * self.half.1,
        )
    }
    /// `x,y x,y …` for a `points` attribute.
    fn points(&self, pts: &[Point]) -> String {
        let mut s = String::with_capacity(pts.len() * 16);
        for (k, p) in pts.iter().enumerate() {
            let (x, y) = self.px(*p);
            if k > 0 {
                s.push(' ');
            }
            let _ = write!(s, "{x:.2},{y:.2}");
        }
        s
    }
    fn left(&self) -> f64 {
        self.pc.0 - self.half.0
    }
    fn top(&self) -> f64 {
        self.pc.1 - self.half.1
    }
    fn right(&self) -> f64 {
        self.pc.0 + self.half.0
    }
    fn bottom(&self) -> f64 {
        self.pc.1 + self.half.1
    }
}

/// One entry of the picture: a ray, one stationary path of a ray, or a search arrival.
#[derive(Clone, Debug)]
struct Item {
    source: usize,
    receiver: usize,
    /// The path (`None` for a search arrival).
    path: Option<usize>,
    /// The step sequence.
    steps: Vec<Step>,
    /// Its place among its triple's stationary paths (`"stationary": "all"` only).
    arrival: Option<usize>,
    status: Status,
    /// Travel time; NaN when it has none.
    time: f64,
    points: Vec<Point>,
    /// Leg media (indices into [`Scene::media`]), when known.
    media: Vec<usize>,
}

/// The entries a picture draws from: its rays (in any form) and a search's arrivals.
struct Entries<'a> {
    scene: &'a Scene,
    rays: RaySet<'a>,
    /// Where each triple's entries start (`RaySet::Stationary` only).
    starts: Vec<usize>,
    arrivals: &'a [SearchArrival],
}

impl<'a> Entries<'a> {
    fn new(scene: &'a Scene, rays: RaySet<'a>, arrivals: &'a [SearchArrival]) -> Entries<'a> {
        let mut starts = Vec::new();
        if let RaySet::Stationary(st) = rays {
            let mut n = 0;
            for t in &st.triples {
                starts.push(n);
                n += t.arrivals.len().max(1);
            }
        }
        Entries {
            scene,
            rays,
            starts,
            arrivals,
        }
    }

    /// Entries of the rays (one per ray, or per stationary path and per triple without one).
    fn rays_len(&self) -> usize {
        match self.rays {
            RaySet::Rays(r) => r.len(),
            RaySet::Batch(b) => b.len(),
            RaySet::Stationary(st) => st.entries(),
        }
    }

    fn len(&self) -> usize {
        self.rays_len() + self.arrivals.len()
    }

    /// The steps of path `p`.
    fn steps(&self, p: usize) -> Vec<Step> {
        self.scene
            .paths()
            .get(p)
            .map(|p| p.steps.clone())
            .unwrap_or_default()
    }

    /// Entry `i`: the rays' entries first, then the arrivals.
    fn item(&self, i: usize) -> Item {
        let n = self.rays_len();
        if i >= n {
            let a = &self.arrivals[i - n];
            return Item {
                source: a.source,
                receiver: a.receiver,
                path: None,
                steps: a.steps.clone(),
                arrival: None,
                status: a.arrival.status,
                time: a.arrival.time,
                points: a.arrival.points.clone(),
                media: a.arrival.media.clone(),
            };
        }
        let ray = |r: eigenray::Ray| Item {
            source: r.source,
            receiver: r.receiver,
            path: Some(r.path),
            steps: self.steps(r.path),
            arrival: None,
            status: r.status,
            time: r.time,
            points: r.points,
            media: r.media,
        };
        match self.rays {
            RaySet::Rays(rays) => ray(rays[i].clone()),
            RaySet::Batch(batch) => ray(batch.ray(i)),
            RaySet::Stationary(st) => {
                let k = self.starts.partition_point(|&s| s <= i) - 1;
                let t = &st.triples[k];
                let arrival = i - self.starts[k];
                let mut item = Item {
                    source: t.source,
                    receiver: t.receiver,
                    path: Some(t.path),
                    steps: self.steps(t.path),
                    arrival: Some(arrival),
                    status: if t.complete {
                        Status::NoPath
                    } else {
                        Status::NotConverged
                    },
                    time: f64::NAN,
                    points: Vec::new(),
                    media: Vec::new(),
                };
                if let Some(a) = t.arrivals.get(arrival) {
                    item.status = a.status;
                    item.time = a.time;
                    item.points = a.points.clone();
                    item.media = a.media.clone();
                }
                item
            }
        }
    }

    /// Entries without a time (never drawn).
    fn timeless(&self) -> usize {
        let has = |status: Status, time: f64| status.has_time() && time.is_finite();
        match self.rays {
            RaySet::Rays(r) => r.iter().filter(|r| !has(r.status, r.time)).count(),
            RaySet::Batch(b) => b
                .records()
                .iter()
                .filter(|r| !has(r.status, r.time))
                .count(),
            RaySet::Stationary(st) => {
                let none = st.triples.iter().filter(|t| t.arrivals.is_empty()).count();
                let bad = st
                    .triples
                    .iter()
                    .flat_map(|t| &t.arrivals)
                    .filter(|a| !has(a.status, a.time))
                    .count();
                none + bad
            }
        }
    }
}

/// The sequence in the scene's words: `reflect w0 → refract surface`, or `direct`.
pub fn sequence_label(scene: &Scene, steps: &[Step]) -> String {
    if steps.is_empty() {
        return "direct".to_string();
    }
    let words: Vec<String> = steps
        .iter()
        .map(|s| {
            let kind = match s.kind {
                StepKind::Reflect => "reflect",
                StepKind::Refract => "refract",
            };
            let name = scene
                .interfaces()
                .get(s.interface)
                .map_or("?", |i| i.name.as_str());
            format!("{kind} {name}")
        })
        .collect();
    words.join(" → ")
}

/// A sequence as a sort key: by number of steps, then step by step (interface, reflect first).
fn sequence_key(steps: &[Step]) -> (usize, Vec<(usize, bool)>) {
    (
        steps.len(),
        steps
            .iter()
            .map(|s| (s.interface, s.kind == StepKind::Refract))
            .collect(),
    )
}

/// One line of a legend.
struct LegendEntry {
    label: String,
    /// Its index into [`PATH_COLOURS`] (and [`path_dash`]).
    colour: usize,
    /// Entries drawn.
    count: usize,
}

/// The legend of a colouring and the legend line of each drawn item (none by time).
struct Legend {
    entries: Vec<LegendEntry>,
    of_item: Vec<usize>,
    /// The legend's heading.
    heading: &'static str,
}

impl Legend {
    fn new(scene: &Scene, items: &[Item], colouring: Colouring) -> Legend {
        let heading = match colouring {
            Colouring::Time => {
                return Legend {
                    entries: Vec::new(),
                    of_item: Vec::new(),
                    heading: "",
                };
            }
            Colouring::Path => "path (rays drawn)",
            Colouring::Sequence => "sequence (paths drawn)",
        };
        // The groups: paths by index, then search sequences in order of their keys (by path);
        // every sequence in order of its key (by sequence).
        let paths = scene.paths().len();
        let mut sequences: Vec<Vec<Step>> = items
            .iter()
            .filter(|r| colouring == Colouring::Sequence || r.path.is_none())
            .map(|r| r.steps.clone())
            .collect();
        sequences.sort_by_key(|s| sequence_key(s));
        sequences.dedup();
        let sequence_of = |steps: &[Step]| {
            sequences
                .binary_search_by_key(&sequence_key(steps), |s| sequence_key(s))
                .unwrap_or(0)
        };
        // Group of each item: a path index, or `paths` + a sequence's place.
        let group = |r: &Item| match (colouring, r.path) {
            (Colouring::Path, Some(p)) => p,
            _ => paths + sequence_of(&r.steps),
        };
        let mut count = vec![0usize; paths + sequences.len()];
        for r in items {
            count[group(r)] += 1;
        }
        let mut entries = Vec::new();
        let mut line = vec![usize::MAX; count.len()];
        for (g, &c) in count.iter().enumerate() {
            if c == 0 {
                continue;
            }
            let (label, colour) = if g < paths {
                (path_label(scene, g), g)
            } else {
                let k = g - paths;
                let colour = match colouring {
                    Colouring::Sequence => k,
                    _ => paths + k,
                };
                (sequence_label(scene, &sequences[k]), colour)
            };
            line[g] = entries.len();
            entries.push(LegendEntry {
                label,
                colour,
                count: c,
            });
        }
        let of_item = items.iter().map(|r| line[group(r)]).collect();
        Legend {
            entries,
            of_item,
            heading,
        }
    }

    /// Lines drawn: at most [`MAX_LEGEND_LINES`], the last then counting the rest.
    fn lines(&self) -> usize {
        self.entries.len().min(MAX_LEGEND_LINES + 1)
    }
}

/// Whether an item is drawn: it has a finite time and at least two finite points.
fn drawable(r: &Item) -> bool {
    r.status.has_time()
        && r.time.is_finite()
        && r.points.len() >= 2
        && r.points.iter().all(|p| p.is_finite())
}

/// The world to show: centre and half extents holding the scene and the drawn rays, never
/// degenerate, with a margin. Computed in halves so that huge coordinates do not overflow.
fn world(scene: &Scene, rays: &[Item]) -> (Point, f64, f64, f64) {
    let mut b = scene.bbox();
    for r in rays {
        for p in &r.points {
            b = b.union(Aabb::from_points(*p, *p));
        }
    }
    let finite = b.min.is_finite() && b.max.is_finite() && b.min.x <= b.max.x && b.min.y <= b.max.y;
    if !finite {
        b = Aabb {
            min: Point::new(-1.0, -1.0),
            max: Point::new(1.0, 1.0),
        };
    }
    let c = Point::new(0.5 * b.min.x + 0.5 * b.max.x, 0.5 * b.min.y + 0.5 * b.max.y);
    let limit = f64::MAX / 2.5;
    let (hw, hh) = (
        (0.5 * b.max.x - 0.5 * b.min.x).min(limit),
        (0.5 * b.max.y - 0.5 * b.min.y).min(limit),
    );
    let ext = hw.max(hh);
    let ext = if ext > 0.0 {
        ext
    } else {
        // A single point: a box of its own magnitude (or 1 at the origin).
        let m = c.x.abs().max(c.y.abs()).min(limit);
        if m > 0.0 { m } else { 1.0 }
    };
    (c, hw.max(0.05 * ext), hh.max(0.05 * ext), 0.08 * ext)
}

/// XML-escapes text for element content and attribute values; characters that XML 1.0 does
/// not allow become spaces (controls) or U+FFFD (U+FFFE, U+FFFF).
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push(' '),
            '\u{fffe}' | '\u{ffff}' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

/// `has` for one, `have` for more.
fn have(n: usize) -> &'static str {
    if n == 1 { "has" } else { "have" }
}

/// `1234567` as `1,234,567`.
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

/// A tick label: enough decimals to tell `lo` from `hi` apart.
fn tick_label(v: f64, span: f64) -> String {
    let mag = v.abs().max(span.abs());
    if mag != 0.0 && !(1e-4..1e6).contains(&mag) {
        return format!("{v:.3e}");
    }
    let decimals = if span > 0.0 {
        (3.0 - span.log10().floor()).clamp(0.0, 10.0) as usize
    } else {
        6
    };
    format!("{v:.decimals$}")
}

/// Ticks at a round step (1, 2 or 5 × 10ⁿ) within `[lo, hi]`, about `target` of them, with
/// labels that differ by that step; empty when the range is not finite.
fn axis_ticks(lo: f64, hi: f64, target: f64) -> Vec<(f64, String)> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0 && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let raw = span / target;
    let mag = 10f64.powf(raw.log10().floor());
    if !(mag.is_finite() && mag > 0.0) {
        return Vec::new();
    }
    let f = raw / mag;
    let step = mag
        * if f <= 1.0 {
            1.0
        } else if f <= 2.0 {
            2.0
        } else if f <= 5.0 {
            5.0
        } else {
            10.0
        };
    let first = (lo / step).ceil();
    let last = (hi / step).floor();
    if !(first.is_finite() && last.is_finite()) || last - first > 40.0 {
        return Vec::new();
    }
    let exponent = step.log10().floor();
    let largest = lo.abs().max(hi.abs());
    let label = |v: f64| -> String {
        if v == 0.0 {
            "0".into()
        } else if (1e-4..1e6).contains(&largest) && (-6.0..=6.0).contains(&exponent) {
            let decimals = (-exponent).max(0.0) as usize;
            let s = format!("{v:.decimals$}");
            if s.trim_start_matches('-')
                .chars()
                .all(|c| c == '0' || c == '.')
            {
                "0".into()
            } else {
                s
            }
        } else {
            // Scientific, with the digits the step needs.
            let digits = (largest.log10().floor() - exponent).clamp(0.0, 12.0) as usize;
            format!("{v:.digits$e}")
        }
    };
    let mut ticks = Vec::new();
    let mut k = first;
    while k <= last {
        let v = k * step;
        ticks.push((v, label(v)));
        k += 1.0;
    }
    ticks
}

/// A five-pointed star of outer radius `r` centred on `(x, y)`, as polygon points.
fn star(x: f64, y: f64, r: f64) -> String {
    let mut s = String::new();
    for k in 0..10 {
        let rad = if k % 2 == 0 { r } else { 0.45 * r };
        let a = std::f64::consts::PI * (k as f64 / 5.0 - 0.5);
        let _ = write!(
            s,
            "{}{:.2},{:.2}",
            if k > 0 { " " } else { "" },
            x + rad * a.cos(),
            y + rad * a.sin()
        );
    }
    s
}

/// A label's box in pixels: `(x0, y0, x1, y1)`.
type LabelBox = (f64, f64, f64, f64);

/// A straight piece of a drawing in pixels: its two ends.
type PixelSegment = ((f64, f64), (f64, f64));

/// The box of a `size`-pixel text of `chars` characters whose baseline starts at `(x, y)`.
fn text_box(x: f64, y: f64, chars: usize, size: f64) -> LabelBox {
    (
        x - 2.0,
        y - size,
        x + 0.6 * size * chars as f64 + 2.0,
        y + 0.3 * size,
    )
}

/// Whether the pixel segments `a → b` and `c → d` cross (touching counts).
fn segments_cross(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 <= 0.0 && o3 * o4 <= 0.0 && (a != b)
}

fn boxes_overlap(a: LabelBox, b: LabelBox) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Whether the pixel segment `p → q` meets box `b` (Liang–Barsky clipping).
fn segment_meets_box(p: (f64, f64), q: (f64, f64), b: LabelBox) -> bool {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (den, num) in [
        (-dx, p.0 - b.0),
        (dx, b.2 - p.0),
        (-dy, p.1 - b.1),
        (dy, b.3 - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return false;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// Text that reads on any background in every renderer: a white outline drawn first, then the
/// text over it (no `paint-order`, which some renderers ignore).
fn halo_text(s: &mut String, x: f64, y: f64, attrs: &str, fill: &str, text: &str) {
    let text = esc(text);
    let _ = writeln!(
        s,
        r#"<text x="{x:.2}" y="{y:.2}" {attrs} fill="white" stroke="white" stroke-width="3.5" stroke-linejoin="round">{text}</text><text x="{x:.2}" y="{y:.2}" {attrs} fill="{fill}">{text}</text>"#
    );
}

/// The entries to draw out of `n`: every one, or past [`MAX_RAYS`] a stratified sample (one
/// at a pseudo-random place in each of [`MAX_RAYS`] equal runs of the ray order), so that a
/// regular grid of receivers or a set of paths does not alias with a stride. The second value
/// says whether it is a sample.
fn sample(n: usize) -> (Vec<usize>, bool) {
    if n <= MAX_RAYS {
        return ((0..n).collect(), false);
    }
    let mut x = 0x9e37_79b9_7f4a_7c15_u64;
    let picked = (0..MAX_RAYS)
        .map(|k| {
            // xorshift64: a fixed sequence, so the same batch gives the same picture.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (lo, hi) = (k * n / MAX_RAYS, (k + 1) * n / MAX_RAYS);
            lo + (x % (hi - lo) as u64) as usize
        })
        .collect();
    (picked, true)
}

/// The line style of path `p` when colouring by path: the colours repeat every 20 paths, solid
/// the first time round, long dashes the second, and so on.
fn path_dash(p: usize) -> &'static str {
    if (p / PATH_COLOURS.len()) % 2 == 1 {
        r#" stroke-dasharray="8 3""#
    } else {
        ""
    }
}

/// The label of path `p`: its name, or `path p`.
fn path_label(scene: &Scene, p: usize) -> String {
    match scene.paths().get(p).and_then(|p| p.name.as_deref()) {
        Some(name) => name.to_string(),
        None => format!("path {p}"),
    }
}

/// An SVG picture of `scene`, its `rays` and a search's `arrivals`: the axes with coordinates,
/// the domain box (dashed), the interfaces (closed ones closed) labelled at their middle, each
/// drawn ray (every stationary path of a ray in `"stationary": "all"`, each arrival) as a
/// polyline coloured as `colouring` says (obstructed ones dashed, vertex ones dotted), sources
/// as stars, receivers as dots, the media labelled, a colour bar (travel time, with its range)
/// or a legend (paths or step sequences), and `title`. The y axis points up. Past [`MAX_RAYS`]
/// entries a sample is drawn; past [`MAX_ASPECT`] one axis is stretched; the caption says both.
pub fn scene_svg(
    scene: &Scene,
    rays: RaySet<'_>,
    arrivals: &[SearchArrival],
    title: &str,
    colouring: Colouring,
) -> String {
    let entries = Entries::new(scene, rays, arrivals);
    let (picked, sampled) = sample(entries.len());
    let rays: Vec<Item> = picked
        .iter()
        .map(|&i| entries.item(i))
        .filter(drawable)
        .collect();
    let (centre, rw, rh, pad) = world(scene, &rays);

    // Stretch the short axis of a flat (or tall) scene so that the plot stays readable: its
    // scale becomes `factor` times the other's. The margin around the scene is the same on
    // every side on the screen, so it is `pad / factor` in the world along the stretched axis.
    let mut stretch = None;
    let (mut fx, mut fy) = (1.0, 1.0);
    if rw > MAX_ASPECT * rh {
        fy = rw / (MAX_ASPECT * rh);
        stretch = Some(("vertical", fy));
    } else if rh > MAX_ASPECT * rw {
        fx = rh / (MAX_ASPECT * rw);
        stretch = Some(("horizontal", fx));
    }
    // The half extents shown, in the world and on the screen (in the world's units of the
    // unstretched axis).
    let (hw, hh) = (rw + pad / fx, rh + pad / fy);
    let (sw, sh) = (hw * fx, hh * fy);
    let (plot_w, plot_h) = if sw >= sh {
        (PLOT_MAX_W, (PLOT_MAX_W * (sh / sw)).min(PLOT_MAX_H))
    } else {
        ((PLOT_MAX_H * (sw / sh)).min(PLOT_MAX_W), PLOT_MAX_H)
    };
    // Both fit within the maxima.
    let fit = (PLOT_MAX_W / plot_w).min(PLOT_MAX_H / plot_h).min(1.0);
    let (plot_w, plot_h) = (plot_w * fit, plot_h * fit);

    // Paths or sequences drawn, for the legend.
    let legend = Legend::new(scene, &rays, colouring);
    let legend_h = match colouring {
        Colouring::Path | Colouring::Sequence => 40.0 + LEGEND_LINE * legend.lines() as f64,
        Colouring::Time => 0.0,
    };
    let longest = legend
        .entries
        .iter()
        .take(MAX_LEGEND_LINES)
        .map(|e| e.label.chars().count() + thousands(e.count).len() + 3)
        .max()
        .unwrap_or(0);
    let side = match colouring {
        Colouring::Time => BAR_AREA,
        Colouring::Path | Colouring::Sequence => {
            (60.0 + 7.0 * longest as f64).clamp(BAR_AREA, 360.0)
        }
    };

    let (area_w, area_h) = (plot_w.max(AREA_MIN_W), plot_h.max(AREA_MIN_H).max(legend_h));
    let (width, height) = (LEFT + area_w + side, TOP + area_h + BOTTOM);
    let view = View {
        c: centre,
        hw,
        hh,
        pc: (LEFT + 0.5 * area_w, TOP + 0.5 * area_h),
        half: (0.5 * plot_w, 0.5 * plot_h),
    };

    let range = rays
        .iter()
        .filter(|r| r.status.has_time())
        .map(|r| r.time)
        .fold(None, |acc: Option<(f64, f64)>, t| match acc {
            None => Some((t, t)),
            Some((lo, hi)) => Some((lo.min(t), hi.max(t))),
        });
    let colour = |k: usize, r: &Item| -> String {
        match colouring {
            Colouring::Path | Colouring::Sequence => {
                let c = legend.entries[legend.of_item[k]].colour;
                PATH_COLOURS[c % PATH_COLOURS.len()].to_string()
            }
            Colouring::Time => {
                let t = r.time;
                match range {
                    Some((lo, hi)) if hi > lo => viridis((t - lo) / (hi - lo)),
                    _ => viridis(0.5),
                }
            }
        }
    };

    let mut s = String::with_capacity(8192 + rays.len() * 96);
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
        view.left(),
        view.top()
    );

    // Title and caption.
    let _ = writeln!(
        s,
        r##"<text x="12" y="24" font-size="16" font-weight="bold" fill="#222">{}</text>"##,
        esc(title)
    );
    let mut caption = match (entries.rays, arrivals.len()) {
        (RaySet::Stationary(st), 0) => format!(
            "{} of {} stationary paths drawn",
            thousands(rays.len()),
            thousands(st.arrivals())
        ),
        (RaySet::Stationary(st), a) => format!(
            "{} of {} stationary paths and search arrivals drawn",
            thousands(rays.len()),
            thousands(st.arrivals() + a)
        ),
        (_, 0) => format!(
            "{} of {} rays drawn",
            thousands(rays.len()),
            thousands(entries.rays_len())
        ),
        (_, a) => format!(
            "{} of {} rays and search arrivals drawn",
            thousands(rays.len()),
            thousands(entries.rays_len() + a)
        ),
    };
    let timeless = entries.timeless();
    let without = match entries.rays {
        RaySet::Stationary(_) => "rays have no stationary path",
        _ => "no time",
    };
    let without = |n: usize| match entries.rays {
        RaySet::Stationary(_) if n == 1 => "ray has no stationary path".to_string(),
        RaySet::Stationary(_) => without.to_string(),
        _ => format!("{} {without}", have(n)),
    };
    match (sampled, timeless) {
        (false, 0) => {}
        (true, 0) => caption.push_str(" (a sample spread over all rays)"),
        (false, n) => {
            let _ = write!(caption, " ({} {})", thousands(n), without(n));
        }
        (true, n) => {
            let _ = write!(
                caption,
                " (a sample spread over all rays; {} {})",
                thousands(n),
                without(n)
            );
        }
    }
    caption.push_str(match colouring {
        Colouring::Time => ", coloured by travel time",
        Colouring::Path => ", coloured by path",
        Colouring::Sequence => ", coloured by step sequence",
    });
    if rays.iter().any(|r| r.status == Status::Obstructed) {
        caption.push_str("; dashed: obstructed");
    }
    if rays.iter().any(|r| r.status == Status::Vertex) {
        caption.push_str("; dotted: vertex (edge-diffracted)");
    }
    let _ = writeln!(
        s,
        r##"<text x="12" y="44" font-size="12" fill="#555">{}</text>"##,
        esc(&caption)
    );
    let mut caption2 = String::from("★ sources, ● receivers");
    let nr = scene.receivers().len();
    let receivers: Vec<usize> = if nr <= MAX_RECEIVERS {
        (0..nr).collect()
    } else {
        let mut seen: Vec<usize> = rays.iter().map(|r| r.receiver).collect();
        seen.sort_unstable();
        seen.dedup();
        seen.truncate(MAX_RECEIVERS);
        let _ = write!(
            caption2,
            " ({} of {} receivers shown: those of the drawn rays)",
            thousands(seen.len()),
            thousands(nr)
        );
        seen
    };
    if let Some((axis, factor)) = stretch {
        let _ = write!(
            caption2,
            "; {axis} scale stretched ×{}",
            tick_label(factor, factor)
        );
    }
    let _ = writeln!(
        s,
        r##"<text x="12" y="60" font-size="12" fill="#555">{}</text>"##,
        esc(&caption2)
    );

    // Axes: ticks, grid lines and coordinates along the plot's left and bottom edges.
    let xt = axis_ticks(centre.x - hw, centre.x + hw, plot_w / 90.0);
    let yt = axis_ticks(centre.y - hh, centre.y + hh, plot_h / 60.0);
    let _ = writeln!(
        s,
        r##"<g class="axes" stroke="#e4e4e4" stroke-width="1" font-size="11" fill="#444">"##
    );
    for (v, label) in &xt {
        let (x, _) = view.px(Point::new(*v, centre.y));
        let _ = writeln!(
            s,
            r##"<path d="M{x:.2},{:.2}V{:.2}"/><path d="M{x:.2},{:.2}v5" stroke="#444"/><text x="{x:.2}" y="{:.2}" text-anchor="middle" stroke="none">{}</text>"##,
            view.top(),
            view.bottom(),
            view.bottom(),
            view.bottom() + 17.0,
            esc(label)
        );
    }
    for (v, label) in &yt {
        let (_, y) = view.px(Point::new(centre.x, *v));
        let _ = writeln!(
            s,
            r##"<path d="M{:.2},{y:.2}H{:.2}"/><path d="M{:.2},{y:.2}h-5" stroke="#444"/><text x="{:.2}" y="{:.2}" text-anchor="end" stroke="none">{}</text>"##,
            view.left(),
            view.right(),
            view.left(),
            view.left() - 8.0,
            y + 4.0,
            esc(label)
        );
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.2}" y="{:.2}" text-anchor="middle" stroke="none" font-size="12">x</text><text x="{:.2}" y="{:.2}" text-anchor="middle" stroke="none" font-size="12">y</text>"##,
        view.pc.0,
        view.bottom() + 36.0,
        view.left() - 62.0,
        view.pc.1 + 4.0
    );
    let _ = writeln!(s, "</g>");

    // Domain box.
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

    // Rays.
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
        let dash = match r.status {
            Status::Obstructed => r#" stroke-dasharray="5 3""#,
            Status::Vertex => r#" stroke-dasharray="1 3""#,
            _ if colouring != Colouring::Time => {
                path_dash(legend.entries[legend.of_item[k]].colour)
            }
            _ => "",
        };
        let what = match r.path {
            Some(p) => path_label(scene, p),
            None => format!("search arrival, {}", sequence_label(scene, &r.steps)),
        };
        let arrival = match r.arrival {
            Some(a) => format!(", arrival {a}"),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            r#"<polyline points="{}" stroke="{}"{dash}><title>source {}, receiver {}, {}: {}{arrival}, time {t}</title></polyline>"#,
            view.points(&r.points),
            colour(k, r),
            r.source,
            r.receiver,
            esc(&what),
            r.status
        );
    }
    let _ = writeln!(s, "</g>");

    // Interfaces, over the rays that end on them.
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

    // Labels: interfaces at their middle, where they cover the fewest rays and no other label
    // (the names of media with `at` points, which stay beside them, are placed first); then
    // the other media.
    let ray_segments: Vec<PixelSegment> = rays
        .iter()
        .flat_map(|r| r.points.windows(2).map(|w| (view.px(w[0]), view.px(w[1]))))
        .collect();
    let mut taken: Vec<LabelBox> = scene
        .media()
        .iter()
        .filter_map(|m| {
            let (x, y) = view.px(m.at?);
            Some(text_box(x + 6.0, y - 6.0, m.name.chars().count(), 13.0))
        })
        .collect();
    let _ = writeln!(s, r#"<g class="labels" font-size="12">"#);
    for i in scene.interfaces() {
        let (x, y) = interface_label_spot(&view, i, &ray_segments, &taken);
        taken.push(text_box(x, y, i.name.chars().count(), 12.0));
        halo_text(&mut s, x, y, "", "#222", &i.name);
    }
    let walls: Vec<PixelSegment> = scene
        .interfaces()
        .iter()
        .flat_map(|i| {
            let v = i.polyline.vertices();
            let closing = if i.polyline.is_closed() && v.len() > 2 {
                Some((v[v.len() - 1], v[0]))
            } else {
                None
            };
            v.windows(2)
                .map(|w| (w[0], w[1]))
                .chain(closing)
                .map(|(a, b)| (view.px(a), view.px(b)))
                .collect::<Vec<_>>()
        })
        .collect();
    let plot = (view.left(), view.top(), view.right(), view.bottom());
    for (m, (x, y)) in medium_spots(scene, &view, &rays) {
        let name = &scene.media()[m].name;
        let chars = name.chars().count();
        let spot = if scene.media()[m].at.is_some() {
            // Beside the user's point.
            (x + 6.0, y - 6.0)
        } else {
            // Near the middle of the medium's legs, where the label covers the fewest rays,
            // crosses no interface on the way and overlaps no other label.
            let mut best = (f64::INFINITY, (x, y));
            for dy in [0.0, -40.0, 40.0, -80.0, 80.0, -120.0, 120.0] {
                for dx in [
                    0.0, -60.0, 60.0, -120.0, 120.0, -180.0, 180.0, -240.0, 240.0,
                ] {
                    let (bx, by) = (x + dx - 0.3 * 13.0 * chars as f64, y + dy + 4.0);
                    let b = text_box(bx, by, chars, 13.0);
                    let inside = b.0 >= plot.0 && b.2 <= plot.2 && b.1 >= plot.1 && b.3 <= plot.3;
                    let crosses = walls.iter().any(|&(p, q)| {
                        segment_meets_box(p, q, b) || segments_cross((x, y), (x + dx, y + dy), p, q)
                    });
                    if !inside || crosses || taken.iter().any(|t| boxes_overlap(*t, b)) {
                        continue;
                    }
                    let covered = ray_segments
                        .iter()
                        .filter(|(p, q)| segment_meets_box(*p, *q, b))
                        .count() as f64;
                    let score = covered + 0.01 * dx.hypot(dy);
                    if score < best.0 {
                        best = (score, (bx, by));
                    }
                }
            }
            best.1
        };
        taken.push(text_box(spot.0, spot.1, chars, 13.0));
        if scene.media()[m].at.is_some() {
            let _ = writeln!(
                s,
                r##"<path d="M{:.2},{y:.2}h8M{x:.2},{:.2}v8" stroke="#777" stroke-width="1"/>"##,
                x - 4.0,
                y - 4.0
            );
        }
        halo_text(
            &mut s,
            spot.0,
            spot.1,
            r#"font-size="13" font-style="italic""#,
            "#555",
            name,
        );
    }
    let _ = writeln!(s, "</g>");

    // Receivers, then sources on top.
    let radius = match receivers.len() {
        0..=100 => 3.0,
        101..=600 => 1.8,
        _ => 1.2,
    };
    let _ = writeln!(
        s,
        r##"<g class="receivers" fill="#111" stroke="white" stroke-width="{:.2}">"##,
        radius * 0.3
    );
    for &k in &receivers {
        let (x, y) = view.px(scene.receivers()[k]);
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="{radius}"><title>receiver {k}</title></circle>"#
        );
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(
        s,
        r##"<g class="sources" fill="#e4572e" stroke="#222" stroke-width="1" stroke-linejoin="round">"##
    );
    for (k, p) in scene.sources().iter().enumerate() {
        let (x, y) = view.px(*p);
        let _ = writeln!(
            s,
            r#"<polygon points="{}"><title>source {k}</title></polygon>"#,
            star(x, y, 9.0)
        );
    }
    let _ = writeln!(s, "</g>");

    let key_x = LEFT + area_w + 26.0;
    match colouring {
        Colouring::Time => colour_bar(&mut s, key_x, TOP, area_h, range),
        Colouring::Path | Colouring::Sequence => path_legend(&mut s, key_x, TOP, &legend),
    }
    let _ = writeln!(s, "</svg>");
    s
}

/// Where interface `i`'s label goes: near the middle of its length, on whichever side and at
/// whichever of a few places along it covers the fewest ray segments and no label in `taken`.
fn interface_label_spot(
    view: &View,
    i: &eigenray::scene_parts::Interface,
    rays: &[PixelSegment],
    taken: &[LabelBox],
) -> (f64, f64) {
    let v = i.polyline.vertices();
    let mut pts: Vec<(f64, f64)> = v.iter().map(|p| view.px(*p)).collect();
    if i.polyline.is_closed() && !pts.is_empty() {
        pts.push(pts[0]);
    }
    let lens: Vec<f64> = pts
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .collect();
    let total: f64 = lens.iter().sum();
    // The point at fraction `f` of the length, and the unit normal there.
    let at = |f: f64| -> ((f64, f64), (f64, f64)) {
        let mut d = f * total;
        for (k, &l) in lens.iter().enumerate() {
            if d <= l || k + 1 == lens.len() {
                let (a, b) = (pts[k], pts[k + 1]);
                let t = if l > 0.0 {
                    (d / l).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (dx, dy) = if l > 0.0 {
                    ((b.0 - a.0) / l, (b.1 - a.1) / l)
                } else {
                    (1.0, 0.0)
                };
                return ((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), (-dy, dx));
            }
            d -= l;
        }
        (pts.first().copied().unwrap_or((0.0, 0.0)), (0.0, -1.0))
    };
    let chars = i.name.chars().count();
    let width = 0.6 * 12.0 * chars as f64;
    let mut best = (f64::INFINITY, (0.0, 0.0));
    for (rank, f) in [0.5, 0.4, 0.6, 0.3, 0.7, 0.2, 0.8].into_iter().enumerate() {
        let ((x, y), n) = at(f);
        for side in [1.0, -1.0] {
            // The label's centre off the line by half its box's extent across it and 5 px.
            let off = 5.0 + 0.5 * (n.0.abs() * width + n.1.abs() * 15.6);
            let (cx, cy) = (x + side * n.0 * off, y + side * n.1 * off);
            let (bx, by) = (cx - 0.5 * width, cy + 4.0);
            let b = text_box(bx, by, chars, 12.0);
            let covered = rays
                .iter()
                .filter(|(p, q)| segment_meets_box(*p, *q, b))
                .count() as f64;
            let inside = b.0 >= view.left()
                && b.2 <= view.right()
                && b.1 >= view.top()
                && b.3 <= view.bottom();
            let clash = if taken.iter().any(|t| boxes_overlap(*t, b)) {
                1e9
            } else if inside {
                0.0
            } else {
                1e6
            };
            // Prefer the middle, then fewer rays under the label.
            let score = clash + covered + 0.5 * rank as f64;
            if score < best.0 {
                best = (score, (bx, by));
            }
        }
    }
    best.1
}

/// Where each medium's name goes: at its `at` point, or else at the middle of the drawn legs in
/// that medium (the centroid of their midpoints); media with neither are not labelled.
fn medium_spots(scene: &Scene, view: &View, rays: &[Item]) -> Vec<(usize, (f64, f64))> {
    let n = scene.media().len();
    let mut sum = vec![(0.0, 0.0, 0usize); n];
    for r in rays {
        for (leg, &m) in r.media.iter().enumerate() {
            if let (Some(a), Some(b), Some(acc)) =
                (r.points.get(leg), r.points.get(leg + 1), sum.get_mut(m))
            {
                let (x, y) = view.px(Point::new(0.5 * a.x + 0.5 * b.x, 0.5 * a.y + 0.5 * b.y));
                acc.0 += x;
                acc.1 += y;
                acc.2 += 1;
            }
        }
    }
    (0..n)
        .filter_map(|m| match scene.media()[m].at {
            Some(p) => Some((m, view.px(p))),
            None => {
                let (x, y, k) = sum[m];
                (k > 0).then(|| (m, (x / k as f64, y / k as f64)))
            }
        })
        .collect()
}

/// The travel-time colour bar: min at the bottom, max at the top, in the scene's time unit.
fn colour_bar(s: &mut String, x: f64, top: f64, area_h: f64, range: Option<(f64, f64)>) {
    let (bar_top, bar_bottom) = (top + 40.0, top + area_h - 6.0);
    let _ = writeln!(
        s,
        r##"<g class="colour-bar"><text x="{:.2}" y="{:.2}" font-size="12" fill="#222">travel time</text><text x="{:.2}" y="{:.2}" font-size="11" fill="#555">(length ÷ speed)</text>"##,
        x - 8.0,
        top + 10.0,
        x - 8.0,
        top + 26.0
    );
    match range {
        Some((lo, hi)) => {
            let _ = writeln!(
                s,
                r#"<defs><linearGradient id="eigenray-viridis" x1="0" y1="1" x2="0" y2="0">"#
            );
            for (k, c) in VIRIDIS.iter().enumerate() {
                let _ = writeln!(
                    s,
                    r##"<stop offset="{:.4}" stop-color="#{:02x}{:02x}{:02x}"/>"##,
                    k as f64 / (VIRIDIS.len() - 1) as f64,
                    c[0],
                    c[1],
                    c[2]
                );
            }
            let _ = writeln!(s, "</linearGradient></defs>");
            let fill = if hi > lo {
                "url(#eigenray-viridis)".to_string()
            } else {
                viridis(0.5)
            };
            let _ = writeln!(
                s,
                r##"<rect x="{x:.2}" y="{bar_top:.2}" width="16" height="{:.2}" fill="{fill}" stroke="#444" stroke-width="0.8"/>"##,
                bar_bottom - bar_top
            );
            let span = hi - lo;
            let ticks: &[f64] = if hi > lo {
                &[0.0, 0.25, 0.5, 0.75, 1.0]
            } else {
                &[0.5]
            };
            for &f in ticks {
                let y = bar_bottom - f * (bar_bottom - bar_top);
                let v = if hi > lo { lo + f * span } else { lo };
                let _ = writeln!(
                    s,
                    r##"<path d="M{:.2},{y:.2}h5" stroke="#444" stroke-width="1"/><text x="{:.2}" y="{:.2}" font-size="12" fill="#222">{}</text>"##,
                    x + 16.0,
                    x + 24.0,
                    y + 4.0,
                    tick_label(v, span)
                );
            }
        }
        None => {
            let _ = writeln!(
                s,
                r##"<text x="{:.2}" y="{:.2}" font-size="12" fill="#555">no ray has a time</text>"##,
                x - 8.0,
                bar_top + 14.0
            );
        }
    }
    let _ = writeln!(s, "</g>");
}

/// The legend of paths or sequences: a line of each drawn one's colour, its name and its drawn
/// rays (past [`MAX_LEGEND_LINES`], a last line counts the rest).
fn path_legend(s: &mut String, x: f64, top: f64, legend: &Legend) {
    let _ = writeln!(
        s,
        r##"<g class="legend" font-size="12" fill="#222"><text x="{:.2}" y="{:.2}">{}</text>"##,
        x - 8.0,
        top + 10.0,
        legend.heading
    );
    if legend.entries.is_empty() {
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{:.2}" fill="#555">no ray has a time</text>"##,
            x - 8.0,
            top + 30.0
        );
    }
    for (k, e) in legend.entries.iter().take(MAX_LEGEND_LINES).enumerate() {
        let y = top + 32.0 + LEGEND_LINE * k as f64;
        let _ = writeln!(
            s,
            r#"<path d="M{:.2},{:.2}h22" stroke="{}" stroke-width="3"{}/><text x="{:.2}" y="{:.2}">{} ({})</text>"#,
            x - 8.0,
            y - 4.0,
            PATH_COLOURS[e.colour % PATH_COLOURS.len()],
            path_dash(e.colour),
            x + 20.0,
            y,
            esc(&e.label),
            thousands(e.count)
        );
    }
    if legend.entries.len() > MAX_LEGEND_LINES {
        let rest = &legend.entries[MAX_LEGEND_LINES..];
        let drawn: usize = rest.iter().map(|e| e.count).sum();
        let y = top + 32.0 + LEGEND_LINE * MAX_LEGEND_LINES as f64;
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{y:.2}" fill="#555">… {} more ({})</text>"##,
            x - 8.0,
            thousands(rest.len()),
            thousands(drawn)
        );
    }
    let _ = writeln!(s, "</g>");
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenray::{BatchOptions, Tracer};

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), "#440154");
        assert_eq!(viridis(1.0), "#fde725");
        assert_eq!(viridis(0.5), "#21918c");
        assert_eq!(viridis(-3.0), "#440154");
        assert_eq!(viridis(7.0), "#fde725");
        assert_eq!(viridis(f64::NAN), "#440154");
    }

    #[test]
    fn escapes_markup_and_characters_xml_forbids() {
        assert_eq!(
            esc(r#"a<b & "c">'"#),
            "a&lt;b &amp; &quot;c&quot;&gt;&apos;"
        );
        assert_eq!(esc("a\u{1}b\u{fffe}c\u{ffff}"), "a b\u{fffd}c\u{fffd}");
    }

    #[test]
    fn tick_labels_separate_the_range() {
        assert_eq!(tick_label(1.8912, 0.81), "1.8912");
        assert_eq!(tick_label(1234.5, 100.0), "1234.5");
        assert_eq!(tick_label(2.5e7, 1.0), "2.500e7");
    }

    #[test]
    fn axis_ticks_are_round() {
        let t: Vec<String> = axis_ticks(-1.3, 2.2, 6.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["-1", "0", "1", "2"]);
        let t: Vec<String> = axis_ticks(-0.3, 0.45, 6.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["-0.2", "0", "0.2", "0.4"]);
        let t: Vec<String> = axis_ticks(0.0, 1000.0, 5.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["0", "200", "400", "600", "800", "1000"]);
        assert!(axis_ticks(0.0, f64::INFINITY, 5.0).is_empty());
        let tiny = axis_ticks(-2e-310, 2e-310, 4.0);
        let labels: Vec<&str> = tiny.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["-2e-310", "-1e-310", "0", "1e-310", "2e-310"]);
    }

    #[test]
    fn thousands_separate() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(1_000_000), "1,000,000");
    }

    fn picture(json: &str, colouring: Colouring) -> String {
        let scene = Scene::from_json(json).expect("valid scene");
        let batch = Tracer::new(&scene)
            .expect("tracer")
            .trace_batch(&BatchOptions::default());
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
            .trace_batch(&BatchOptions::default());
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
                complete: true,
                amplitude: None,
            },
        }
    }

    #[test]
    fn search_arrivals_are_drawn_with_their_sequences_in_the_legend() {
        let scene = Scene::from_json(ROOM).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default());
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
}
