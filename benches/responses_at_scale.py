"""Responses at scale (issue 39's targets): the shallow-water transmission-loss grids (flat
and sloping bottom, 9,850 receivers, every reflection path of up to 40 bounces, 100 Hz) and
the room response (a 6 x 4 m room, absorption 0.1, ten listeners, 2 s at 16 kHz), each the
whole `eigenray solve --tl` / `--ir` on one thread, timed alternately against the
collect-then-sum path of a reference build (what Python's `transmission_loss()` and
`impulse_response()` did before streaming: `echoes_of_scene`, then `pressure_into` or
`render_into`).

The reference is `benches/support/response_reference.rs`, built as an example of the
reference commit:

  git worktree add /tmp/base bcfcb8d
  cp benches/support/response_reference.rs /tmp/base/examples/
  (cd /tmp/base && cargo build --release --example response_reference)
  cargo build --release
  python3 benches/responses_at_scale.py /tmp/base/target/release/examples/response_reference [ROUNDS]
      [--room-only | --tl-only] [--previous BINARY]

ROUNDS (default 3) for the TL grids; the room against the reference (about a minute a run)
runs once. `--room-only` leaves the TL grids out, `--tl-only` the room. `--previous BINARY`
(an `eigenray` built from another commit) times the room's ten listeners alternating with it,
ROUNDS rounds, and compares the two responses (each listener's relative to its peak):

  python3 benches/responses_at_scale.py REFERENCE 5 --tl-only

Reports per scene: CPU seconds (user + sys, median of ROUNDS alternating runs), the ratio,
the peak resident memory of each (/usr/bin/time -f %M), and the largest difference of the
results (TL in dB where finite, and where each is infinite; a response relative to its peak).
The reference gets the receivers as a list (it has no grids) and one listener for the room
(ten abort it on memory at 8 kHz already); the new build runs the scene as given, and the
room with that one listener too for the comparison.
"""

import json
import os
import pathlib
import statistics
import struct
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = ROOT / "benches" / "scenes"
NEW = ROOT / "target" / "release" / "eigenray"


def linspace(first, last, count):
    count = int(count)
    if count == 1:
        return [first]
    step = (last - first) / (count - 1)
    return [i * step + first if i + 1 < count else last for i in range(count)]


def as_reference(doc):
    """The scene as the reference reads it: receivers as a list, no transmission_loss."""
    doc = json.loads(json.dumps(doc))
    doc.pop("transmission_loss", None)
    r = doc["receivers"]
    if isinstance(r, dict):
        g = r["grid"]
        doc["receivers"] = [[x, y] for x in linspace(*g["x"]) for y in linspace(*g["y"])]
    return doc


def timed(cmd):
    """(CPU seconds, peak KB) of one run of `cmd` on one thread."""
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    out = subprocess.run(
        ["/usr/bin/time", "-f", "%U %S %M", *map(str, cmd)],
        env=env, capture_output=True, text=True,
    )
    if out.returncode != 0:
        sys.exit(f"{cmd}: {out.stderr}")
    user, system, kb = out.stderr.strip().splitlines()[-1].split()
    return float(user) + float(system), int(kb)


def read_npy(path):
    data = pathlib.Path(path).read_bytes()
    n = struct.unpack("<H", data[8:10])[0]
    body = data[10 + n:]
    return list(struct.unpack(f"<{len(body) // 8}d", body))


def read_raw(path):
    body = pathlib.Path(path).read_bytes()
    return list(struct.unpack(f"<{len(body) // 8}d", body))


def compare_tl(a, b):
    finite = [abs(x - y) for x, y in zip(a, b) if x != float("inf") and y != float("inf")]
    inf_mismatch = sum((x == float("inf")) != (y == float("inf")) for x, y in zip(a, b))
    return f"largest TL difference {max(finite):.2e} dB, {inf_mismatch} infinities differ"


def compare_ir(a, b):
    peak = max(abs(v) for v in b)
    return f"largest response difference {max(abs(x - y) for x, y in zip(a, b)) / peak:.2e} of its peak"


def bench(name, doc, kind, reference, rounds, tmp, new_doc=None):
    new_doc = new_doc or doc
    new_scene = tmp / f"{name}.json"
    new_scene.write_text(json.dumps(new_doc))
    ref_scene = tmp / f"{name}.ref.json"
    ref_scene.write_text(json.dumps(as_reference(doc)))
    new_out, ref_out = tmp / f"{name}.npy", tmp / f"{name}.ref.bin"
    option = "--tl" if kind == "tl" else "--ir"
    new_cmd = [NEW, "solve", new_scene, option, new_out]
    ref_cmd = [reference, ref_scene, kind, ref_out]
    new_t, ref_t, new_m, ref_m = [], [], [], []
    for _ in range(rounds):
        t, m = timed(ref_cmd)
        ref_t.append(t)
        ref_m.append(m)
        t, m = timed(new_cmd)
        new_t.append(t)
        new_m.append(m)
    a, b = statistics.median(new_t), statistics.median(ref_t)
    print(f"{name}: {a:.3f} CPU s (peak {max(new_m) / 1024:.1f} MB) against the reference's "
          f"{b:.3f} CPU s (peak {max(ref_m) / 1024:.1f} MB): {b / a:.1f}x")
    if new_doc is doc:
        new, ref = read_npy(new_out), read_raw(ref_out)
        print("   ", compare_tl(new, ref) if kind == "tl" else compare_ir(new, ref))


def per_listener(a, b, listeners):
    """The largest difference of two responses (flat, `listeners` of equal length), each
    listener's relative to its peak in `b`."""
    n = len(b) // listeners
    worst = 0.0
    for k in range(listeners):
        x, y = a[k * n:(k + 1) * n], b[k * n:(k + 1) * n]
        peak = max(abs(v) for v in y)
        worst = max(worst, max(abs(p - q) for p, q in zip(x, y)) / peak)
    return worst


def main():
    args = sys.argv[1:]
    previous = None
    if "--previous" in args:
        at = args.index("--previous")
        previous = pathlib.Path(args[at + 1])
        del args[at:at + 2]
    room_only = "--room-only" in args
    tl_only = "--tl-only" in args
    args = [a for a in args if a not in ("--room-only", "--tl-only")]
    reference = pathlib.Path(args[0])
    rounds = int(args[1]) if len(args) > 1 else 3
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        if not room_only:
            for name in ("shallow_water_tl_flat", "shallow_water_tl_slope"):
                doc = json.loads((SCENES / f"{name}.json").read_text())
                bench(name, doc, "tl", reference, rounds, tmp)
        if tl_only:
            return
        room = json.loads((SCENES / "room_response.json").read_text())
        one = dict(room, receivers=room["receivers"][:1])
        # The reference's tree takes about a minute a run: one round.
        bench("room_response_one_listener", one, "ir", reference, 1, tmp)
        # Ten listeners: the new build (the reference's row is one listener's), alternating
        # with a previous build where given.
        ten = tmp / "room_ten.json"
        ten.write_text(json.dumps(room))
        new_cmd = [NEW, "solve", ten, "--ir", tmp / "ten.npy"]
        runs, before = [], []
        for _ in range(rounds if previous else 1):
            if previous:
                before.append(timed([previous, "solve", ten, "--ir", tmp / "ten.previous.npy"]))
            runs.append(timed(new_cmd))
        a = statistics.median(t for t, _ in runs)
        print(f"room_response (10 listeners): {a:.3f} CPU s (runs {[t for t, _ in runs]}), "
              f"peak {max(m for _, m in runs) / 1024:.1f} MB")
        if previous:
            b = statistics.median(t for t, _ in before)
            diff = per_listener(read_npy(tmp / "ten.npy"), read_npy(tmp / "ten.previous.npy"),
                                len(room["receivers"]))
            print(f"    previous build: {b:.3f} CPU s (runs {[t for t, _ in before]}), "
                  f"peak {max(m for _, m in before) / 1024:.1f} MB: {b / a:.1f}x; "
                  f"largest response difference {diff:.2e} of its listener's peak")


if __name__ == "__main__":
    main()
