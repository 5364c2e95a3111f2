"""A summer profile over a sloping sandy bottom (`examples/scenes/profile_slope.json`) drawn
from its rays' curves: `docs/profile_slope.png`.

Left, the speed profile c(y) (five knots, piecewise linear: downward refracting to 80 m);
right, every stationary path of the scene's three paths (a bottom bounce, surface–bottom,
bottom–surface–bottom) from the source at 30 m depth to the receiver at 60 m depth and
3 km, over a bottom sloping from 100 m to 118 m at 2 km and 130 m at 5 km. Each ray is drawn
through `Rays.curve` (each leg the profile's ray between its two points: arcs per layer and
turning points, the ray parameter changing at each reflection off the slope), its
reflection points marked and the chords between its points dashed for comparison; the
legend gives each ray's path, turning points and time.

    python python/examples/profile_slope.py [out.png]
"""

import json
import pathlib
import sys

import numpy as np

import eigenray

SCENE = pathlib.Path(__file__).parents[2] / "examples" / "scenes" / "profile_slope.json"


def main():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = sys.argv[1] if len(sys.argv) > 1 else "docs/profile_slope.png"
    doc = json.loads(SCENE.read_text())
    scene = eigenray.Scene(doc)
    rays = eigenray.Tracer(scene).trace_stationary()
    timed = [i for i in range(len(rays.time)) if np.isfinite(rays.time[i])]
    names = rays.path_names
    missing = sorted({names[int(rays.path[i])] for i in range(len(rays.time))
                      if not np.isfinite(rays.time[i])})
    fig, (left, ax) = plt.subplots(
        1, 2, figsize=(11, 4.6), layout="constrained", gridspec_kw={"width_ratios": [1, 6]}
    )
    knots = np.array(doc["media"]["water"]["profile"], dtype=float)
    left.plot(knots[:, 1], -knots[:, 0], "o-", color="tab:blue")
    left.set_ylim(140, -5)
    left.set_xlabel("speed (m/s)")
    left.set_ylabel("depth (m)")
    left.set_title("profile", fontsize=9)
    left.grid(alpha=0.3)
    for name, vertices in scene.interfaces.items():
        ax.plot(vertices[:, 0], -vertices[:, 1], color="0.25", linewidth=1.6)
    colours = plt.get_cmap("tab10").colors
    for c, i in enumerate(timed):
        k = int(rays.num_points[i])
        points = rays.points[i, :k]
        curve = rays.curve(i, 800)
        # Every curve passes through its ray's points, the first and last exactly.
        assert np.array_equal(curve[0], points[0]) and np.array_equal(curve[-1], points[-1])
        assert all(np.any(np.all(curve == p, axis=1)) for p in points)
        colour = colours[c % len(colours)]
        label = (f"{names[int(rays.path[i])]}: {int(rays.turns[i])} turning point"
                 f"{'' if int(rays.turns[i]) == 1 else 's'}, {rays.time[i]:.5f} s")
        ax.plot(curve[:, 0], -curve[:, 1], color=colour, linewidth=1.8, label=label)
        ax.plot(points[:, 0], -points[:, 1], "--", color=colour, linewidth=0.8, alpha=0.6)
        ax.plot(points[1:-1, 0], -points[1:-1, 1], "o", color=colour, markersize=4)
    source, receiver = scene.sources[0], scene.receivers[0]
    ax.plot(source[0], -source[1], "*", color="tab:red", markersize=14, zorder=5)
    ax.plot(receiver[0], -receiver[1], "o", color="k", markersize=6, zorder=5)
    ax.set_xlim(-100, 3300)
    ax.set_ylim(140, -5)
    ax.set_xlabel("range (m)")
    ax.set_ylabel("depth (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    none = f"; {', '.join(missing)}: no ray" if missing else ""
    ax.set_title(
        f"examples/scenes/profile_slope.json: the {len(timed)} eigenrays at 3 km over a bottom "
        f"sloping 100 → 118 → 130 m{none}\ndrawn through Rays.curve (solid; each leg the "
        f"profile's ray between its points), the chords between their points dashed",
        fontsize=9,
    )
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
