//! `eigenray solve --ir FILE`: the scene's impulse responses, as `.npy` or `.wav`.

use std::fs;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use eigenray::Scene;
use eigenray::amplitude::Complex64;
use eigenray::output::write_f64_array;
use eigenray::response::{Echo, ImpulseResponses, pressure_into, transmission_loss};

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

    /// Renders the responses of `echoes` (a progress bar over them on a terminal) and writes
    /// them to the file.
    pub(super) fn write(&self, echoes: &[Echo]) -> Result<(), Failure> {
        let r = &self.responses;
        let bar = super::Bar::new(Some(echoes.len()), "echoes rendered");
        let data = r.render(echoes.iter().copied(), &bar.run());
        bar.finish();
        let data = data.map_err(|_| {
            Failure::Input(format!(
                "impulse_response: {} numbers could not be allocated",
                r.len()
            ))
        })?;
        // Straight into the file, a buffer at a time: the responses are the one copy held
        // (what the check before the solve counts). A file left short by an error goes.
        let file = fs::File::create(&self.path).map_err(|e| write_failure(&self.path, &e))?;
        let mut out = BufWriter::new(file);
        let written = match self.format {
            IrFormat::Npy => {
                let shape = [r.sources(), r.receivers(), r.samples()];
                write_f64_array(&shape, &data, &mut out).map_err(|e| write_failure(&self.path, &e))
            }
            IrFormat::Wav => write_wav(r, &data, &mut out)
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

    /// Draws the charts of `echoes` (every echo of the scene) and writes them.
    pub(super) fn write(&self, scene: &Scene, echoes: &[Echo]) -> Result<(), Failure> {
        if let Some(path) = &self.echogram {
            let mut pair: Vec<Echo> = (echoes.iter())
                .filter(|e| e.source == self.source && e.receiver == self.receiver)
                .copied()
                .collect();
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
            let mut p = vec![Complex64::new(0.0, 0.0); scene.sources().len() * receivers];
            pressure_into(
                echoes.iter().copied(),
                *frequency,
                scene.sources().len(),
                &eigenray::options::Run::new(),
                &mut p,
            );
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
