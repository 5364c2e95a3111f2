"""The transmission loss of the sloping-bottom shallow-water scene
(benches/scenes/shallow_water_tl_slope.json: 100 m deep to 1.5 km, sloping to 130 m at
3.5 km, then flat; a source at 25 m, axisymmetric, 100 Hz, every reflection path of up to
40 bounces) along one depth, without and with `"search": {"diffraction": true}`: docs/
diffraction_tl.png.

Two changes to the benchmark's scene, and why:
- the bottom is `rigid`, not `"media"`: the vertices of a fluid bottom are penetrable
  wedges, whose diffracted arrivals have a `null` amplitude by the contract (no UTD
  coefficient for them), so the fluid bottom's TL would not change;
- the surface and the bottom run on to 8 km behind the source and 13 km beyond the last
  receiver, and `max_time` is 5 s: their open ends are the scene's truncation, not the
  ocean's, and their diffracted arrivals (from 10.7 s on) are left out.

The receivers are a line at DEPTH m from 1 to 5 km every STEP m. Without diffraction the TL
jumps where an arrival switches off at a corner's shadow or reflection boundary (the
bottom-reflected ray that grazes the corner at 1.5 km or 3.5 km); with it the corner's
diffracted arrivals fill the jumps: the search lists every path of reflections, one
diffraction and reflections (within `max_steps` and `max_time`), so the boundaries of paths
with surface and bottom bounces before or after the corner are filled too.

How to run (the Python package built, matplotlib installed):
  python benches/diffraction_tl.py [DEPTH] [STEP]
"""

import json
import pathlib
import sys
import time

import numpy as np

import eigenray

ROOT = pathlib.Path(__file__).resolve().parents[1]


def scene(receivers, diffraction):
    s = json.loads((ROOT / "benches/scenes/shallow_water_tl_slope.json").read_text())
    s["interfaces"]["surface"]["points"] = [[-8000.0, 0.0], [18000.0, 0.0]]
    s["interfaces"]["bottom"]["points"] = [
        [-8000.0, -100.0], [1500.0, -100.0], [3500.0, -130.0], [18000.0, -130.0]
    ]
    s["interfaces"]["bottom"]["reflection"] = "rigid"
    s["domain"] = [[-8000.0, -300.0], [18000.0, 0.0]]
    s["receivers"] = [[float(x), float(y)] for x, y in receivers]
    s["search"] = {"max_steps": 40, "refract": False, "max_time": 5.0,
                   "diffraction": diffraction}
    s["description"] = "benches/diffraction_tl.py"
    return eigenray.Scene(s)


def tl_of(receivers, diffraction):
    return eigenray.Tracer(scene(receivers, diffraction)).transmission_loss()[0]


def mirror(p, a, b):
    """`p` mirrored in the line through `a` and `b`."""
    p, a, b = (np.asarray(v, dtype=float) for v in (p, a, b))
    t = (b - a) / np.linalg.norm(b - a)
    v = p - a
    return a + 2 * (v @ t) * t - v


def boundaries(depth):
    """The ranges at `depth` where a once-bottom-reflected ray grazes the corner at 1.5 km:
    the flat part's reflection ends there (beyond, none), the slope's begins (before, none)."""
    source, corner = np.array([0.0, -25.0]), np.array([1500.0, -100.0])
    out = []
    for face in (((-8000.0, -100.0), (1500.0, -100.0)), ((1500.0, -100.0), (3500.0, -130.0))):
        image = mirror(source, *face)
        d = corner - image
        out.append(float(corner[0] + (-depth - corner[1]) / d[1] * d[0]))
    return out


def main():
    depth = float(sys.argv[1]) if len(sys.argv) > 1 else 50.0
    step = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    xs = np.arange(1000.0, 5000.0 + step / 2, step)
    line = [(x, -depth) for x in xs]
    edges = boundaries(depth)
    tl, near = {}, {}
    for diffraction in (False, True):
        start = time.perf_counter()
        tl[diffraction] = tl_of(line, diffraction)
        print(f"diffraction {diffraction}: {len(xs)} receivers in "
              f"{time.perf_counter() - start:.2f} s", file=sys.stderr)
        near[diffraction] = [tl_of([(x - 3.0037 + 0.01 * i, -depth) for i in range(601)],
                                   diffraction) for x in edges]
    # The jump at each boundary: receivers 1 mm either side of it. (The zooms' receivers miss
    # the boundary itself: within round-off of a boundary the side a term's limit is taken
    # from is the round-off's, docs/method.md.)
    for x in edges:
        for d in (False, True):
            a, b = tl_of([(x - 1e-3, -depth), (x + 1e-3, -depth)], d)
            print(f"boundary at {x:.2f} m, diffraction {d}: TL {a:.3f} | {b:.3f} dB "
                  f"(jump {abs(a - b):.3f} dB)", file=sys.stderr)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(10, 7), layout="constrained")
    grid = fig.add_gridspec(2, 2, height_ratios=[1.25, 1])
    top = fig.add_subplot(grid[0, :])
    colours = {False: ("#e15759", "reflections only"),
               True: ("#222222", "reflections + corner diffraction")}
    for d, (colour, label) in colours.items():
        top.plot(xs / 1e3, tl[d], color=colour, lw=0.9, label=label)
    top.invert_yaxis()
    top.set_ylabel("transmission loss (dB)")
    top.set_xlabel("range (km)")
    top.set_title(f"Sloping bottom (rigid), 100 Hz, receivers at {depth:g} m depth: TL without "
                  "and with the search's diffraction (reflections before and after it)\n"
                  "dotted: where the once "
                  "bottom-reflected ray grazes the 1.5 km corner; below, 6 m about each",
                  fontsize=9)
    top.legend(fontsize=8, loc="lower left")
    top.grid(alpha=0.3)
    for k, x in enumerate(edges):
        top.axvline(x / 1e3, color="0.5", lw=0.8, ls=":")
        ax = fig.add_subplot(grid[1, k])
        zoom = x - 3.0037 + 0.01 * np.arange(601)
        for d, (colour, label) in colours.items():
            ax.plot(zoom, near[d][k], color=colour, lw=1.1, label=label)
        ax.axvline(x, color="0.5", lw=0.8, ls=":")
        ax.invert_yaxis()
        ax.set_xlabel("range (m)")
        ax.set_ylabel("TL (dB)")
        which = "flat part's" if k == 0 else "slope's"
        ax.set_title(f"the {which} reflection {'ends' if k == 0 else 'begins'} at {x:.1f} m "
                     "\n(the red curve's other steps: paths with more reflections that graze\n"
                     "a corner, filled by their reflected and diffracted paths)", fontsize=8)
        ax.grid(alpha=0.3)
    out = ROOT / "docs" / "diffraction_tl.png"
    fig.savefig(out, dpi=100)
    print(out, file=sys.stderr)


if __name__ == "__main__":
    main()
