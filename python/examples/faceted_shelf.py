"""Where the specular points of a faceted bottom jump over a joint: a shelf flat at 80 m to
1.5 km, then sloping to 120 m at 5 km, a source at 25 m on the axis and receivers at 2 and 4 km
every 2 m in depth. Each receiver's one-bounce bottom reflection is searched with
`"vertex": true`: a specular point on the flat facet (blue; none reaches 4 km), on the slope
(green), or, in the
wedge between the rays the two facets reflect at the joint, only the path held at the joint
(red, `vertex`: edge diffraction).

Checked against an independent computation: the image method on each facet's line (in this
file) puts a specular point strictly inside the facet exactly where the search finds a
`converged` bounce there, at the same time; where it puts none on either facet, the search
finds the `vertex` path through the joint, at the time of the path through it.

    python faceted_shelf.py [faceted_shelf.png]
"""

import sys

import numpy as np

import eigenray

SPEED = 1500.0
SOURCE = (0.0, -25.0)
JOINT = (1500.0, -80.0)
BOTTOM = [(0.0, -80.0), JOINT, (5000.0, -120.0)]
RANGES = (2000.0, 4000.0)


def bottom_depth(x):
    """The bottom's depth at range `x`."""
    return -np.interp(x, [p[0] for p in BOTTOM], [p[1] for p in BOTTOM])


# Receivers every 2 m in depth at 2 and 4 km, down to 2 m above the bottom.
RECEIVERS = [(x, z) for x in RANGES for z in np.arange(2.0, bottom_depth(x) - 1.0, 2.0)]


def scene():
    return eigenray.Scene({
        "media": {"water": {"speed": SPEED}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[0, 0], [5000, 0]], "reflection": "pressure-release"},
            "bottom": {"points": [list(p) for p in BOTTOM]},
        },
        "sources": [list(SOURCE)],
        "receivers": [[x, -z] for x, z in RECEIVERS],
        "search": {"max_steps": 1, "interfaces": ["bottom"], "vertex": True},
    })


def image_point(receiver, a, b):
    """The specular point on the line through facet `a b` by the image method: its fraction
    along `a → b` and the path's length."""
    s, r, a, b = (np.asarray(p, float) for p in (SOURCE, receiver, a, b))
    t = (b - a) / np.linalg.norm(b - a)
    n = np.array([-t[1], t[0]])
    image = s - 2 * np.dot(s - a, n) * n
    d = r - image
    cross = lambda p, q: p[0] * q[1] - p[1] * q[0]  # noqa: E731
    u = cross(d, image - a) / cross(d, t)
    return u / np.linalg.norm(b - a), np.linalg.norm(d)


def bounces():
    """Each receiver's bottom bounces: (receiver, status, reflection point, time)."""
    arrivals = eigenray.Tracer(scene()).search()
    out = []
    for a in arrivals:
        if len(a["steps"]) == 1:
            out.append((a["receiver"], a["status"], tuple(a["points"][1]), a["time"]))
    return out


def check(found):
    """The search's bounces against the image method on each facet (and the time through the
    joint for the held paths)."""
    for k, (x, z) in enumerate(RECEIVERS):
        receiver = (x, -z)
        want = []
        for a, b in zip(BOTTOM, BOTTOM[1:]):
            u, length = image_point(receiver, a, b)
            if 0 < u < 1:
                want.append(length / SPEED)
        got = sorted(t for r, status, _, t in found if r == k and status == "converged")
        assert len(got) == len(want), (z, got, want)
        for g, w in zip(got, sorted(want)):
            assert abs(g - w) <= 1e-14 * w, (z, g, w)
        held = [t for r, status, p, t in found if r == k and status == "vertex"]
        through = (np.hypot(JOINT[0] - SOURCE[0], JOINT[1] - SOURCE[1])
                   + np.hypot(x - JOINT[0], -z - JOINT[1])) / SPEED
        if not want:
            assert held and abs(held[0] - through) <= 1e-14 * through, (z, held, through)


def limiting_rays():
    """The directions of the rays each facet reflects at the joint: the edges of the wedge
    that neither facet's reflections reach."""
    s, j = np.asarray(SOURCE), np.asarray(JOINT)
    incoming = (j - s) / np.linalg.norm(j - s)
    out = {}
    for name, (a, b) in [("flat", BOTTOM[:2]), ("slope", BOTTOM[1:])]:
        t = (np.asarray(b) - np.asarray(a)) / np.linalg.norm(np.asarray(b) - np.asarray(a))
        n = np.array([-t[1], t[0]])
        d = incoming - 2 * np.dot(incoming, n) * n
        out[name] = d
    return out


def main(out):
    import matplotlib.pyplot as plt

    found = bounces()
    check(found)
    specular = {r for r, s, _, _ in found if s == "converged"}
    gaps = {}
    for x in RANGES:
        gap = [z for k, (xk, z) in enumerate(RECEIVERS) if xk == x and k not in specular]
        gaps[x] = (min(gap), max(gap))
        print(f"receivers at {x / 1000:g} km without a specular bottom bounce: depths "
              f"{min(gap):g} to {max(gap):g} m")

    fig = plt.figure(figsize=(9, 8))
    grid = fig.add_gridspec(2, 2, height_ratios=[1.4, 1])
    top = fig.add_subplot(grid[0, :])
    lower = [fig.add_subplot(grid[1, 0]), fig.add_subplot(grid[1, 1])]
    colours = {"flat": "tab:blue", "slope": "tab:green", "vertex": "tab:red"}
    names = {"flat": "specular off the flat facet", "slope": "specular off the slope",
             "vertex": "only the path held at the joint (vertex)"}
    # The wedge between the rays the two facets reflect at the joint: no specular bounce.
    rays = limiting_rays()
    j = np.asarray(JOINT)
    ends = []
    for name in ["flat", "slope"]:
        d = rays[name]
        k = min((5000.0 - j[0]) / d[0], -j[1] / d[1] if d[1] > 0 else np.inf)
        ends.append(j + k * d)
    wedge = [j, ends[0]] + ([np.array([5000.0, 0.0])] if ends[0][1] >= 0 > ends[1][1] else []) \
        + [ends[1]]
    top.fill([p[0] / 1000 for p in wedge], [-p[1] for p in wedge], color="tab:red", alpha=0.12,
             lw=0, label="no specular bottom bounce")
    bx, by = [p[0] / 1000 for p in BOTTOM], [-p[1] for p in BOTTOM]
    top.fill_between(bx, by, 130, color="0.85")
    top.plot(bx, by, color="0.3", lw=1.5)
    top.axhline(0, color="0.3", lw=1)
    drawn = set()
    for r, status, p, t in sorted(found):
        x, z = RECEIVERS[r]
        if z % 8:
            continue
        kind = "vertex" if status == "vertex" else ("flat" if p[0] < JOINT[0] else "slope")
        if status == "vertex" and r in specular:
            continue  # a receiver with a specular bounce: its held path is not drawn
        top.plot([SOURCE[0] / 1000, p[0] / 1000, x / 1000], [-SOURCE[1], -p[1], z],
                 "--" if kind == "vertex" else "-", color=colours[kind], lw=0.8,
                 label=None if kind in drawn else names[kind])
        drawn.add(kind)
    top.plot([SOURCE[0] / 1000], [-SOURCE[1]], "k*", ms=12, label="source (25 m)")
    for x in RANGES:
        zs = [z for xk, z in RECEIVERS if xk == x]
        top.plot(np.full(len(zs), x / 1000), zs, "k.", ms=2.5)
    top.annotate("joint (1.5 km, 80 m)", (1.5, 80), (2.3, 122), arrowprops={"arrowstyle": "->"})
    top.set_ylim(130, -5)
    top.set_xlim(0, 5)
    top.set_xlabel("range (km)")
    top.set_ylabel("depth (m)")
    top.set_title("One-bounce bottom reflections to receivers at 2 and 4 km "
                  "(depth exaggerated)")
    top.legend(loc="lower left", fontsize=8)

    for ax, x in zip(lower, RANGES):
        for kind in ["flat", "slope", "vertex"]:
            pts = [(RECEIVERS[r][1], p[0] / 1000) for r, s, p, _ in found
                   if RECEIVERS[r][0] == x
                   and kind == ("vertex" if s == "vertex"
                                else ("flat" if p[0] < JOINT[0] else "slope"))]
            if pts:
                zs, ps = zip(*pts)
                ax.plot(zs, ps, "x" if kind == "vertex" else "o", color=colours[kind], ms=3.5,
                        label={"flat": "specular, flat facet", "slope": "specular, slope",
                               "vertex": "held at the joint"}[kind])
        lo, hi = gaps[x]
        ax.axvspan(lo - 1, hi + 1, color="tab:red", alpha=0.12, label="no specular bounce")
        ax.axhline(JOINT[0] / 1000, color="0.5", lw=0.8, ls=":")
        ax.set_xlabel(f"receiver depth at {x / 1000:g} km (m)")
        ax.set_ylabel("reflection point's range (km)")
        ax.set_xlim(0, bottom_depth(x))
        ax.set_title(f"at {x / 1000:g} km: the reflection point jumps the joint", fontsize=10)
        ax.legend(loc="upper left", fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "faceted_shelf.png")
