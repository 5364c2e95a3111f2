"""Extruded rooms against pyroomacoustics, one thread, alternating in one run: the L-shaped
room of `python/tests/test_rooms_pyroomacoustics.py` extruded to 3 m (a different absorption
per wall, floor and ceiling), 1 source x 10 microphones, every path to `--order` reflections:
pyroomacoustics' `from_corners(...).extrude(...)` + `compute_rir` against
`eigenray.rooms.from_corners(...)` + `compute_rir`, best of `--repeat`.

How to run (pyroomacoustics in a venv, the package installed):
  RAYON_NUM_THREADS=1 python benches/extruded_rooms.py --order 6
"""

import argparse
import time

import numpy as np
import pyroomacoustics as pra

from eigenray import rooms

parser = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--order", type=int, default=6)
parser.add_argument("--repeat", type=int, default=3)
args = parser.parse_args()

RATE = 16000
CORNERS = np.array([[0, 0], [5, 0], [5, 3], [3, 3], [3, 5], [0, 5]], dtype=float).T
ALPHAS = [0.2, 0.4, 0.1, 0.3, 0.25, 0.15]
FLOOR, CEILING, HEIGHT = 0.35, 0.05, 3.0
SOURCE = [1.125, 0.875, 1.3125]
MICS = [[4.203125 - 0.3 * k % 3.0, 2.296875 + 0.05 * k, 1.6875] for k in range(5)] + [
    [0.703125 + 0.2 * k, 4.296875 - 0.3 * k, 1.1875 + 0.1 * k] for k in range(5)
]


def theirs():
    pra.constants.set("rir_hpf_enable", False)
    room = pra.Room.from_corners(
        CORNERS, fs=RATE, max_order=args.order,
        materials=[pra.Material(energy_absorption=a) for a in ALPHAS],
        ray_tracing=False, air_absorption=False,
    )
    room.extrude(HEIGHT, materials={"floor": pra.Material(energy_absorption=FLOOR),
                                    "ceiling": pra.Material(energy_absorption=CEILING)})
    room.add_source(SOURCE)
    room.add_microphone_array(np.array(MICS).T)
    room.compute_rir()
    return room


def ours():
    room = rooms.from_corners(CORNERS, HEIGHT, absorption=ALPHAS, floor=FLOOR,
                              ceiling=CEILING, fs=RATE, max_order=args.order)
    room.add_source(SOURCE)
    for m in MICS:
        room.add_microphone(m)
    return room.compute_rir()


best = {"pyroomacoustics": float("inf"), "eigenray": float("inf")}
for _ in range(args.repeat):
    for name, f in [("pyroomacoustics", theirs), ("eigenray", ours)]:
        started = time.perf_counter()
        f()
        best[name] = min(best[name], time.perf_counter() - started)
print(f"order {args.order}, 1 source x {len(MICS)} microphones: pyroomacoustics "
      f"{best['pyroomacoustics']:.3f} s, eigenray {best['eigenray']:.3f} s, "
      f"ratio {best['pyroomacoustics'] / best['eigenray']:.1f}")
