"""The Python package against the Rust library and the seed's numpy + autograd gradient
descent, on the seed's scene: one refraction (air over water, index 1 / 1.333, the surface
y = 0 from x = -1 to 2, source (0, 1)) to 100,000 receivers on a jittered grid, in one run.

    cargo build --release --example batch_timing
    pip install --force-reinstall ./python autograd   # the release build of the package
    python python/benches/bench.py [rounds]

Prints a Markdown table:
- a batch of every ray through Python (`Tracer.trace(out=rays)`, into the arrays of the
  previous result, as the Rust batch reuses its own) beside the Rust library's
  `Tracer::trace_batch_into` (the example `batch_timing`, run as a subprocess), alternating,
  the median of each over the rounds; and `Tracer.trace()` into new arrays (the first touch
  of fresh memory costs as much as the rays here);
- one-ray calls from Python (`Tracer.time` and `Tracer.solve`), per call;
- the seed's method: gradient descent on all crossing points as one numpy vector, gradients by
  autograd, run until every time is within 1e-12 (relative) of eigenray's.
"""

import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time
import timeit

import numpy as np

import eigenray

ROOT = pathlib.Path(__file__).resolve().parents[2]
# Batches a side in each round (after a warm-up), their median the round's figure: medians of
# 5 scattered the ratio of the two batches by about ±5 % on a shared 2-core machine.
BATCHES = 15
N1, N2 = 1.0, 1.333
SOURCE = (0.0, 1.0)


def seed_receivers():
    """500 × 200 receivers: X = linspace(0, 1, 500), Y = linspace(-1, -0.2, 200), each
    coordinate jittered by U[0, 1) / 10 (RandomState(2018))."""
    rng = np.random.RandomState(2018)
    x, y = np.meshgrid(np.linspace(0, 1, 500), np.linspace(-1, -0.2, 200))
    x = x.ravel() + rng.uniform(0, 1, x.size) / 10
    y = y.ravel() + rng.uniform(0, 1, y.size) / 10
    return np.column_stack([x, y])


def scene_dict(receivers):
    return {
        "media": {"air": {"index": N1}, "water": {"index": N2}},
        "interfaces": {"surface": {"points": [[-1.0, 0.0], [2.0, 0.0]]}},
        "sources": [list(SOURCE)],
        "receivers": receivers.tolist(),
        "paths": [{"name": "transmitted", "steps": [{"refract": "surface"}],
                   "media": ["air", "water"]}],
    }


def rust_batch_seconds(scene_file, repetitions):
    binary = ROOT / "target" / "release" / "examples" / "batch_timing"
    out = subprocess.run([str(binary), str(scene_file), str(repetitions)],
                         capture_output=True, text=True, check=True)
    return float(out.stdout)


def python_batch_seconds(tracer, repetitions, reuse):
    """The median time of `Tracer.trace()`: into new arrays, or (`reuse`) into the arrays
    of the previous result (`out=`), as the Rust batch reuses its own."""
    rays = tracer.trace()  # warm-up
    runs = []
    for _ in range(repetitions):
        start = time.perf_counter()
        if reuse:
            tracer.trace(out=rays)
        else:
            tracer.trace()
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def seed_gradient_descent(receivers, reference, tolerance=1e-12, most=10_000):
    """The seed's method: x (one crossing per receiver) by gradient descent with autograd."""
    import autograd.numpy as anp
    from autograd import grad

    rx, ry = receivers[:, 0], receivers[:, 1]
    sx, sy = SOURCE

    def total_time(x):
        return anp.sum(N1 * anp.sqrt((x - sx) ** 2 + sy**2) + N2 * anp.sqrt((rx - x) ** 2 + ry**2))

    def times(x):
        return N1 * np.sqrt((x - sx) ** 2 + sy**2) + N2 * np.sqrt((rx - x) ** 2 + ry**2)

    gradient = grad(total_time)
    x = rx * sy / (sy - ry)  # the straight line's crossing
    # The largest fixed step that converges here: T's curvature along x reaches 14.1 on
    # these receivers (the shallowest, 0.1 under the surface), so a step must stay below
    # 2 / 14.1; 0.2 and more oscillate for ever.
    step = 0.1
    start = time.perf_counter()
    for iteration in range(1, most + 1):
        x = x - step * gradient(x)
        error = np.max(np.abs(times(x) - reference) / reference)
        if error <= tolerance:
            break
    seconds = time.perf_counter() - start
    return seconds, iteration, error


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    receivers = seed_receivers()
    spec = scene_dict(receivers)
    with tempfile.TemporaryDirectory() as scratch:
        scene_file = pathlib.Path(scratch) / "seed100k.json"
        scene_file.write_text(json.dumps(spec))
        scene = eigenray.Scene(scene_file)
        tracer = eigenray.Tracer(scene)
        rays = tracer.trace()
        assert (rays.status == 0).all()
        rust, python, fresh = [], [], []
        for _ in range(rounds):  # alternating
            rust.append(rust_batch_seconds(scene_file, BATCHES))
            python.append(python_batch_seconds(tracer, BATCHES, reuse=True))
            fresh.append(python_batch_seconds(tracer, BATCHES, reuse=False))
    n = len(receivers)
    rust_s, python_s = statistics.median(rust), statistics.median(python)
    fresh_s = statistics.median(fresh)

    one = eigenray.Tracer(eigenray.Scene(scene_dict(receivers[:1])))
    pairs = [(SOURCE, tuple(r)) for r in receivers[:1000]]

    def time_calls():
        for s, r in pairs:
            one.time(s, r)

    def solve_calls():
        for s, r in pairs:
            one.solve(s, r)

    time_call = min(timeit.repeat(time_calls, number=20, repeat=5)) / (20 * len(pairs))
    solve_call = min(timeit.repeat(solve_calls, number=20, repeat=5)) / (20 * len(pairs))
    gd_s, gd_iterations, gd_error = seed_gradient_descent(receivers, rays.time)

    print(f"| what ({n:,} single refractions) | time | per ray |")
    print("| --- | ---: | ---: |")
    print(f"| Rust `Tracer::trace_batch_into` (2 threads) | {rust_s * 1e3:.1f} ms "
          f"| {rust_s / n * 1e9:.0f} ns |")
    print(f"| Python `Tracer.trace(out=rays)` into the same arrays (2 threads) "
          f"| {python_s * 1e3:.1f} ms | {python_s / n * 1e9:.0f} ns |")
    print(f"| Python over Rust | {python_s / rust_s:.3f}× | |")
    print(f"| Python `Tracer.trace()` into new arrays (2 threads) | {fresh_s * 1e3:.1f} ms "
          f"| {fresh_s / n * 1e9:.0f} ns |")
    print(f"| Python `Tracer.time(s, r)`, one ray per call | | {time_call * 1e9:.0f} ns |")
    print(f"| Python `Tracer.solve(s, r)`, one `Ray` per call | | {solve_call * 1e9:.0f} ns |")
    print(f"| seed: numpy + autograd gradient descent, {gd_iterations} iterations to "
          f"{gd_error:.1e} (1 thread) | {gd_s * 1e3:.0f} ms | {gd_s / n * 1e9:.0f} ns |")


if __name__ == "__main__":
    main()
