"""Extruded rooms from Python (`eigenray.rooms`, `"extrusion"` scenes): the 3-D arrivals
against an independent enumeration written here (the 2-D plan search's paths × the vertical
image sources), 3-D points and floor/ceiling steps, the room parameters against a Schroeder
integration written here, and keys named for bad rooms."""

import numpy as np
import pytest

import eigenray
from eigenray import rooms

SPEED = 343.0
CORNERS = [[0, 0], [6, 0], [6, 3], [3, 3], [3, 5], [0, 5]]
ALPHAS = [0.1, 0.2, 0.3, 0.15, 0.25, 0.35]
HEIGHT = 3.0
SOURCE = [1.0, 1.2, 1.1]
MICS = [[5.1, 2.2, 1.7], [1.4, 4.1, 2.6]]


def l_room(max_order=5, max_time=None):
    room = rooms.from_corners(
        np.array(CORNERS, dtype=float).T, HEIGHT, absorption=ALPHAS, floor=0.4,
        ceiling=0.05, fs=8000, max_order=max_order, max_time=max_time,
    )
    room.add_source(SOURCE)
    for m in MICS:
        room.add_microphone(m)
    return room


def vertical_images(zs, zr, h, most):
    """(reflections, unfolded vertical length) of every alternating floor/ceiling sequence
    of up to `most` reflections: the floor z -> -z and the ceiling z -> 2h - z in turn."""
    out = [(0, abs(zr - zs))]
    for floor_first in (True, False):
        z, floor = zs, floor_first
        for n in range(1, most + 1):
            z = -z if floor else 2 * h - z
            floor = not floor
            out.append((n, abs(zr - z)))
    return out


def test_the_arrivals_are_the_plan_paths_times_their_vertical_images():
    order = 5
    room = l_room(order)
    arrivals = room.arrivals()
    # The plan: the same walls in 2-D, its own search.
    doc = room.scene_dict()
    del doc["extrusion"]
    doc["sources"] = [p[:2] for p in doc["sources"]]
    doc["receivers"] = [p[:2] for p in doc["receivers"]]
    plan = eigenray.Tracer(eigenray.Scene(doc)).search()
    want = []
    for a in plan:
        length = np.sum(np.linalg.norm(np.diff(a["points"], axis=0), axis=1))
        r = a["receiver"]
        for n, z in vertical_images(SOURCE[2], MICS[r][2], HEIGHT, order):
            if len(a["steps"]) + n <= order:
                want.append((r, np.hypot(length, z) / SPEED))
    want.sort()
    got = sorted(zip(arrivals.receiver.tolist(), arrivals.time.tolist()))
    assert len(got) == len(want) > 100
    for (gr, gt), (wr, wt) in zip(got, want):
        assert gr == wr and abs(gt - wt) <= 1e-12 * wt


def test_points_are_3d_and_steps_name_the_floor_and_ceiling():
    arrivals = l_room(3).arrivals()
    assert arrivals.points.shape[2] == 3
    seen = set()
    for a in arrivals:
        p = a["points"]
        assert p.shape == (len(a["steps"]) + 2, 3)
        for step, point in zip(a["steps"], p[1:-1]):
            name = step["reflect"]
            seen.add(name)
            if name == "floor":
                assert point[2] == 0.0
            elif name == "ceiling":
                assert point[2] == HEIGHT
        # The legs add up to the path's length.
        length = np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))
        assert abs(length / SPEED - a["time"]) < 1e-12
    assert {"floor", "ceiling", "wall0"} <= seen


def test_room_parameters_match_a_schroeder_integration_written_here():
    room = l_room(max_order=None, max_time=0.35)
    tracer = room.tracer()
    h = tracer.impulse_response()[0, 0]
    found = tracer.room_parameters()
    assert len(found) == 2 and found[0]["receiver"] == 0
    p = found[0]
    t0 = p["first_arrival"]
    rate = 8000.0
    energy = h * h
    tail = np.cumsum(energy[::-1])[::-1]
    level = 10 * np.log10(tail / tail[0])
    start = int(np.floor(t0 * rate))
    last = start + int(np.argmax(level[start:] < -25.0))
    n = np.arange(start, last)
    keep = (level[n] <= -5.0) & (level[n] >= -25.0)
    slope = np.polyfit(n[keep] / rate, level[n][keep], 1)[0]
    assert p["t20"] == pytest.approx(-60.0 / slope, rel=0.01)
    cut = int(np.ceil((t0 + 0.05) * rate))
    early, total = energy[:cut].sum(), energy.sum()
    assert p["c50"] == pytest.approx(10 * np.log10(early / (total - early)), rel=0.01)
    assert p["d50"] == pytest.approx(early / total, rel=0.01)
    # 0.35 s of response is too short for T30 here, or T30 is a number: never both.
    assert (p["t30"] is None) == ("t30_reason" in p)


def test_a_bad_room_names_its_key():
    room = l_room(3)
    room.microphones[1] = [1.4, 4.1, 3.5]
    with pytest.raises(eigenray.EigenrayError, match=r"receivers\[1\]"):
        room.scene()
    with pytest.raises(ValueError, match="absorption"):
        rooms.from_corners(np.array(CORNERS).T, 3.0, absorption=[0.1, 0.2], max_order=2)


def test_a_level_map_is_the_energy_sum_of_each_listeners_arrivals():
    """The grid at one height against each listener's arrivals listed and summed here."""
    room = l_room(4)
    xs, ys, z = np.linspace(0.5, 4.5, 3), np.linspace(0.5, 4.5, 4), 1.6
    level = room.level_map((0.5, 4.5, 3), (0.5, 4.5, 4), z=z, frequency=250)
    assert level.shape == (1, 3, 4)
    listed = l_room(4)
    listed.microphones = [[x, y, z] for x in xs for y in ys]
    doc = listed.scene_dict()
    doc["amplitudes"]["frequency"] = 250.0
    arrivals = eigenray.Tracer(eigenray.Scene(doc)).search()
    energy = np.zeros(len(listed.microphones))
    for a in arrivals:
        energy[a["receiver"]] += abs(complex(a["amplitude"])) ** 2
    with np.errstate(divide="ignore"):
        want = 10 * np.log10((4 * np.pi) ** 2 * energy).reshape(3, 4)
    # The plan's missing corner (x > 3, y > 3) hears nothing.
    assert np.isneginf(want[2, 2:]).all() and np.isfinite(want[:2]).all()
    np.testing.assert_allclose(level[0], want, rtol=0, atol=1e-9)
    coherent = room.level_map((0.5, 4.5, 3), (0.5, 4.5, 4), z=z, frequency=250, mode="coherent")
    assert coherent.shape == (1, 3, 4) and np.isneginf(coherent[0, 2, 2:]).all()
