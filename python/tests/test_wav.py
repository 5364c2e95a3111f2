"""The WAV of `eigenray solve --ir FILE.wav`: 32-bit float samples in WAVE_FORMAT_EXTENSIBLE,
which Python's `wave` module cannot read and `scipy.io.wavfile` (and `soundfile`) can. Its
samples are the `.npy` response's, channel s × receivers + r for source s and receiver r."""

import json
import struct
import subprocess
import wave

import numpy as np
import pytest

import eigenray

RATE = 8000

# A floor under two sources and three receivers: the direct sound and the floor's echo.
SCENE = {
    "media": {"air": {"speed": 343.0}},
    "background": "air",
    "interfaces": {"floor": {"points": [[-50, 0], [50, 0]], "reflection": {"absorption": 0.3}}},
    "sources": [[0.0, 1.5], [2.0, 1.0]],
    "receivers": [[3.0, 1.2], [6.0, 2.0], [-4.0, 0.5]],
    "search": {"max_steps": 1, "refract": False},
    "amplitudes": {"source": "point"},
    "impulse_response": {"rate": RATE, "duration": 0.05},
}


@pytest.fixture(scope="module")
def written(tmp_path_factory, cli):
    """The responses written by the command-line tool as `.npy` and as `.wav`."""
    folder = tmp_path_factory.mktemp("wav")
    scene = folder / "floor.json"
    scene.write_text(json.dumps(SCENE))
    paths = {}
    for ext in ("npy", "wav"):
        paths[ext] = folder / f"ir.{ext}"
        subprocess.run(
            [cli, "solve", str(scene), "--ir", str(paths[ext])], check=True, capture_output=True
        )
    return paths


def test_the_wav_is_float32_in_the_extensible_format(written):
    data = written["wav"].read_bytes()
    assert data[:4] == b"RIFF" and data[8:16] == b"WAVEfmt "
    tag, channels, rate = struct.unpack_from("<HHI", data, 20)
    bits = struct.unpack_from("<H", data, 34)[0]
    # WAVE_FORMAT_EXTENSIBLE, its sub-format KSDATAFORMAT_SUBTYPE_IEEE_FLOAT (GUID 00000003-…).
    assert (tag, channels, rate, bits) == (0xFFFE, 6, RATE, 32)
    assert data[44:48] == b"\x03\x00\x00\x00"


def test_pythons_wave_module_cannot_read_it(written):
    # What docs/python.md says: `wave` reads integer PCM only.
    with pytest.raises(wave.Error):
        wave.open(str(written["wav"])).close()


def test_scipy_reads_the_npy_responses_from_the_wav(written):
    from scipy.io import wavfile

    responses = np.load(written["npy"])
    sources, receivers, samples = responses.shape
    assert (sources, receivers, samples) == (2, 3, 400)
    rate, data = wavfile.read(written["wav"])
    assert rate == RATE and data.dtype == np.float32
    assert data.shape == (samples, sources * receivers)
    for s in range(sources):
        for r in range(receivers):
            channel = data[:, s * receivers + r]
            # The same samples, rounded once to float32; none of them all zero.
            assert np.array_equal(channel, responses[s, r].astype(np.float32)), (s, r)
            assert np.abs(channel).max() > 0
    # And the package's own call gives the `.npy`'s numbers.
    tracer = eigenray.Tracer(eigenray.Scene(SCENE))
    assert np.array_equal(tracer.impulse_response(), responses)


def test_soundfile_reads_the_wav(written):
    soundfile = pytest.importorskip("soundfile")
    data, rate = soundfile.read(written["wav"], dtype="float32", always_2d=True)
    responses = np.load(written["npy"])
    assert rate == RATE
    assert np.array_equal(data, responses.reshape(6, -1).T.astype(np.float32))
