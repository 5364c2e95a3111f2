//! The `eigenray solve` output: the contract's JSON document, JSON Lines and CSV.
//!
//! Written by hand with `ryu` (shortest round-trip floats, as `serde_json` prints them) and
//! `itoa`, straight from either owned [`Ray`]s or a flat [`Batch`], so that writing a large
//! batch costs about as much as solving it.

use std::io::{self, Write};

use crate::batch::Batch;
use crate::geom::Point;
use crate::scene::Scene;
use crate::trace::{Ray, Reason, Status};

/// Output formats of `eigenray solve`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Format {
    /// The contract's document: `{"rays": [...]}`.
    #[default]
    Json,
    /// One ray object per line (the same objects as in `Json`).
    Jsonl,
    /// A header line, then one line per ray:
    /// `source,receiver,path,status,time,iterations,residual,points` with the points as
    /// `x y;x y;…` (empty `time` and `points` for rays without a time).
    Csv,
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

/// Escaped JSON strings of the medium and interface names, made once per document.
struct Names {
    media: Vec<Vec<u8>>,
}

impl Names {
    fn new(scene: &Scene) -> Names {
        let media = scene
            .media()
            .iter()
            .map(|m| serde_json::to_vec(&m.name).unwrap_or_else(|_| b"\"?\"".to_vec()))
            .collect();
        Names { media }
    }
}

fn float(buf: &mut Vec<u8>, v: f64) {
    if v.is_finite() {
        buf.extend_from_slice(ryu::Buffer::new().format_finite(v).as_bytes());
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
        let text = reason.describe(scene);
        buf.extend_from_slice(&serde_json::to_vec(&text).unwrap_or_else(|_| b"\"?\"".to_vec()));
    }
    buf.push(b'}');
}

fn ray_csv<M: Iterator<Item = usize>>(buf: &mut Vec<u8>, r: View<'_, M>) {
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
    buf.push(b'\n');
}

/// Writes `n` rays produced by `view` in `format`, flushing the buffer every 64 KiB.
fn write_all<'a, W: Write, M: Iterator<Item = usize>>(
    scene: &Scene,
    n: usize,
    format: Format,
    mut out: W,
    view: impl Fn(usize) -> View<'a, M>,
) -> io::Result<()> {
    let names = Names::new(scene);
    let mut buf = Vec::with_capacity(1 << 17);
    match format {
        Format::Json => buf.extend_from_slice(b"{\"rays\":["),
        Format::Csv => {
            buf.extend_from_slice(b"source,receiver,path,status,time,iterations,residual,points\n")
        }
        Format::Jsonl => {}
    }
    for i in 0..n {
        match format {
            Format::Json => {
                if i > 0 {
                    buf.push(b',');
                }
                ray_json(&mut buf, scene, &names, view(i));
            }
            Format::Jsonl => {
                ray_json(&mut buf, scene, &names, view(i));
                buf.push(b'\n');
            }
            Format::Csv => ray_csv(&mut buf, view(i)),
        }
        if buf.len() >= 1 << 16 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
    if format == Format::Json {
        buf.extend_from_slice(b"]}\n");
    }
    out.write_all(&buf)?;
    out.flush()
}

/// Writes the contract's `{"rays": [...]}` document for `rays` (compact, one line).
///
/// Each ray has `source`, `receiver`, `path`, `status`, `time` and `points` (when it has a
/// time), `iterations`, `residual` (when finite), the leg `media` names (when known) and a
/// `reason` when it is not converged.
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
            time: r.time,
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
