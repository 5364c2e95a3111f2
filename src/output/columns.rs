//! The column schema of the quantities that follow a ray's or an arrival's own fields (its
//! time's gradient, its amplitude): each quantity says once when a scene asks for it, its
//! columns (name and type), and what they hold for an entry. The writers of [`super`]
//! (JSON, JSON Lines, CSV, `.npy` and the names sidecar) and the Python package (its arrays,
//! its batch sink, its dicts and its pickles) iterate over the [`Schema`]: a new per-ray
//! quantity is one `Quantity` here, one field of [`Entry`], and the code that computes it.
//!
//! A quantity of plain columns ([`ColumnType`]: one number, one complex number, or why it
//! has no value) needs only `Quantity::columns` and `Quantity::cells`: its JSON fields,
//! CSV cells, `.npy` fields and numpy columns follow from them. A quantity of another shape
//! (the gradient: one number per medium, a list of vertices) writes each format itself.

mod caustics;
mod launch_angle;
mod turns;

use std::io;

use num_complex::Complex64;

use super::{AMPLITUDE_NOT_COMPUTED, Names, csv_field, float, json_string};
use crate::amplitude::{Amplitude, NoAmplitude};
use crate::batch::Batch;
use crate::derivatives::Gradient;
use crate::geom::Point;
use crate::scene::{Scene, Step};
use crate::search::SearchArrival;
use crate::stationary::StationaryEntry;
use crate::trace::{Arrival, Ray, RayRecord, Status, Tracer, Workspace};

/// How a column holds one entry's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColumnType {
    /// A number (`<f8` in `.npy`, `float64` in numpy; `null` in JSON and empty in CSV when
    /// not finite).
    Float,
    /// A complex number (`<f8` of shape `(2,)` in `.npy`, `complex128` in numpy; `[re, im]`
    /// in JSON and `re im` in CSV, `null` and empty when a part is not finite).
    Complex,
    /// Why the quantity has no value (a [`Why`]): in JSON and CSV its words where it has
    /// none, in `.npy` a `u1` code (0: a value, or no time; else
    /// [`NoAmplitude::code`], or [`AMPLITUDE_NOT_COMPUTED`]), in Python a list of words.
    Why,
}

/// One column of a quantity: its name (the JSON key, the CSV column, the `.npy` field, the
/// numpy array's attribute and its pickled key) and its type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// Its name.
    pub name: &'static str,
    /// How it holds a value.
    pub ty: ColumnType,
}

/// Why an entry's quantity has no value, as a [`ColumnType::Why`] column holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Why {
    /// It has a value, or the entry has no time (nothing is written).
    Value,
    /// The entry has a time but the quantity was not computed (rays traced without it).
    NotComputed,
    /// No value, for this reason.
    Because(NoAmplitude),
}

impl Why {
    /// Its `.npy` code.
    fn code(self) -> u8 {
        match self {
            Why::Value => 0,
            Why::NotComputed => AMPLITUDE_NOT_COMPUTED,
            Why::Because(r) => r.code(),
        }
    }

    /// Its words (`None` with a value).
    fn words(self) -> Option<String> {
        match self {
            Why::Value => None,
            Why::NotComputed => Some(NOT_COMPUTED_TEXT.to_string()),
            Why::Because(r) => Some(r.to_string()),
        }
    }

    /// The reason, when there is one (`NotComputed` has none of the library's).
    pub fn reason(self) -> Option<NoAmplitude> {
        match self {
            Why::Because(r) => Some(r),
            Why::Value | Why::NotComputed => None,
        }
    }
}

/// The reason of a timed entry whose quantity was not computed, in JSON and CSV.
const NOT_COMPUTED_TEXT: &str = "not computed (the ray was traced without amplitudes)";

/// One entry of a column.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell {
    /// Of a [`ColumnType::Float`] column.
    Float(f64),
    /// Of a [`ColumnType::Complex`] column.
    Complex(Complex64),
    /// Of a [`ColumnType::Why`] column.
    Why(Why),
}

/// What the quantities of one entry (a ray, a stationary path, a search arrival) are read
/// from: each quantity's value where it was computed. Made by its constructors from each
/// kind of result (and by [`Entry::computed`] and [`Entry::solved`] for a ray just solved),
/// the one place that reads a quantity off the results.
#[derive(Clone, Copy, Debug, Default)]
pub struct Entry<'a> {
    /// Whether the entry has a time (a quantity is written only for timed entries in JSON,
    /// and its CSV cells are empty without).
    pub timed: bool,
    /// Its amplitude, when computed.
    pub amplitude: Option<Amplitude>,
    /// Its time's gradient, when computed (the writer computes it; the Python package has
    /// `Tracer.gradients` for it).
    pub gradient: Option<&'a Gradient>,
    /// The number of turning points on its legs, where known (a ray through a `profile`
    /// medium).
    pub turns: Option<u32>,
    /// The number of caustics its ray tube passed, where known (a ray through a `profile`
    /// or `gradient` medium).
    pub caustics: Option<u32>,
    /// Its direction at the source (radians from +x), where the path alone does not give
    /// it (a ray through a `profile` medium).
    pub launch_angle: Option<f64>,
}

impl Entry<'static> {
    /// The quantities of a ray.
    pub fn of_ray(ray: &Ray) -> Self {
        Entry {
            timed: ray.status.has_time(),
            amplitude: ray.amplitude,
            ..Entry::default()
        }
    }

    /// The quantities of ray `i` of a batch.
    pub fn of_batch(batch: &Batch, i: usize) -> Self {
        Entry {
            timed: batch.record(i).status.has_time(),
            amplitude: batch.amplitude(i).copied(),
            ..Entry::default()
        }
    }

    /// The quantities of a stationary path.
    pub fn of_arrival(arrival: &Arrival) -> Self {
        Entry {
            timed: arrival.status.has_time(),
            amplitude: arrival.amplitude,
            turns: arrival.turns,
            caustics: arrival.caustics,
            launch_angle: arrival.launch_angle,
            ..Entry::default()
        }
    }

    /// The quantities of an entry of every stationary path (a stationary path, or a triple
    /// without one).
    pub fn of_stationary(entry: &StationaryEntry<'_>) -> Self {
        Entry {
            timed: entry.record.status.has_time(),
            amplitude: entry.amplitude.copied(),
            turns: entry.turns,
            caustics: entry.caustics,
            launch_angle: entry.launch_angle,
            ..Entry::default()
        }
    }

    /// The quantities of a search arrival (every one has a time).
    pub fn of_search(arrival: &SearchArrival) -> Self {
        Entry {
            timed: true,
            amplitude: arrival.arrival.amplitude,
            turns: arrival.arrival.turns,
            caustics: arrival.arrival.caustics,
            launch_angle: arrival.arrival.launch_angle,
            ..Entry::default()
        }
    }

    /// The quantities `tracer`'s scene asks for of a ray of `steps` that ended with
    /// `status` at `points` through the leg media `media` (`&[]` where unknown), computed
    /// from them: what a batch's sink writes beside each ray.
    #[inline]
    pub fn computed(
        tracer: &Tracer,
        steps: &[Step],
        status: Status,
        points: &[Point],
        media: &[usize],
    ) -> Self {
        let shape = Self::shape(tracer.scene(), steps, status.has_time(), points, media);
        Entry {
            timed: status.has_time(),
            amplitude: tracer.amplitude_of(steps, status, points, media),
            turns: shape.map(|s| s.turns),
            caustics: shape
                .map(|s| s.caustics)
                .or_else(|| tracer.gradient_caustics(steps, status, points, media, None)),
            launch_angle: shape.map(|s| s.launch_angle),
            ..Entry::default()
        }
    }

    /// The quantities `tracer`'s scene asks for of the ray of path `path` last solved in
    /// `ws`, which ended as `record`.
    pub fn solved(tracer: &Tracer, path: usize, record: &RayRecord, ws: &Workspace) -> Self {
        let steps = tracer
            .scene()
            .paths()
            .get(path)
            .map_or(&[][..], |p| &p.steps[..]);
        let shape = Self::shape(
            tracer.scene(),
            steps,
            record.status.has_time(),
            ws.points(),
            ws.media(),
        );
        Entry {
            timed: record.status.has_time(),
            amplitude: tracer.amplitude(path, record, ws),
            turns: shape.map(|s| s.turns),
            caustics: shape.map(|s| s.caustics).or_else(|| {
                let steps = tracer.scene().paths().get(path).map(|p| &p.steps[..])?;
                let segments = Some(&ws.newton.seg[..steps.len()]);
                tracer.gradient_caustics(steps, record.status, ws.points(), ws.media(), segments)
            }),
            launch_angle: shape.map(|s| s.launch_angle),
            ..Entry::default()
        }
    }

    /// The turns and caustics of a default-mode ray with a time through a `profile`
    /// medium (`None` for any other).
    pub(crate) fn shape(
        scene: &Scene,
        steps: &[Step],
        timed: bool,
        points: &[Point],
        media: &[usize],
    ) -> Option<crate::trace::ProfileShape> {
        if !(timed && scene.curved() && points.len() >= 2) {
            return None;
        }
        crate::trace::sloped_shape(scene, steps, points, media)
            .or_else(|| crate::trace::profile_shape(scene, points, media))
    }
}

/// What a writer knows besides the entry: the scene, its names, the most steps of a record.
pub(super) struct Context<'a> {
    /// The scene.
    pub(super) scene: &'a Scene,
    /// Its names as each format writes them.
    pub(super) names: &'a Names,
    /// The most steps of an entry: fixes the shape of a `.npy` record.
    pub(super) steps: usize,
}

/// A per-ray and per-arrival quantity: when a scene asks for it, its columns and their
/// values. The writers' methods follow from [`columns`](Self::columns) and
/// [`cells`](Self::cells) unless a quantity writes a format itself.
pub(super) trait Quantity: Sync {
    /// Whether `scene` asks for it.
    fn asked(&self, scene: &Scene) -> bool;

    /// Its plain columns, in their written order (none for a quantity that writes each
    /// format itself).
    fn columns(&self) -> &'static [Column];

    /// The values of its columns for `entry`, handed to `each` in the columns' order.
    fn cells(&self, entry: &Entry<'_>, each: &mut dyn FnMut(Cell));

    /// Its JSON fields, each after a comma (written for timed entries only).
    fn json(&self, buf: &mut Vec<u8>, _context: &Context<'_>, entry: &Entry<'_>) {
        let mut columns = self.columns().iter();
        self.cells(entry, &mut |cell| {
            let Some(column) = columns.next() else {
                return;
            };
            let key = |buf: &mut Vec<u8>| {
                buf.extend_from_slice(b",\"");
                buf.extend_from_slice(column.name.as_bytes());
                buf.extend_from_slice(b"\":");
            };
            match cell {
                Cell::Float(v) => {
                    key(buf);
                    float(buf, v);
                }
                Cell::Complex(c) => {
                    key(buf);
                    if c.re.is_finite() && c.im.is_finite() {
                        buf.push(b'[');
                        float(buf, c.re);
                        buf.push(b',');
                        float(buf, c.im);
                        buf.push(b']');
                    } else {
                        buf.extend_from_slice(b"null");
                    }
                }
                Cell::Why(why) => {
                    if let Some(words) = why.words() {
                        key(buf);
                        buf.extend_from_slice(&json_string(&words));
                    }
                }
            }
        });
    }

    /// Its CSV column names.
    fn csv_header(&self) -> Vec<&'static str> {
        self.columns().iter().map(|c| c.name).collect()
    }

    /// Its CSV cells, each after a comma (all empty for an entry without a time).
    fn csv(&self, buf: &mut Vec<u8>, _context: &Context<'_>, entry: &Entry<'_>) {
        if !entry.timed {
            buf.extend(std::iter::repeat_n(b',', self.columns().len()));
            return;
        }
        self.cells(entry, &mut |cell| {
            buf.push(b',');
            match cell {
                Cell::Float(v) => {
                    if v.is_finite() {
                        float(buf, v);
                    }
                }
                Cell::Complex(c) => {
                    if c.re.is_finite() && c.im.is_finite() {
                        float(buf, c.re);
                        buf.push(b' ');
                        float(buf, c.im);
                    }
                }
                Cell::Why(why) => {
                    if let Some(words) = why.words() {
                        csv_field(buf, &words);
                    }
                }
            }
        });
    }

    /// Its `.npy` fields, each after a comma and a space.
    fn npy_descr(&self, _context: &Context<'_>) -> String {
        let mut descr = String::new();
        for c in self.columns() {
            let ty = match c.ty {
                ColumnType::Float => "'<f8'",
                ColumnType::Complex => "'<f8', (2,)",
                ColumnType::Why => "'|u1'",
            };
            descr.push_str(&format!(", ('{}', {ty})", c.name));
        }
        descr
    }

    /// Its `.npy` fields of one record.
    fn npy(&self, buf: &mut Vec<u8>, _context: &Context<'_>, entry: &Entry<'_>) {
        self.cells(entry, &mut |cell| match cell {
            Cell::Float(v) => buf.extend_from_slice(&v.to_le_bytes()),
            Cell::Complex(c) => {
                buf.extend_from_slice(&c.re.to_le_bytes());
                buf.extend_from_slice(&c.im.to_le_bytes());
            }
            Cell::Why(why) => buf.push(why.code()),
        });
    }

    /// Its tables in the `.npy` names sidecar: for each [`ColumnType::Why`] column `NAME`,
    /// `NAMEs` (the words of each code: `null` for 0) and `QUANTITY_not_computed`.
    fn names(&self, doc: &mut serde_json::Value) {
        for c in self.columns().iter().filter(|c| c.ty == ColumnType::Why) {
            let reasons: Vec<Option<&str>> = std::iter::once(None)
                .chain(NoAmplitude::CODES.iter().map(|r| Some(r.name())))
                .collect();
            doc[format!("{}s", c.name)] = serde_json::json!(reasons);
            let quantity = c.name.strip_suffix("_reason").unwrap_or(c.name);
            doc[format!("{quantity}_not_computed")] = serde_json::json!(AMPLITUDE_NOT_COMPUTED);
        }
    }

    /// A bound on its text in one entry, bytes (for the writer's window).
    fn text_bytes(&self, _scene: &Scene) -> usize {
        0
    }
}

/// Every quantity, in the order in which they follow an entry's own fields.
static QUANTITIES: [&dyn Quantity; 5] = [
    &GradientQuantity,
    &AmplitudeQuantity,
    &turns::TurnsQuantity,
    &caustics::CausticsQuantity,
    &launch_angle::LaunchAngleQuantity,
];

/// The quantities a scene asks for, in their written order.
#[derive(Clone)]
pub struct Schema {
    /// The quantities.
    quantities: Vec<&'static dyn Quantity>,
}

impl std::fmt::Debug for Schema {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.quantities.iter().map(|q| q.columns()))
            .finish()
    }
}

impl Schema {
    /// The quantities `scene` asks for.
    pub fn of(scene: &Scene) -> Schema {
        Schema {
            quantities: QUANTITIES
                .iter()
                .copied()
                .filter(|q| q.asked(scene))
                .collect(),
        }
    }

    /// Every quantity, asked or not.
    pub fn every() -> Schema {
        Schema {
            quantities: QUANTITIES.to_vec(),
        }
    }

    /// Whether it holds no quantity.
    pub fn is_empty(&self) -> bool {
        self.quantities.is_empty()
    }

    /// The plain columns of each quantity (a group each; empty for a quantity that writes
    /// each format itself).
    pub fn groups(&self) -> impl Iterator<Item = &'static [Column]> + '_ {
        self.quantities.iter().map(|q| q.columns())
    }

    /// Every plain column, in order.
    pub fn columns(&self) -> impl Iterator<Item = &'static Column> + '_ {
        self.groups().flatten()
    }

    /// The values of every plain column for `entry`, handed to `each` in the order of
    /// [`columns`](Self::columns).
    pub fn cells(&self, entry: &Entry<'_>, mut each: impl FnMut(Cell)) {
        for q in &self.quantities {
            q.cells(entry, &mut each);
        }
    }

    /// Every quantity's JSON fields (for a timed entry).
    pub(super) fn json(&self, buf: &mut Vec<u8>, context: &Context<'_>, entry: &Entry<'_>) {
        if entry.timed {
            for q in &self.quantities {
                q.json(buf, context, entry);
            }
        }
    }

    /// Every quantity's CSV cells.
    pub(super) fn csv(&self, buf: &mut Vec<u8>, context: &Context<'_>, entry: &Entry<'_>) {
        for q in &self.quantities {
            q.csv(buf, context, entry);
        }
    }

    /// Every quantity's `.npy` fields of one record.
    pub(super) fn npy(&self, buf: &mut Vec<u8>, context: &Context<'_>, entry: &Entry<'_>) {
        for q in &self.quantities {
            q.npy(buf, context, entry);
        }
    }

    /// Every quantity's `.npy` field descriptions, each after a comma.
    pub(super) fn npy_descr(&self, context: &Context<'_>) -> String {
        self.quantities
            .iter()
            .map(|q| q.npy_descr(context))
            .collect()
    }

    /// Every quantity's CSV columns, each after a comma.
    pub(super) fn csv_header(&self, out: &mut impl io::Write) -> io::Result<()> {
        for q in &self.quantities {
            for name in q.csv_header() {
                out.write_all(b",")?;
                out.write_all(name.as_bytes())?;
            }
        }
        Ok(())
    }

    /// Every quantity's tables in the names sidecar.
    pub(super) fn names(&self, doc: &mut serde_json::Value) {
        for q in &self.quantities {
            q.names(doc);
        }
    }

    /// A bound on the quantities' text in one entry, bytes.
    pub(super) fn text_bytes(&self, scene: &Scene) -> usize {
        self.quantities.iter().map(|q| q.text_bytes(scene)).sum()
    }
}

/// The amplitude (`"amplitudes"`): `amplitude` and `coefficient` (complex), `spreading` and
/// `attenuation_db`, and `amplitude_reason` (see [`Amplitude`]).
struct AmplitudeQuantity;

impl Quantity for AmplitudeQuantity {
    fn asked(&self, scene: &Scene) -> bool {
        scene.amplitudes().is_some()
    }

    fn columns(&self) -> &'static [Column] {
        &[
            Column {
                name: "amplitude",
                ty: ColumnType::Complex,
            },
            Column {
                name: "spreading",
                ty: ColumnType::Float,
            },
            Column {
                name: "coefficient",
                ty: ColumnType::Complex,
            },
            Column {
                name: "attenuation_db",
                ty: ColumnType::Float,
            },
            Column {
                name: "amplitude_reason",
                ty: ColumnType::Why,
            },
        ]
    }

    fn cells(&self, entry: &Entry<'_>, each: &mut dyn FnMut(Cell)) {
        let (a, why) = match entry.amplitude {
            Some(a) => (a, a.reason.map_or(Why::Value, Why::Because)),
            None => (
                Amplitude::none(NoAmplitude::UnknownMedia),
                if entry.timed {
                    Why::NotComputed
                } else {
                    Why::Value
                },
            ),
        };
        each(Cell::Complex(a.value));
        each(Cell::Float(a.spreading));
        each(Cell::Complex(a.coefficient));
        each(Cell::Float(a.attenuation_db));
        each(Cell::Why(why));
    }
}

/// The gradient of the time (`"derivatives": true`): source, receiver, slowness per medium
/// and every touched vertex; of varying shape, so it writes each format itself.
struct GradientQuantity;

impl Quantity for GradientQuantity {
    fn asked(&self, scene: &Scene) -> bool {
        scene.solver().derivatives
    }

    fn columns(&self) -> &'static [Column] {
        &[]
    }

    fn cells(&self, _entry: &Entry<'_>, _each: &mut dyn FnMut(Cell)) {}

    /// `,"gradient":{"source":[…],"receiver":[…],"slowness":{"air":…},"vertices":
    /// [{"interface":"surface","vertex":3,"d":[…]}]}`.
    fn json(&self, buf: &mut Vec<u8>, context: &Context<'_>, entry: &Entry<'_>) {
        if let Some(g) = entry.gradient {
            super::gradient_json(buf, context.names, g);
        }
    }

    fn csv_header(&self) -> Vec<&'static str> {
        vec![
            "gradient_source",
            "gradient_receiver",
            "gradient_slowness",
            "gradient_vertices",
        ]
    }

    fn csv(&self, buf: &mut Vec<u8>, _context: &Context<'_>, entry: &Entry<'_>) {
        super::gradient_csv(buf, entry.gradient);
    }

    fn npy_descr(&self, context: &Context<'_>) -> String {
        super::gradient_npy_descr(context.scene.media().len(), 2 * context.steps)
    }

    fn npy(&self, buf: &mut Vec<u8>, context: &Context<'_>, entry: &Entry<'_>) {
        let media = context.scene.media().len();
        super::gradient_npy(buf, media, 2 * context.steps, entry.gradient);
    }

    fn text_bytes(&self, scene: &Scene) -> usize {
        let steps = scene.paths().iter().map(|p| p.steps.len()).max();
        32 * scene.media().len() + 96 * 2 * steps.unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries of every kind a quantity meets: without a time, timed without a computed
    /// value, with a value, and with a reason.
    fn entries() -> Vec<Entry<'static>> {
        let value = Amplitude {
            value: Complex64::new(0.25, -0.5),
            spreading: 0.5,
            coefficient: Complex64::new(0.5, -1.0),
            attenuation_db: 0.0,
            reason: None,
        };
        let none = Amplitude::none(NoAmplitude::Caustic);
        let mut out = Vec::new();
        for timed in [false, true] {
            for amplitude in [None, Some(value), Some(none)] {
                out.push(Entry {
                    timed,
                    amplitude,
                    gradient: None,
                    turns: timed.then_some(2),
                    caustics: None,
                    launch_angle: None,
                });
            }
        }
        out
    }

    #[test]
    fn every_quantity_gives_one_cell_of_its_type_per_column() {
        for q in QUANTITIES {
            for entry in entries() {
                let mut types = Vec::new();
                q.cells(&entry, &mut |cell| {
                    types.push(match cell {
                        Cell::Float(_) => ColumnType::Float,
                        Cell::Complex(_) => ColumnType::Complex,
                        Cell::Why(_) => ColumnType::Why,
                    });
                });
                let want: Vec<ColumnType> = q.columns().iter().map(|c| c.ty).collect();
                assert_eq!(types, want, "{:?}", q.columns());
            }
        }
    }

    #[test]
    fn column_names_are_unique_and_not_an_entrys_own_fields() {
        let own = [
            "source",
            "receiver",
            "path",
            "path_name",
            "status",
            "time",
            "points",
            "media",
            "iterations",
            "residual",
            "reason",
            "arrival",
            "kink",
            "complete",
            "steps",
        ];
        // (A quantity's CSV columns are its plain columns, or its own.)
        let mut names: Vec<&str> = QUANTITIES.iter().flat_map(|q| q.csv_header()).collect();
        let n = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), n, "{names:?}");
        assert!(names.iter().all(|n| !own.contains(n)), "{names:?}");
    }

    #[test]
    fn plain_columns_write_each_format_from_their_cells() {
        // The amplitude's fields, written by hand from the same numbers.
        let q = AmplitudeQuantity;
        let scene = Scene::from_spec(&crate::demo::air_water(2, 2)).unwrap();
        let names = Names::new(&scene);
        let context = Context {
            scene: &scene,
            names: &names,
            steps: 1,
        };
        let [_, _, _, _, value, none] = entries()[..] else {
            panic!("six entries")
        };
        let mut json = Vec::new();
        q.json(&mut json, &context, &value);
        assert_eq!(
            String::from_utf8(json).unwrap(),
            ",\"amplitude\":[0.25,-0.5],\"spreading\":0.5,\"coefficient\":[0.5,-1.0],\
             \"attenuation_db\":0.0"
        );
        let mut csv = Vec::new();
        q.csv(&mut csv, &context, &none);
        let mut want = b",,,,,".to_vec();
        csv_field(&mut want, &NoAmplitude::Caustic.to_string());
        assert_eq!(csv, want);
        let mut npy = Vec::new();
        q.npy(&mut npy, &context, &value);
        let mut want = Vec::new();
        for v in [0.25, -0.5, 0.5, 0.5, -1.0, 0.0] {
            want.extend_from_slice(&f64::to_le_bytes(v));
        }
        want.push(0);
        assert_eq!(npy, want);
        assert_eq!(
            q.npy_descr(&context),
            ", ('amplitude', '<f8', (2,)), ('spreading', '<f8'), ('coefficient', '<f8', (2,)), \
             ('attenuation_db', '<f8'), ('amplitude_reason', '|u1')"
        );
        // A timed entry without a computed amplitude: its code and words.
        let [_, _, _, not_computed, _, _] = entries()[..] else {
            panic!("six entries")
        };
        let mut npy = Vec::new();
        q.npy(&mut npy, &context, &not_computed);
        assert_eq!(npy.last(), Some(&AMPLITUDE_NOT_COMPUTED));
        let mut csv = Vec::new();
        q.csv(&mut csv, &context, &not_computed);
        assert!(String::from_utf8(csv).unwrap().ends_with(NOT_COMPUTED_TEXT));
    }
}
