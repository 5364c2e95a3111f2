"""Rays through a `profile` medium off a sloping bottom from Python: `Tracer.gradients(rays)`
of every arrival against central differences of re-solved rays (each found again by its
turns and nearest launch angle), and `Rays.curve` on the ray (its ends and reflection points
among the samples, the time along the samples the ray's, not its chords)."""

import copy
import math

import numpy as np

import eigenray

KNOTS = [[20, 1521], [-30, 1512], [-70, 1496], [-130, 1493], [-230, 1506]]
SCENE = {
    "media": {"water": {"profile": KNOTS}},
    "background": "water",
    "interfaces": {
        "surface": {"points": [[-1000, 0], [7000, 0]], "reflection": "pressure-release"},
        "bottom": {"points": [[-1000, -95], [2000, -118], [7000, -125]], "reflection": "rigid"},
    },
    "sources": [[0, -40]],
    "receivers": [[2000, -60]],
    "paths": [{"name": "bottom", "steps": [{"reflect": "bottom"}], "media": ["water"] * 2}],
}


def rays_of(doc):
    return eigenray.Tracer(eigenray.Scene(doc)).trace_stationary()


def speed(y):
    ys = [k[0] for k in KNOTS][::-1]
    cs = [k[1] for k in KNOTS][::-1]
    return float(np.interp(y, ys, cs))


def test_gradients_off_a_sloping_bottom_match_finite_differences():
    """Three rays of one bottom bounce (one and two turning points): each row's source,
    receiver, the bottom's middle vertex (x and y) and two knots against central
    differences of that ray's re-solved time."""
    rays = rays_of(SCENE)
    n = len(rays.time)
    assert n == 3 and np.all(np.isfinite(rays.time))
    grads = eigenray.Tracer(eigenray.Scene(SCENE)).gradients(rays)
    assert grads.profile_speed["water"].shape == (n, len(KNOTS))
    bottom = grads.interface_names.index("bottom")

    def time_of(doc, i):
        again = rays_of(doc)
        same = [j for j in range(len(again.time)) if again.turns[j] == rays.turns[i]]
        j = min(same, key=lambda j: abs(again.launch_angle[j] - rays.launch_angle[i]))
        return again.time[j]

    def difference(change, h, i):
        times = []
        for d in (h, -h):
            doc = copy.deepcopy(SCENE)
            change(doc, d)
            times.append(time_of(doc, i))
        return (times[0] - times[1]) / (2 * h)

    def vertex_d(i, v):
        rows = (grads.vertex_interface[i] == bottom) & (grads.vertex[i] == v)
        return grads.vertex_d[i][rows].sum(axis=0)

    worst = 0.0
    for i in range(n):
        for axis in range(2):
            for key, got in (("sources", grads.source[i]), ("receivers", grads.receiver[i])):
                def move(doc, d, key=key, axis=axis):
                    doc[key][0][axis] += d
                fd = difference(move, 1e-2, i)
                worst = max(worst, abs(got[axis] - fd))
                assert abs(got[axis] - fd) < 1e-10, (i, key, axis, got[axis], fd)

            def tilt(doc, d, axis=axis):
                doc["interfaces"]["bottom"]["points"][1][axis] += d
            fd = difference(tilt, 1e-2, i)
            got = vertex_d(i, 1)[axis]
            worst = max(worst, abs(got - fd))
            assert abs(got - fd) < 1e-10, (i, "vertex", axis, got, fd)
        for k in (1, 3):
            def knot(doc, d, k=k):
                doc["media"]["water"]["profile"][k][1] += d
            fd = difference(knot, 1e-3, i)
            got = grads.profile_speed["water"][i, k]
            assert abs(got - fd) < 1e-10, (i, k, got, fd)
    assert worst > 0.0
    # The rows are of different rays.
    assert len({tuple(np.round(grads.receiver[i], 12)) for i in range(n)}) == n


def test_curves_off_a_sloping_bottom_are_the_rays():
    """Each ray's curve: its first and last samples the source and receiver, its reflection
    point a sample, `Σ ds / c` over the samples its time (1e-8), and metres off its
    chords."""
    rays = rays_of(SCENE)
    for i in range(len(rays.time)):
        xy = rays.curve(i, 3000)
        k = int(rays.num_points[i])
        points = rays.points[i, :k]
        assert xy.shape == (3000, 2)
        np.testing.assert_array_equal(xy[0], points[0])
        np.testing.assert_array_equal(xy[-1], points[-1])
        at = np.flatnonzero(np.all(xy == points[1], axis=1))
        assert len(at) == 1, points[1]
        steps = np.diff(xy, axis=0)
        mid = 0.5 * (xy[1:, 1] + xy[:-1, 1])
        time = np.sum(np.hypot(steps[:, 0], steps[:, 1]) / [speed(y) for y in mid])
        assert abs(time - rays.time[i]) < 1e-8 * rays.time[i], (time, rays.time[i])
        off = 0.0
        for a, b, part in ((points[0], points[1], xy[: at[0] + 1]), (points[1], points[2], xy[at[0]:])):
            d = (b - a) / math.hypot(*(b - a))
            off = max(off, np.max(np.abs((part[:, 0] - a[0]) * d[1] - (part[:, 1] - a[1]) * d[0])))
        assert off > 1.0, off


def test_the_plot_draws_the_curves_off_a_sloping_bottom():
    """`eigenray.plot` of the rays: each drawn through its curve (many vertices, not its
    three points), the same points as `Rays.curve`."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.collections import LineCollection

    scene = eigenray.Scene(SCENE)
    rays = eigenray.Tracer(scene).trace_stationary()
    ax = eigenray.plot(scene, rays, aspect="auto")
    lines = [c for c in ax.collections if isinstance(c, LineCollection)][0].get_segments()
    assert len(lines) == len(rays.time) == 3
    for i, line in enumerate(lines):
        assert len(line) > 100
        np.testing.assert_allclose(line, rays.curve(i, len(line)), rtol=0, atol=1e-9)
