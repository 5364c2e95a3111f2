"""Instructions per ray of a batch through Python: `Tracer.trace(out=rays)` of 100,000 single
refractions (the seed's scene: air over water), `REPS` times, with or without
`"amplitudes": {"source": "point"}`. Under callgrind at 1 and 3 repetitions, with collection
inside rayon's bridge helper only (the batch's work: the solve and the rows written, not the
scene's set-up nor threads waiting), the difference over 2 × 100,000 is the cost of one ray:

    pip install --force-reinstall ./python        # the release build of the package
    for reps in 1 3; do
      OPENBLAS_NUM_THREADS=1 RAYON_NUM_THREADS=1 valgrind --tool=callgrind \\
        --toggle-collect='rayon::iter::plumbing::bridge_producer_consumer::helper*' \\
        --callgrind-out-file=cg.$reps python python/benches/batch_instructions.py $reps
    done
    callgrind_annotate cg.1 | grep TOTALS; callgrind_annotate cg.3 | grep TOTALS

Add `amplitudes` after REPS for the scene with amplitudes. Prints nanoseconds per ray.
"""

import sys
import time

import numpy as np

import eigenray

N = 100_000


def main():
    reps = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    amplitudes = len(sys.argv) > 2 and sys.argv[2] == "amplitudes"
    receivers = np.column_stack([np.linspace(-3, 3, N), np.full(N, -1.0)])
    scene = {
        "media": {"air": {"index": 1.0}, "water": {"index": 1.333}},
        "interfaces": {"surface": {"points": [[-4, 0], [4, 0]]}},
        "sources": [[0, 1]],
        "receivers": receivers.tolist(),
        "paths": [{"steps": [{"refract": "surface"}], "media": ["air", "water"]}],
    }
    if amplitudes:
        scene["amplitudes"] = {"source": "point"}
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    rays = tracer.trace()
    start = time.perf_counter()
    for _ in range(reps):
        tracer.trace(out=rays)
    print(f"{(time.perf_counter() - start) / (reps * N) * 1e9:.2f} ns per ray")


if __name__ == "__main__":
    main()
