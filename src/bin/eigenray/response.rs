//! The response outputs of `eigenray solve`: `--ir FILE` (the scene's impulse responses, as
//! `.npy` or `.wav`), `--tl FILE.npy` (the transmission loss), and the charts of
//! `--echogram` and `--tl-map`. Each echo goes into every output asked for the moment it is
//! found ([`Sums`]): the search's arrivals are not listed unless written.

use std::fs;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use eigenray::Scene;
use eigenray::amplitude::Complex64;
use eigenray::output::write_f64_array;
use eigenray::response::{
    Echo, ImpulseResponses, RoomParameters, incoherent_loss, room_parameters, transmission_loss,
};
use eigenray::scene::TransmissionLossMode;
use eigenray::search::{ArrivalSink, StreamedArrival};

use super::phase::{unit_phase, unit_phases};
use super::{Failure, available_memory, write_failure};

/// The file formats of `--ir`, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum IrFormat {
    /// NumPy's `.npy`: float64 `[sources, receivers, samples]`.
    Npy,
    /// WAV: 32-bit float samples, one channel per (source, receiver), source-major.
    Wav,
}

/// Where and how the impulse responses go: checked before anything is solved.
pub(super) struct IrOutput {
    path: PathBuf,
    format: IrFormat,
    responses: ImpulseResponses,
}

/// Most channels a WAV file holds.
const WAV_CHANNELS: usize = u16::MAX as usize;

impl IrOutput {
    /// The output of `--ir path` for `scene`: refused (naming `--ir` or the scene's key) for
    /// a scene without `impulse_response`, a file that is neither `.npy` nor `.wav`, a WAV
    /// that cannot hold the responses, or responses beyond the available memory.
    pub(super) fn check(path: &Path, scene: &Scene) -> Result<IrOutput, Failure> {
        let Some(options) = scene.impulse_response() else {
            return Err(Failure::Input(
                "--ir: the scene has no `impulse_response` section (add \"impulse_response\": \
                 {\"rate\": 48000, \"duration\": 0.5}, with \"amplitudes\")"
                    .into(),
            ));
        };
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_lowercase);
        let format = match ext.as_deref() {
            Some("npy") => IrFormat::Npy,
            Some("wav") => IrFormat::Wav,
            _ => {
                return Err(Failure::Input(
                    "--ir: the file's name must end in .npy or .wav (its format)".into(),
                ));
            }
        };
        let responses =
            ImpulseResponses::new(options, scene.sources().len(), scene.receivers().len());
        if format == IrFormat::Wav {
            wav_fits(&responses)?;
        }
        let bytes = responses.checked_len().and_then(|n| n.checked_mul(8));
        let have = available_memory();
        let fits = match (bytes, have) {
            (None, _) => false,
            (Some(b), Some(h)) => b as u64 <= h,
            (Some(_), None) => true,
        };
        if !fits {
            return Err(Failure::Input(format!(
                "impulse_response: {} sources × {} receivers × {} samples of 8 bytes are more \
                 than the memory available: lower `rate` or `duration`, or split the receivers",
                responses.sources(),
                responses.receivers(),
                responses.samples()
            )));
        }
        Ok(IrOutput {
            path: path.to_path_buf(),
            format,
            responses,
        })
    }

    /// Writes the rendered responses `data` to the file.
    fn write(&self, data: &[f64]) -> Result<(), Failure> {
        let r = &self.responses;
        // Straight into the file, a buffer at a time: the responses are the one copy held
        // (what the check before the solve counts). A file left short by an error goes.
        let file = fs::File::create(&self.path).map_err(|e| write_failure(&self.path, &e))?;
        let mut out = BufWriter::new(file);
        let written = match self.format {
            IrFormat::Npy => {
                let shape = [r.sources(), r.receivers(), r.samples()];
                write_f64_array(&shape, data, &mut out).map_err(|e| write_failure(&self.path, &e))
            }
            IrFormat::Wav => write_wav(r, data, &mut out)
                .map_err(|e| Failure::Output(format!("{}: {e}", self.path.display()))),
        }
        .and_then(|()| out.flush().map_err(|e| write_failure(&self.path, &e)));
        if written.is_err() {
            let _ = fs::remove_file(&self.path);
        }
        written
    }
}

/// A WAV file's channels and rate must fit its header: at most 65,535 channels (sources ×
/// receivers) and a whole number of samples per second.
fn wav_fits(r: &ImpulseResponses) -> Result<(), Failure> {
    let channels = r.sources().saturating_mul(r.receivers());
    if channels == 0 || channels > WAV_CHANNELS {
        return Err(Failure::Input(format!(
            "--ir: a WAV file holds 1 to {WAV_CHANNELS} channels, one per source and receiver; \
             this scene has {channels} (write .npy instead)"
        )));
    }
    let rate = r.rate();
    if rate.fract() != 0.0 || rate > f64::from(u32::MAX) {
        return Err(Failure::Input(format!(
            "impulse_response.rate: a WAV file needs a whole number of samples per second, not \
             {rate} (write .npy instead)"
        )));
    }
    Ok(())
}

/// Writes the responses as a WAV file of 32-bit float samples, one channel per (source,
/// receiver), source-major, interleaved as WAV is.
fn write_wav<W: Write + Seek>(
    r: &ImpulseResponses,
    data: &[f64],
    out: &mut W,
) -> hound::Result<()> {
    let channels = r.sources() * r.receivers();
    let spec = hound::WavSpec {
        channels: channels as u16,
        sample_rate: r.rate() as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut writer = hound::WavWriter::new(out, spec)?;
    let samples = r.samples();
    for n in 0..samples {
        for c in 0..channels {
            writer.write_sample(data[c * samples + n] as f32)?;
        }
    }
    writer.finalize()
}

/// The charts of what arrives, asked for with `--echogram` and `--tl-map`: checked before
/// anything is solved.
pub(super) struct Charts {
    echogram: Option<PathBuf>,
    tl_map: Option<(PathBuf, f64)>,
    source: usize,
    receiver: usize,
    /// How the charts are drawn.
    style: ChartStyle,
}

/// How the charts are drawn: the map's axes and the echogram's start of time.
pub(super) struct ChartStyle {
    /// The map's axes: names, units and scales.
    pub(super) axes: super::svg::Axes,
    /// Whether the echogram's time axis starts at t = 0 (else just before the first arrival).
    pub(super) echogram_from_zero: bool,
}

impl Charts {
    /// The charts asked for: refused (naming the option or the scene's key) for a scene
    /// without amplitudes, a map without `amplitudes.frequency`, or a source or receiver the
    /// scene does not have.
    pub(super) fn check(
        echogram: Option<&Path>,
        tl_map: Option<&Path>,
        (source, receiver): (usize, usize),
        style: ChartStyle,
        scene: &Scene,
    ) -> Result<Option<Charts>, Failure> {
        let option = match (echogram, tl_map) {
            (None, None) => return Ok(None),
            (Some(_), _) => "--echogram",
            (None, Some(_)) => "--tl-map",
        };
        let Some(amplitudes) = scene.amplitudes() else {
            return Err(Failure::Input(format!(
                "{option}: the scene does not ask for amplitudes (add \"amplitudes\": \
                 {{\"source\": \"point\"}} or another source model)"
            )));
        };
        if source >= scene.sources().len() {
            return Err(Failure::Input(format!(
                "--source: the scene has {} sources (0 to {})",
                scene.sources().len(),
                scene.sources().len().saturating_sub(1)
            )));
        }
        if echogram.is_some() && receiver >= scene.receivers().len() {
            return Err(Failure::Input(format!(
                "--receiver: the scene has {} receivers (0 to {})",
                scene.receivers().len(),
                scene.receivers().len().saturating_sub(1)
            )));
        }
        let tl_map = match tl_map {
            Some(path) => {
                let Some(f) = amplitudes.frequency else {
                    return Err(Failure::Input(
                        "--tl-map: the map is at `amplitudes.frequency`, which the scene does \
                         not give"
                            .into(),
                    ));
                };
                Some((path.to_path_buf(), f))
            }
            None => None,
        };
        Ok(Some(Charts {
            echogram: echogram.map(Path::to_path_buf),
            tl_map,
            source,
            receiver,
            style,
        }))
    }

    /// Draws the charts (the echoes of the echogram's pair, the pressures of every pair
    /// for the map) and writes them.
    fn write(&self, scene: &Scene, mut pair: Vec<Echo>, p: &[Complex64]) -> Result<(), Failure> {
        if let Some(path) = &self.echogram {
            pair.sort_by(|a, b| a.time.total_cmp(&b.time));
            let title = format!(
                "Echogram: source {} at receiver {}",
                self.source, self.receiver
            );
            let svg =
                super::svg::charts::echogram_svg(&title, &pair, self.style.echogram_from_zero);
            fs::write(path, svg).map_err(|e| write_failure(path, &e))?;
        }
        if let Some((path, frequency)) = &self.tl_map {
            let receivers = scene.receivers().len();
            let row = &p[self.source * receivers..(self.source + 1) * receivers];
            let tl: Vec<f64> = row.iter().map(|&p| transmission_loss(p)).collect();
            let title = format!("Transmission loss from source {}", self.source);
            let svg = super::svg::charts::tl_map_svg(&super::svg::charts::TlMap {
                title: &title,
                scene,
                source: self.source,
                tl: &tl,
                frequency: *frequency,
                axes: &self.style.axes,
            });
            fs::write(path, svg).map_err(|e| write_failure(path, &e))?;
        }
        Ok(())
    }
}

/// `--tl FILE.npy`: the transmission loss of every (source, receiver), checked before the
/// solve.
pub(super) struct TlOutput {
    path: PathBuf,
    mode: TransmissionLossMode,
    frequency: f64,
    /// `[sources, receivers]`, or `[sources, nx, ny]` for a grid.
    shape: Vec<usize>,
}

impl TlOutput {
    /// The output of `--tl path` for `scene`: refused (naming `--tl` or the scene's key)
    /// without `amplitudes.frequency`, for a file that is not `.npy`, or where the loss and
    /// its sums do not fit in the memory available.
    pub(super) fn check(path: &Path, scene: &Scene) -> Result<TlOutput, Failure> {
        let Some(frequency) = scene.amplitudes().and_then(|a| a.frequency) else {
            return Err(Failure::Input(
                "--tl: the loss is at `amplitudes.frequency`, which the scene does not give \
                 (add \"amplitudes\": {\"source\": \"point\", \"frequency\": 100})"
                    .into(),
            ));
        };
        let npy = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
        if !npy {
            return Err(Failure::Input(
                "--tl: the file's name must end in .npy (float64 dB)".into(),
            ));
        }
        let (s, r) = (scene.sources().len(), scene.receivers().len());
        // The loss (8 bytes) and the complex sums it is made of (16 bytes), per pair.
        let bytes = s.checked_mul(r).and_then(|n| n.checked_mul(24));
        let fits = match (bytes, available_memory()) {
            (None, _) => false,
            (Some(b), Some(h)) => b as u64 <= h,
            (Some(_), None) => true,
        };
        if !fits {
            return Err(Failure::Input(format!(
                "--tl: {s} sources × {r} receivers need more than the memory available: split \
                 the receivers"
            )));
        }
        let shape = match scene.receiver_grid().and_then(|g| g.shape()) {
            Some((nx, ny)) if nx * ny == r => vec![s, nx, ny],
            _ => vec![s, r],
        };
        Ok(TlOutput {
            path: path.to_path_buf(),
            mode: scene.transmission_loss().unwrap_or_default(),
            frequency,
            shape,
        })
    }

    /// Writes the loss `tl` to the file.
    fn write(&self, tl: &[f64]) -> Result<(), Failure> {
        let file = fs::File::create(&self.path).map_err(|e| write_failure(&self.path, &e))?;
        let mut out = BufWriter::new(file);
        let written = write_f64_array(&self.shape, tl, &mut out)
            .and_then(|()| out.flush())
            .map_err(|e| write_failure(&self.path, &e));
        if written.is_err() {
            let _ = fs::remove_file(&self.path);
        }
        written
    }
}

/// Every response output's sums, filled echo by echo (from the search's threads, each
/// output behind its lock): the impulse responses, the coherent pressures (`--tl` coherent
/// and `--tl-map`), the intensities (`--tl` incoherent) and the echoes of the echogram's
/// pair. Nothing else of an echo is kept.
/// The impulse responses a run renders: for `--ir`, for `--parameters`, or one buffer for
/// both.
struct Rendered<'a> {
    responses: &'a ImpulseResponses,
    data: Mutex<Vec<f64>>,
    /// Where `--ir` writes them.
    file: Option<&'a IrOutput>,
    /// Each pair's first arrival (the time zero of its parameters), when `--parameters`
    /// reads them.
    first: Option<Mutex<Vec<f64>>>,
}

pub(super) struct Sums<'a> {
    ir: Option<Rendered<'a>>,
    tl: Option<&'a TlOutput>,
    charts: Option<&'a Charts>,
    pressure: Option<(f64, Mutex<Vec<Complex64>>)>,
    intensity: Option<Mutex<Vec<f64>>>,
    pair: Mutex<Vec<Echo>>,
    receivers: usize,
    /// The processor's vector instructions ([`AddColumns`]).
    arch: pulp::Arch,
    /// Echoes summed.
    pub(super) echoes: AtomicU64,
    /// Timed arrivals and rays without an amplitude value: they add nothing.
    pub(super) without_amplitude: AtomicU64,
}

/// A search's arrivals streamed into [`Sums`]: each batch's echoes summed under one lock
/// per output.
pub(super) struct StreamedSums<'s, 'a>(pub(super) &'s Sums<'a>);

impl ArrivalSink for StreamedSums<'_, '_> {
    fn arrival(&self, a: StreamedArrival) {
        self.0.add_all([Echo::of_streamed(&a)]);
    }

    fn arrivals(&self, batch: &[StreamedArrival]) {
        self.0.add_streamed(batch);
    }
}

/// A streamed batch's loss sums ([`Sums::add_streamed`]) as [`pulp::Arch::dispatch`]
/// compiles them for each set of vector instructions (everything inlined, so compiled with
/// them): the echoes of `arrivals` a column batch at a time into the coherent `pressure`
/// (its frequency and sums) and the `intensity`; the echoes added.
struct AddColumns<'c, 'a, 'p> {
    columns: &'c mut EchoColumns,
    arrivals: &'a [StreamedArrival],
    receivers: usize,
    pressure: Option<(f64, &'p mut [Complex64])>,
    intensity: Option<&'p mut [f64]>,
}

impl pulp::WithSimd for AddColumns<'_, '_, '_> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> usize {
        let AddColumns {
            columns,
            arrivals,
            receivers,
            mut pressure,
            mut intensity,
        } = self;
        let mut added = 0;
        for batch in arrivals.chunks(COLUMN_ECHOES) {
            columns.fill(batch, receivers);
            if let Some((f, p)) = &mut pressure {
                columns.add_pressures(*f, p);
            }
            if let Some(i) = &mut intensity {
                columns.add_intensities(i);
            }
            added += columns.len;
        }
        added
    }
}

/// The lock of `m`, also when another thread panicked holding it (the sums are only added
/// to: a sum left half added is still a sum).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// How many echoes an [`EchoColumns`] holds: a batch of the search's sink (256 arrivals).
const COLUMN_ECHOES: usize = 256;

/// Multiplies each complex number `re[i] + i·im[i]` by `a[i] + i·b[i]` as `Complex64`'s
/// product `(a + ib) × (re + i·im)` does, term for term: the pressures of a batch's phase
/// factors. Slices of one length, apart (so the loop goes two at a time).
#[inline(always)]
fn times_amplitudes(re: &mut [f64], im: &mut [f64], a: &[f64], b: &[f64]) {
    let n = re.len();
    let (im, a, b) = (&mut im[..n], &a[..n], &b[..n]);
    for i in 0..n {
        let (c, s) = (re[i], im[i]);
        (re[i], im[i]) = (a[i] * c - b[i] * s, a[i] * s + b[i] * c);
    }
}

/// A batch of echoes column by column, for the sums that read only an echo's pair, time and
/// amplitude (the loss's, coherent and incoherent): each sum a straight loop over columns,
/// then one scatter into the pairs' sums. One a thread ([`COLUMNS`]), filled again for
/// each batch: not zeroed each time (12 KB).
struct EchoColumns {
    /// Echoes held (the first `len` of each column).
    len: usize,
    /// The echo's pair, `source × receivers + receiver`.
    pair: [usize; COLUMN_ECHOES],
    /// The echo's travel time.
    time: [f64; COLUMN_ECHOES],
    /// The amplitude's real part.
    re: [f64; COLUMN_ECHOES],
    /// The amplitude's imaginary part.
    im: [f64; COLUMN_ECHOES],
    /// The real part of the phase factor, then of the pressure (scratch of
    /// [`add_pressures`](Self::add_pressures)).
    pressure_re: [f64; COLUMN_ECHOES],
    /// The imaginary part of the phase factor, then of the pressure.
    pressure_im: [f64; COLUMN_ECHOES],
}

thread_local! {
    /// Each thread's columns, for [`Sums::add_streamed`].
    static COLUMNS: std::cell::RefCell<EchoColumns> =
        const { std::cell::RefCell::new(EchoColumns::new()) };
}

impl EchoColumns {
    const fn new() -> EchoColumns {
        EchoColumns {
            len: 0,
            pair: [0; COLUMN_ECHOES],
            time: [0.0; COLUMN_ECHOES],
            re: [0.0; COLUMN_ECHOES],
            im: [0.0; COLUMN_ECHOES],
            pressure_re: [0.0; COLUMN_ECHOES],
            pressure_im: [0.0; COLUMN_ECHOES],
        }
    }

    /// Holds the echoes of `arrivals` (at most [`COLUMN_ECHOES`] of them), in order: those
    /// that [`Echo::of_streamed`] makes an echo of, the pairs of a scene of `receivers`.
    #[inline(always)]
    fn fill(&mut self, arrivals: &[StreamedArrival], receivers: usize) {
        let mut len = 0;
        for a in &arrivals[..arrivals.len().min(COLUMN_ECHOES)] {
            let Some(e) = Echo::of_streamed(a) else {
                continue;
            };
            self.pair[len] = e.source * receivers + e.receiver;
            self.time[len] = e.time;
            (self.re[len], self.im[len]) = (e.amplitude.re, e.amplitude.im);
            len += 1;
        }
        self.len = len;
    }

    /// Adds each echo's pressure at `frequency`, `amplitude × unit_phase(frequency × time)`,
    /// to its pair's sum in `sums`: the phases and the products a straight loop each, then
    /// the sums in order, bit for bit what one echo at a time adds.
    #[inline(always)]
    fn add_pressures(&mut self, frequency: f64, sums: &mut [Complex64]) {
        let n = self.len;
        let (re, im) = (&mut self.pressure_re[..n], &mut self.pressure_im[..n]);
        unit_phases(frequency, &self.time[..n], re, im);
        times_amplitudes(re, im, &self.re[..n], &self.im[..n]);
        for ((&k, &c), &s) in self.pair[..n].iter().zip(&*re).zip(&*im) {
            sums[k] += Complex64::new(c, s);
        }
    }

    /// Adds each echo's intensity, `|amplitude|²`, to its pair's sum in `sums`.
    #[inline(always)]
    fn add_intensities(&self, sums: &mut [f64]) {
        let n = self.len;
        let amplitudes = self.re[..n].iter().zip(&self.im[..n]);
        for (&k, (&a, &b)) in self.pair[..n].iter().zip(amplitudes) {
            sums[k] += Complex64::new(a, b).norm_sqr();
        }
    }
}

/// A buffer of `n` numbers, or the failure that names what could not be allocated.
fn buffer<T: Clone>(n: usize, zero: T, what: &str) -> Result<Vec<T>, Failure> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| Failure::Input(format!("{what}: {n} numbers could not be allocated")))?;
    v.resize(n, zero);
    Ok(v)
}

impl<'a> Sums<'a> {
    /// The sums of the outputs asked for (`None` when none is), allocated before the solve.
    /// `parameters`: the responses `--parameters` reads (rendered once with `--ir`'s).
    pub(super) fn new(
        scene: &Scene,
        ir: Option<&'a IrOutput>,
        tl: Option<&'a TlOutput>,
        charts: Option<&'a Charts>,
        parameters: Option<&'a ImpulseResponses>,
    ) -> Result<Option<Sums<'a>>, Failure> {
        if ir.is_none() && tl.is_none() && charts.is_none() && parameters.is_none() {
            return Ok(None);
        }
        let pairs = scene.sources().len() * scene.receivers().len();
        let first = match parameters {
            Some(_) => Some(Mutex::new(buffer(pairs, f64::INFINITY, "--parameters")?)),
            None => None,
        };
        let ir = match (ir, parameters) {
            (Some(o), _) => Some(Rendered {
                responses: &o.responses,
                data: Mutex::new(buffer(o.responses.len(), 0.0, "impulse_response")?),
                file: Some(o),
                first,
            }),
            (None, Some(responses)) => Some(Rendered {
                responses,
                data: Mutex::new(buffer(responses.len(), 0.0, "--parameters")?),
                file: None,
                first,
            }),
            (None, None) => None,
        };
        let coherent = tl.filter(|t| t.mode == TransmissionLossMode::Coherent);
        let map = charts.and_then(|c| c.tl_map.as_ref().map(|(_, f)| *f));
        let pressure = match coherent.map(|t| t.frequency).or(map) {
            Some(f) => Some((
                f,
                Mutex::new(buffer(pairs, Complex64::new(0.0, 0.0), "--tl")?),
            )),
            None => None,
        };
        let intensity = match tl.filter(|t| t.mode == TransmissionLossMode::Incoherent) {
            Some(_) => Some(Mutex::new(buffer(pairs, 0.0, "--tl")?)),
            None => None,
        };
        Ok(Some(Sums {
            ir,
            tl,
            charts,
            pressure,
            intensity,
            pair: Mutex::new(Vec::new()),
            receivers: scene.receivers().len(),
            arch: pulp::Arch::new(),
            echoes: AtomicU64::new(0),
            without_amplitude: AtomicU64::new(0),
        }))
    }

    /// Adds `e` to every output.
    pub(super) fn add(&self, e: Echo) {
        self.add_all([Some(e)]);
    }

    /// Adds each echo of `echoes` to every output, each output locked once for them all;
    /// counts each `None` (a timed arrival without an amplitude value) as
    /// [`skip`](Self::skip) does.
    pub(super) fn add_all(&self, echoes: impl IntoIterator<Item = Option<Echo>>) {
        let mut ir = self.ir.as_ref().map(|r| {
            let first = r.first.as_ref().map(lock);
            (r.responses, lock(&r.data), first)
        });
        let mut pressure = self.pressure.as_ref().map(|(f, p)| (*f, lock(p)));
        let mut intensity = self.intensity.as_ref().map(lock);
        let echogram = self.charts.filter(|c| c.echogram.is_some());
        let mut pair = echogram.map(|_| lock(&self.pair));
        let (mut added, mut skipped) = (0u64, 0u64);
        for e in echoes {
            let Some(e) = e else {
                skipped += 1;
                continue;
            };
            added += 1;
            let k = e.source * self.receivers + e.receiver;
            if let Some((r, data, first)) = &mut ir {
                let start = k * r.samples();
                r.pulse().add(
                    &mut data[start..start + r.samples()],
                    e.time * r.rate(),
                    e.amplitude,
                );
                if let Some(first) = first {
                    first[k] = first[k].min(e.time);
                }
            }
            if let Some((f, p)) = &mut pressure {
                p[k] += e.amplitude * unit_phase(*f * e.time);
            }
            if let Some(i) = &mut intensity {
                i[k] += e.amplitude.norm_sqr();
            }
            if let (Some(c), Some(pair)) = (echogram, &mut pair)
                && (e.source, e.receiver) == (c.source, c.receiver)
            {
                pair.push(e);
            }
        }
        if added > 0 {
            self.echoes.fetch_add(added, Ordering::Relaxed);
        }
        if skipped > 0 {
            self.without_amplitude.fetch_add(skipped, Ordering::Relaxed);
        }
    }

    /// Adds the echoes of a search's `arrivals` as [`add_all`](Self::add_all) adds them,
    /// bit for bit, each output locked once: the loss's sums (and `--tl-map`'s) a batch of
    /// [`EchoColumns`] at a time; with impulse responses or an echogram to fill, one echo at
    /// a time.
    pub(super) fn add_streamed(&self, arrivals: &[StreamedArrival]) {
        if self.ir.is_some() || self.charts.is_some_and(|c| c.echogram.is_some()) {
            self.add_all(arrivals.iter().map(Echo::of_streamed));
            return;
        }
        let mut pressure = self.pressure.as_ref().map(|(f, p)| (*f, lock(p)));
        let mut intensity = self.intensity.as_ref().map(lock);
        let added = COLUMNS.with_borrow_mut(|columns| {
            // Compiled for the processor's vector instructions where it has them (AVX2,
            // AVX-512): the same operations, so the same sums.
            self.arch.dispatch(AddColumns {
                columns,
                arrivals,
                receivers: self.receivers,
                pressure: pressure.as_mut().map(|(f, p)| (*f, &mut p[..])),
                intensity: intensity.as_mut().map(|i| &mut i[..]),
            })
        });
        let skipped = arrivals.len() - added;
        if added > 0 {
            self.echoes.fetch_add(added as u64, Ordering::Relaxed);
        }
        if skipped > 0 {
            self.without_amplitude
                .fetch_add(skipped as u64, Ordering::Relaxed);
        }
    }

    /// Counts a timed arrival or ray without an amplitude value.
    pub(super) fn skip(&self) {
        self.without_amplitude.fetch_add(1, Ordering::Relaxed);
    }

    /// Writes every output; `--parameters` to `parameters` (when given), read off the
    /// rendered responses, with `incomplete_pairs` from the search.
    pub(super) fn write(
        self,
        scene: &Scene,
        parameters: Option<&Path>,
        incomplete_pairs: usize,
    ) -> Result<(), Failure> {
        let Sums {
            ir,
            tl,
            charts,
            pressure,
            intensity,
            pair,
            ..
        } = self;
        let inner = |m: Mutex<Vec<f64>>| m.into_inner().unwrap_or_else(|e| e.into_inner());
        if let Some(rendered) = ir {
            let data = inner(rendered.data);
            if let Some(o) = rendered.file {
                o.write(&data)?;
            }
            if let (Some(path), Some(first)) = (parameters, rendered.first) {
                let first = inner(first);
                let r = rendered.responses;
                let found: Vec<RoomParameters> = (0..first.len())
                    .map(|k| {
                        let (s, rc) = (k / r.receivers().max(1), k % r.receivers().max(1));
                        let t0 = first[k].is_finite().then_some(first[k]);
                        room_parameters(r.response(&data, s, rc), r.rate(), t0)
                    })
                    .collect();
                write_parameters_file(scene, &found, incomplete_pairs, path)?;
            }
        }
        let pressure = pressure.map(|(_, p)| p.into_inner().unwrap_or_else(|e| e.into_inner()));
        if let Some(t) = tl {
            let loss: Vec<f64> = match (&pressure, intensity) {
                (_, Some(i)) => inner(i).into_iter().map(incoherent_loss).collect(),
                (Some(p), None) => p.iter().map(|&p| transmission_loss(p)).collect(),
                (None, None) => unreachable!("--tl sums one or the other"),
            };
            t.write(&loss)?;
        }
        if let Some(c) = charts {
            let pair = pair.into_inner().unwrap_or_else(|e| e.into_inner());
            c.write(scene, pair, pressure.as_deref().unwrap_or_default())?;
        }
        Ok(())
    }
}

/// The responses `--parameters` reads (the scene's `impulse_response`), checked before the
/// solve: exit 2 without one.
pub(super) fn parameters_check(scene: &Scene) -> Result<ImpulseResponses, Failure> {
    let Some(options) = scene.impulse_response() else {
        return Err(Failure::Input(
            "--parameters: the parameters are read from impulse responses, and the scene has \
             no `impulse_response` section (add \"impulse_response\": {\"rate\": 48000, \
             \"duration\": 1.0}, with \"amplitudes\")"
                .into(),
        ));
    };
    let responses = ImpulseResponses::new(options, scene.sources().len(), scene.receivers().len());
    if responses
        .checked_len()
        .is_none_or(|n| n.checked_mul(8).is_none())
    {
        return Err(Failure::Input(
            "--parameters: the responses do not fit in memory (fewer pairs, or a shorter \
             `impulse_response.duration`)"
                .into(),
        ));
    }
    Ok(responses)
}

/// Writes `--parameters`: the room acoustic parameters `found` of every (source, receiver),
/// source-major, with the search's count of `incomplete_pairs`.
fn write_parameters_file(
    scene: &Scene,
    found: &[RoomParameters],
    incomplete_pairs: usize,
    path: &Path,
) -> Result<(), Failure> {
    let receivers = scene.receivers().len().max(1);
    let entries: Vec<serde_json::Value> = found
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut v = serde_json::to_value(p).unwrap_or_default();
            if let Some(o) = v.as_object_mut() {
                o.insert("source".into(), (k / receivers).into());
                o.insert("receiver".into(), (k % receivers).into());
            }
            v
        })
        .collect();
    let doc = serde_json::json!({
        "parameters": entries,
        "incomplete_pairs": incomplete_pairs,
    });
    let text = serde_json::to_string_pretty(&doc).unwrap_or_default();
    std::fs::write(path, text + "\n").map_err(|e| {
        Failure::Output(format!(
            "--parameters: {}: cannot write: {e}",
            path.display()
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenray::Status;
    use eigenray::amplitude::{Amplitude, NoAmplitude};

    /// Sums of a scene of `pairs` (2 sources × `pairs / 2` receivers) with the coherent
    /// pressures at `frequency` and the intensities, nothing else.
    fn loss_sums(frequency: f64, pairs: usize) -> Sums<'static> {
        Sums {
            ir: None,
            tl: None,
            charts: None,
            pressure: Some((frequency, Mutex::new(vec![Complex64::new(0.0, 0.0); pairs]))),
            intensity: Some(Mutex::new(vec![0.0; pairs])),
            pair: Mutex::new(Vec::new()),
            receivers: pairs / 2,
            arch: pulp::Arch::new(),
            echoes: AtomicU64::new(0),
            without_amplitude: AtomicU64::new(0),
        }
    }

    /// What [`loss_sums`] summed, the sums as their bits.
    #[derive(Debug, PartialEq)]
    struct SummedBits {
        /// Each pair's pressure, real and imaginary part.
        pressures: Vec<u64>,
        intensities: Vec<u64>,
        echoes: u64,
        without_amplitude: u64,
    }

    fn bits(s: Sums<'_>) -> SummedBits {
        let p = s.pressure.unwrap().1.into_inner().unwrap();
        let i = s.intensity.unwrap().into_inner().unwrap();
        SummedBits {
            pressures: p
                .iter()
                .flat_map(|z| [z.re.to_bits(), z.im.to_bits()])
                .collect(),
            intensities: i.iter().map(|x| x.to_bits()).collect(),
            echoes: s.echoes.into_inner(),
            without_amplitude: s.without_amplitude.into_inner(),
        }
    }

    /// A batch's sums ([`StreamedSums`] over [`EchoColumns`]) are bit for bit the sums of
    /// one echo at a time ([`Sums::add_all`] of each arrival's echo, the way every echo went
    /// before the batches), and so are the counts: ten thousand arrivals to 2 × 7 pairs, in
    /// batches of 1 to 700 arrivals (so over several columns' worth), some `vertex` or
    /// `obstructed`, some without an amplitude or without its value, some at times beyond the
    /// phase's fast reduction (each way of [`unit_phases`]), zero and negative amplitudes.
    #[test]
    fn a_batch_sums_as_one_echo_at_a_time_does() {
        let mut state = 0x0123_4567_89ab_cdefu64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state >> 11
        };
        let unit = |u: u64| (u >> 11) as f64 / (1u64 << 42) as f64;
        let arrivals: Vec<StreamedArrival> = (0..10_000)
            .map(|_| {
                let u = next();
                let time = match u % 16 {
                    0 => 1e13 * (1.0 + unit(next())),
                    1 => (next() % 8_000) as f64 / 800.0,
                    _ => 30.0 * unit(next()),
                };
                let value = match u % 13 {
                    0 => Complex64::new(0.0, -0.0),
                    _ => Complex64::new(unit(next()) - 0.5, unit(next()) - 0.5) * 1e-3,
                };
                let amplitude = match u % 11 {
                    0 => None,
                    1 => Some(Amplitude::none(NoAmplitude::Vertex)),
                    _ => Some(Amplitude {
                        value,
                        spreading: 1.0,
                        coefficient: Complex64::new(1.0, 0.0),
                        attenuation_db: 0.0,
                        reason: None,
                    }),
                };
                StreamedArrival {
                    source: (u >> 8) as usize % 2,
                    receiver: (u >> 12) as usize % 7,
                    steps: 3,
                    diffractions: 0,
                    vertical_reflections: 0,
                    status: [Status::Converged, Status::Vertex, Status::Obstructed]
                        [usize::from(u % 17 == 0) + usize::from(u % 19 == 0)],
                    time,
                    amplitude,
                }
            })
            .collect();
        let (batched, one_at_a_time) = (loss_sums(37.5, 14), loss_sums(37.5, 14));
        let mut rest = &arrivals[..];
        while !rest.is_empty() {
            let (batch, after) = rest.split_at((next() as usize % 700 + 1).min(rest.len()));
            StreamedSums(&batched).arrivals(batch);
            rest = after;
        }
        for a in &arrivals {
            one_at_a_time.add_all([Echo::of_streamed(a)]);
        }
        let (want, got) = (bits(one_at_a_time), bits(batched));
        assert_eq!(got, want);
        // Not a test that cannot fail: echoes were summed and others skipped.
        let (echoes, skipped) = (want.echoes, want.without_amplitude);
        assert!(echoes > 7_000 && skipped > 1_000, "{echoes} {skipped}");
    }
}
