#!/usr/bin/env python3
"""The adversarial scenes of issue 29: two wavy walls of 50 segments each, with

- `walls_reflect_K.json`: one ray of K reflections alternating between the walls (default
  settings: the default mode, whose fallback search is bounded per ray);
- `walls_all_K.json`: the same with `"solver": {"stationary": "all"}`;
- `walls_fallback_K.json`: K reflections from a source beneath the floor, so that the
  default start leads to no admissible path and every ray falls back to the complete
  search (bounded per ray), for a grid of 10 × 10 sources and receivers
  (`walls_fallback_K_1.json`: one ray);
- `walls_search_S.json`: `"search": {"max_steps": S, "refract": false}` over the walls.

Usage: python3 benches/adversarial_scenes.py [OUTDIR]   (default: ./adversarial; or let
benches/adversarial_cpu.sh write and time them). `--help` prints this and writes nothing.
"""

import argparse
import json
import math
import os
import sys

SEGMENTS = 50


def wall(y0, phase):
    """A wavy wall from x = 0 to x = 10 around height `y0`, `SEGMENTS` segments."""
    pts = []
    for i in range(SEGMENTS + 1):
        x = 10.0 * i / SEGMENTS
        y = y0 + 0.15 * math.sin(3.1 * x + phase) + 0.05 * math.sin(7.3 * x)
        pts.append([round(x, 4), round(y, 4)])
    return pts


def base():
    return {
        "media": {"air": {"speed": 1.0}},
        "interfaces": {"floor": {"points": wall(0.0, 0.0)}, "roof": {"points": wall(2.0, 1.3)}},
        "sources": [[1.0, 1.0]],
        "receivers": [[9.0, 1.1]],
    }


def reflections(k):
    steps = [{"reflect": "floor" if i % 2 == 0 else "roof"} for i in range(k)]
    return [{"name": f"zigzag{k}", "steps": steps, "media": ["air"] * (k + 1)}]


def arguments(argv):
    """The command line: one optional output folder, which must not look like an option."""
    parser = argparse.ArgumentParser(
        prog="adversarial_scenes.py",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "outdir",
        nargs="?",
        default="adversarial",
        help="folder the scenes are written to (created if missing; default: adversarial)",
    )
    return parser.parse_args(argv)


def main(argv=None):
    out = arguments(sys.argv[1:] if argv is None else argv).outdir
    os.makedirs(out, exist_ok=True)
    scenes = {}
    for k in (8, 10, 12):
        s = base()
        s["paths"] = reflections(k)
        scenes[f"walls_reflect_{k}.json"] = s
        a = base()
        a["paths"] = reflections(k)
        a["solver"] = {"stationary": "all"}
        scenes[f"walls_all_{k}.json"] = a
    for k in (10, 12):
        for grid in (1, 10):
            s = base()
            s["sources"] = [[1.0 + 0.3 * i, -1.0] for i in range(grid)]
            s["receivers"] = [[9.0 - 0.3 * i, 1.1] for i in range(grid)]
            s["paths"] = reflections(k)
            scenes[f"walls_fallback_{k}_{grid}.json"] = s
    for steps in (4, 6):
        s = base()
        # The regions' media: air fills the plane between the walls (no domain needed).
        s["media"]["air"]["at"] = [5.0, 1.0]
        s["background"] = "air"
        s["search"] = {"max_steps": steps, "refract": False}
        scenes[f"walls_search_{steps}.json"] = s
    for name, s in scenes.items():
        with open(os.path.join(out, name), "w") as f:
            json.dump(s, f, separators=(",", ":"))
        print(name, os.path.getsize(os.path.join(out, name)), "bytes")


if __name__ == "__main__":
    main()
