"""eigenray's impulse response beside pyroomacoustics' `compute_rir`, in one picture: the
L-shaped room of `python/tests/test_response.py` (walls absorbing 10 % of the energy, every
reflection to order 3, 16 kHz), pyroomacoustics' response shifted back by its 40-sample delay
and eigenray's multiplied by 4π (pyroomacoustics leaves out 1/(4π)), and their difference
magnified 100 times.

How to run (pyroomacoustics and matplotlib in a venv, the package installed):
  python benches/rir_against_pyroomacoustics.py [picture.png]
"""

import argparse
import math
import pathlib
import sys

# The arguments first: `--help` prints this and writes nothing (not a picture named `--help`).
parser = argparse.ArgumentParser(
    description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
)
parser.add_argument(
    "picture",
    nargs="?",
    default="rir_against_pyroomacoustics.png",
    help="the PNG written (default: rir_against_pyroomacoustics.png)",
)
picture = parser.parse_args().picture

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python" / "tests"))
import eigenray  # noqa: E402
import test_response as rooms  # noqa: E402

corners, source, receiver, order = rooms.ROOMS["L"]
room = rooms.pra_room(corners, source, receiver, order)
h_pra = np.asarray(room.rir[0][0], dtype=float)
n = len(h_pra) - 40
tracer = eigenray.Tracer(eigenray.Scene(rooms.room_scene(corners, source, receiver, order)))
ours = 4 * math.pi * tracer.impulse_response(rate=rooms.RATE, duration=n / rooms.RATE)[0, 0]
theirs = h_pra[40 : 40 + n]
error = np.linalg.norm(ours - theirs) / np.linalg.norm(theirs)

t = np.arange(n) / rooms.RATE * 1000
fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
ax.plot(t, theirs, color="tab:orange", linewidth=2.4, label="pyroomacoustics compute_rir")
ax.plot(t, ours, color="black", linewidth=0.8, label="eigenray impulse_response × 4π")
ax.plot(t, 100 * (ours - theirs) - 0.45, color="tab:red", linewidth=0.8,
        label="difference × 100 (offset)")
ax.set_xlabel("time (ms)")
ax.set_ylabel("pressure × 4π")
ax.set_title(f"L-shaped room, order {order}, {rooms.RATE} Hz: relative L2 difference "
             f"{error:.1e}", fontsize=10)
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
fig.savefig(picture, dpi=120)
print(f"wrote {picture}: relative L2 difference {error:.2e}")
