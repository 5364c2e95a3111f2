"""The transmission-loss map of issue 32's target: a shallow-water scene (a pressure-release
surface, a fluid bottom sloping from 100 m to 130 m deep over 5 km, "reflection": "media"),
a source at 30 m, 200 x 100 receivers, every arrival of up to 4 bounces, at 100 Hz.

Writes the scene, then runs `eigenray solve` on one thread (RAYON_NUM_THREADS=1) with
`--tl-map`, ROUNDS times, and reports the median wall and CPU time of the whole command
(parsing, search, amplitudes, the map and writing every arrival as CSV).

How to run:
  cargo build --release
  python3 benches/shallow_water_tl.py [ROUNDS]
"""

import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def scene():
    xs = [25.0 + 25.0 * i for i in range(200)]
    ys = [-1.0 - 1.0 * j for j in range(100)]
    return {
        "description": "Shallow water: 200 x 100 receivers, every arrival of up to 4 bounces.",
        "media": {
            "water": {"speed": 1500.0, "density": 1000.0},
            "sediment": {"speed": 1700.0, "density": 1800.0, "at": [10.0, -150.0]},
        },
        "background": "water",
        "domain": [[-10.0, -300.0], [5100.0, 0.0]],
        "interfaces": {
            "surface": {"points": [[-10.0, 0.0], [5100.0, 0.0]], "reflection": "pressure-release"},
            "bottom": {"points": [[-10.0, -100.0], [5100.0, -130.0]], "reflection": "media"},
        },
        "sources": [[0.0, -30.0]],
        "receivers": [[x, y] for y in ys for x in xs],
        "search": {"max_steps": 4, "refract": False},
        "amplitudes": {"source": "point", "frequency": 100.0},
    }


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    binary = ROOT / "target" / "release" / "eigenray"
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "shallow.json"
        path.write_text(json.dumps(scene()))
        walls, cpus = [], []
        for _ in range(rounds):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            subprocess.run(
                [binary, "solve", path, "--format", "csv", "--arrivals", pathlib.Path(tmp) / "a.csv",
                 "--tl-map", pathlib.Path(tmp) / "tl.svg"],
                check=True, stdout=subprocess.DEVNULL,
                env={**os.environ, "RAYON_NUM_THREADS": "1"},
            )
            walls.append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        arrivals = sum(1 for _ in open(pathlib.Path(tmp) / "a.csv")) - 1
    print(f"20,000 receivers, {arrivals} arrivals: median wall {statistics.median(walls):.3f} s, "
          f"CPU {statistics.median(cpus):.3f} s over {rounds} runs (one thread)")


if __name__ == "__main__":
    main()
