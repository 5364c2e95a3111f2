"""The eigenrays of the Munk profile at 60 km drawn from their curves: `docs/munk_curves.png`.

The profile (c(z) = 1500 [1 + 0.00737 (η − 1 + e^(−η))], η = 2 (z − 1300) / 1300, 0–5000 m,
30 knots) between a pressure-release surface and a bottom at 5000 m, a source at 1000 m,
a receiver at 800 m depth and 60 km range, `"search"` up to `MAX_STEPS` reflections
(`benches/munk_profile.py`'s waveguide). `eigenray.plot` draws each arrival through
`Arrivals.curve`: its arcs, layer by layer, through its turning points and its surface and
bottom reflections, sampled on the ray (the chords between its points would be straight
lines from reflection to reflection).

    python python/examples/munk_curves.py [out.png]
"""

import sys
import time

import numpy as np

import eigenray

MAX_STEPS = 12


def munk(z):
    eta = 2.0 * (z - 1300.0) / 1300.0
    return 1500.0 * (1.0 + 0.00737 * (eta - 1.0 + np.exp(-eta)))


def scene():
    z = np.linspace(0.0, 5000.0, 30)
    return eigenray.Scene({
        "media": {
            "ocean": {"profile": [[-float(zi), float(munk(zi))] for zi in z], "at": [0, -2000]},
            "halfspace": {"speed": 1600.0, "density": 1.0, "at": [0, -5500]},
            "air": {"speed": 340.0, "density": 0.0012, "at": [0, 500]},
        },
        "domain": [[-1000, -6000], [100000, 1000]],
        "interfaces": {
            "surface": {"points": [[-1000, 0], [100000, 0]], "reflection": "pressure-release"},
            "bottom": {"points": [[-1000, -5000], [100000, -5000]], "reflection": "media"},
        },
        "sources": [[0, -1000]],
        "receivers": [[60000, -800]],
        "search": {"max_steps": MAX_STEPS},
    })


def main():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = sys.argv[1] if len(sys.argv) > 1 else "docs/munk_curves.png"
    s = scene()
    t0 = time.perf_counter()
    arrivals = eigenray.Tracer(s).search()
    searched = time.perf_counter() - t0
    t0 = time.perf_counter()
    curves = [arrivals.curve(i, 400) for i in range(len(arrivals))]
    sampled = time.perf_counter() - t0
    turns = np.asarray(arrivals.turns)
    print(f"{len(arrivals)} arrivals (up to {MAX_STEPS} reflections, {int(turns.max())} turns) "
          f"searched in {searched:.2f} s; their curves (400 points each) in {sampled:.2f} s")
    # Every curve passes through its arrival's points, the first and last exactly.
    for i, c in enumerate(curves):
        pts = arrivals.points[i, : arrivals.order[i] + 2]
        assert np.array_equal(c[0], pts[0]) and np.array_equal(c[-1], pts[-1])
        assert all(np.any(np.all(c == p, axis=1)) for p in pts)
    fig, ax = plt.subplots(figsize=(11, 4.8), layout="constrained")
    eigenray.plot(s, arrivals, ax=ax, aspect="auto", labels=False,
                  x_axis=("range", "km", 1e-3), y_axis=("depth", "m", -1))
    ax.set_xlim(-1000, 61000)
    ax.set_ylim(-5050, 50)
    ax.set_title(
        f"Munk profile (30 knots), surface and bottom at 5000 m: the {len(arrivals)} eigenrays "
        f"at 60 km with up to {MAX_STEPS} reflections,\ndrawn through Arrivals.curve "
        f"(arcs per layer, turning points and reflections on the ray)",
        fontsize=9,
    )
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
