"""Room impulse responses in the comb-shaped room of pyroomacoustics issue #383 (12 walls, each
absorbing 10 % of the energy), 1 source x 9 listeners, 16 kHz: eigenray's every arrival up to
0.1 s against pyroomacoustics' `image_source_model` + `compute_rir` at the highest order it
can reach in seconds, side by side in one run; then the samples of both where they cover the
same arrivals.

eigenray: `Tracer(scene)` and `tracer.impulse_response()` of a scene whose search is
`{"max_time": 0.1}` (every arrival before 0.1 s, any order; the room as one closed polyline),
timed in this process on one thread (RAYON_NUM_THREADS=1). pyroomacoustics 0.10:
`Room.from_corners(..., max_order=K)`, `image_source_model()` and `compute_rir()`, its order
capped at PRA_ORDER (order 9 takes about 15 s for the nine listeners, each order 4-6 times
the one before; reaching 0.1 s would need order ORDER_NEEDED, the highest order among
eigenray's arrivals, which it cannot reach).

Samples: at order SAMPLE_ORDER both lists are complete; pyroomacoustics' visible images
include some that are no valid path in this non-convex room (see benches/comb_room.py), so the
comparison places its visible images that eigenray also finds (matched by distance, 1e-5)
with its own exact filter (`pra.utilities.fractional_delay`, Hann(81) x sinc, 40 samples late,
damping / distance), and compares 4 pi times eigenray's response with them.

How to run (pyroomacoustics in the venv, the package installed):
  RAYON_NUM_THREADS=1 python benches/comb_rir.py [ROUNDS]
"""

import math
import os
import statistics
import sys
import time

os.environ.setdefault("RAYON_NUM_THREADS", "1")

import eigenray  # noqa: E402
import numpy as np  # noqa: E402
import pyroomacoustics as pra  # noqa: E402

RATE = 16000
SPEED = 343.0
ABSORPTION = 0.1
MAX_TIME = 0.1
PRA_ORDER = 9
SAMPLE_ORDER = 6
CORNERS = [[0, 0], [0, 5], [1, 5], [1, 2], [2, 2], [2, 5], [3, 5], [3, 0], [2, 0], [2, 1],
           [1, 1], [1, 0]]
SOURCE = [0.5, 0.5]
LISTENERS = [[2.5, 4.5], [0.5, 4.5], [0.5, 2.5], [2.5, 2.5], [2.5, 0.5], [1.5, 1.5],
             [0.25, 1.25], [2.75, 3.75], [1.25, 1.75]]


def scene(search, duration):
    return eigenray.Scene({
        "media": {"air": {"speed": SPEED, "at": SOURCE}},
        "interfaces": {"room": {"points": CORNERS, "closed": True,
                                "reflection": {"absorption": ABSORPTION}}},
        "sources": [SOURCE],
        "receivers": LISTENERS,
        "search": search,
        "amplitudes": {"source": "point"},
        "impulse_response": {"rate": RATE, "duration": duration},
    })


def pra_room(order):
    pra.constants.set("rir_hpf_enable", False)
    room = pra.Room.from_corners(np.array(CORNERS, dtype=float).T, fs=RATE, max_order=order,
                                 materials=pra.Material(energy_absorption=ABSORPTION),
                                 ray_tracing=False, air_absorption=False)
    room.add_source(SOURCE)
    room.add_microphone_array(pra.MicrophoneArray(np.array(LISTENERS, dtype=float).T, RATE))
    return room


def time_eigenray(doc_scene):
    t0 = time.perf_counter()
    tracer = eigenray.Tracer(doc_scene)
    h = tracer.impulse_response()
    return (time.perf_counter() - t0) * 1e3, h, tracer


def time_pra(order):
    room = pra_room(order)
    t0 = time.perf_counter()
    room.image_source_model()
    room.compute_rir()
    return (time.perf_counter() - t0) * 1e3, room


def matched_images_response(room, receiver, valid, samples):
    """pyroomacoustics' visible images of listener `receiver` that are valid paths (their
    distances within 1e-5 of one of `valid`), each placed by its exact filter."""
    src = room.sources[0]
    visible = np.asarray(room.visibility[0][receiver], dtype=bool)
    mic = np.array(LISTENERS[receiver], dtype=float)
    left = sorted(valid)
    h = np.zeros(samples + 81)
    used = 0
    for i in np.nonzero(visible)[0]:
        dist = float(np.hypot(*(src.images[:, i] - mic)))
        k = min(range(len(left)), key=lambda j: abs(left[j] - dist), default=None)
        if k is None or abs(left[k] - dist) > 1e-5 * dist:
            continue
        left.pop(k)
        used += 1
        position = dist / SPEED * RATE
        whole = int(math.floor(position))
        if whole + 81 <= len(h):
            h[whole: whole + 81] += (float(src.damping[0][i]) / dist
                                     * pra.utilities.fractional_delay(position - whole))
    return h[40: 40 + samples], used


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    full = scene({"max_time": MAX_TIME, "refract": False}, MAX_TIME)
    _, _, tracer = time_eigenray(full)
    echoes = tracer.echoes()
    needed = int(echoes["order"].max())
    ours, theirs = [], []
    for _ in range(rounds):
        ms, h, _ = time_eigenray(full)
        ours.append(ms)
        ms_pra, room = time_pra(PRA_ORDER)
        theirs.append(ms_pra)
    m_ours, m_pra = statistics.median(ours), statistics.median(theirs)
    ratios = [p / o for p, o in zip(theirs, ours)]
    covered = max(len(r[0]) for r in room.rir) / RATE
    print(f"comb room, 1 source x {len(LISTENERS)} listeners, {RATE} Hz, absorption "
          f"{ABSORPTION}; {rounds} rounds alternating, the median round:")
    print("| tool | what it computes | time | pyroomacoustics / eigenray "
          "(rounds: least, most) |")
    print("| --- | --- | ---: | ---: |")
    print(f"| eigenray `Tracer` + `impulse_response` | every arrival to {MAX_TIME} s: "
          f"{len(echoes['time'])} echoes, orders up to {needed} | {m_ours:.1f} ms | "
          f"{m_pra / m_ours:.0f}x ({min(ratios):.0f}x, {max(ratios):.0f}x) |")
    print(f"| pyroomacoustics `image_source_model` + `compute_rir` | order {PRA_ORDER} "
          f"(capped; {MAX_TIME} s needs order {needed}) | {m_pra:.0f} ms | 1 |")
    print(f"pyroomacoustics' order {PRA_ORDER} responses run to {covered:.3f} s, but hold "
          f"only the images of up to {PRA_ORDER} reflections")

    # The samples where both cover the same arrivals: order SAMPLE_ORDER.
    samples = int(0.06 * RATE)
    part = scene({"max_steps": SAMPLE_ORDER, "refract": False}, samples / RATE)
    t = eigenray.Tracer(part)
    h = 4 * math.pi * t.impulse_response()[0]
    arrivals = t.search()
    room = pra_room(SAMPLE_ORDER)
    room.image_source_model()
    worst, used_all, visible_all = 0.0, 0, 0
    for r in range(len(LISTENERS)):
        valid = [a["time"] * SPEED for a in arrivals if a["receiver"] == r]
        reference, used = matched_images_response(room, r, valid, samples)
        used_all += used
        visible_all += int(np.sum(room.visibility[0][r]))
        error = np.linalg.norm(h[r] - reference) / np.linalg.norm(reference)
        worst = max(worst, error)
    print(f"order {SAMPLE_ORDER}, first {samples} samples: eigenray's {len(arrivals)} arrivals; "
          f"pyroomacoustics' {visible_all} visible images, {used_all} of them eigenray's "
          f"arrivals, the others no valid path; eigenray's response against those "
          f"{used_all} placed by pyroomacoustics' filter: largest relative L2 difference "
          f"{worst:.1e} over the listeners")


if __name__ == "__main__":
    main()
