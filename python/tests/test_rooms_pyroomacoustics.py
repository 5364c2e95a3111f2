"""An extruded L-shaped room against pyroomacoustics (skipped where it is not installed):
`pra.Room.from_corners(corners, materials=[one per wall]).extrude(3.0, materials={floor,
ceiling})` and `eigenray.rooms.from_corners(...)` give the same arrivals (its visible image
sources) and the same impulse response (its images placed by its own fractional-delay
filter, with its 4π and 40-sample delay accounted for as in `test_response.py`), and
`Tracer.room_parameters` beside `pyroomacoustics.experimental.measure_rt60`."""

import math

import numpy as np
import pytest

from eigenray import rooms

pra = pytest.importorskip("pyroomacoustics")

RATE = 16000
ORDER = 6
HEIGHT = 3.0
CORNERS = [[0, 0], [5, 0], [5, 3], [3, 3], [3, 5], [0, 5]]
ALPHAS = [0.2, 0.4, 0.1, 0.3, 0.25, 0.15]
FLOOR, CEILING = 0.35, 0.05
SOURCE = [1.125, 0.875, 1.3125]  # multiples of 1/64: exact in float32
RECEIVER = [4.203125, 2.296875, 1.6875]


def pra_room(order=ORDER):
    pra.constants.set("rir_hpf_enable", False)
    room = pra.Room.from_corners(
        np.array(CORNERS, dtype=float).T, fs=RATE, max_order=order,
        materials=[pra.Material(energy_absorption=a) for a in ALPHAS],
        ray_tracing=False, air_absorption=False,
    )
    room.extrude(HEIGHT, materials={
        "floor": pra.Material(energy_absorption=FLOOR),
        "ceiling": pra.Material(energy_absorption=CEILING),
    })
    room.add_source(SOURCE)
    room.add_microphone(RECEIVER)
    room.compute_rir()
    return room


def ours(order=ORDER):
    room = rooms.from_corners(
        np.array(CORNERS, dtype=float).T, HEIGHT, absorption=ALPHAS, floor=FLOOR,
        ceiling=CEILING, fs=RATE, max_order=order,
    )
    room.add_source(SOURCE)
    room.add_microphone(RECEIVER)
    return room


def visible_images(room):
    """pyroomacoustics' visible images (each position once: a path through a vertical edge
    can come twice) with their dampings, and how many it listed twice."""
    src = room.sources[0]
    visible = np.asarray(room.visibility[0][0], dtype=bool)
    images = src.images[:, visible].T.astype(float)
    damping = src.damping[0, visible].astype(float)
    _, first = np.unique(np.round(images, 6), axis=0, return_index=True)
    return images[first], damping[first], len(images) - len(first)


def placed(distances, damping, samples):
    """Each image's `damping / distance` placed by pyroomacoustics' own filter,
    `pra.utilities.fractional_delay` (Hann(81) x sinc), 40 samples late."""
    h = np.zeros(samples + 81)
    for dist, a in zip(distances, damping):
        position = dist / 343.0 * RATE
        whole = int(np.floor(position))
        if whole < samples:
            h[whole : whole + 81] += a / dist * pra.utilities.fractional_delay(position - whole)
    return h[40 : 40 + samples]


def test_the_arrivals_and_the_response_are_pyroomacoustics():
    room = pra_room()
    arrivals = ours().arrivals()
    h_pra = np.asarray(room.rir[0][0], dtype=float)
    n = len(h_pra) - 40
    images, damping, twice = visible_images(room)
    distances = np.linalg.norm(images - np.asarray(RECEIVER, dtype=float), axis=1)
    print(f"pyroomacoustics: {room.sources[0].images.shape[1]} images to order {ORDER}, "
          f"{len(images) + twice} visible ({twice} listed twice); eigenray: "
          f"{len(arrivals)} arrivals")
    # The same arrivals as its visible images: times to its float32 images' precision.
    assert len(arrivals) == len(images) > 100
    times = np.sort(arrivals.time)
    assert np.max(np.abs(times - np.sort(distances) / 343.0)) < 1e-6
    h = 4 * math.pi * ours().tracer().impulse_response(rate=RATE, duration=n / RATE)[0, 0]
    # Its dampings at the exact distances (its images' float32 rounding taken out): the
    # same response to round-off.
    exact = [times[np.argmin(np.abs(times - d / 343.0))] * 343.0 for d in distances]
    error = np.linalg.norm(h - placed(exact, damping, n)) / np.linalg.norm(h)
    assert error < 1e-6, f"relative L2 difference {error:.2e} from its dampings"
    # Its images as it computes them (float32: up to ~2e-3 of a sample at order 6).
    error = np.linalg.norm(h - placed(distances, damping, n)) / np.linalg.norm(h)
    print(f"relative L2 difference from its images: {error:.2e}")
    assert error < 5e-4, f"relative L2 difference {error:.2e} from its images"
    error = np.linalg.norm(h - h_pra[40 : 40 + n]) / np.linalg.norm(h_pra)
    print(f"relative L2 difference from compute_rir: {error:.2e}")
    assert error < 3e-3


def test_the_decay_times_beside_measure_rt60():
    # A shoebox (pyroomacoustics' high orders are fast there only), each face its own
    # absorption; pyroomacoustics to order 60, eigenray every arrival within 0.4 s.
    size, alphas = [5.0, 4.0, 3.0], [0.2, 0.4, 0.1, 0.3, 0.35, 0.05]
    names = ["west", "east", "south", "north", "floor", "ceiling"]
    pra.constants.set("rir_hpf_enable", False)
    box = pra.ShoeBox(
        size, fs=RATE, max_order=60, ray_tracing=False, air_absorption=False,
        materials={n: pra.Material(energy_absorption=a) for n, a in zip(names, alphas)},
    )
    box.add_source(SOURCE)
    box.add_microphone(RECEIVER)
    box.compute_rir()
    h_pra = np.asarray(box.rir[0][0], dtype=float)
    # Walls from corner k to corner k + 1: south, east, north, west.
    corners = np.array([[0, 0], [5, 0], [5, 4], [0, 4]], dtype=float).T
    room = rooms.from_corners(
        corners, 3.0, absorption=[alphas[2], alphas[1], alphas[3], alphas[0]],
        floor=alphas[4], ceiling=alphas[5], fs=RATE, max_time=0.4,
    )
    room.add_source(SOURCE)
    room.add_microphone(RECEIVER)
    found = room.room_parameters()[0]
    for name, decay in [("t20", 20), ("t30", 30)]:
        value = pra.experimental.measure_rt60(h_pra, fs=RATE, decay_db=decay)
        print(f"{name}: eigenray {found[name]:.4f} s, measure_rt60 {value:.4f} s "
              f"({100 * (found[name] - value) / value:+.1f} %)")
        # Different fits of one decay (measure_rt60: two points of the curve from −5 dB;
        # here a least-squares line): close, not equal.
        assert abs(found[name] - value) < 0.1 * value
