"""A ray's curve from Python (`Ray.curve`, `Rays.curve`, `Arrivals.curve`, `Scene.curve`):
a profile's rays against scipy's integration of the ray equations (y and the angle as
functions of x, every knot an event), the legs of a linear profile between walls and of a
gradient medium against the circle through each leg's ends centred where the speed is 0,
the interaction points among the samples, the `turns`, `caustics` and `launch_angle`
columns of `Arrivals`, pickling, the plot's lines, and the errors naming the argument."""

import math
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import eigenray

KNOTS = [[0.0, 1520.0], [-1000.0, 1490.0], [-3000.0, 1530.0]]
CHANNEL = {
    "media": {"sea": {"profile": KNOTS}},
    "sources": [[0, -800]],
    "receivers": [[15000, -1200], [30000, -1100]],
    "paths": [{"name": "direct", "steps": [], "media": ["sea"]}],
}


def layer(y, going_up):
    """The layer's speed line (c at y, slope) at y, the one a ray going up or down enters
    at a knot; the end knots' speeds beyond them."""
    ys = [k[0] for k in KNOTS]
    if y > ys[0] or (y == ys[0] and going_up):
        return KNOTS[0][1], 0.0
    if y < ys[-1] or (y == ys[-1] and not going_up):
        return KNOTS[-1][1], 0.0
    for (y0, c0), (y1, c1) in zip(KNOTS[:-1], KNOTS[1:]):
        if y1 < y < y0 or (y == y0 and not going_up) or (y == y1 and going_up):
            slope = (c1 - c0) / (y1 - y0)
            return c0 + slope * (y - y0), slope
    raise AssertionError(y)


def integrated(theta, x_end):
    """The ray from the source at launch angle theta as y(x): dy/dx = tan θ, dθ/dx = −c′/c,
    by DOP853 (rtol 1e-12), each knot a terminal event where the layer changes. Returns
    a function of x (dense output, piece by piece)."""
    x, u, pieces = 0.0, [-800.0, theta], []
    while x < x_end:
        up = math.sin(u[1]) >= 0
        c0, slope = layer(u[0], up)
        y_ref = u[0]

        def rhs(_x, v, c0=c0, slope=slope, y_ref=y_ref):
            return [math.tan(v[1]), -slope / (c0 + slope * (v[0] - y_ref))]

        events = []
        for k in KNOTS:
            ev = lambda _x, v, ky=k[0]: v[0] - ky  # noqa: E731
            ev.terminal = True
            if k[0] == u[0]:
                # The knot it leaves: only its return through it.
                ev.direction = 1.0 if not up else -1.0
            events.append(ev)
        sol = solve_ivp(rhs, (x, x_end), u, method="DOP853", rtol=1e-12, atol=1e-10,
                        dense_output=True, events=events)
        pieces.append((x, sol.t[-1], sol.sol))
        x, u = sol.t[-1], list(sol.y[:, -1])
        if sol.status == 1:
            # Onto the knot exactly, into the next layer.
            u[0] = min((k[0] for k in KNOTS), key=lambda ky: abs(ky - u[0]))

    def y_of(xq):
        # (The longest piece that holds xq: a knot's event can leave a piece of no length.)
        holding = [(b - a, f) for a, b, f in pieces if a <= xq <= b]
        return max(holding, key=lambda h: h[0])[1](xq)[0]

    return y_of


def test_profile_curves_lie_on_the_integrated_ray():
    """Every ray of a sound channel (3 at 15 km, 4 at 30 km, up to 3 turns), `Ray.curve(301)`:
    301 points, the source first and the receiver last, every point within 1e-6 m (in y at
    its x) of scipy's integration from the ray's launch angle, in x order."""
    tracer = eigenray.Tracer(eigenray.Scene(CHANNEL))
    worst, count, turns = 0.0, 0, 0
    for receiver in CHANNEL["receivers"]:
        rays, _ = tracer.stationary_paths((0, -800), receiver, "direct")
        assert len(rays) >= 3
        for ray in rays:
            curve = ray.curve(301)
            assert curve.shape == (301, 2) and curve.dtype == np.float64
            np.testing.assert_array_equal(curve[0], ray.points[0])
            np.testing.assert_array_equal(curve[-1], ray.points[-1])
            assert np.all(np.diff(curve[:, 0]) > 0)
            y_of = integrated(ray.launch_angle, receiver[0])
            off = max(abs(y_of(x) - y) for x, y in curve)
            worst = max(worst, off)
            assert off < 1e-6, (ray.launch_angle, off)
            count += 1
            turns = max(turns, ray.turns)
    assert count >= 7 and turns >= 3
    print(f"{count} rays: worst {worst:.1e} m from scipy's")


def circle(a, b, yc):
    """The centre's x (on y = yc) equidistant from a and b, and the radius."""
    xc = ((b[0] ** 2 - a[0] ** 2) + (b[1] - yc) ** 2 - (a[1] - yc) ** 2) / (2 * (b[0] - a[0]))
    return xc, math.hypot(a[0] - xc, a[1] - yc)


def guide(water):
    return {
        "media": {
            "water": dict(water, at=[0, -50]),
            "mud": {"speed": 1700, "at": [0, -150]},
            "air": {"speed": 340, "at": [0, 50]},
        },
        "domain": [[-3000, -300], [6000, 100]],
        "interfaces": {
            "surface": {"points": [[-3000, 0], [6000, 0]]},
            "bottom": {"points": [[-3000, -100], [6000, -100]]},
        },
        "sources": [[0, -30]],
        "receivers": [[2500, -70], [-1500, -10]],
        "search": {"max_steps": 3},
    }


def test_arrivals_curves_pass_their_reflections_on_circles():
    """A linear profile (c = 1500 + 0.2 y, 0 at y = −7500) between walls: each search
    arrival's `Arrivals.curve(i, 120)` has its points among its samples in order, and every
    sample lies on its leg's circle to 1e-9 of the radius; the columns `turns`, `caustics`
    and `launch_angle` are arrays of one entry per arrival, in the dicts too."""
    scene = eigenray.Scene(guide({"profile": [[0, 1500], [-100, 1480]]}))
    arrivals = eigenray.Tracer(scene).search()
    n = len(arrivals)
    assert n >= 8 and max(arrivals.order) == 3
    for name in ("turns", "caustics", "launch_angle"):
        column = getattr(arrivals, name)
        assert column.shape == (n,) and np.all(np.isfinite(column)), name
        assert arrivals[0][name] == column[0]
    for i in range(n):
        points = arrivals.points[i, : arrivals.order[i] + 2]
        curve = arrivals.curve(i, 120)
        assert curve.shape == (120, 2)
        at = []
        for p in points:
            start = at[-1] + 1 if at else 0
            hits = np.flatnonzero(np.all(curve[start:] == p, axis=1))
            assert len(hits), (i, p)
            at.append(start + hits[0])
        assert at[0] == 0 and at[-1] == 119
        for leg, (j, k) in enumerate(zip(at[:-1], at[1:])):
            xc, radius = circle(points[leg], points[leg + 1], -7500.0)
            d = np.hypot(curve[j : k + 1, 0] - xc, curve[j : k + 1, 1] + 7500.0) - radius
            assert np.max(np.abs(d)) < 1e-9 * radius, (i, leg)


def test_gradient_legs_and_the_rays_arrays():
    """A reflection in a gradient medium (c = 1500 − 0.05 y): `Rays.curve` and the `Ray`'s
    `curve` are the same points, both legs on their circles (1e-9 of the radius), evenly
    spaced along each; `Scene.curve` of the points and media gives them too; a pickled
    `Rays` keeps its scene for its curves."""
    scene = eigenray.Scene({
        "media": {"sea": {"speed": 1500, "gradient": [0, -0.05]}},
        "interfaces": {"floor": {"points": [[-100, -2000], [9000, -2000]]}},
        "sources": [[0, -100]],
        "receivers": [[7000, -400]],
        "paths": [{"steps": [{"reflect": "floor"}], "media": ["sea", "sea"]}],
    })
    tracer = eigenray.Tracer(scene)
    rays = tracer.trace()
    ray = tracer.solve((0, -100), (7000, -400))
    curve = rays.curve(0, 81)
    np.testing.assert_array_equal(curve, ray.curve(81))
    np.testing.assert_array_equal(curve, scene.curve(ray.points, ray.media, n=81))
    np.testing.assert_array_equal(curve, pickle.loads(pickle.dumps(rays)).curve(-1, 81))
    mid = int(np.flatnonzero(np.all(curve == ray.points[1], axis=1))[0])
    yc = 1500 / 0.05
    for a, b, part in ((ray.points[0], ray.points[1], curve[: mid + 1]),
                       (ray.points[1], ray.points[2], curve[mid:])):
        xc, radius = circle(a, b, yc)
        assert np.max(np.abs(np.hypot(part[:, 0] - xc, part[:, 1] - yc) - radius)) < 1e-9 * radius
        angles = np.unwrap(np.arctan2(part[:, 1] - yc, part[:, 0] - xc))
        steps = np.diff(angles)
        assert np.max(np.abs(steps - steps.mean())) < 1e-9 * abs(steps.mean())


def test_straight_legs_and_errors_naming_the_argument():
    scene = eigenray.Scene({
        "media": {"air": {"speed": 340}},
        "interfaces": {"wall": {"points": [[-10, 0], [10, 0]]}},
        "sources": [[0, 1]],
        "receivers": [[4, 3]],
        "paths": [{"steps": [{"reflect": "wall"}], "media": ["air", "air"]}],
    })
    ray = eigenray.Tracer(scene).solve((0, 1), (4, 3))
    curve = ray.curve(3)
    np.testing.assert_array_equal(curve, ray.points)
    with pytest.raises(eigenray.EigenrayError) as e:
        ray.curve(2)
    assert e.value.key == "n"
    with pytest.raises(eigenray.EigenrayError) as e:
        scene.curve([[0, 1], [math.nan, 0]], ["air"])
    assert e.value.key == "points"
    with pytest.raises(KeyError):
        scene.curve([[0, 1], [1, 0]], ["water"])
    tracer = eigenray.Tracer(eigenray.Scene(CHANNEL))
    ray = tracer.solve((0, -800), (15000, -1200), "direct")
    with pytest.raises(eigenray.EigenrayError) as e:
        tracer.scene.curve(ray.points, ray.media, launch_angle=1.2)
    assert e.value.key == "launch_angle"
    # Without a launch angle, the default mode's ray: the Ray's own.
    np.testing.assert_array_equal(tracer.scene.curve(ray.points, ray.media, n=50), ray.curve(50))
    with pytest.raises(IndexError):
        tracer.trace().curve(5)


def test_the_plot_draws_the_curves():
    """`eigenray.plot` of a channel's stationary paths: each ray drawn through its curve
    (hundreds of vertices, not its two points)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.collections import LineCollection

    scene = eigenray.Scene(dict(CHANNEL, solver={"stationary": "all"}))
    rays = eigenray.Tracer(scene).trace_stationary()
    ax = eigenray.plot(scene, rays)
    lines = [c for c in ax.collections if isinstance(c, LineCollection)][0].get_segments()
    assert len(lines) == len(rays) >= 7
    for i, line in enumerate(lines):
        assert len(line) > 100
        np.testing.assert_allclose(line, rays.curve(i, len(line)), rtol=0, atol=1e-9)
