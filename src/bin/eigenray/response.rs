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
        self.0.add_all(batch.iter().map(Echo::of_streamed));
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
        fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
            m.lock().unwrap_or_else(|e| e.into_inner())
        }
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

/// `e^(2πi · frac(turns))`, the phase factor of an echo at `turns = f · T` cycles: what
/// `Complex64::from_polar(1, 2π frac(turns))` gives, without its general range reduction
/// (nor the library calls of `fract` and `round` on a CPU without SSE4.1), and without a
/// branch on the quarter. `y = 4 · turns` (exact) is split exactly into its nearest integer
/// `q` (below 2^51, the sum with 1.5 · 2^52 rounds it there, ties to even, and the sum's
/// last bits are `q` modulo 4) and a rest `f = y − q`, `|f| ≤ 1/2` (a difference of two
/// numbers within a half of each other: no rounding); the sine and cosine of `π/2 · f` (at
/// most π/4) are fdlibm's kernels (within an ulp), turned by `q` quarter turns, exactly.
/// So each component is within about 2e-16 of the true phase factor of `2π · frac(turns)`
/// (`tests::the_phase_kernel_is_within_an_ulp_or_two_of_libm`).
#[inline]
fn unit_phase(turns: f64) -> Complex64 {
    /// 1.5 · 2^52: a sum with it below 2^51 in size is rounded to an integer.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let y = 4.0 * turns;
    let (q, f) = if y.abs() < 2_251_799_813_685_248.0 {
        let shifted = y + ROUND;
        (shifted.to_bits(), y - (shifted - ROUND))
    } else {
        // Beyond 2^51 quarter turns `y` is a multiple of 1/4 (of 2 above 2^53): `fract`
        // takes the fraction of the turns, exactly.
        let y = 4.0 * turns.fract();
        let r = y.round();
        (r as i64 as u64, y - r)
    };
    let t = std::f64::consts::FRAC_PI_2 * f;
    let (s, c) = (sin_kernel(t), cos_kernel(t));
    // Turned by `q` quarter turns: (c, s), (−s, c), (−c, −s), (s, −c), picked (not branched
    // on: the quarter is as good as random from one echo to the next).
    let turned = [c, -s, -c, s];
    let q = q as usize;
    Complex64::new(turned[q & 3], turned[q.wrapping_add(3) & 3])
}

/// `sin t` for `|t| ≤ π/4`: fdlibm's `__kernel_sin` (its tail `y` zero), within one ulp.
#[inline(always)]
fn sin_kernel(t: f64) -> f64 {
    const S1: f64 = -0.16666666666666632;
    const S2: f64 = 0.00833333333332249;
    const S3: f64 = -0.0001984126982985795;
    const S4: f64 = 2.7557313707070068e-06;
    const S5: f64 = -2.5050760253406863e-08;
    const S6: f64 = 1.58969099521155e-10;
    let z = t * t;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    t + z * t * (S1 + z * r)
}

/// `cos t` for `|t| ≤ π/4`: fdlibm's `__kernel_cos` (its tail `y` zero), within one ulp.
#[inline(always)]
fn cos_kernel(t: f64) -> f64 {
    const C1: f64 = 0.0416666666666666;
    const C2: f64 = -0.001388888888887411;
    const C3: f64 = 2.480158728947673e-05;
    const C4: f64 = -2.7557314351390663e-07;
    const C5: f64 = 2.087572321298175e-09;
    const C6: f64 = -1.1359647557788195e-11;
    let z = t * t;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let one_less = 1.0 - hz;
    one_less + (((1.0 - one_less) - hz) + z * r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel against libm's `sin` and `cos` of the same reduced argument `2π r` (within
    /// 2.3e-16 a component: an ulp or two), and against `from_polar` of `2π frac(turns)`
    /// (within 1e-15: that argument's own rounding, up to 4.4e-16 rad near a full turn),
    /// over a million fractions spread over `[−3, 3000)` turns, the eighths of a turn and
    /// their neighbours.
    #[test]
    fn the_phase_kernel_is_within_an_ulp_or_two_of_libm() {
        let (mut kernel, mut polar) = (0.0f64, 0.0f64);
        let mut check = |turns: f64| {
            let got = unit_phase(turns);
            let want = Complex64::from_polar(1.0, std::f64::consts::TAU * turns.fract());
            polar = polar
                .max((got.re - want.re).abs())
                .max((got.im - want.im).abs());
            let x = turns.fract();
            let q = (4.0 * x).round();
            let t = std::f64::consts::TAU * (x - 0.25 * q);
            let quarter = Complex64::new(0.0, 1.0).powi((q as i32).rem_euclid(4));
            let exact = Complex64::new(t.cos(), t.sin()) * quarter;
            kernel = kernel
                .max((got.re - exact.re).abs())
                .max((got.im - exact.im).abs());
        };
        // A fixed linear congruential sequence: the same numbers every run.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..1_000_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            check(u * 3003.0 - 3.0);
        }
        for k in -8..=8 {
            let at = f64::from(k) / 8.0;
            for t in [at, at.next_up(), at.next_down(), 300.0 + at, -2.0 + at] {
                check(t);
            }
            // Four times the turns at and beyond 2^51 (the reduction's other way), and below.
            for big in [562_949_953_421_312.0, 1e15, 4_503_599_627_370_496.0] {
                for t in [big + at, big.next_down() + at, -big + at] {
                    check(t);
                }
            }
        }
        assert!(kernel <= 2.3e-16, "{kernel:e}");
        assert!(polar <= 1e-15, "{polar:e}");
        // Exact at the quarter turns, as `from_polar`'s multiples of π/2 are not.
        assert_eq!(unit_phase(0.25), Complex64::new(0.0, 1.0));
        assert_eq!(unit_phase(2.5), Complex64::new(-1.0, 0.0));
        assert_eq!(unit_phase(-0.75), Complex64::new(0.0, 1.0));
        assert!(unit_phase(f64::NAN).re.is_nan());
    }
}
