//! The `eigenray solve` output: a JSON document, JSON Lines, CSV and NumPy's `.npy`, and the
//! name tables that give the `.npy` file's indices their names.
//!
//! Written by hand with `zmij` (shortest round-trip floats, as `serde_json` prints them: it
//! uses `zmij` too) and `itoa`, straight from either owned [`Ray`]s or a flat [`Batch`], and
//! formatted in parallel (rayon) a window of rays at a time, so that writing a large batch
//! costs less than solving it.

use std::io::{self, Write};

use rayon::prelude::*;

use crate::batch::Batch;
use crate::geom::Point;
use crate::scene::Scene;
use crate::trace::{Ray, Reason, Status};

/// Output formats of `eigenray solve`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    /// One JSON document, `{"rays": [...]}`: one object per ray, in ray order (see
    /// [`write_rays_json`] for its fields).
    #[default]
    Json,
    /// One ray object per line (the same objects as in `Json`).
    Jsonl,
    /// A header line, then one line per ray:
    /// `source,receiver,path,status,time,iterations,residual,points,path_name,media,reason`,
    /// with the points as `x y;x y;…` and the leg media as names joined by `;`. Empty fields
    /// where the ray has no such value (`time` and `points` without a time, `residual` when
    /// not finite, `path_name` for an unnamed path, `media` when unknown, `reason` when
    /// converged). A field holding `,`, `"` or a line break is quoted as RFC 4180 says.
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
    /// records: the compact format for large batches.
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
/// `n` records of `shape`.
fn npy_header(n: usize, shape: NpyShape) -> Vec<u8> {
    let dict = format!(
        "{{'descr': [('source', '<u4'), ('receiver', '<u4'), ('path', '<u4'), \
         ('status', '|u1'), ('iterations', '<u4'), ('time', '<f8'), ('residual', '<f8'), \
         ('points', '<f8', ({}, 2)), ('media', '<u4', ({},))], \
         'fortran_order': False, 'shape': ({},), }}",
        shape.points(),
        shape.legs(),
        n
    );
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

fn ray_npy<M: Iterator<Item = usize>>(buf: &mut Vec<u8>, shape: NpyShape, r: View<'_, M>) {
    for v in [r.source, r.receiver, r.path] {
        buf.extend_from_slice(&(v as u32).to_le_bytes());
    }
    buf.push(status_code(r.status));
    buf.extend_from_slice(&(r.iterations.min(u32::MAX as usize) as u32).to_le_bytes());
    buf.extend_from_slice(&r.time.unwrap_or(f64::NAN).to_le_bytes());
    buf.extend_from_slice(&r.residual.to_le_bytes());
    let points = if r.time.is_some() { r.points } else { &[] };
    for i in 0..shape.points() {
        let p = points
            .get(i)
            .copied()
            .unwrap_or(Point::new(f64::NAN, f64::NAN));
        buf.extend_from_slice(&p.x.to_le_bytes());
        buf.extend_from_slice(&p.y.to_le_bytes());
    }
    let mut media = r.media;
    for _ in 0..shape.legs() {
        let m = media
            .as_mut()
            .and_then(|m| m.next())
            .map_or(NO_MEDIUM, |m| m as u32);
        buf.extend_from_slice(&m.to_le_bytes());
    }
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
}

/// The medium and path names as each format writes them, made once per document.
struct Names {
    /// Escaped JSON strings of the media.
    media: Vec<Vec<u8>>,
    /// Escaped JSON strings of the path names (`None` for an unnamed path).
    paths: Vec<Option<Vec<u8>>>,
    /// CSV fields of the path names (quoted where needed; empty for an unnamed path).
    paths_csv: Vec<Vec<u8>>,
    /// The medium names for CSV, when none needs quoting (else the field is quoted whole).
    media_csv: Option<Vec<Vec<u8>>>,
}

/// `s` as a JSON string.
fn json_string(s: &str) -> Vec<u8> {
    serde_json::to_vec(s).unwrap_or_else(|_| b"\"?\"".to_vec())
}

/// Appends `field` to a CSV line, quoted (RFC 4180) when it holds `,`, `"` or a line break.
fn csv_field(buf: &mut Vec<u8>, field: &str) {
    if field.contains([',', '"', '\n', '\r']) {
        buf.push(b'"');
        buf.extend_from_slice(field.replace('"', "\"\"").as_bytes());
        buf.push(b'"');
    } else {
        buf.extend_from_slice(field.as_bytes());
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
            .map(|m| (!m.name.contains([',', '"', '\n', '\r'])).then(|| m.name.as_bytes().to_vec()))
            .collect();
        Names {
            media,
            paths,
            paths_csv,
            media_csv,
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

fn ray_json<M: Iterator<Item = usize>>(
    buf: &mut Vec<u8>,
    scene: &Scene,
    names: &Names,
    r: View<'_, M>,
) {
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
    buf.extend_from_slice(b",\"status\":\"");
    buf.extend_from_slice(r.status.as_str().as_bytes());
    buf.push(b'"');
    if let Some(t) = r.time {
        buf.extend_from_slice(b",\"time\":");
        float(buf, t);
        buf.extend_from_slice(b",\"points\":[");
        for (i, p) in r.points.iter().enumerate() {
            if i > 0 {
                buf.push(b',');
            }
            buf.push(b'[');
            float(buf, p.x);
            buf.push(b',');
            float(buf, p.y);
            buf.push(b']');
        }
        buf.push(b']');
    }
    buf.extend_from_slice(b",\"iterations\":");
    int(buf, r.iterations);
    if r.residual.is_finite() {
        buf.extend_from_slice(b",\"residual\":");
        float(buf, r.residual);
    }
    if let Some(media) = r.media {
        buf.extend_from_slice(b",\"media\":[");
        for (i, m) in media.enumerate() {
            if i > 0 {
                buf.push(b',');
            }
            buf.extend_from_slice(&names.media[m]);
        }
        buf.push(b']');
    }
    if let Some(reason) = r.reason {
        buf.extend_from_slice(b",\"reason\":");
        buf.extend_from_slice(&json_string(&reason.describe(scene)));
    }
    buf.push(b'}');
}

fn ray_csv<M: Iterator<Item = usize>>(
    buf: &mut Vec<u8>,
    scene: &Scene,
    names: &Names,
    r: View<'_, M>,
) {
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
        for (i, p) in r.points.iter().enumerate() {
            if i > 0 {
                buf.push(b';');
            }
            float(buf, p.x);
            buf.push(b' ');
            float(buf, p.y);
        }
    }
    buf.push(b',');
    if let Some(name) = names.paths_csv.get(r.path) {
        buf.extend_from_slice(name);
    }
    buf.push(b',');
    if let Some(media) = r.media {
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
                    joined.push_str(scene.media().get(m).map_or("?", |m| m.name.as_str()));
                }
                csv_field(buf, &joined);
            }
        }
    }
    buf.push(b',');
    if let Some(reason) = r.reason {
        csv_field(buf, &reason.describe(scene));
    }
    buf.push(b'\n');
}

/// The header line of [`Format::Csv`].
const CSV_HEADER: &[u8] =
    b"source,receiver,path,status,time,iterations,residual,points,path_name,media,reason\n";

/// Rays formatted at a time (in [`PIECE`]s, in parallel) before they are written out in order.
const WINDOW: usize = 1 << 14;
/// Rays per parallel piece of a window.
const PIECE: usize = 1 << 10;

/// Writes `n` rays produced by `view` in `format`: a window of rays at a time, formatted in
/// parallel pieces (rayon) while the previous window is written, in order.
fn write_all<'a, W: Write, M: Iterator<Item = usize>>(
    scene: &Scene,
    n: usize,
    format: Format,
    mut out: W,
    view: impl Fn(usize) -> View<'a, M> + Sync,
) -> io::Result<()> {
    let names = Names::new(scene);
    let shape = NpyShape::of(scene);
    match format {
        Format::Npy => out.write_all(&npy_header(n, shape))?,
        Format::Json => out.write_all(b"{\"rays\":[")?,
        Format::Csv => out.write_all(CSV_HEADER)?,
        Format::Jsonl => {}
    }
    let format_piece = |buf: &mut Vec<u8>, rays: std::ops::Range<usize>| {
        buf.clear();
        for i in rays {
            match format {
                Format::Json => {
                    if i > 0 {
                        buf.push(b',');
                    }
                    ray_json(buf, scene, &names, view(i));
                }
                Format::Jsonl => {
                    ray_json(buf, scene, &names, view(i));
                    buf.push(b'\n');
                }
                Format::Csv => ray_csv(buf, scene, &names, view(i)),
                Format::Npy => ray_npy(buf, shape, view(i)),
            }
        }
    };
    // Formats window `w` into `pieces` (one buffer per piece, in order).
    let format_window = |pieces: &mut Vec<Vec<u8>>, w: usize| {
        let (start, end) = (w * WINDOW, n.min((w + 1) * WINDOW));
        let count = (end - start).div_ceil(PIECE);
        pieces.resize_with(count, Vec::new);
        pieces.par_iter_mut().enumerate().for_each(|(j, buf)| {
            let lo = start + j * PIECE;
            format_piece(buf, lo..end.min(lo + PIECE));
        });
    };
    // Double-buffered: this thread writes one window while the pool formats the next.
    let (mut ready, mut next) = (Vec::new(), Vec::new());
    let windows = n.div_ceil(WINDOW);
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
    if format == Format::Json {
        out.write_all(b"]}\n")?;
    }
    out.flush()
}

/// Writes the `{"rays": [...]}` document of `eigenray solve` for `rays` (compact, one line).
///
/// Each ray has `source`, `receiver` and `path` (indices), `path_name` (when the path has a
/// name), `status`, `time` and `points` (when it has a time), `iterations`, `residual` (when
/// finite), the leg `media` names (when known) and a `reason` when it is not converged.
///
/// # Errors
/// Any error of the writer.
pub fn write_rays_json<W: Write>(scene: &Scene, rays: &[Ray], out: W) -> io::Result<()> {
    write_rays(scene, rays, Format::Json, out)
}

/// Writes `rays` in `format`.
///
/// # Errors
/// Any error of the writer.
pub fn write_rays<W: Write>(scene: &Scene, rays: &[Ray], format: Format, out: W) -> io::Result<()> {
    write_all(scene, rays.len(), format, out, |i| {
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
        }
    })
}

/// Writes every ray of a batch in `format`, in ray order.
///
/// # Errors
/// Any error of the writer.
pub fn write_batch<W: Write>(
    scene: &Scene,
    batch: &Batch,
    format: Format,
    out: W,
) -> io::Result<()> {
    write_all(scene, batch.len(), format, out, |i| {
        let r = batch.record(i);
        let (source, receiver, path) = batch.triple(i);
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
        }
    })
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
/// the order of [`Scene::interfaces`].
///
/// # Errors
/// Any error of the writer.
pub fn write_names<W: Write>(scene: &Scene, mut out: W) -> io::Result<()> {
    let doc = serde_json::json!({
        "status": STATUS_CODES.map(Status::as_str),
        "paths": scene.paths().iter().map(|p| p.name.as_deref()).collect::<Vec<_>>(),
        "media": scene.media().iter().map(|m| m.name.as_str()).collect::<Vec<_>>(),
        "interfaces": scene.interfaces().iter().map(|i| i.name.as_str()).collect::<Vec<_>>(),
        "no_medium": NO_MEDIUM,
    });
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
            .trace_batch(&BatchOptions::default());
        let write = |format| {
            let mut out = Vec::new();
            write_batch(&scene, &batch, format, &mut out).unwrap();
            String::from_utf8(out).unwrap()
        };
        let json = write(Format::Json);
        let doc: serde_json::Value = serde_json::from_str(&json).unwrap();
        let rays = doc["rays"].as_array().unwrap();
        assert_eq!(rays.len(), n);
        for (i, ray) in rays.iter().enumerate() {
            let (s, r, p) = batch.triple(i);
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
        write_rays_json(&scene, &batch.to_rays(), &mut owned).unwrap();
        assert_eq!(String::from_utf8(owned).unwrap(), json);
    }

    #[test]
    fn npy_records_hold_the_batch() {
        // Reflection sequences of orders 0 to 2 (paths of 2 to 4 points) with every status a
        // room gives.
        let path = format!("{}/fixtures/bench/room2d.json", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default());
        let mut out = Vec::new();
        write_batch(&scene, &batch, Format::Npy, &mut out).unwrap();
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
            let (s, rc, pa) = batch.triple(i);
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
