"""eigenray's automatic search against pyroomacoustics' image source model, side by side in
one run, on the two rooms of `benches/pyroomacoustics_rooms.py` (a convex hexagon, 2 sources
x 8 receivers; an L-shaped room, 3 x 9; every wall sequence to order 4).

Per round, in alternation: pyroomacoustics' `room.image_source_model()` timed in this process
(the median of REPETITIONS calls after a warm-up, the model recomputed each time), then
eigenray's `Tracer::search` timed in the process of `examples/search_rooms.rs` (the median of
REPETITIONS calls, one thread, the tracer built once before the timing; and a figure that
includes `Tracer::new`). Reports the median over the rounds of each, and their ratio.

It also checks both tools' paths against exact ones: every wall sequence of up to 4
reflections (no wall twice in a row), its image and points computed in rational arithmetic
(the coordinates are multiples of 1/64), kept when every point lies strictly inside its wall,
every leg reaches its wall from the room's side and no leg meets another wall; its time the
exact distance over 343 m/s, to 40 digits. eigenray's arrivals must be those paths, each time
within 1e-12 relative; pyroomacoustics' visible images are compared with them too.

How to run (pyroomacoustics in a venv outside the repository):
  python3 -m venv ../venv-pra && ../venv-pra/bin/pip install pyroomacoustics numpy
  cargo build --release --example search_rooms
  ../venv-pra/bin/python benches/search_rooms.py [ROUNDS] [REPETITIONS]
"""

import decimal
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import pyroomacoustics as pra

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
import exact_rooms  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
EXAMPLE = os.path.join(ROOT, "target", "release", "examples", "search_rooms")
ORDER = 4
SPEED = 343
decimal.getcontext().prec = 40


def build(corners, sources, receivers):
    """The pyroomacoustics room, as `benches/pyroomacoustics_rooms.py` builds it."""
    room = pra.Room.from_corners(
        np.array(corners, dtype=float).T, fs=16000, max_order=ORDER, ray_tracing=False
    )
    for s in sources:
        room.add_source(s)
    room.add_microphone_array(pra.MicrophoneArray(np.array(receivers, dtype=float).T, room.fs))
    return room


def time_ism(room, repetitions):
    """Median wall time (ms) of `image_source_model()` after a warm-up."""
    for _ in range(max(1, repetitions // 10)):
        room.simulator_state["ism_needed"] = True
        room.image_source_model()
    times = []
    for _ in range(repetitions):
        room.simulator_state["ism_needed"] = True
        t0 = time.perf_counter()
        room.image_source_model()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def exact_paths(corners, sources, receivers):
    """{(source, receiver): {walls tuple: exact time as Decimal}} of every valid path: the
    exhaustive enumeration of `python/tests/exact_rooms.py`, in rational arithmetic."""
    out = {}
    for si, s in enumerate(sources):
        paths = exact_rooms.exact_paths(corners, s, receivers, ORDER, exhaustive=True)
        for ri, found in paths.items():
            out[(si, ri)] = {
                seq: (decimal.Decimal(d2.numerator) / decimal.Decimal(d2.denominator)).sqrt()
                / SPEED
                for seq, (d2, _) in found.items()
            }
    return out


def run_example(repetitions, arrivals=False):
    args = [EXAMPLE, str(repetitions)] + (["--arrivals"] if arrivals else [])
    text = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return {d["room"]: d for d in map(json.loads, text.splitlines())}


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 7
    repetitions = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    with open(os.path.join(ROOT, "fixtures", "pyroomacoustics", "rooms.json")) as f:
        spec = {r["name"]: r for r in json.load(f)["rooms"]}
    rooms = {n: build(r["corners"], r["sources"], r["receivers"]) for n, r in spec.items()}

    # Which paths: eigenray's arrivals and pyroomacoustics' visible images against exact ones.
    listing = run_example(1, arrivals=True)
    for name, r in spec.items():
        exact = exact_paths(r["corners"], r["sources"], r["receivers"])
        n_exact = sum(len(v) for v in exact.values())
        ours = {}
        for s, rec, walls, status, t, _segments in listing[name]["list"]:
            ours.setdefault((s, rec), {})[tuple(int(w[1:]) for w in walls)] = (status, t)
        missing, extra, worst = [], [], 0.0
        for key, paths in exact.items():
            got = ours.get(key, {})
            for seq, t in paths.items():
                if seq not in got:
                    missing.append((key, seq))
                else:
                    worst = max(worst, abs(decimal.Decimal(got[seq][1]) / t - 1))
            extra += [(key, seq) for seq in got if seq not in paths]
        statuses = sorted({st for v in ours.values() for st, _ in v.values()})
        print(f"{name}: {n_exact} exact paths; eigenray {sum(len(v) for v in ours.values())} "
              f"arrivals ({', '.join(statuses)}), missing {len(missing)}, extra {len(extra)}, "
              f"largest relative time error {float(worst):.2e}")
        for m in missing[:10]:
            print("  eigenray misses", m)
        for e in extra[:10]:
            print("  eigenray lists", e)
        # pyroomacoustics: its visible images per pair, matched to exact paths by distance.
        room = rooms[name]
        room.simulator_state["ism_needed"] = True
        room.image_source_model()
        pra_only, exact_only, both, pra_worst = [], [], 0, 0.0
        for (s, rec), paths in exact.items():
            src = room.sources[s]
            visible = [
                float(np.hypot(*(src.images[:, i] - np.array(r["receivers"][rec]))))
                for i in range(src.images.shape[1])
                if room.visibility[s][rec, i]
            ]
            left = sorted(float(t) * SPEED for t in paths.values())
            for d in sorted(visible):
                k = min(range(len(left)), key=lambda j: abs(left[j] - d), default=None)
                if k is not None and abs(left[k] - d) <= 1e-5 * d:
                    both += 1
                    pra_worst = max(pra_worst, abs(d / left.pop(k) - 1))
                else:
                    pra_only.append(((s, rec), d))
            exact_only += [((s, rec), d) for d in left]
        print(f"  pyroomacoustics: {both} visible images match exact paths (distance within "
              f"1e-5), {len(pra_only)} visible images match none, {len(exact_only)} exact "
              f"paths without a visible image; largest relative distance error {pra_worst:.2e}")
        for p in pra_only[:10]:
            print("    pyroomacoustics only", p)
        for p in exact_only[:10]:
            print("    exact only", p)

    # Time, alternating.
    times = {n: {"pra": [], "search": [], "new": []} for n in spec}
    for _ in range(rounds):
        for name, room in rooms.items():
            times[name]["pra"].append(time_ism(room, repetitions))
        ours = run_example(repetitions)
        for name in spec:
            times[name]["search"].append(ours[name]["search_ms"])
            times[name]["new"].append(ours[name]["new_and_search_ms"])
    print(f"\n{rounds} rounds, each the median of {repetitions} calls; the median round:")
    print("| room | pairs | pyroomacoustics `image_source_model` | eigenray `Tracer::search` "
          "| ratio (rounds: fewest, most) | `Tracer::new` + `search` | ratio |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, r in spec.items():
        m = {k: statistics.median(v) for k, v in times[name].items()}
        pairs = f"{len(r['sources'])} x {len(r['receivers'])}"
        each = [p / e for p, e in zip(times[name]["pra"], times[name]["search"])]
        print(f"| {name} | {pairs} | {m['pra']:.3f} ms | {m['search']:.3f} ms | "
              f"{m['pra'] / m['search']:.1f}x faster ({min(each):.1f}, {max(each):.1f}) | "
              f"{m['new']:.3f} ms | {m['pra'] / m['new']:.1f}x faster |")


if __name__ == "__main__":
    main()
