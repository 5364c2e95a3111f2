//! The `eigenray solve` output document: `{"rays": [...]}` in ray order.

use std::io::{self, Write};

use serde::Serialize;
use serde::ser::{SerializeMap, SerializeSeq, Serializer};

use crate::scene::Scene;
use crate::trace::Ray;

/// The output document of `eigenray solve`: serializes as `{"rays": [...]}`, each ray with
/// `source`, `receiver`, `path`, `status`, `time` and `points` (when it has a time),
/// `iterations`, `residual`, the leg `media` names (when known) and a `reason` when it is not
/// converged.
pub struct RaysDocument<'a> {
    /// The scene the rays belong to (for medium names).
    pub scene: &'a Scene,
    /// The rays, in ray order.
    pub rays: &'a [Ray],
}

struct RayJson<'a> {
    scene: &'a Scene,
    ray: &'a Ray,
}

impl Serialize for RayJson<'_> {
    fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        let r = self.ray;
        let mut m = ser.serialize_map(None)?;
        m.serialize_entry("source", &r.source)?;
        m.serialize_entry("receiver", &r.receiver)?;
        m.serialize_entry("path", &r.path)?;
        m.serialize_entry("status", r.status.as_str())?;
        if let Some(t) = r.time {
            m.serialize_entry("time", &t)?;
            let pts: Vec<[f64; 2]> = r.points.iter().map(|p| [p.x, p.y]).collect();
            m.serialize_entry("points", &pts)?;
        }
        m.serialize_entry("iterations", &r.iterations)?;
        if r.residual.is_finite() {
            m.serialize_entry("residual", &r.residual)?;
        }
        if !r.media.is_empty() {
            let names: Vec<&str> = r.media.iter().map(|&i| self.scene.media()[i].name.as_str()).collect();
            m.serialize_entry("media", &names)?;
        }
        if let Some(reason) = &r.reason {
            m.serialize_entry("reason", &reason.to_string())?;
        }
        m.end()
    }
}

impl Serialize for RaysDocument<'_> {
    fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        struct Rays<'a>(&'a RaysDocument<'a>);
        impl Serialize for Rays<'_> {
            fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
                let mut seq = ser.serialize_seq(Some(self.0.rays.len()))?;
                for ray in self.0.rays {
                    seq.serialize_element(&RayJson { scene: self.0.scene, ray })?;
                }
                seq.end()
            }
        }
        let mut m = ser.serialize_map(Some(1))?;
        m.serialize_entry("rays", &Rays(self))?;
        m.end()
    }
}

/// Writes the `{"rays": [...]}` document for `rays` to `out` (compact JSON and a newline).
///
/// # Errors
/// Any error of the writer.
pub fn write_rays_json<W: Write>(scene: &Scene, rays: &[Ray], out: W) -> io::Result<()> {
    let mut out = io::BufWriter::with_capacity(1 << 16, out);
    serde_json::to_writer(&mut out, &RaysDocument { scene, rays }).map_err(io::Error::other)?;
    out.write_all(b"\n")?;
    out.flush()
}
