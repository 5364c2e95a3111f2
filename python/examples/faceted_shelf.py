"""Where the specular points of a faceted bottom jump over a joint: a shelf flat at 80 m to
1.5 km, then sloping to 120 m at 5 km, a source at 25 m on the axis and receivers at 25 m every
50 m out to 5 km. Each receiver's one-bounce bottom reflection is searched with
`"vertex": true`: a specular point on the flat facet (blue), on the slope (green), or, in the
gap between them, only the path held at the joint (red, `vertex`: edge diffraction).

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
RANGES = np.arange(100.0, 5000.0 + 1, 50.0)
DEPTH = 25.0


def scene():
    return eigenray.Scene({
        "media": {"water": {"speed": SPEED}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[0, 0], [5000, 0]], "reflection": "pressure-release"},
            "bottom": {"points": [list(p) for p in BOTTOM]},
        },
        "sources": [list(SOURCE)],
        "receivers": [[x, -DEPTH] for x in RANGES],
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
    u = np.cross(d, image - a) / np.cross(d, t)
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
    for k, x in enumerate(RANGES):
        receiver = (x, -DEPTH)
        want = []
        for a, b in zip(BOTTOM, BOTTOM[1:]):
            u, length = image_point(receiver, a, b)
            if 0 < u < 1:
                want.append(length / SPEED)
        got = sorted(t for r, status, _, t in found if r == k and status == "converged")
        assert len(got) == len(want), (x, got, want)
        for g, w in zip(got, sorted(want)):
            assert abs(g - w) <= 1e-14 * w, (x, g, w)
        held = [t for r, status, p, t in found if r == k and status == "vertex"]
        through = (np.hypot(JOINT[0] - SOURCE[0], JOINT[1] - SOURCE[1])
                   + np.hypot(x - JOINT[0], -DEPTH - JOINT[1])) / SPEED
        if not want:
            assert held and abs(held[0] - through) <= 1e-14 * through, (x, held, through)


def main(out):
    import matplotlib.pyplot as plt

    found = bounces()
    check(found)
    gap = [RANGES[r] for r in set(range(len(RANGES)))
           if not any(q == r and s == "converged" for q, s, _, _ in found)]
    print(f"receivers at {DEPTH:g} m without a specular bottom bounce: "
          f"{min(gap):g} to {max(gap):g} m ({len(gap)} of {len(RANGES)})")

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 7.5), height_ratios=[1.3, 1])
    colours = {"flat": "tab:blue", "slope": "tab:green", "vertex": "tab:red"}
    bx = [p[0] / 1000 for p in BOTTOM]
    by = [-p[1] for p in BOTTOM]
    top.fill_between(bx, by, 130, color="0.85")
    top.plot(bx, by, color="0.3", lw=1.5)
    top.axhline(0, color="0.3", lw=1)
    drawn = set()
    for r, status, p, t in sorted(found):
        x = RANGES[r]
        if x % 250 and x != 4000:
            continue
        kind = "vertex" if status == "vertex" else ("flat" if p[0] < JOINT[0] else "slope")
        if status == "vertex" and any(q == r and s == "converged" for q, s, _, _ in found):
            continue  # a receiver with a specular bounce: its held path is not drawn
        style = "--" if kind == "vertex" else "-"
        label = None if kind in drawn else {
            "flat": "specular off the flat facet",
            "slope": "specular off the slope",
            "vertex": "only a path held at the joint (vertex)"}[kind]
        drawn.add(kind)
        top.plot([SOURCE[0] / 1000, p[0] / 1000, x / 1000], [-SOURCE[1], -p[1], DEPTH],
                 style, color=colours[kind], lw=0.9 if x != 4000 else 2.2, label=label)
    top.plot([SOURCE[0] / 1000], [-SOURCE[1]], "k*", ms=12, label="source (25 m)")
    top.plot(RANGES / 1000, np.full(len(RANGES), DEPTH), "k.", ms=2)
    top.annotate("4 km: 50 m of gap", (4.0, DEPTH), (3.3, 8), arrowprops={"arrowstyle": "->"})
    top.annotate("joint (1.5 km, 80 m)", (1.5, 80), (1.7, 100), arrowprops={"arrowstyle": "->"})
    top.set_ylim(130, -5)
    top.set_xlim(0, 5)
    top.set_xlabel("range (km)")
    top.set_ylabel("depth (m)")
    top.set_title("One-bounce bottom reflections to receivers at 25 m (depth exaggerated)")
    top.legend(loc="lower left", fontsize=8)

    for kind, select in [
        ("flat", lambda s, p: s == "converged" and p[0] < JOINT[0]),
        ("slope", lambda s, p: s == "converged" and p[0] > JOINT[0]),
        ("vertex", lambda s, p: s == "vertex"),
    ]:
        pts = [(RANGES[r] / 1000, p[0] / 1000) for r, s, p, _ in found if select(s, p)]
        if pts:
            xs, ys = zip(*pts)
            bottom.plot(xs, ys, "o" if kind != "vertex" else "x", color=colours[kind], ms=4,
                        label={"flat": "specular point, flat facet",
                               "slope": "specular point, slope",
                               "vertex": "held at the joint (vertex)"}[kind])
    bottom.axhline(JOINT[0] / 1000, color="0.5", lw=0.8, ls=":")
    bottom.axvspan(min(gap) / 1000, max(gap) / 1000, color="tab:red", alpha=0.08,
                   label="no specular bounce")
    bottom.set_xlabel("receiver range (km)")
    bottom.set_ylabel("reflection point (km)")
    bottom.set_xlim(0, 5)
    bottom.legend(loc="upper left", fontsize=8)
    bottom.set_title("Where the reflection point lies: it jumps over the joint")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "faceted_shelf.png")
