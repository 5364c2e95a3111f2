"""eigenray's amplitudes against pyroomacoustics' image sources in two 2-D rooms with absorbing
walls.

pyroomacoustics (2-D, `max_order=3`, no ray tracing, no air absorption) gives each visible
image source its damping (the product of `sqrt(1 - absorption)` of the walls it reflects off,
in float32) and its distance; its image amplitude is `damping / (4 pi distance)`. eigenray's
scene of the same room (one interface per wall, `"reflection": {"absorption": a}`, a `search`
of up to 3 reflections and `"amplitudes": {"source": "point"}`) lists every converged arrival
with its amplitude. Each pyroomacoustics image is matched to the eigenray arrival of equal
path length (to 1e-6), and the script prints the largest relative difference of the
amplitudes (float32's rounding, about 1e-7) and checks that both list the same arrivals.

Rooms: (a) a convex hexagon, (b) an L-shaped room (not convex: images are hidden by the
re-entrant corner in both). Coordinates are multiples of 1/64 (exact in float32).

How to run (a venv outside the repository):
  python3 -m venv ../venv-pra && ../venv-pra/bin/pip install pyroomacoustics numpy
  cargo build --release
  ../venv-pra/bin/python benches/amplitude_pyroomacoustics.py [path/to/eigenray]
"""

import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
import pyroomacoustics as pra

ORDER = 3
SPEED = 343.0
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def q(x):
    """`x` rounded to a multiple of 1/64 (exact in float32)."""
    return round(x * 64.0) / 64.0


def rooms():
    """The two rooms: name, corners (counter-clockwise), absorption per wall, source, receivers."""
    hexagon = [
        [q(3.0 * np.cos(a) + 0.21 * np.sin(3 * a)), q(2.4 * np.sin(a) + 0.13 * np.cos(2 * a))]
        for a in np.linspace(0.0, 2.0 * np.pi, 6, endpoint=False) + 0.1
    ]
    l_shape = [[0, 0], [6, 0], [6, 2.5], [2.5, 2.5], [2.5, 5], [0, 5]]
    return [
        ("hexagon", hexagon, [0.1, 0.35, 0.2, 0.5, 0.05, 0.3], [q(-0.83), q(0.37)],
         [[q(1.5), q(0.9)], [q(-1.2), q(-1.1)], [q(0.4), q(1.6)]]),
        ("l_shape", l_shape, [0.2, 0.4, 0.1, 0.3, 0.25, 0.15], [1.0, 1.0],
         [[5.0, 1.5], [1.5, 4.0], [4.0, 0.5]]),
    ]


def pra_images(corners, alphas, source, receiver):
    """Every visible image source of pyroomacoustics: (distance, damping)."""
    materials = [pra.Material(energy_absorption=a) for a in alphas]
    room = pra.Room.from_corners(
        np.array(corners, dtype=float).T, fs=16000, max_order=ORDER, materials=materials,
        ray_tracing=False, air_absorption=False,
    )
    room.add_source(source)
    room.add_microphone(receiver)
    room.image_source_model()
    src = room.sources[0]
    visible = room.visibility[0][0, :].astype(bool)
    images = src.images[:, visible]
    damping = src.damping[0, visible]
    dist = np.linalg.norm(images - np.array(receiver)[:, None], axis=0)
    return list(zip(dist.tolist(), damping.tolist()))


def eigenray_arrivals(binary, corners, alphas, source, receivers):
    """eigenray's arrivals for the room: per receiver, (length, amplitude)."""
    n = len(corners)
    scene = {
        "media": {"air": {"speed": SPEED}},
        "background": "air",
        "interfaces": {
            f"w{i}": {"points": [corners[i], corners[(i + 1) % n]],
                      "reflection": {"absorption": alphas[i]}}
            for i in range(n)
        },
        "sources": [source],
        "receivers": receivers,
        "search": {"max_steps": ORDER, "refract": False},
        "amplitudes": {"source": "point"},
    }
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(scene, f)
    out = subprocess.run([binary, "solve", f.name], check=True, capture_output=True, text=True)
    os.unlink(f.name)
    per = [[] for _ in receivers]
    for a in json.loads(out.stdout)["arrivals"]:
        per[a["receiver"]].append((a["time"] * SPEED, a["amplitude"][0]))
    return per


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target/release/eigenray")
    worst_all = 0.0
    for name, corners, alphas, source, receivers in rooms():
        ours = eigenray_arrivals(binary, corners, alphas, source, receivers)
        worst, count = 0.0, 0
        for r, receiver in enumerate(receivers):
            # Paths of equal length (in a room of right angles) pair up by their amplitudes.
            theirs = sorted((round(d, 6), g / (4.0 * math.pi * d), d)
                            for d, g in pra_images(corners, alphas, source, receiver))
            mine = sorted((round(length, 6), amp, length) for length, amp in ours[r])
            assert len(mine) == len(theirs), (name, r, len(mine), len(theirs))
            for (_, want, d), (_, amp, length) in zip(theirs, mine):
                assert abs(d - length) < 1e-6 * d, (name, r, d, length)
                worst = max(worst, abs(amp - want) / want)
                count += 1
        print(f"{name}: {count} arrivals, largest relative difference {worst:.2e}")
        worst_all = max(worst_all, worst)
    assert worst_all < 1e-6, worst_all


if __name__ == "__main__":
    main()
