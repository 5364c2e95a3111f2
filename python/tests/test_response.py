"""Impulse responses, pressures and transmission loss (`Tracer.impulse_response`,
`Tracer.pressure`, `Tracer.transmission_loss`), against pyroomacoustics and closed forms."""

import json
import math
import subprocess

import numpy as np
import pytest

import eigenray

pra = pytest.importorskip("pyroomacoustics")

SPEED = 343.0
RATE = 16000
ABSORPTION = 0.1

# Two 2-D polygon rooms: a non-convex L and a convex pentagon.
ROOMS = {
    "L": ([[0, 0], [5, 0], [5, 3], [3, 3], [3, 5], [0, 5]], [1.1, 0.9], [4.2, 2.1], 3),
    "pentagon": ([[0, 0], [4, 0], [5, 3], [2, 5], [-1, 3]], [1.0, 1.2], [3.1, 3.3], 4),
}


def room_scene(corners, source, receiver, order, duration=None):
    """The room with one interface per wall, each absorbing ABSORPTION of the energy."""
    n = len(corners)
    walls = {
        f"w{i}": {
            "points": [corners[i], corners[(i + 1) % n]],
            "reflection": {"absorption": ABSORPTION},
        }
        for i in range(n)
    }
    scene = {
        "media": {"air": {"speed": SPEED}},
        "background": "air",
        "interfaces": walls,
        "sources": [source],
        "receivers": [receiver],
        "search": {"max_steps": order, "refract": False},
        "amplitudes": {"source": "point"},
    }
    if duration is not None:
        scene["impulse_response"] = {"rate": RATE, "duration": duration}
    return scene


def pra_room(corners, source, receiver, order):
    """pyroomacoustics' room of the same walls, its image sources to `order` computed."""
    pra.constants.set("rir_hpf_enable", False)
    room = pra.Room.from_corners(
        np.array(corners, dtype=float).T,
        fs=RATE,
        max_order=order,
        materials=pra.Material(energy_absorption=ABSORPTION),
        ray_tracing=False,
        air_absorption=False,
    )
    room.add_source(source)
    room.add_microphone(receiver)
    room.compute_rir()
    return room


def images_response(room, receiver, samples):
    """The response of pyroomacoustics' visible image sources, each placed by its own
    documented filter, `pra.utilities.fractional_delay` (Hann(81) × sinc, exact in numpy):
    `damping / distance` at sample `floor(t·fs) + k`, k = 0 … 80 (40 samples late)."""
    src = room.sources[0]
    visible = np.asarray(room.visibility[0][0], dtype=bool)
    images = src.images[:, visible]
    damping = src.damping[0, visible]
    h = np.zeros(samples + 81)
    for image, a in zip(images.T, damping):
        dist = np.linalg.norm(image - np.asarray(receiver, dtype=float))
        position = dist / room.c * RATE
        whole = int(np.floor(position))
        if whole < samples:
            h[whole : whole + 81] += a / dist * pra.utilities.fractional_delay(position - whole)
    return h, int(visible.sum())


@pytest.mark.parametrize("name", sorted(ROOMS))
def test_the_room_response_is_pyroomacoustics(name):
    corners, source, receiver, order = ROOMS[name]
    room = pra_room(corners, source, receiver, order)
    h_pra = np.asarray(room.rir[0][0], dtype=float)
    # pyroomacoustics delays everything by 40 samples (half its 81-tap pulse) and scales each
    # image by damping / distance, without 1/(4π).
    n = len(h_pra) - 40
    tracer = eigenray.Tracer(eigenray.Scene(room_scene(corners, source, receiver, order)))
    h = tracer.impulse_response(rate=RATE, duration=n / RATE)
    assert h.shape == (1, 1, n)
    ours = 4 * math.pi * h[0, 0]
    # Against its images placed by its exact filter: the same samples, to the precision of
    # its image coordinates (float32: about 1e-7 of a distance, 1e-5 of a sample here).
    reference, visible = images_response(room, receiver, n)
    assert visible == len(tracer.search()) > 5
    error = np.linalg.norm(ours - reference[40 : 40 + n]) / np.linalg.norm(ours)
    assert error < 2e-4, f"relative L2 difference {error:.2e} from the images"
    # Against `compute_rir`, which interpolates a sinc tabulated 20 points a sample
    # (linearly: about 1e-3 of a pulse) in float32.
    error = np.linalg.norm(ours - h_pra[40 : 40 + n]) / np.linalg.norm(h_pra)
    assert error < 3e-3, f"relative L2 difference {error:.2e} from compute_rir"


def test_the_scene_settings_and_the_cli_give_the_same_responses(tmp_path, cli):
    corners, source, receiver, order = ROOMS["L"]
    scene = room_scene(corners, source, receiver, order, duration=0.05)
    path = tmp_path / "room.json"
    path.write_text(json.dumps(scene))
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    h = tracer.impulse_response()
    assert h.shape == (1, 1, 800)
    out = tmp_path / "ir.npy"
    subprocess.run(
        [cli, "solve", str(path), "--ir", str(out)], check=True, capture_output=True
    )
    assert np.array_equal(np.load(out), h)
    wav = tmp_path / "ir.wav"
    subprocess.run(
        [cli, "solve", str(path), "--ir", str(wav)], check=True, capture_output=True
    )
    from scipy.io import wavfile

    rate, data = wavfile.read(wav)
    assert rate == RATE and data.dtype == np.float32
    assert np.array_equal(data, h[0, 0].astype(np.float32))


def lloyd_scene(ranges):
    """A pressure-release sea surface above a source at depth 5, receivers at depth 10."""
    return {
        "media": {"water": {"speed": 1500.0}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[-10, 0], [2000, 0]], "reflection": "pressure-release"}
        },
        "sources": [[0.0, -5.0]],
        "receivers": [[x, -10.0] for x in ranges],
        "search": {"max_steps": 1, "refract": False},
        "amplitudes": {"source": "point", "frequency": 150.0},
    }


def test_lloyds_mirror_transmission_loss_against_its_closed_form():
    ranges = np.linspace(10.0, 1000.0, 400)
    tracer = eigenray.Tracer(eigenray.Scene(lloyd_scene(ranges)))
    tl = tracer.transmission_loss()
    p = tracer.pressure()
    assert tl.shape == p.shape == (1, len(ranges))
    k = 2 * math.pi * 150.0 / 1500.0
    r1 = np.hypot(ranges, 5.0)
    r2 = np.hypot(ranges, 15.0)
    want = (np.exp(1j * k * r1) / r1 - np.exp(1j * k * r2) / r2) / (4 * math.pi)
    want_tl = -20 * np.log10(np.abs(want) * 4 * math.pi)
    # Away from the nulls: the sum at least 1 % of the direct arrival.
    away = np.abs(want) > 0.01 / (4 * math.pi * r1)
    assert away.sum() > 350
    assert np.max(np.abs(tl[0, away] - want_tl[away])) < 0.01
    assert np.max(np.abs(p[0] - want)) < 1e-12 * np.max(np.abs(want))


def test_missing_settings_are_named():
    corners, source, receiver, order = ROOMS["L"]
    scene = room_scene(corners, source, receiver, order)
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    with pytest.raises(eigenray.EigenrayError) as e:
        tracer.impulse_response()
    assert e.value.key == "impulse_response"
    with pytest.raises(eigenray.EigenrayError) as e:
        tracer.impulse_response(rate=0.0, duration=1.0)
    assert e.value.key == "impulse_response.rate"
    with pytest.raises(eigenray.EigenrayError) as e:
        tracer.pressure()
    assert e.value.key == "frequency"
    del scene["amplitudes"]
    with pytest.raises(eigenray.EigenrayError) as e:
        eigenray.Tracer(eigenray.Scene(scene)).pressure(100.0)
    assert e.value.key == "amplitudes"


def test_the_echogram_and_the_map_draw_their_keys():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    from eigenray.plotting import echogram, tl_map

    corners, source, receiver, order = ROOMS["pentagon"]
    tracer = eigenray.Tracer(eigenray.Scene(room_scene(corners, source, receiver, order)))
    echoes = tracer.echoes()
    assert set(echoes) == {"source", "receiver", "order", "diffractions", "vertical",
                           "time", "amplitude"}
    assert echoes["amplitude"].dtype == np.complex128
    assert len(echoes["time"]) == len(tracer.search())
    ax = echogram(echoes)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend[:2] == ["direct", "1 interaction"] and len(legend) == order + 1
    assert ax.get_xlabel() == "time (s)"

    ranges = np.linspace(10.0, 500.0, 20)
    grid = np.array([[x, y] for y in (-10.0, -20.0, -30.0) for x in ranges])
    scene = lloyd_scene(ranges)
    scene["receivers"] = grid.tolist()
    tl = eigenray.Tracer(eigenray.Scene(scene)).transmission_loss()[0]
    ax = tl_map(grid, tl)
    assert ax.figure.axes[1].get_ylabel() == "transmission loss (dB)"
