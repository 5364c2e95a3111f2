"""pyroomacoustics' image source model on two 2-D rooms, for comparison with eigenray's
mirror search (src/trace/mirrors.rs).

What it measures: the in-process time of `room.image_source_model()` (pyroomacoustics 2-D,
`max_order=4`, no ray tracing) on (a) a convex hexagon with 2 sources x 8 receivers and (b) an
L-shaped room with 3 sources x 9 receivers: the median of many repetitions after a warm-up
(the model is recomputed each time: `simulator_state["ism_needed"]` is set again before each
call). It also records, per (source, receiver), every image path that pyroomacoustics finds
visible: its order, image position, distance and the wall sequences that produce that image
(pyroomacoustics 0.10 no longer reports the sequence, so it is recovered by mirroring the
source in every sequence of walls of that order and matching the image; two sequences can
give one image, as at a right-angled corner).

Coordinates are multiples of 1/64, exact in float32 (pyroomacoustics keeps walls in float32),
so that both libraries see the same geometry.

Writes:
  fixtures/pyroomacoustics/rooms.json   rooms, sources, receivers, times, visible paths
  fixtures/pyroomacoustics/hexagon.json eigenray scene of room (a): wall i is interface `w{i}`
  fixtures/pyroomacoustics/l_shape.json eigenray scene of room (b)
(the scenes carry the automatic search's section, `"search": {"max_steps": 4, "refract":
false}`).

How to run (a venv outside the repository):
  python3 -m venv ../venv-pra && ../venv-pra/bin/pip install pyroomacoustics numpy
  ../venv-pra/bin/python benches/pyroomacoustics_rooms.py [repetitions]
then eigenray's side, the comparison and its timing:
  cargo test --profile test-opt --lib mirrors::tests::pyroomacoustics -- --nocapture
  cargo test --release --lib mirrors -- --ignored --nocapture
"""

import itertools
import json
import os
import statistics
import sys
import time

import numpy as np
import pyroomacoustics as pra

ORDER = 4
SPEED = 343.0
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
OUT = os.path.join(ROOT, "fixtures", "pyroomacoustics")


def q(x):
    """`x` rounded to a multiple of 1/64 (exact in float32)."""
    return round(x * 64.0) / 64.0


def rooms():
    """The two rooms: name, corners (counter-clockwise), sources, receivers."""
    hexagon = [
        [q(3.0 * np.cos(a) + 0.21 * np.sin(3 * a)), q(2.4 * np.sin(a) + 0.13 * np.cos(2 * a))]
        for a in np.linspace(0.0, 2.0 * np.pi, 6, endpoint=False) + 0.1
    ]
    hex_sources = [[q(-0.83), q(0.37)], [q(1.12), q(-0.64)]]
    hex_receivers = [
        [q(-1.9 + 0.53 * i), q(-1.1 + 0.31 * ((i * 5) % 8))] for i in range(8)
    ]
    l_shape = [[0.0, 0.0], [6.0, 0.0], [6.0, q(2.6)], [q(2.3), q(2.6)], [q(2.3), 5.0], [0.0, 5.0]]
    l_sources = [[q(1.1), q(0.9)], [q(4.7), q(1.3)], [q(1.2), q(4.1)]]
    l_receivers = [
        [q(0.4 + 0.61 * i), q(0.5 + 0.23 * ((i * 3) % 9))] if i < 7
        else [q(0.6 + 0.8 * (i - 7)), q(3.3 + 0.7 * (i - 7))]
        for i in range(9)
    ]
    return [
        ("hexagon", hexagon, hex_sources, hex_receivers),
        ("l_shape", l_shape, l_sources, l_receivers),
    ]


def mirror(x, a, b):
    """`x` mirrored in the line through `a` and `b`."""
    e = b - a
    n = np.array([-e[1], e[0]]) / np.hypot(e[0], e[1])
    return x - 2.0 * np.dot(n, x - a) * n


def sequences_of_images(corners, source):
    """Every wall sequence of 1..ORDER walls (none twice in a row) with its image."""
    walls = [(corners[i], corners[(i + 1) % len(corners)]) for i in range(len(corners))]
    found = {0: [((), source)]}
    for k in range(1, ORDER + 1):
        found[k] = [
            (seq + (w,), mirror(img, *walls[w]))
            for seq, img in found[k - 1]
            for w in range(len(walls))
            if not seq or seq[-1] != w
        ]
    return found


def build(corners, sources, receivers):
    """The pyroomacoustics room."""
    room = pra.Room.from_corners(
        np.array(corners, dtype=float).T, fs=16000, max_order=ORDER, ray_tracing=False
    )
    for s in sources:
        room.add_source(s)
    room.add_microphone_array(pra.MicrophoneArray(np.array(receivers, dtype=float).T, room.fs))
    return room


def time_ism(room, repetitions):
    """Median wall time of `image_source_model()` (ms) after a warm-up."""
    times = []
    for i in range(repetitions + 20):
        room.simulator_state["ism_needed"] = True
        t0 = time.perf_counter()
        room.image_source_model()
        t1 = time.perf_counter()
        if i >= 20:
            times.append((t1 - t0) * 1e3)
    return statistics.median(times)


def scene(corners, sources, receivers):
    """The eigenray scene of a room."""
    n = len(corners)
    return {
        "media": {"air": {"speed": SPEED, "at": sources[0]}},
        "interfaces": {
            f"w{i}": {"points": [corners[i], corners[(i + 1) % n]]} for i in range(n)
        },
        "sources": sources,
        "receivers": receivers,
        "paths": [{"steps": [], "media": ["air"]}],
        "search": {"max_steps": ORDER, "refract": False},
    }


def main():
    repetitions = int(sys.argv[1]) if len(sys.argv) > 1 else 500
    os.makedirs(OUT, exist_ok=True)
    report = {"pyroomacoustics": pra.__version__, "order": ORDER, "speed": SPEED, "rooms": []}
    for name, corners, sources, receivers in rooms():
        room = build(corners, sources, receivers)
        median = time_ism(room, repetitions)
        room.simulator_state["ism_needed"] = True
        room.image_source_model()
        paths = []
        for s, src in enumerate(sources):
            source = room.sources[s]
            by_order = sequences_of_images(np.array(corners, dtype=float), np.array(src, dtype=float))
            for r, rec in enumerate(receivers):
                found = []
                for i in range(source.images.shape[1]):
                    if not room.visibility[s][r, i]:
                        continue
                    image = source.images[:, i].astype(float)
                    k = int(source.orders[i])
                    seqs = [
                        list(seq)
                        for seq, img in by_order[k]
                        if np.hypot(*(img - image)) <= 1e-4 * (1.0 + np.hypot(*image))
                    ]
                    distance = float(np.hypot(*(image - np.array(rec, dtype=float))))
                    found.append(
                        {
                            "order": k,
                            "image": image.tolist(),
                            "distance": distance,
                            "time": distance / SPEED,
                            "sequences": seqs,
                        }
                    )
                found.sort(key=lambda f: f["distance"])
                paths.append({"source": s, "receiver": r, "images": found})
        report["rooms"].append(
            {
                "name": name,
                "corners": corners,
                "sources": sources,
                "receivers": receivers,
                "image_source_model_ms": median,
                "repetitions": repetitions,
                "paths": paths,
            }
        )
        with open(os.path.join(OUT, f"{name}.json"), "w") as f:
            json.dump(scene(corners, sources, receivers), f, indent=1)
        count = sum(len(p["images"]) for p in paths)
        print(f"{name}: image_source_model {median:.3f} ms (median of {repetitions}), {count} visible paths")
    with open(os.path.join(OUT, "rooms.json"), "w") as f:
        json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
