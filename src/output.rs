//! The `eigenray solve` output: a JSON document, JSON Lines, CSV and NumPy's `.npy`, and the
//! name tables that give the `.npy` file's indices their names.
//!
//! Written by hand with `zmij` (shortest round-trip floats, as `serde_json` prints them: it
//! uses `zmij` too) and `itoa`, straight from owned [`Ray`]s, a flat [`Batch`] or the
//! [`StationaryRays`] of `"stationary": "all"`, and formatted in parallel (rayon) a window of
//! rays at a time, so that writing a large batch costs less than solving it. A search's
//! [`SearchArrival`]s follow the rays in JSON and JSON Lines, or go to a file of their own
//! (a [`Document`] of arrivals alone); [`write()`] writes them all.

use std::io::{self, Write};

use rayon::prelude::*;

pub mod columns;

use self::columns::{Context, Entry, Schema};
use crate::batch::Batch;
use crate::derivatives::Gradient;
use crate::geom::Point;
use crate::scene::{RayTriple, Scene, StepKind};
use crate::search::SearchArrival;
use crate::stationary::StationaryRays;
use crate::trace::{Kink, Ray, Reason, Status};

/// Output formats of `eigenray solve`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    /// One JSON document, `{"rays": [...]}`: one object per ray, in ray order (see
    /// [`write()`] for its fields). With `"stationary": "all"` ([`StationaryRays`])
    /// one object per stationary path, each with three more fields: `arrival` (0, 1, … within
    /// its triple, by time), `kink` (`"minimum"`, `"maximum"` or `"mixed"`, on `vertex`
    /// entries) and `complete` (whether its triple's search was complete); a triple without a
    /// stationary path is one entry, `no_path` (or `not_converged` when its search was not
    /// complete), `arrival` 0. A scene's search arrivals follow as a second key,
    /// `{"rays": [...], "arrivals": [...]}` ([`Document::with_arrivals`]; the fields are
    /// listed at [`write()`]). A scene that asks for amplitudes adds to every timed entry
    /// (ray, stationary path or arrival) `amplitude` and `coefficient` (`[re, im]`),
    /// `spreading` and `attenuation_db` (`null` where there is no number), and
    /// `amplitude_reason` where `amplitude` is `null` ([`Amplitude`](crate::Amplitude)).
    #[default]
    Json,
    /// One ray object per line (the same objects as in `Json`), then one line per search
    /// arrival: the arrival objects of `Json` with `"kind": "arrival"` first (ray lines have
    /// no `kind`).
    Jsonl,
    /// A header line, then one line per ray:
    /// `source,receiver,path,status,time,iterations,residual,points,path_name,media,reason`,
    /// with the points as `x y;x y;…` and the leg media as names joined by `;`. Empty fields
    /// where the ray has no such value (`time` and `points` without a time, `residual` when
    /// not finite, `path_name` for an unnamed path, `media` when unknown, `reason` when
    /// converged). A field holding `,`, `"` or a line break is quoted as RFC 4180 says; a text
    /// field that starts with `=`, `+`, `-`, `@`, a tab or a carriage return is quoted with a
    /// `'` before it (`"'=name"`), so that a spreadsheet does not run it as a formula (OWASP's
    /// advice on CSV injection); in the list columns (`media`, an arrival's `steps`) a name's
    /// own `;` is written `\;` and its backslash `\\`. With
    /// `"stationary": "all"` three columns follow: `arrival`, `kink` (empty but on `vertex`
    /// entries) and `complete` (`true` or `false`). Search arrivals are a table of their own,
    /// written to a second file by [`write()`]. With `"derivatives": true` the four gradient
    /// columns follow; with `"amplitudes"` five more: `amplitude` and `coefficient` (`re im`),
    /// `spreading`, `attenuation_db` and `amplitude_reason` (a number empty where there is
    /// none, all five empty without a time).
    Csv,
    /// NumPy's `.npy` file (format version 1.0): one record per ray, in ray order, of a packed
    /// little-endian structured array that `numpy.load` reads as it is:
    /// `source`, `receiver`, `path` (`<u4`), `status` (`u1`: 0 `converged`, 1 `vertex`,
    /// 2 `no_path`, 3 `obstructed`, 4 `not_converged`), `iterations` (`<u4`), `time` and
    /// `residual` (`<f8`, NaN when the ray has none), `points` (`<f8`, shape `(P, 2)` with `P`
    /// the most points of a path, padded with NaN; all NaN for a ray without a time) and `media`
    /// (`<u4`, shape `(L,)` with `L` the most legs, the leg media as indices into
    /// [`Scene::media`], which lists the media in the order of their names, padded with
    /// `2³² − 1`, all of it when unknown). Names and reasons are left out: [`write_names`]
    /// writes the tables that turn `status`, `path` and `media` into names. Binary, fixed-size
    /// records: the compact format for large batches. With `"stationary": "all"` three fields
    /// follow: `arrival` (`<u4`), `kink` (`u1`: 0 none, 1 `minimum`, 2 `maximum`, 3 `mixed`,
    /// the places in [`KINK_CODES`]) and `complete` (`u1`: 0 or 1). Search arrivals are records
    /// of their own, written to a second file by [`write()`]. With `"amplitudes"` five more
    /// fields follow (after the gradient's): `amplitude` and `coefficient` (`<f8`, shape
    /// `(2,)`), `spreading` and `attenuation_db` (`<f8`, NaN where there is none) and
    /// `amplitude_reason` (`u1`: 0 with a value or without a time, else
    /// [`NoAmplitude::code`](crate::amplitude::NoAmplitude::code), or
    /// [`AMPLITUDE_NOT_COMPUTED`]).
    Npy,
}

/// The statuses in the order of their [`Format::Npy`] codes (0 to 4).
pub const STATUS_CODES: [Status; 5] = [
    Status::Converged,
    Status::Vertex,
    Status::NoPath,
    Status::Obstructed,
    Status::NotConverged,
];

/// The [`Format::Npy`] `media` entry of a leg whose medium is not known.
pub const NO_MEDIUM: u32 = u32::MAX;

/// The kinks in the order of their [`Format::Npy`] `kink` codes (0 to 3; 0: not a `vertex`
/// entry).
pub const KINK_CODES: [Option<Kink>; 4] = [
    None,
    Some(Kink::Minimum),
    Some(Kink::Maximum),
    Some(Kink::Mixed),
];

/// The arrivals' `.npy` `step_kind` codes: 0 reflect, 1 refract; this one pads the
/// steps beyond an arrival's own.
pub const NO_STEP_KIND: u8 = u8::MAX;

/// The arrivals' `.npy` `step_interface` entry that pads the steps beyond an
/// arrival's own.
pub const NO_INTERFACE: u32 = u32::MAX;

/// Code of a kink in [`Format::Npy`]: its place in [`KINK_CODES`].
fn kink_code(kink: Option<Kink>) -> u8 {
    match kink {
        None => 0,
        Some(Kink::Minimum) => 1,
        Some(Kink::Maximum) => 2,
        Some(Kink::Mixed) => 3,
    }
}

/// Code of a status in [`Format::Npy`]: its place in [`STATUS_CODES`].
fn status_code(status: Status) -> u8 {
    match status {
        Status::Converged => 0,
        Status::Vertex => 1,
        Status::NoPath => 2,
        Status::Obstructed => 3,
        Status::NotConverged => 4,
    }
}

/// The shape of a [`Format::Npy`] record: the most interactions `k` of a path, so `k + 2`
/// points and `k + 1` legs.
#[derive(Clone, Copy, Debug)]
struct NpyShape {
    k: usize,
}

impl NpyShape {
    /// The shape for the scene's paths.
    fn of(scene: &Scene) -> NpyShape {
        let k = scene.paths().iter().map(|p| p.steps.len()).max();
        NpyShape { k: k.unwrap_or(0) }
    }

    fn points(self) -> usize {
        self.k + 2
    }

    fn legs(self) -> usize {
        self.k + 1
    }
}

/// The `.npy` header (magic, version 1.0, the dictionary padded to a multiple of 64 bytes) of
/// `n` records whose fields `descr` lists.
fn npy_header_of(n: usize, descr: &str) -> Vec<u8> {
    npy_header_with(&format!(
        "{{'descr': [{descr}], 'fortran_order': False, 'shape': ({n},), }}"
    ))
}

/// The `.npy` header of the dictionary `dict`.
fn npy_header_with(dict: &str) -> Vec<u8> {
    let mut header = b"\x93NUMPY\x01\x00".to_vec();
    // The dictionary ends in a newline, padded with spaces so that the data starts at a
    // multiple of 64 bytes.
    let len = (10 + dict.len() + 1).div_ceil(64) * 64 - 10;
    header.extend_from_slice(&(len as u16).to_le_bytes());
    header.extend_from_slice(dict.as_bytes());
    header.resize(10 + len - 1, b' ');
    header.push(b'\n');
    header
}

/// Writes `data` as a `.npy` array of little-endian float64 numbers of shape `shape`, in C
/// order (the last index fastest), as `numpy.load` reads it.
///
/// ```
/// let mut out = Vec::new();
/// eigenray::output::write_f64_array(&[2, 3], &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0], &mut out).unwrap();
/// assert_eq!(&out[..6], b"\x93NUMPY");
/// assert_eq!(out.len() % 16, 0); // a 64-byte header (its length a multiple of 64), 48 bytes
/// ```
///
/// # Errors
/// Any error of the writer.
///
/// # Panics
/// If `data` does not hold the product of `shape` numbers.
pub fn write_f64_array<W: Write>(shape: &[usize], data: &[f64], mut out: W) -> io::Result<()> {
    assert_eq!(
        shape.iter().product::<usize>(),
        data.len(),
        "array of the wrong size for its shape"
    );
    let dims: String = shape.iter().map(|d| format!("{d}, ")).collect();
    let dims = if shape.len() == 1 {
        dims
    } else {
        dims.trim_end_matches(", ").to_string()
    };
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({dims}), }}");
    out.write_all(&npy_header_with(&dict))?;
    let mut buf = Vec::with_capacity(8 * 8192);
    for chunk in data.chunks(8192) {
        buf.clear();
        for v in chunk {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        out.write_all(&buf)?;
    }
    out.flush()
}

/// The `.npy` header of `n` ray records of `shape`, with the stationary-all fields when
/// `layout` has them and the fields of the quantities of `schema`.
fn npy_header(
    n: usize,
    shape: NpyShape,
    layout: Layout,
    schema: &Schema,
    context: &Context<'_>,
) -> Vec<u8> {
    let mut descr = format!(
        "('source', '<u4'), ('receiver', '<u4'), ('path', '<u4'), \
         ('status', '|u1'), ('iterations', '<u4'), ('time', '<f8'), ('residual', '<f8'), \
         ('points', '<f8', ({}, 2)), ('media', '<u4', ({},))",
        shape.points(),
        shape.legs(),
    );
    if layout == Layout::Stationary {
        descr.push_str(", ('arrival', '<u4'), ('kink', '|u1'), ('complete', '|u1')");
    }
    descr.push_str(&schema.npy_descr(context));
    npy_header_of(n, &descr)
}

/// The `.npy` `amplitude_reason` of a timed ray whose amplitude was not computed (rays traced
/// without the scene's `amplitudes`).
pub const AMPLITUDE_NOT_COMPUTED: u8 = u8::MAX;

/// The `.npy` fields of a gradient of `media` media and `slots` vertices (after others).
fn gradient_npy_descr(media: usize, slots: usize) -> String {
    format!(
        ", ('gradient_source', '<f8', (2,)), ('gradient_receiver', '<f8', (2,)), \
         ('gradient_slowness', '<f8', ({media},)), \
         ('gradient_vertex_interface', '<u4', ({slots},)), \
         ('gradient_vertex', '<u4', ({slots},)), ('gradient_vertices', '<f8', ({slots}, 2))"
    )
}

/// A count as a `.npy` `<u4` (saturating).
fn u32_le(buf: &mut Vec<u8>, v: usize) {
    buf.extend_from_slice(&u32::try_from(v).unwrap_or(u32::MAX).to_le_bytes());
}

/// `points` padded with NaN rows to `rows` (all NaN when `points` is empty), then `media`
/// padded with [`NO_MEDIUM`] to `legs`.
fn points_media_npy(
    buf: &mut Vec<u8>,
    points: &[Point],
    rows: usize,
    media: Option<impl Iterator<Item = usize>>,
    legs: usize,
) {
    for i in 0..rows {
        let p = points
            .get(i)
            .copied()
            .unwrap_or(Point::new(f64::NAN, f64::NAN));
        buf.extend_from_slice(&p.x.to_le_bytes());
        buf.extend_from_slice(&p.y.to_le_bytes());
    }
    let mut media = media;
    for _ in 0..legs {
        let m = media
            .as_mut()
            .and_then(|m| m.next())
            .map_or(NO_MEDIUM, |m| u32::try_from(m).unwrap_or(NO_MEDIUM));
        buf.extend_from_slice(&m.to_le_bytes());
    }
}

fn ray_npy<M: Iterator<Item = usize>>(
    buf: &mut Vec<u8>,
    shape: NpyShape,
    schema: &Schema,
    context: &Context<'_>,
    r: View<'_, M>,
    entry: Option<&Entry<'_>>,
) {
    for v in [r.source, r.receiver, r.path] {
        buf.extend_from_slice(&(v as u32).to_le_bytes());
    }
    buf.push(status_code(r.status));
    buf.extend_from_slice(&(r.iterations.min(u32::MAX as usize) as u32).to_le_bytes());
    buf.extend_from_slice(&r.time.unwrap_or(f64::NAN).to_le_bytes());
    buf.extend_from_slice(&r.residual.to_le_bytes());
    let points = if r.time.is_some() { r.points } else { &[] };
    points_media_npy(buf, points, shape.points(), r.media, shape.legs());
    if let Some(e) = r.every {
        u32_le(buf, e.arrival);
        buf.push(kink_code(e.kink));
        buf.push(u8::from(e.complete));
    }
    if let Some(entry) = entry {
        schema.npy(buf, context, entry);
    }
}

/// The gradient fields of a `.npy` record: NaN and [`NO_INTERFACE`] where there is none, the
/// vertices padded to `slots`.
fn gradient_npy(buf: &mut Vec<u8>, media: usize, slots: usize, gradient: Option<&Gradient>) {
    let f = |buf: &mut Vec<u8>, v: f64| buf.extend_from_slice(&v.to_le_bytes());
    let nan = f64::NAN;
    match gradient {
        Some(g) => {
            for v in [g.source.x, g.source.y, g.receiver.x, g.receiver.y] {
                f(buf, v);
            }
            for m in 0..media {
                f(buf, g.slowness.get(m).copied().unwrap_or(nan));
            }
        }
        None => {
            for _ in 0..4 + media {
                f(buf, nan);
            }
        }
    }
    let vertices = gradient.map_or(&[][..], |g| &g.vertices[..]);
    for i in 0..slots {
        let v = vertices.get(i).map_or(NO_INTERFACE, |v| v.interface as u32);
        buf.extend_from_slice(&v.to_le_bytes());
    }
    for i in 0..slots {
        let v = vertices.get(i).map_or(NO_INTERFACE, |v| v.vertex as u32);
        buf.extend_from_slice(&v.to_le_bytes());
    }
    for i in 0..slots {
        let d = vertices.get(i).map_or([nan, nan], |v| [v.d.x, v.d.y]);
        f(buf, d[0]);
        f(buf, d[1]);
    }
}

/// Which fields the ray entries of a document have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    /// One entry per ray (`"stationary": "one"`).
    Rays,
    /// One entry per stationary path, with `arrival`, `kink` and `complete`
    /// (`"stationary": "all"`).
    Stationary,
}

/// The fields of an entry of every stationary path of its triple.
#[derive(Clone, Copy, Debug)]
struct EveryFields {
    /// Its place within its triple, by time.
    arrival: usize,
    /// How the time behaves at its held vertices (a `vertex` entry).
    kink: Option<Kink>,
    /// Whether its triple's search was complete.
    complete: bool,
}

/// One ray as the writers see it.
struct View<'a, M: Iterator<Item = usize>> {
    source: usize,
    receiver: usize,
    path: usize,
    status: Status,
    time: Option<f64>,
    points: &'a [Point],
    iterations: usize,
    residual: f64,
    media: Option<M>,
    reason: Option<Reason>,
    /// Present exactly in [`Layout::Stationary`].
    every: Option<EveryFields>,
    /// The result its quantities are read from ([`Source::entry`], made only when the
    /// scene asks for a quantity).
    values: Source<'a>,
}

/// The result a ray of a document is, for reading its quantities ([`Entry`]).
#[derive(Clone, Copy)]
enum Source<'a> {
    /// An owned ray.
    Ray(&'a Ray),
    /// Ray `i` of a batch.
    Batch(&'a Batch, usize),
    /// An entry of every stationary path.
    Stationary(&'a crate::stationary::StationaryEntry<'a>),
}

impl Source<'_> {
    /// What its quantities are read from, with the gradient `gradient`.
    fn entry<'g>(self, gradient: Option<&'g Gradient>) -> Entry<'g> {
        let entry = match self {
            Source::Ray(r) => Entry::of_ray(r),
            Source::Batch(b, i) => Entry::of_batch(b, i),
            Source::Stationary(e) => Entry::of_stationary(e),
        };
        Entry { gradient, ..entry }
    }

    /// Its direction at the source, where its result gives it (an entry of every stationary
    /// path through a profile medium: which of the rays between its points it is).
    fn launch_angle(self) -> Option<f64> {
        match self {
            Source::Stationary(e) => e.launch_angle,
            Source::Ray(_) | Source::Batch(..) => None,
        }
    }
}

/// The medium, path and interface names as each format writes them, made once per document.
struct Names {
    /// Escaped JSON strings of the media.
    media: Vec<Vec<u8>>,
    /// Escaped JSON strings of the path names (`None` for an unnamed path).
    paths: Vec<Option<Vec<u8>>>,
    /// CSV fields of the path names (quoted where needed; empty for an unnamed path).
    paths_csv: Vec<Vec<u8>>,
    /// The medium names for CSV, when none needs quoting (else the field is quoted whole).
    media_csv: Option<Vec<Vec<u8>>>,
    /// Escaped JSON strings of the interface names.
    interfaces: Vec<Vec<u8>>,
    /// Per medium: whether its speed has a gradient.
    gradient: Vec<bool>,
}

/// `s` as a JSON string.
fn json_string(s: &str) -> Vec<u8> {
    serde_json::to_vec(s).unwrap_or_else(|_| b"\"?\"".to_vec())
}

/// The characters that make a spreadsheet read a cell as a formula when the cell starts with
/// one (OWASP's list for CSV injection).
const FORMULA_STARTS: [char; 6] = ['=', '+', '-', '@', '\t', '\r'];

/// Appends the text cell `field` to a CSV line: quoted (RFC 4180) when it holds `,`, `"` or a
/// line break, and, when it starts with a character a spreadsheet takes for a formula
/// ([`FORMULA_STARTS`]), quoted with a `'` before it, as OWASP advises (the cell then reads
/// as text: `'=name`).
fn csv_field(buf: &mut Vec<u8>, field: &str) {
    let formula = field.starts_with(FORMULA_STARTS);
    if formula || field.contains([',', '"', '\n', '\r']) {
        buf.push(b'"');
        if formula {
            buf.push(b'\'');
        }
        buf.extend_from_slice(field.replace('"', "\"\"").as_bytes());
        buf.push(b'"');
    } else {
        buf.extend_from_slice(field.as_bytes());
    }
}

/// A name as an item of a CSV list column (items joined by `;`): a backslash in the name
/// written as two, and its `;` as `\;`, so that splitting at the other `;` gives the names
/// back.
fn csv_list_item(name: &str) -> std::borrow::Cow<'_, str> {
    if name.contains([';', '\\']) {
        name.replace('\\', "\\\\").replace(';', "\\;").into()
    } else {
        name.into()
    }
}

impl Names {
    fn new(scene: &Scene) -> Names {
        let media = scene.media().iter().map(|m| json_string(&m.name)).collect();
        let paths = scene
            .paths()
            .iter()
            .map(|p| p.name.as_deref().map(json_string))
            .collect();
        let paths_csv = scene
            .paths()
            .iter()
            .map(|p| {
                let mut f = Vec::new();
                csv_field(&mut f, p.name.as_deref().unwrap_or(""));
                f
            })
            .collect();
        let media_csv = scene
            .media()
            .iter()
            .map(|m| {
                let plain = !m.name.contains([',', '"', '\n', '\r', ';', '\\'])
                    && !m.name.starts_with(FORMULA_STARTS);
                plain.then(|| m.name.as_bytes().to_vec())
            })
            .collect();
        let flat: &[&str] = if scene.extrusion().is_some() {
            &[crate::scene::FLOOR, crate::scene::CEILING]
        } else {
            &[]
        };
        let interfaces = scene
            .interfaces()
            .iter()
            .map(|i| i.name.as_str())
            .chain(flat.iter().copied())
            .map(json_string)
            .collect();
        Names {
            media,
            paths,
            paths_csv,
            media_csv,
            interfaces,
            gradient: scene.media().iter().map(|m| m.gradient.is_some()).collect(),
        }
    }
}

fn float(buf: &mut Vec<u8>, v: f64) {
    if v.is_finite() {
        buf.extend_from_slice(zmij::Buffer::new().format_finite(v).as_bytes());
    } else {
        buf.extend_from_slice(b"null");
    }
}

fn int(buf: &mut Vec<u8>, v: usize) {
    buf.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// `[[x,y],…]`.
fn points_json(buf: &mut Vec<u8>, points: &[Point]) {
    points_heights_json(buf, points, &[]);
}

/// `[[x,y],…]`, or `[[x,y,z],…]` with the heights `heights` (an extruded scene's arrival).
fn points_heights_json(buf: &mut Vec<u8>, points: &[Point], heights: &[f64]) {
    buf.push(b'[');
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.push(b'[');
        float(buf, p.x);
        buf.push(b',');
        float(buf, p.y);
        if let Some(&z) = heights.get(i) {
            buf.push(b',');
            float(buf, z);
        }
        buf.push(b']');
    }
    buf.push(b']');
}

/// `["air",…]` (an index beyond the scene's media as `"?"`).
fn media_json(buf: &mut Vec<u8>, names: &Names, media: impl Iterator<Item = usize>) {
    buf.push(b'[');
    for (i, m) in media.enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(names.media.get(m).map_or(b"\"?\"", Vec::as_slice));
    }
    buf.push(b']');
}

fn ray_json<M: Iterator<Item = usize>>(
    buf: &mut Vec<u8>,
    schema: &Schema,
    context: &Context<'_>,
    r: View<'_, M>,
    entry: Option<&Entry<'_>>,
) {
    let (scene, names) = (context.scene, context.names);
    buf.extend_from_slice(b"{\"source\":");
    int(buf, r.source);
    buf.extend_from_slice(b",\"receiver\":");
    int(buf, r.receiver);
    buf.extend_from_slice(b",\"path\":");
    int(buf, r.path);
    if let Some(Some(name)) = names.paths.get(r.path) {
        buf.extend_from_slice(b",\"path_name\":");
        buf.extend_from_slice(name);
    }
    if let Some(e) = r.every {
        buf.extend_from_slice(b",\"arrival\":");
        int(buf, e.arrival);
    }
    buf.extend_from_slice(b",\"status\":\"");
    buf.extend_from_slice(r.status.as_str().as_bytes());
    buf.push(b'"');
    if let Some(kink) = r.every.and_then(|e| e.kink) {
        buf.extend_from_slice(b",\"kink\":\"");
        buf.extend_from_slice(kink.as_str().as_bytes());
        buf.push(b'"');
    }
    if let Some(t) = r.time {
        buf.extend_from_slice(b",\"time\":");
        float(buf, t);
        buf.extend_from_slice(b",\"points\":");
        points_json(buf, r.points);
    }
    if let Some(entry) = entry {
        schema.json(buf, context, entry);
    }
    buf.extend_from_slice(b",\"iterations\":");
    int(buf, r.iterations);
    if r.residual.is_finite() {
        buf.extend_from_slice(b",\"residual\":");
        float(buf, r.residual);
    }
    if let Some(media) = r.media {
        buf.extend_from_slice(b",\"media\":");
        media_json(buf, names, media);
    }
    if let Some(reason) = r.reason {
        buf.extend_from_slice(b",\"reason\":");
        buf.extend_from_slice(&json_string(&reason.describe(scene)));
    }
    if let Some(e) = r.every {
        buf.extend_from_slice(if e.complete {
            b",\"complete\":true"
        } else {
            b",\"complete\":false"
        });
    }
    buf.push(b'}');
}

/// `[x,y]`.
fn vec_json(buf: &mut Vec<u8>, v: crate::geom::Vec2) {
    buf.push(b'[');
    float(buf, v.x);
    buf.push(b',');
    float(buf, v.y);
    buf.push(b']');
}

/// `,"gradient":{"source":[…],"receiver":[…],"slowness":{"air":…},"vertices":[{"interface":
/// "surface","vertex":3,"d":[…]}]}`.
fn gradient_json(buf: &mut Vec<u8>, names: &Names, g: &Gradient) {
    buf.extend_from_slice(b",\"gradient\":{\"source\":");
    vec_json(buf, g.source);
    buf.extend_from_slice(b",\"receiver\":");
    vec_json(buf, g.receiver);
    buf.extend_from_slice(b",\"slowness\":{");
    for (m, (name, d)) in names.media.iter().zip(&g.slowness).enumerate() {
        if m > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(name);
        buf.push(b':');
        float(buf, *d);
    }
    buf.push(b'}');
    // In a scene with a gradient medium: `dT/dG` of each medium that has a gradient.
    if !g.speed_gradient.is_empty() {
        buf.extend_from_slice(b",\"speed_gradient\":{");
        let mut first = true;
        for (name, (d, m)) in (names.media.iter()).zip(g.speed_gradient.iter().zip(&names.gradient))
        {
            if !*m {
                continue;
            }
            if !first {
                buf.push(b',');
            }
            first = false;
            buf.extend_from_slice(name);
            buf.push(b':');
            vec_json(buf, *d);
        }
        buf.push(b'}');
    }
    // In a scene with a profile medium: `dT/dc` of each knot of each profile.
    if !g.profile_speed.is_empty() {
        buf.extend_from_slice(b",\"profile_speed\":{");
        let mut first = true;
        for (name, knots) in names.media.iter().zip(&g.profile_speed) {
            if knots.is_empty() {
                continue;
            }
            if !first {
                buf.push(b',');
            }
            first = false;
            buf.extend_from_slice(name);
            buf.extend_from_slice(b":[");
            for (k, d) in knots.iter().enumerate() {
                if k > 0 {
                    buf.push(b',');
                }
                float(buf, *d);
            }
            buf.push(b']');
        }
        buf.push(b'}');
    }
    buf.extend_from_slice(b",\"vertices\":[");
    for (i, v) in g.vertices.iter().enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(b"{\"interface\":");
        buf.extend_from_slice(
            names
                .interfaces
                .get(v.interface)
                .map_or(b"\"?\"", Vec::as_slice),
        );
        buf.extend_from_slice(b",\"vertex\":");
        int(buf, v.vertex);
        buf.extend_from_slice(b",\"d\":");
        vec_json(buf, v.d);
        buf.push(b'}');
    }
    buf.extend_from_slice(b"]}");
}

/// The four gradient columns of a CSV line (each after a comma; empty without a gradient):
/// `x y`, `x y`, the media's `dT/dw` joined by `;`, and `interface vertex x y;…`.
fn gradient_csv(buf: &mut Vec<u8>, gradient: Option<&Gradient>) {
    let Some(g) = gradient else {
        buf.extend_from_slice(b",,,,");
        return;
    };
    for v in [g.source, g.receiver] {
        buf.push(b',');
        float(buf, v.x);
        buf.push(b' ');
        float(buf, v.y);
    }
    buf.push(b',');
    for (m, d) in g.slowness.iter().enumerate() {
        if m > 0 {
            buf.push(b';');
        }
        float(buf, *d);
    }
    buf.push(b',');
    for (i, v) in g.vertices.iter().enumerate() {
        if i > 0 {
            buf.push(b';');
        }
        int(buf, v.interface);
        buf.push(b' ');
        int(buf, v.vertex);
        buf.push(b' ');
        float(buf, v.d.x);
        buf.push(b' ');
        float(buf, v.d.y);
    }
}

/// `x y;x y;…`.
fn points_csv(buf: &mut Vec<u8>, points: &[Point]) {
    points_heights_csv(buf, points, &[]);
}

/// `x y;x y;…`, or `x y z;…` with the heights `heights` (an extruded scene's arrival).
fn points_heights_csv(buf: &mut Vec<u8>, points: &[Point], heights: &[f64]) {
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            buf.push(b';');
        }
        float(buf, p.x);
        buf.push(b' ');
        float(buf, p.y);
        if let Some(&z) = heights.get(i) {
            buf.push(b' ');
            float(buf, z);
        }
    }
}

/// The leg media's names joined by `;` (each name's own `;` and `\\` escaped; the cell quoted
/// whole when it needs it).
fn media_csv(buf: &mut Vec<u8>, scene: &Scene, names: &Names, media: impl Iterator<Item = usize>) {
    match &names.media_csv {
        // No name needs quoting: the names as they are, joined by `;`.
        Some(plain) => {
            for (i, m) in media.enumerate() {
                if i > 0 {
                    buf.push(b';');
                }
                buf.extend_from_slice(plain.get(m).map_or(b"?", Vec::as_slice));
            }
        }
        None => {
            let mut joined = String::new();
            for (i, m) in media.enumerate() {
                if i > 0 {
                    joined.push(';');
                }
                joined.push_str(&csv_list_item(
                    scene.media().get(m).map_or("?", |m| m.name.as_str()),
                ));
            }
            csv_field(buf, &joined);
        }
    }
}

fn ray_csv<M: Iterator<Item = usize>>(
    buf: &mut Vec<u8>,
    schema: &Schema,
    context: &Context<'_>,
    r: View<'_, M>,
    entry: Option<&Entry<'_>>,
) {
    let (scene, names) = (context.scene, context.names);
    int(buf, r.source);
    buf.push(b',');
    int(buf, r.receiver);
    buf.push(b',');
    int(buf, r.path);
    buf.push(b',');
    buf.extend_from_slice(r.status.as_str().as_bytes());
    buf.push(b',');
    if let Some(t) = r.time {
        float(buf, t);
    }
    buf.push(b',');
    int(buf, r.iterations);
    buf.push(b',');
    if r.residual.is_finite() {
        float(buf, r.residual);
    }
    buf.push(b',');
    if r.time.is_some() {
        points_csv(buf, r.points);
    }
    buf.push(b',');
    if let Some(name) = names.paths_csv.get(r.path) {
        buf.extend_from_slice(name);
    }
    buf.push(b',');
    if let Some(media) = r.media {
        media_csv(buf, scene, names, media);
    }
    buf.push(b',');
    if let Some(reason) = r.reason {
        csv_field(buf, &reason.describe(scene));
    }
    if let Some(e) = r.every {
        buf.push(b',');
        int(buf, e.arrival);
        buf.push(b',');
        if let Some(kink) = e.kink {
            buf.extend_from_slice(kink.as_str().as_bytes());
        }
        buf.push(b',');
        buf.extend_from_slice(if e.complete { b"true" } else { b"false" });
    }
    if let Some(entry) = entry {
        schema.csv(buf, context, entry);
    }
    buf.push(b'\n');
}

/// The header line of [`Format::Csv`].
const CSV_HEADER: &[u8] =
    b"source,receiver,path,status,time,iterations,residual,points,path_name,media,reason\n";

/// The header line of [`Format::Csv`] with `"stationary": "all"`.
const CSV_HEADER_STATIONARY: &[u8] = b"source,receiver,path,status,time,iterations,residual,\
points,path_name,media,reason,arrival,kink,complete\n";

/// Writes the CSV header line `header`, then the columns of the quantities of `schema`.
fn csv_header<W: Write>(out: &mut W, header: &[u8], schema: &Schema) -> io::Result<()> {
    let columns = header.strip_suffix(b"\n").unwrap_or(header);
    out.write_all(columns)?;
    schema.csv_header(out)?;
    out.write_all(b"\n")
}

/// Rays formatted at a time (in [`PIECE`]s, in parallel) before they are written out in order,
/// at most: fewer where long names make each ray's text long ([`Window::of`]).
const WINDOW: usize = 1 << 14;
/// Rays per parallel piece of a window, at most.
const PIECE: usize = 1 << 10;
/// The most bytes of text one window may hold, by the estimate of [`Window::of`]: two windows
/// are in memory at a time (one written while the next is formatted).
const WINDOW_BYTES: usize = 32 << 20;

/// How many rays the writer formats at a time: a window, in parallel pieces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Window {
    /// Rays per window.
    rays: usize,
    /// Rays per parallel piece.
    piece: usize,
}

impl Window {
    /// The window for `scene`'s rays: [`WINDOW`] rays, or as many as fit in [`WINDOW_BYTES`]
    /// by a bound on one ray's text. A name can take six bytes a character in JSON (`\u00xx`),
    /// and a ray names its path, each leg's medium and, in a reason, an interface; the
    /// quantities of `schema` add their own bound.
    fn of(scene: &Scene, schema: &Schema) -> Window {
        let longest = |names: &mut dyn Iterator<Item = usize>| names.max().unwrap_or(0);
        let medium = longest(&mut scene.media().iter().map(|m| m.name.len()));
        let path = longest(
            &mut scene
                .paths()
                .iter()
                .filter_map(|p| p.name.as_ref().map(String::len)),
        );
        let interface = longest(&mut scene.interfaces().iter().map(|i| i.name.len()));
        let steps = longest(&mut scene.paths().iter().map(|p| p.steps.len()));
        let (points, legs) = (steps + 2, steps + 1);
        let bytes = 512
            + 64 * points
            + legs * (6 * medium + 8)
            + 6 * (path + interface)
            + schema.text_bytes(scene);
        let rays = (WINDOW_BYTES / bytes).clamp(1, WINDOW);
        Window {
            rays,
            piece: (rays / 16).clamp(1, PIECE),
        }
    }
}

/// The error of a request for arrivals beside the rays in a format that holds one table.
fn one_table(format: Format) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} holds one table: write the search arrivals to a second file, as a document of their own",
            if format == Format::Csv { "CSV" } else { ".npy" }
        ),
    )
}

/// Writes `n` rays produced by `view` in `format`: a window of rays at a time, formatted in
/// parallel pieces (rayon) while the previous window is written, in order; then, in JSON and
/// JSON Lines, `arrivals` (refused before anything is written in CSV and `.npy`).
fn write_all<'a, W: Write, M: Iterator<Item = usize>>(
    scene: &Scene,
    n: usize,
    layout: Layout,
    arrivals: Option<&[SearchArrival]>,
    format: Format,
    mut out: W,
    view: impl Fn(usize) -> View<'a, M> + Sync,
) -> io::Result<()> {
    if arrivals.is_some() && matches!(format, Format::Csv | Format::Npy) {
        return Err(one_table(format));
    }
    let names = Names::new(scene);
    let shape = NpyShape::of(scene);
    let schema = Schema::of(scene);
    let context = Context {
        scene,
        names: &names,
        steps: shape.k,
    };
    let derivatives = scene.solver().derivatives;
    let window = Window::of(scene, &schema);
    match format {
        Format::Npy => out.write_all(&npy_header(n, shape, layout, &schema, &context))?,
        Format::Json => out.write_all(b"{\"rays\":[")?,
        Format::Csv => {
            let header = match layout {
                Layout::Rays => CSV_HEADER,
                Layout::Stationary => CSV_HEADER_STATIONARY,
            };
            csv_header(&mut out, header, &schema)?;
        }
        Format::Jsonl => {}
    }
    let format_piece = |buf: &mut Vec<u8>, rays: std::ops::Range<usize>| {
        buf.clear();
        let mut gradient = Gradient::default();
        for i in rays {
            // The gradient from the ray's points and leg media (a first view of the ray).
            let has_gradient = derivatives && {
                let v = view(i);
                let steps = scene.paths().get(v.path).map(|p| &p.steps[..]);
                match (v.time, v.media, steps) {
                    (Some(_), Some(media), Some(steps)) => {
                        let launch = v.values.launch_angle();
                        (gradient.fill_at(scene, steps, v.points, media, None, launch)).is_ok()
                    }
                    _ => false,
                }
            };
            let r = view(i);
            // (Made only for a scene that asks for a quantity.)
            let entry = (!schema.is_empty()).then(|| {
                let mut e = r.values.entry(has_gradient.then_some(&gradient));
                // A default-mode ray through a profile medium: its turns and caustics.
                if e.turns.is_none() && scene.curved() && r.points.len() >= 2 {
                    let media: Vec<usize> = view(i).media.into_iter().flatten().collect();
                    let steps = scene.paths().get(r.path).map_or(&[][..], |p| &p.steps[..]);
                    let shape = Entry::shape(scene, steps, e.timed, r.points, &media);
                    e = Entry {
                        turns: shape.map(|s| s.turns),
                        caustics: shape.map(|s| s.caustics),
                        launch_angle: shape.map(|s| s.launch_angle),
                        ..e
                    };
                }
                if e.caustics.is_none() && scene.curved() {
                    // A ray through a gradient medium: its caustics from its path.
                    let v = view(i);
                    let steps = scene.paths().get(v.path).map(|p| &p.steps[..]);
                    let media: Vec<usize> = v.media.into_iter().flatten().collect();
                    let caustics = match (v.status, steps) {
                        (crate::Status::Converged, Some(steps)) => {
                            let path = crate::amplitude::PathGeometry {
                                steps,
                                points: r.points,
                                media: &media,
                                segments: None,
                            };
                            crate::amplitude::caustics_of_path(scene, path)
                        }
                        _ => None,
                    };
                    Entry { caustics, ..e }
                } else {
                    e
                }
            });
            let entry = entry.as_ref();
            match format {
                Format::Json => {
                    if i > 0 {
                        buf.push(b',');
                    }
                    ray_json(buf, &schema, &context, r, entry);
                }
                Format::Jsonl => {
                    ray_json(buf, &schema, &context, r, entry);
                    buf.push(b'\n');
                }
                Format::Csv => ray_csv(buf, &schema, &context, r, entry),
                Format::Npy => ray_npy(buf, shape, &schema, &context, r, entry),
            }
        }
    };
    // Formats window `w` into `pieces` (one buffer per piece, in order).
    let format_window = |pieces: &mut Vec<Vec<u8>>, w: usize| {
        let (start, end) = (w * window.rays, n.min((w + 1) * window.rays));
        let count = (end - start).div_ceil(window.piece);
        pieces.resize_with(count, Vec::new);
        pieces.par_iter_mut().enumerate().for_each(|(j, buf)| {
            let lo = start + j * window.piece;
            format_piece(buf, lo..end.min(lo + window.piece));
        });
    };
    // Double-buffered: this thread writes one window while the pool formats the next.
    let (mut ready, mut next) = (Vec::new(), Vec::new());
    let windows = n.div_ceil(window.rays);
    if windows > 0 {
        format_window(&mut ready, 0);
    }
    for w in 0..windows {
        let mut written = Ok(());
        rayon::in_place_scope(|scope| {
            if w + 1 < windows {
                let next = &mut next;
                let format_window = &format_window;
                scope.spawn(move |_| format_window(next, w + 1));
            }
            written = ready.iter().try_for_each(|piece| out.write_all(piece));
        });
        written?;
        std::mem::swap(&mut ready, &mut next);
    }
    match (format, arrivals) {
        (Format::Json, None) => out.write_all(b"]}\n")?,
        (Format::Json, Some(arrivals)) => {
            out.write_all(b"],\"arrivals\":[")?;
            arrival_lines(scene, &names, &schema, arrivals, format, &mut out)?;
            out.write_all(b"]}\n")?;
        }
        (Format::Jsonl, Some(arrivals)) => {
            arrival_lines(scene, &names, &schema, arrivals, format, &mut out)?;
        }
        _ => {}
    }
    out.flush()
}

/// What one document of `eigenray solve` holds: rays in one of their forms, a search's
/// arrivals, or both (see [`write()`]). Every form the library gives converts into it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Document<'a> {
    /// The rays: `{"rays": [...]}` (an empty list when `None` and arrivals are given beside
    /// nothing else: then the document is the arrivals' table alone).
    pub rays: Option<RaySet<'a>>,
    /// A search's arrivals ([`Tracer::search`](crate::Tracer::search)).
    pub arrivals: Option<&'a [SearchArrival]>,
}

impl<'a> Document<'a> {
    /// `self` with a search's arrivals after the rays.
    pub fn with_arrivals(self, arrivals: &'a [SearchArrival]) -> Document<'a> {
        Document {
            arrivals: Some(arrivals),
            ..self
        }
    }
}

impl<'a> From<RaySet<'a>> for Document<'a> {
    fn from(rays: RaySet<'a>) -> Self {
        Document {
            rays: Some(rays),
            arrivals: None,
        }
    }
}

impl<'a> From<&'a [Ray]> for Document<'a> {
    fn from(rays: &'a [Ray]) -> Self {
        RaySet::Rays(rays).into()
    }
}

impl<'a> From<&'a Vec<Ray>> for Document<'a> {
    fn from(rays: &'a Vec<Ray>) -> Self {
        RaySet::Rays(rays).into()
    }
}

impl<'a> From<&'a Batch> for Document<'a> {
    fn from(batch: &'a Batch) -> Self {
        RaySet::Batch(batch).into()
    }
}

impl<'a> From<&'a StationaryRays> for Document<'a> {
    fn from(rays: &'a StationaryRays) -> Self {
        RaySet::Stationary(rays).into()
    }
}

impl<'a> From<&'a [SearchArrival]> for Document<'a> {
    fn from(arrivals: &'a [SearchArrival]) -> Self {
        Document {
            rays: None,
            arrivals: Some(arrivals),
        }
    }
}

impl<'a> From<&'a Vec<SearchArrival>> for Document<'a> {
    fn from(arrivals: &'a Vec<SearchArrival>) -> Self {
        arrivals.as_slice().into()
    }
}

/// Writes one document of `eigenray solve` in `format`: rays ([`Ray`]s, a [`Batch`] or every
/// stationary path, [`StationaryRays`]), a search's arrivals ([`SearchArrival`]s), or rays
/// followed by arrivals ([`Document::with_arrivals`]). [`Format`] lists each format's fields.
///
/// - Rays: one entry per ray in ray order, `{"rays": [...]}` in JSON (compact, one line).
///   Each ray has `source`, `receiver` and `path` (indices), `path_name` (when the path has a
///   name), `status`, `time` and `points` (when it has a time), `iterations`, `residual`
///   (when finite), the leg `media` names (when known) and a `reason` when it is not
///   converged. Every stationary path (`"stationary": "all"`) is one entry per stationary
///   path, in ray order and within a triple by time, with the fields of a ray plus `arrival`,
///   `kink` and `complete`; a triple without any is one `no_path` entry (or `not_converged`,
///   when the triple's search was not complete).
/// - Arrivals alone: the table described at [`Format`]'s arrival fields (below).
/// - Rays and arrivals: in JSON the document `{"rays": [...], "arrivals": [...]}`, in JSON
///   Lines one line per arrival after the rays' lines, marked `"kind": "arrival"`.
///
/// Each arrival has `source` and `receiver` (indices), `steps` (the step sequence in the
/// scene's notation), the leg `media`, `status` (`converged`, `vertex` or `obstructed`),
/// `kink` (on `vertex` arrivals), `time`, `points` (source, interaction points, receiver),
/// `iterations`, `residual` (when finite), a `reason` when it is not converged, and `complete`
/// (whether the search of its sequence was complete). With `"derivatives": true` each also
/// carries its gradient, as the rays do in each format.
///
/// - [`Format::Json`]: `{"arrivals": [{"source": 0, "receiver": 0, "steps": [{"reflect":
///   "w0"}], "media": ["air", "air"], "status": "converged", "time": …, "points": […], …}]}`.
/// - [`Format::Jsonl`]: one arrival object per line, `"kind": "arrival"` first.
/// - [`Format::Csv`]: the header
///   `source,receiver,steps,media,status,kink,time,points,iterations,residual,reason,complete`,
///   then one line per arrival; `steps` as `reflect:w0;refract:surface` (empty for the direct
///   ray), `media` and `points` as in the rays' CSV.
/// - [`Format::Npy`]: one record per arrival: `source`, `receiver`, `steps` (the number of
///   steps) (`<u4`), `step_kind` (`u1`, shape `(K,)`: 0 reflect, 1 refract,
///   [`NO_STEP_KIND`] beyond the arrival's steps), `step_interface` (`<u4`, shape `(K,)`:
///   indices into [`Scene::interfaces`], [`NO_INTERFACE`] beyond), `status`, `kink` (the
///   codes of [`Format::Npy`]), `complete` (`u1`), `iterations` (`<u4`), `time`, `residual`
///   (`<f8`), `points` (`<f8`, shape `(K + 2, 2)`, padded with NaN) and `media` (`<u4`, shape
///   `(K + 1,)`, padded with [`NO_MEDIUM`]), with `K` the search's `max_steps` (or the most
///   steps of an arrival, when more).
///
/// ```
/// use eigenray::{Format, Scene, Tracer, options::Run, write};
/// let scene = Scene::from_json(r#"{
///     "media": { "air": { "speed": 1.0 } },
///     "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
///     "sources": [[-0.5, 2]], "receivers": [[0.5, 2]],
///     "paths": [{ "steps": [{ "reflect": "valley" }], "media": ["air", "air"] }],
///     "solver": { "stationary": "all" }
/// }"#).unwrap();
/// let rays = Tracer::new(&scene).unwrap().trace_stationary(&Run::new()).unwrap();
/// let mut out = Vec::new();
/// write(&scene, &rays, Format::Jsonl, &mut out).unwrap();
/// let lines: Vec<serde_json::Value> = out
///     .split(|&b| b == b'\n')
///     .filter(|l| !l.is_empty())
///     .map(|l| serde_json::from_slice(l).unwrap())
///     .collect();
/// assert_eq!(lines.len(), 3);
/// assert_eq!(lines[2]["arrival"], 2);
/// assert_eq!(lines[2]["status"], "vertex");
/// assert_eq!(lines[2]["kink"], "maximum");
/// assert_eq!(lines[2]["complete"], true);
/// ```
///
/// # Errors
/// Any error of the writer; rays and arrivals together in [`Format::Csv`] or [`Format::Npy`],
/// which hold one table each ([`io::ErrorKind::InvalidInput`], before anything is written:
/// write the arrivals to a second file, as a document of their own).
pub fn write<'a, W: Write>(
    scene: &Scene,
    document: impl Into<Document<'a>>,
    format: Format,
    out: W,
) -> io::Result<()> {
    match document.into() {
        Document {
            rays: None,
            arrivals: Some(arrivals),
        } => write_arrivals(scene, arrivals, format, out),
        Document { rays, arrivals } => write_rays_and_arrivals(
            scene,
            rays.unwrap_or(RaySet::Rays(&[])),
            arrivals,
            format,
            out,
        ),
    }
}

/// The rays of an `eigenray solve` document, in any of the forms the library gives them.
#[derive(Clone, Copy, Debug)]
pub enum RaySet<'a> {
    /// One ray per triple, as [`Tracer::trace_all`](crate::Tracer::trace_all) gives them.
    Rays(&'a [Ray]),
    /// One ray per triple, in flat arrays ([`Tracer::trace_batch`](crate::Tracer::trace_batch)).
    Batch(&'a Batch),
    /// Every stationary path of every triple
    /// ([`Tracer::trace_stationary`](crate::Tracer::trace_stationary)).
    Stationary(&'a StationaryRays),
}

/// [`write()`]: `rays`, then `arrivals` when given.
fn write_rays_and_arrivals<W: Write>(
    scene: &Scene,
    rays: RaySet<'_>,
    arrivals: Option<&[SearchArrival]>,
    format: Format,
    out: W,
) -> io::Result<()> {
    match rays {
        RaySet::Rays(rays) => write_all(
            scene,
            rays.len(),
            Layout::Rays,
            arrivals,
            format,
            out,
            |i| {
                let r = &rays[i];
                View {
                    source: r.source,
                    receiver: r.receiver,
                    path: r.path,
                    status: r.status,
                    time: r.status.has_time().then_some(r.time),
                    points: &r.points,
                    iterations: r.iterations,
                    residual: r.residual,
                    media: (!r.media.is_empty()).then(|| r.media.iter().copied()),
                    reason: r.reason,
                    every: None,
                    values: Source::Ray(r),
                }
            },
        ),
        RaySet::Batch(batch) => write_all(
            scene,
            batch.len(),
            Layout::Rays,
            arrivals,
            format,
            out,
            |i| {
                let r = batch.record(i);
                let RayTriple {
                    source,
                    receiver,
                    path,
                } = batch.triple(i);
                let has = r.status.has_time();
                View {
                    source,
                    receiver,
                    path,
                    status: r.status,
                    time: has.then_some(r.time),
                    points: batch.points(i),
                    iterations: r.iterations as usize,
                    residual: r.residual,
                    media: batch.media(i),
                    reason: r.reason,
                    every: None,
                    values: Source::Batch(batch, i),
                }
            },
        ),
        RaySet::Stationary(rays) => {
            let mut entries = Vec::with_capacity(rays.entries());
            entries.extend(rays.entries_in_order(scene));
            write_all(
                scene,
                entries.len(),
                Layout::Stationary,
                arrivals,
                format,
                out,
                |i| {
                    let e = &entries[i];
                    View {
                        source: e.source,
                        receiver: e.receiver,
                        path: e.path,
                        status: e.record.status,
                        time: e.record.status.has_time().then_some(e.record.time),
                        points: e.points,
                        iterations: e.record.iterations as usize,
                        residual: e.record.residual,
                        media: e.media.map(|m| m.iter().copied()),
                        reason: e.record.reason,
                        every: Some(EveryFields {
                            arrival: e.arrival,
                            kink: e.kink,
                            complete: e.complete,
                        }),
                        values: Source::Stationary(e),
                    }
                },
            )
        }
    }
}

/// The most steps of an arrival (at least the search's `max_steps`), which fixes the shape of
/// an arrivals `.npy` record.
fn arrival_steps(scene: &Scene, arrivals: &[SearchArrival]) -> usize {
    let most = arrivals.iter().map(|a| a.steps.len()).max().unwrap_or(0);
    most.max(scene.search().and_then(|s| s.max_steps).unwrap_or(0))
}

/// The `.npy` header of `n` arrival records of at most `k` steps (the context's), with the
/// fields of the quantities of `schema`.
fn arrivals_npy_header(n: usize, schema: &Schema, context: &Context<'_>) -> Vec<u8> {
    let k = context.steps;
    let mut descr = format!(
        "('source', '<u4'), ('receiver', '<u4'), ('steps', '<u4'), ('step_kind', '|u1', ({k},)), \
         ('step_interface', '<u4', ({k},)), ('status', '|u1'), ('kink', '|u1'), \
         ('complete', '|u1'), ('iterations', '<u4'), ('time', '<f8'), ('residual', '<f8'), \
         ('points', '<f8', ({}, {})), ('media', '<u4', ({},))",
        k + 2,
        if context.scene.extrusion().is_some() {
            3
        } else {
            2
        },
        k + 1
    );
    descr.push_str(&schema.npy_descr(context));
    npy_header_of(n, &descr)
}

/// What the quantities of a search arrival are read from, with its gradient `gradient`.
fn arrival_values<'a>(s: &SearchArrival, gradient: Option<&'a Gradient>) -> Entry<'a> {
    Entry {
        gradient,
        ..Entry::of_search(s)
    }
}

/// One search arrival as a JSON object (`"kind": "arrival"` first when `marked`).
fn arrival_json(
    buf: &mut Vec<u8>,
    schema: &Schema,
    context: &Context<'_>,
    s: &SearchArrival,
    marked: bool,
) {
    let (scene, names) = (context.scene, context.names);
    let a = &s.arrival;
    buf.extend_from_slice(if marked {
        b"{\"kind\":\"arrival\",\"source\":"
    } else {
        b"{\"source\":"
    });
    int(buf, s.source);
    buf.extend_from_slice(b",\"receiver\":");
    int(buf, s.receiver);
    buf.extend_from_slice(b",\"steps\":[");
    for (i, step) in s.steps.iter().enumerate() {
        if i > 0 {
            buf.push(b',');
        }
        buf.extend_from_slice(match step.kind {
            StepKind::Reflect => b"{\"reflect\":",
            StepKind::Refract => b"{\"refract\":",
            StepKind::Diffract { .. } => b"{\"diffract\":",
        });
        buf.extend_from_slice(
            names
                .interfaces
                .get(step.interface)
                .map_or(b"\"?\"", Vec::as_slice),
        );
        if let Some(v) = step.kind.vertex() {
            buf.extend_from_slice(b",\"vertex\":");
            int(buf, v);
        }
        buf.push(b'}');
    }
    buf.extend_from_slice(b"],\"media\":");
    media_json(buf, names, a.media.iter().copied());
    buf.extend_from_slice(b",\"status\":\"");
    buf.extend_from_slice(a.status.as_str().as_bytes());
    buf.push(b'"');
    if let Some(kink) = a.kink {
        buf.extend_from_slice(b",\"kink\":\"");
        buf.extend_from_slice(kink.as_str().as_bytes());
        buf.push(b'"');
    }
    buf.extend_from_slice(b",\"time\":");
    float(buf, a.time);
    buf.extend_from_slice(b",\"points\":");
    points_heights_json(buf, &a.points, &s.heights);
    let gradient = arrival_gradient(scene, s);
    schema.json(buf, context, &arrival_values(s, gradient.as_ref()));
    buf.extend_from_slice(b",\"iterations\":");
    int(buf, a.iterations);
    if a.residual.is_finite() {
        buf.extend_from_slice(b",\"residual\":");
        float(buf, a.residual);
    }
    if let Some(reason) = a.reason {
        buf.extend_from_slice(b",\"reason\":");
        buf.extend_from_slice(&json_string(&reason.describe(scene)));
    }
    buf.extend_from_slice(if s.complete {
        b",\"complete\":true}"
    } else {
        b",\"complete\":false}"
    });
}

/// The gradient of an arrival's time when the scene asks for derivatives.
fn arrival_gradient(scene: &Scene, s: &SearchArrival) -> Option<Gradient> {
    let a = &s.arrival;
    let derivatives = scene.solver().derivatives;
    if !derivatives {
        return None;
    }
    let mut g = Gradient::default();
    let media = a.media.iter().copied();
    g.fill_at(scene, &s.steps, &a.points, media, None, a.launch_angle)
        .ok()?;
    Some(g)
}

/// One search arrival as a CSV line.
fn arrival_csv(buf: &mut Vec<u8>, schema: &Schema, context: &Context<'_>, s: &SearchArrival) {
    let (scene, names) = (context.scene, context.names);
    let a = &s.arrival;
    int(buf, s.source);
    buf.push(b',');
    int(buf, s.receiver);
    buf.push(b',');
    let steps: Vec<String> = s
        .steps
        .iter()
        .map(|step| {
            let kind = step.kind.as_str();
            let name = scene.step_name(step.interface).unwrap_or("?");
            match step.kind.vertex() {
                Some(v) => format!("{kind}:{}@{v}", csv_list_item(name)),
                None => format!("{kind}:{}", csv_list_item(name)),
            }
        })
        .collect();
    csv_field(buf, &steps.join(";"));
    buf.push(b',');
    media_csv(buf, scene, names, a.media.iter().copied());
    buf.push(b',');
    buf.extend_from_slice(a.status.as_str().as_bytes());
    buf.push(b',');
    if let Some(kink) = a.kink {
        buf.extend_from_slice(kink.as_str().as_bytes());
    }
    buf.push(b',');
    float(buf, a.time);
    buf.push(b',');
    points_heights_csv(buf, &a.points, &s.heights);
    buf.push(b',');
    int(buf, a.iterations);
    buf.push(b',');
    if a.residual.is_finite() {
        float(buf, a.residual);
    }
    buf.push(b',');
    if let Some(reason) = a.reason {
        csv_field(buf, &reason.describe(scene));
    }
    buf.push(b',');
    buf.extend_from_slice(if s.complete { b"true" } else { b"false" });
    let gradient = arrival_gradient(scene, s);
    schema.csv(buf, context, &arrival_values(s, gradient.as_ref()));
    buf.push(b'\n');
}

/// One search arrival as a `.npy` record of at most `k` steps (the context's).
fn arrival_npy(buf: &mut Vec<u8>, schema: &Schema, context: &Context<'_>, s: &SearchArrival) {
    let (scene, k) = (context.scene, context.steps);
    let a = &s.arrival;
    u32_le(buf, s.source);
    u32_le(buf, s.receiver);
    u32_le(buf, s.steps.len());
    for j in 0..k {
        buf.push(s.steps.get(j).map_or(NO_STEP_KIND, |step| match step.kind {
            StepKind::Reflect => 0,
            StepKind::Refract => 1,
            StepKind::Diffract { .. } => 2,
        }));
    }
    for j in 0..k {
        let i = s.steps.get(j).map_or(NO_INTERFACE, |step| {
            u32::try_from(step.interface).unwrap_or(NO_INTERFACE)
        });
        buf.extend_from_slice(&i.to_le_bytes());
    }
    buf.push(status_code(a.status));
    buf.push(kink_code(a.kink));
    buf.push(u8::from(s.complete));
    u32_le(buf, a.iterations);
    buf.extend_from_slice(&a.time.to_le_bytes());
    buf.extend_from_slice(&a.residual.to_le_bytes());
    if scene.extrusion().is_some() {
        // [x, y, z] per point, padded with NaN rows.
        for i in 0..k + 2 {
            let (p, z) = match (a.points.get(i), s.heights.get(i)) {
                (Some(p), Some(&z)) => (*p, z),
                _ => (Point::new(f64::NAN, f64::NAN), f64::NAN),
            };
            for v in [p.x, p.y, z] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        points_media_npy(buf, &[], 0, Some(a.media.iter().copied()), k + 1);
    } else {
        points_media_npy(buf, &a.points, k + 2, Some(a.media.iter().copied()), k + 1);
    }
    let gradient = arrival_gradient(scene, s);
    schema.npy(buf, context, &arrival_values(s, gradient.as_ref()));
}

/// Bytes gathered before they are handed to the writer.
const CHUNK: usize = 1 << 16;

/// The arrivals' entries in `format` (no header, no document around them; in JSON separated
/// by commas, in JSON Lines one marked line each).
fn arrival_lines<W: Write>(
    scene: &Scene,
    names: &Names,
    schema: &Schema,
    arrivals: &[SearchArrival],
    format: Format,
    out: &mut W,
) -> io::Result<()> {
    let context = Context {
        scene,
        names,
        steps: arrival_steps(scene, arrivals),
    };
    let mut buf = Vec::with_capacity(CHUNK + 1024);
    for (i, a) in arrivals.iter().enumerate() {
        match format {
            Format::Json => {
                if i > 0 {
                    buf.push(b',');
                }
                arrival_json(&mut buf, schema, &context, a, false);
            }
            Format::Jsonl => {
                arrival_json(&mut buf, schema, &context, a, true);
                buf.push(b'\n');
            }
            Format::Csv => arrival_csv(&mut buf, schema, &context, a),
            Format::Npy => arrival_npy(&mut buf, schema, &context, a),
        }
        if buf.len() >= CHUNK {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    out.write_all(&buf)
}

/// The header line of the arrivals' CSV.
const ARRIVALS_CSV_HEADER: &[u8] =
    b"source,receiver,steps,media,status,kink,time,points,iterations,residual,reason,complete\n";

/// [`write()`]: a search's arrivals on their own.
fn write_arrivals<W: Write>(
    scene: &Scene,
    arrivals: &[SearchArrival],
    format: Format,
    mut out: W,
) -> io::Result<()> {
    let names = Names::new(scene);
    let schema = Schema::of(scene);
    match format {
        Format::Json => out.write_all(b"{\"arrivals\":[")?,
        Format::Jsonl => {}
        Format::Csv => csv_header(&mut out, ARRIVALS_CSV_HEADER, &schema)?,
        Format::Npy => {
            let context = Context {
                scene,
                names: &names,
                steps: arrival_steps(scene, arrivals),
            };
            out.write_all(&arrivals_npy_header(arrivals.len(), &schema, &context))?;
        }
    }
    arrival_lines(scene, &names, &schema, arrivals, format, &mut out)?;
    if format == Format::Json {
        out.write_all(b"]}\n")?;
    }
    out.flush()
}

/// Writes the name tables of `scene` as one JSON document: what the indices of the other
/// formats mean, for readers of [`Format::Npy`], which holds numbers only.
///
/// ```json
/// {"status": ["converged", "vertex", "no_path", "obstructed", "not_converged"],
///  "paths": ["transmitted", null], "media": ["air", "water"],
///  "interfaces": ["surface"], "no_medium": 4294967295}
/// ```
///
/// `status[code]` is the name of an `.npy` status code, `paths[path]` the name of a path
/// (`null` when it has none), `media[index]` the name of a medium index (the scene's media in
/// the order of their names, as [`Scene::media`] lists them) and `no_medium` the index
/// written for a leg whose medium is not known. `interfaces` lists the interface names in
/// the order of [`Scene::interfaces`]. A scene that asks for amplitudes adds
/// `amplitude_reasons`, the names of the `amplitude_reason` codes (`null` for 0, a value or
/// no time; see [`NoAmplitude::CODES`](crate::amplitude::NoAmplitude::CODES)), and
/// `amplitude_not_computed`, the code of a timed ray traced without them.
///
/// # Errors
/// Any error of the writer.
pub fn write_names<W: Write>(scene: &Scene, mut out: W) -> io::Result<()> {
    let mut doc = serde_json::json!({
        "status": STATUS_CODES.map(Status::as_str),
        "paths": scene.paths().iter().map(|p| p.name.as_deref()).collect::<Vec<_>>(),
        "media": scene.media().iter().map(|m| m.name.as_str()).collect::<Vec<_>>(),
        "interfaces": (0..scene.interfaces().len() + 2)
            .filter_map(|i| scene.step_name(i))
            .collect::<Vec<_>>(),
        "no_medium": NO_MEDIUM,
    });
    Schema::of(scene).names(&mut doc);
    serde_json::to_writer_pretty(&mut out, &doc)?;
    out.write_all(b"\n")?;
    out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BatchOptions, Tracer, demo};

    #[test]
    fn status_codes_are_their_places_in_the_table() {
        for (k, s) in STATUS_CODES.into_iter().enumerate() {
            assert_eq!(usize::from(status_code(s)), k, "{s}");
        }
    }

    #[test]
    fn floats_are_printed_as_serde_json_prints_them() {
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        let mut values = vec![
            0.0, -0.0, 1e-7, 1e21, 1e22, 1.5e300, 5e-324, 0.1, 1e15, 1e16,
        ];
        for _ in 0..10_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            values.push(f64::from_bits(x));
        }
        for v in values.into_iter().filter(|v| v.is_finite()) {
            let mut buf = Vec::new();
            float(&mut buf, v);
            let ours = String::from_utf8(buf).unwrap();
            assert_eq!(ours, serde_json::to_string(&v).unwrap(), "{v:e}");
            assert_eq!(ours.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{v:e}");
        }
    }

    #[test]
    fn a_batch_of_several_windows_is_written_in_ray_order() {
        // More than two windows, the last one and its last piece partial.
        let n = 2 * WINDOW + PIECE + 17;
        let scene = Scene::from_spec(&demo::air_water(n, 3)).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &crate::options::Run::new())
            .unwrap();
        let write = |format| {
            let mut out = Vec::new();
            write(&scene, &batch, format, &mut out).unwrap();
            String::from_utf8(out).unwrap()
        };
        let json = write(Format::Json);
        let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
        let rays = doc["rays"].as_array().unwrap();
        assert_eq!(rays.len(), n);
        for (i, ray) in rays.iter().enumerate() {
            let RayTriple {
                source: s,
                receiver: r,
                path: p,
            } = batch.triple(i);
            assert_eq!(ray["source"], s);
            assert_eq!(ray["receiver"], r);
            assert_eq!(ray["path"], p);
            assert_eq!(
                ray["time"].as_f64().unwrap(),
                batch.record(i).time,
                "ray {i}"
            );
        }
        // JSON Lines holds the same objects, one per line; CSV one line per ray.
        let jsonl = write(Format::Jsonl);
        let lines: Vec<&str> = jsonl.lines().collect();
        assert_eq!(lines.len(), n);
        assert_eq!(format!("{{\"rays\":[{}]}}\n", lines.join(",")), json);
        assert_eq!(write(Format::Csv).lines().count(), n + 1);
        // The owned rays give the same document.
        let mut owned = Vec::new();
        super::write(&scene, &batch.to_rays(), Format::Json, &mut owned).unwrap();
        assert_eq!(String::from_utf8(owned).unwrap(), json);
    }

    /// Ordinary scenes keep the full window; long names shrink it so that a window's text
    /// stays within its budget, whatever the names (each ray's real line measured here).
    #[test]
    fn the_window_fits_its_budget_of_bytes() {
        let ordinary = Scene::from_spec(&demo::air_water(10, 3)).unwrap();
        let full = Window {
            rays: WINDOW,
            piece: PIECE,
        };
        assert_eq!(Window::of(&ordinary, &Schema::of(&ordinary)), full);
        assert_eq!(Window::of(&ordinary, &Schema::every()), full);
        for len in [1 << 10, 32 << 10, 1 << 20] {
            let name = "\u{1}".repeat(len);
            let doc = serde_json::json!({
                "media": { &name: { "speed": 1.0 } },
                "interfaces": { &name: { "points": [[-1, 0], [1, 0]] } },
                "sources": [[0, 1]], "receivers": [[0.5, 1], [5, 1]],
                "paths": [{ "name": &name, "steps": [{ "reflect": &name }], "media": [&name, &name] }]
            });
            let scene = Scene::from_json(&doc.to_string()).unwrap();
            let window = Window::of(&scene, &Schema::of(&scene));
            assert!(window.rays < WINDOW && window.piece >= 1);
            let rays = Tracer::new(&scene).unwrap().trace_all();
            // One line per ray in JSON Lines and CSV (the JSON document holds the same
            // objects as JSON Lines).
            for format in [Format::Jsonl, Format::Csv] {
                let mut out = Vec::new();
                super::write(&scene, &rays, format, &mut out).unwrap();
                let per_ray = out.split(|&b| b == b'\n').map(<[u8]>::len).max().unwrap();
                assert!(
                    per_ray * window.rays <= WINDOW_BYTES,
                    "{len}: {per_ray} bytes a ray, {} rays a window",
                    window.rays
                );
            }
        }
    }

    #[test]
    fn npy_records_hold_the_batch() {
        // Reflection sequences of orders 0 to 2 (paths of 2 to 4 points) with every status a
        // room gives.
        let path = format!("{}/fixtures/bench/room2d.json", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &crate::options::Run::new())
            .unwrap();
        let mut out = Vec::new();
        write(&scene, &batch, Format::Npy, &mut out).unwrap();
        assert_eq!(&out[..8], b"\x93NUMPY\x01\x00");
        let len = u16::from_le_bytes([out[8], out[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
        let dict = std::str::from_utf8(&out[10..10 + len]).unwrap();
        assert!(dict.ends_with('\n'), "{dict:?}");
        let (p, l) = (4, 3);
        for part in [
            "('points', '<f8', (4, 2))".to_owned(),
            "('media', '<u4', (3,))".to_owned(),
            format!("'shape': ({},)", batch.len()),
        ] {
            assert!(dict.contains(&part), "{part} not in {dict}");
        }
        let size = 3 * 4 + 1 + 4 + 8 + 8 + 16 * p + 4 * l;
        let data = &out[10 + len..];
        assert_eq!(data.len(), batch.len() * size);
        let f64_at = |r: &[u8], at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap());
        let u32_at = |r: &[u8], at: usize| u32::from_le_bytes(r[at..at + 4].try_into().unwrap());
        let mut codes = std::collections::BTreeSet::new();
        for (i, r) in data.chunks(size).enumerate() {
            let rec = batch.record(i);
            let RayTriple {
                source: s,
                receiver: rc,
                path: pa,
            } = batch.triple(i);
            assert_eq!(
                [u32_at(r, 0), u32_at(r, 4), u32_at(r, 8)],
                [s, rc, pa].map(|v| v as u32)
            );
            // The published table (tests/output.rs checks the codes by hand).
            assert_eq!(STATUS_CODES[usize::from(r[12])], rec.status);
            codes.insert(r[12]);
            assert_eq!(u32_at(r, 13), rec.iterations);
            let (time, residual) = (f64_at(r, 17), f64_at(r, 25));
            assert_eq!(time.to_bits(), rec.time.to_bits(), "ray {i}");
            assert_eq!(residual.to_bits(), rec.residual.to_bits(), "ray {i}");
            let points = batch.points(i);
            for j in 0..p {
                let (x, y) = (f64_at(r, 33 + 16 * j), f64_at(r, 41 + 16 * j));
                match points.get(j) {
                    Some(q) if rec.status.has_time() => assert_eq!((x, y), (q.x, q.y)),
                    _ => assert!(x.is_nan() && y.is_nan(), "ray {i} point {j}"),
                }
            }
            let media: Vec<usize> = batch.media(i).map(|m| m.collect()).unwrap_or_default();
            for j in 0..l {
                let want = media.get(j).map_or(u32::MAX, |&m| m as u32);
                assert_eq!(u32_at(r, 33 + 16 * p + 4 * j), want, "ray {i} leg {j}");
            }
        }
        assert!(codes.len() >= 2, "statuses {codes:?}");
    }
}
