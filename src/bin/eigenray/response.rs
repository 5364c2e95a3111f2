//! `eigenray solve --ir FILE`: the scene's impulse responses, as `.npy` or `.wav`.

use std::fs;
use std::path::{Path, PathBuf};

use eigenray::response::{Echo, ImpulseResponses};
use eigenray::{Scene, npy};

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

    /// Renders the responses of `echoes` and writes them to the file.
    pub(super) fn write(&self, echoes: impl Iterator<Item = Echo>) -> Result<(), Failure> {
        let r = &self.responses;
        let data = r.try_render(echoes).map_err(|_| {
            Failure::Input(format!(
                "impulse_response: {} numbers could not be allocated",
                r.len()
            ))
        })?;
        let mut file = Vec::new();
        match self.format {
            IrFormat::Npy => {
                let shape = [r.sources(), r.receivers(), r.samples()];
                npy::write_f64_array(&shape, &data, &mut file)
                    .map_err(|e| write_failure(&self.path, &e))?;
            }
            IrFormat::Wav => write_wav(r, &data, &mut file)
                .map_err(|e| Failure::Output(format!("{}: {e}", self.path.display())))?,
        }
        fs::write(&self.path, file).map_err(|e| write_failure(&self.path, &e))
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
fn write_wav(r: &ImpulseResponses, data: &[f64], out: &mut Vec<u8>) -> hound::Result<()> {
    let channels = r.sources() * r.receivers();
    let spec = hound::WavSpec {
        channels: channels as u16,
        sample_rate: r.rate() as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut writer = hound::WavWriter::new(std::io::Cursor::new(out), spec)?;
    let samples = r.samples();
    for n in 0..samples {
        for c in 0..channels {
            writer.write_sample(data[c * samples + n] as f32)?;
        }
    }
    writer.finalize()
}
