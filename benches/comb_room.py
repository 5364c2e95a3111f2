"""The comb-shaped room of pyroomacoustics issue #383 (12 walls), eigenray's `search` against
pyroomacoustics' image source model: side by side at order 8, then the time against the
order and against `max_time`, and a picture of both (docs/comb_room_search.png).

The room: corners [[0,0],[0,5],[1,5],[1,2],[2,2],[2,5],[3,5],[3,0],[2,0],[2,1],[1,1],[1,0]],
source (0.5, 0.5), nine listeners (those of `tests/search.rs`), 343 m/s. eigenray runs it
drawn two ways: each wall its own interface (`walls`) and the outline as one closed polyline
(`polyline`); its times come from `examples/search_rooms.rs` (one thread, in-process, the
median of REPETITIONS calls with the tracer built once). pyroomacoustics' time is the median
of its `room.image_source_model()` calls in this process (after a warm-up, the model
recomputed each time); its order is capped at PRA_MAX_ORDER, beyond which a call takes
seconds (about 4x per order).

Side by side: ROUNDS rounds alternating the two tools, the median round and the ratio per
round. The sweeps are one pass each.

How to run (pyroomacoustics and matplotlib in a venv outside the repository):
  python3 -m venv ../venv-pra && ../venv-pra/bin/pip install pyroomacoustics numpy matplotlib
  cargo build --release --example search_rooms
  ../venv-pra/bin/python benches/comb_room.py [ROUNDS] [REPETITIONS]
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import pyroomacoustics as pra

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
import exact_rooms  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
EXAMPLE = os.path.join(ROOT, "target", "release", "examples", "search_rooms")
PICTURE = os.path.join(ROOT, "docs", "comb_room_search.png")
SPEED = 343.0
CORNERS = [[0, 0], [0, 5], [1, 5], [1, 2], [2, 2], [2, 5], [3, 5], [3, 0], [2, 0], [2, 1],
           [1, 1], [1, 0]]
SOURCE = [0.5, 0.5]
LISTENERS = [[2.5, 4.5], [0.5, 4.5], [0.5, 2.5], [2.5, 2.5], [2.5, 0.5], [1.5, 1.5],
             [0.25, 1.25], [2.75, 3.75], [1.25, 1.75]]
SIDE_BY_SIDE_ORDER = 8
PRA_MAX_ORDER = 8
ORDERS = list(range(1, 15))
MAX_TIMES = [0.02, 0.04, 0.06, 0.08, 0.09, 0.1, 0.11, 0.12]


def scene(drawing, search):
    """The comb room's scene document, drawn as `walls` or one `polyline`."""
    if drawing == "walls":
        n = len(CORNERS)
        interfaces = {f"w{i}": {"points": [CORNERS[i], CORNERS[(i + 1) % n]]} for i in range(n)}
    else:
        interfaces = {"room": {"points": CORNERS, "closed": True}}
    return {
        "media": {"air": {"speed": SPEED, "at": SOURCE}},
        "interfaces": interfaces,
        "sources": [SOURCE],
        "receivers": LISTENERS,
        "search": search,
    }


def eigenray_ms(documents, repetitions):
    """`search_ms` and arrivals of each document, timed by the example in one process."""
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, doc in enumerate(documents):
            path = os.path.join(tmp, f"scene{i}.json")
            with open(path, "w") as f:
                json.dump(doc, f)
            paths.append(path)
        out = subprocess.run([EXAMPLE, str(repetitions), *paths], check=True,
                             capture_output=True, text=True).stdout
    lines = [json.loads(line) for line in out.splitlines()]
    return [(line["search_ms"], line["arrivals"]) for line in lines]


def pra_room(order):
    room = pra.Room.from_corners(np.array(CORNERS, dtype=float).T, fs=16000, max_order=order,
                                 ray_tracing=False)
    room.add_source(SOURCE)
    room.add_microphone_array(pra.MicrophoneArray(np.array(LISTENERS, dtype=float).T, room.fs))
    return room


def pra_ms(room, repetitions):
    """Median wall time (ms) of `image_source_model()` after one warm-up call, and the
    number of visible images over all listeners."""
    room.simulator_state["ism_needed"] = True
    room.image_source_model()
    times = []
    for _ in range(repetitions):
        room.simulator_state["ism_needed"] = True
        t0 = time.perf_counter()
        room.image_source_model()
        times.append((time.perf_counter() - t0) * 1e3)
    visible = int(sum(np.sum(v) for v in room.visibility[0]))
    return statistics.median(times), visible


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    repetitions = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    search = {"max_steps": SIDE_BY_SIDE_ORDER, "refract": False}
    docs = [scene("walls", search), scene("polyline", search)]
    room = pra_room(SIDE_BY_SIDE_ORDER)
    rows = {"pra": [], "walls": [], "polyline": []}
    for _ in range(rounds):
        ms, visible = pra_ms(room, repetitions)
        rows["pra"].append(ms)
        (walls_ms, walls_n), (poly_ms, poly_n) = eigenray_ms(docs, 20 * repetitions)
        rows["walls"].append(walls_ms)
        rows["polyline"].append(poly_ms)
    m = {k: statistics.median(v) for k, v in rows.items()}
    print(f"comb room, 1 source x {len(LISTENERS)} listeners, order {SIDE_BY_SIDE_ORDER}; "
          f"{rounds} rounds alternating, the median round "
          f"(pyroomacoustics {pra.__version__}: {repetitions} calls a round, eigenray "
          f"{20 * repetitions}):")
    print("| tool | arrivals | time | pyroomacoustics / this (rounds: least, most) |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| pyroomacoustics `image_source_model` | {visible} visible images | "
          f"{m['pra']:.1f} ms | 1 |")
    for key, n in (("walls", walls_n), ("polyline", poly_n)):
        each = [p / e for p, e in zip(rows["pra"], rows[key])]
        name = "one interface per wall" if key == "walls" else "one closed polyline"
        print(f"| eigenray `search`, {name} | {n} | {m[key]:.3f} ms | "
              f"{m['pra'] / m[key]:.0f}x ({min(each):.0f}x, {max(each):.0f}x) |")

    # The time against the order.
    by_order = {"pra": [], "walls": [], "polyline": []}
    docs = []
    for k in ORDERS:
        docs += [scene("walls", {"max_steps": k, "refract": False}),
                 scene("polyline", {"max_steps": k, "refract": False})]
    ours = eigenray_ms(docs, repetitions)
    print("\n| order | pyroomacoustics | visible images | eigenray, walls | arrivals | "
          "eigenray, polyline | arrivals |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for i, k in enumerate(ORDERS):
        (w_ms, w_n), (p_ms, p_n) = ours[2 * i], ours[2 * i + 1]
        by_order["walls"].append(w_ms)
        by_order["polyline"].append(p_ms)
        if k == SIDE_BY_SIDE_ORDER:
            ms = m["pra"]
            by_order["pra"].append(ms)
            pra_cells = f"{ms:.2f} ms | {visible}"
        elif k <= PRA_MAX_ORDER:
            ms, visible_k = pra_ms(pra_room(k), max(1, repetitions // (1 + k // 3)))
            by_order["pra"].append(ms)
            pra_cells = f"{ms:.2f} ms | {visible_k}"
        else:
            pra_cells = "(not run) | "
        print(f"| {k} | {pra_cells} | {w_ms:.3f} ms | {w_n} | {p_ms:.3f} ms | {p_n} |")

    # The time against max_time.
    docs = []
    for t in MAX_TIMES:
        docs += [scene("walls", {"max_time": t, "refract": False}),
                 scene("polyline", {"max_time": t, "refract": False})]
    ours = eigenray_ms(docs, repetitions)
    by_time = {"walls": [], "polyline": []}
    print("\n| max_time | eigenray, walls | arrivals | eigenray, polyline | arrivals |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    for i, t in enumerate(MAX_TIMES):
        (w_ms, w_n), (p_ms, p_n) = ours[2 * i], ours[2 * i + 1]
        by_time["walls"].append(w_ms)
        by_time["polyline"].append(p_ms)
        print(f"| {t} s | {w_ms:.3f} ms | {w_n} | {p_ms:.3f} ms | {p_n} |")

    check_order = 6
    print(f"\nWhich paths, order {check_order}, against the exact ones (python/tests/"
          f"exact_rooms.py: points strictly inside their walls, no leg meeting another wall):")
    exact = exact_rooms.exact_paths(CORNERS, SOURCE, LISTENERS, check_order)
    room = pra_room(check_order)
    room.image_source_model()
    src = room.sources[0]
    matched = pra_only = exact_only = 0
    for r, paths in exact.items():
        left = sorted(float(d2) ** 0.5 for d2, _ in paths.values())
        for i in range(src.images.shape[1]):
            if not room.visibility[0][r, i]:
                continue
            d = float(np.hypot(*(src.images[:, i] - np.array(LISTENERS[r]))))
            k = min(range(len(left)), key=lambda j: abs(left[j] - d), default=None)
            if k is not None and abs(left[k] - d) <= 1e-5 * d:
                matched += 1
                left.pop(k)
            else:
                pra_only += 1
        exact_only += len(left)
    n = sum(len(p) for p in exact.values())
    print(f"{n} exact paths; pyroomacoustics' visible images: {matched} of them, "
          f"{pra_only} that are none of them, {exact_only} exact paths missing; eigenray's "
          f"polyline: exactly the exact paths (python/tests/test_exact_rooms.py)")

    picture(by_order, by_time)


def picture(by_order, by_time):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    a.semilogy(ORDERS[: len(by_order["pra"])], by_order["pra"], "o-", color="tab:red",
               label="pyroomacoustics image_source_model")
    a.semilogy(ORDERS, by_order["walls"], "s-", color="tab:blue",
               label="eigenray search, one interface per wall")
    a.semilogy(ORDERS, by_order["polyline"], "^--", color="tab:green",
               label="eigenray search, one closed polyline")
    a.set_xlabel("reflection order (max_steps)")
    a.set_ylabel("time per call, ms (one thread)")
    a.set_title("Comb room, 1 source x 9 listeners: time against order")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8)
    b.semilogy(MAX_TIMES, by_time["walls"], "s-", color="tab:blue",
               label="one interface per wall")
    b.semilogy(MAX_TIMES, by_time["polyline"], "^--", color="tab:green",
               label="one closed polyline")
    b.set_xlabel("max_time, s (every arrival before it, any order)")
    b.set_ylabel("time per call, ms (one thread)")
    b.set_title("eigenray search: time against max_time")
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(PICTURE, dpi=110)
    print(f"\nwrote {os.path.relpath(PICTURE, ROOT)}")


if __name__ == "__main__":
    main()
