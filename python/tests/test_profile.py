"""Media with a speed profile from Python: the rays of a turning branch through two layers
against scipy's quadrature of the ray integrals (the turning point's square-root singularity
removed by a substitution, the ray parameter by brentq), the turns, caustics and
launch_angle columns, and the refusals naming the key."""

import copy
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import eigenray

KNOTS = [[0.0, 1520.0], [-1000.0, 1490.0], [-3000.0, 1530.0]]
SCENE = {
    "media": {"sea": {"profile": KNOTS}},
    "sources": [[0, -500]],
    "receivers": [[8000, -500]],
    "paths": [{"name": "direct", "steps": [], "media": ["sea"]}],
    "amplitudes": {"source": "point"},
}


def speed(y):
    ys = [k[0] for k in KNOTS][::-1]
    cs = [k[1] for k in KNOTS][::-1]
    return float(np.interp(y, ys, cs))


def down_and_back(p, y0):
    """Range and time of the ray of parameter p from y0 (in the upper layer) down through
    the axis to its turning point in the lower layer and back: 2 ∫ g(c) / s dy with s =
    √(1 − p²c²), g = p c for the range and 1/c for the time. With y = y_turn + u², below the
    knot at −1000 (where c = c_turn + slope·(y_turn − y), the layer's line) s = u √(p |slope|
    (1 + p c)), so the integrand 2u g / s = 2 g / √(p |slope| (1 + p c)) has no singularity."""
    slope = (1530.0 - 1490.0) / 2000.0
    y_turn = brentq(lambda y: speed(y) - 1.0 / p, -3000.0, -1000.0, xtol=1e-14)
    top = math.sqrt(y0 - y_turn)
    cut = math.sqrt(-1000.0 - y_turn)

    def both(g):
        def lower(u):
            c = speed(y_turn + u * u)
            return 2.0 * g(c) / math.sqrt(p * slope * (1.0 + p * c))

        def upper(u):
            c = speed(y_turn + u * u)
            return 2.0 * u * g(c) / math.sqrt(1.0 - p * p * c * c)

        a = quad(lower, 0.0, cut, epsabs=0, epsrel=1e-13, limit=200)[0]
        b = quad(upper, cut, top, epsabs=0, epsrel=1e-13, limit=200)[0]
        return 2.0 * (a + b)

    return both(lambda c: p * c), both(lambda c: 1.0 / c)


Y0 = -500.0
P_GRID = np.linspace(1.0 / 1530.0 * (1 + 1e-9), 1.0 / speed(Y0) * (1 - 1e-6), 300)


def receivers():
    """Two ranges the branch (down, one turn) reaches: within its range's span."""
    xs = [down_and_back(p, Y0)[0] for p in P_GRID]
    return [float(round(q)) for q in np.quantile(xs, [0.3, 0.7])]


def test_turning_rays_match_quadrature():
    tracer = eigenray.Tracer(eigenray.Scene(SCENE))
    values_at = [down_and_back(p, Y0)[0] for p in P_GRID]
    for rx in receivers():
        values = [v - rx for v in values_at]
        roots = [
            brentq(lambda p: down_and_back(p, Y0)[0] - rx, P_GRID[i], P_GRID[i + 1], xtol=1e-20, rtol=1e-15)
            for i in range(len(P_GRID) - 1)
            if values[i] * values[i + 1] < 0
        ]
        expected = sorted(down_and_back(p, Y0)[1] for p in roots)
        rays, complete = tracer.stationary_paths((0, Y0), (rx, Y0), "direct")
        assert not complete
        ours = sorted(r.time for r in rays if r.turns == 1 and r.launch_angle < 0)
        assert len(ours) == len(expected) >= 1, (rx, ours, expected)
        for a, b in zip(ours, expected):
            assert abs(a - b) < 1e-9 * b, (a, b)
        # Every ray has its columns, and amplitudes with a caustic phase of -π/2 each.
        for r in rays:
            assert r.turns >= 0 and r.caustics >= 0
            phase = math.atan2(r.amplitude.imag, r.amplitude.real)
            expect = math.remainder(-math.pi / 2 * r.caustics, 2 * math.pi)
            assert abs(math.remainder(phase - expect, 2 * math.pi)) < 1e-9


def test_columns_of_a_batch():
    scene = dict(SCENE, solver={"stationary": "all"}, receivers=[[x, Y0] for x in receivers()])
    rays = eigenray.Tracer(eigenray.Scene(scene)).trace()
    assert len(rays.time) >= 2
    assert np.all(np.isfinite(rays.turns))
    assert np.all(np.isfinite(rays.caustics))
    assert np.all(np.isfinite(rays.launch_angle))


@pytest.mark.parametrize(
    "change, key",
    [
        (lambda s: s["media"]["sea"].update(profile=[[0, 1500]]), "media.sea.profile"),
        (lambda s: s["media"]["sea"].update(profile=[[0, 1500], [1, 1490]]), r"media.sea.profile\[1\]"),
        (lambda s: s["media"]["sea"].update(profile=[[0, 1500], [-1, -3]]), r"media.sea.profile\[1\]"),
        (lambda s: s["media"]["sea"].update(speed=1500), "media.sea.profile"),
        (lambda s: s["media"]["sea"].update(gradient=[0, 1]), "media.sea.gradient"),
    ],
)
def test_bad_profiles_are_refused_naming_the_key(change, key):
    scene = copy.deepcopy(SCENE)
    change(scene)
    with pytest.raises((eigenray.EigenrayError, ValueError), match=key.replace(".", r"\.") if "[" not in key else key):
        eigenray.Scene(scene)


def guide(water):
    """A waveguide 100 m deep: a pressure-release surface, a `"media"` bottom over mud."""
    return {
        "media": {
            "water": dict(water, at=[0, -50]),
            "mud": {"speed": 1700, "density": 1.8, "at": [0, -150]},
            "air": {"speed": 340, "density": 0.0012, "at": [0, 50]},
        },
        "domain": [[-3000, -300], [6000, 100]],
        "interfaces": {
            "surface": {"points": [[-3000, 0], [6000, 0]], "reflection": "pressure-release"},
            "bottom": {"points": [[-3000, -100], [6000, -100]], "reflection": "media"},
        },
        "sources": [[0, -30]],
        "receivers": {"grid": {"x": [100, 3000, 12], "y": [-5, -95, 7]}},
        "search": {"max_steps": 5},
        "amplitudes": {"source": "point", "frequency": 100},
    }


def test_an_isovelocity_waveguide_is_the_uniform_medium():
    """A profile of one speed between a surface and a bottom: the search lists the uniform
    medium's (image-method) arrivals, and the transmission loss streamed from them is the
    uniform medium's to 1e-9 dB."""
    iso = eigenray.Tracer(eigenray.Scene(guide({"profile": [[0, 1500], [-100, 1500]]})))
    uniform = eigenray.Tracer(eigenray.Scene(guide({"speed": 1500})))
    a, b = iso.search(), uniform.search()
    assert len(a) == len(b) > 12 * 7
    assert not np.any(a.complete)
    np.testing.assert_allclose(np.sort(a.time), np.sort(b.time), rtol=1e-12, atol=0)
    tl_a, tl_b = iso.transmission_loss(), uniform.transmission_loss()
    assert tl_a.shape == (1, 12, 7)
    np.testing.assert_allclose(tl_a, tl_b, rtol=0, atol=1e-9)


def test_a_sloping_bottom_search_is_the_uniform_medium():
    """A profile of one speed over a bottom sloping from 100 to 130 (and a `"media"` bottom
    over mud): the search lists the uniform medium's (beam tree, image method) arrivals up to
    three reflections, the same walls, times to 1e-12 and amplitudes (the angle-dependent
    bottom coefficient included) to 1e-9."""
    def sloping(water):
        scene = guide(water)
        scene["interfaces"]["bottom"]["points"] = [[-3000, -100], [6000, -130]]
        scene["receivers"] = [[2000, -60], [-1500, -95], [4500, -10]]
        scene["search"] = {"max_steps": 3, "refract": False}
        return scene

    iso = eigenray.Tracer(eigenray.Scene(sloping({"profile": [[0, 1500], [-150, 1500]]})))
    uniform = eigenray.Tracer(eigenray.Scene(sloping({"speed": 1500})))
    a, b = iso.search(), uniform.search()
    assert len(a) == len(b) >= 20
    assert not np.any(a.complete)
    np.testing.assert_array_equal(a.receiver, b.receiver)
    np.testing.assert_array_equal(a.step_interface, b.step_interface)
    np.testing.assert_allclose(a.time, b.time, rtol=1e-12, atol=0)
    np.testing.assert_allclose(a.amplitude, b.amplitude, rtol=1e-9, atol=0)


def test_a_closed_interface_in_a_profile_search_is_refused_naming_the_key():
    scene = guide({"profile": [[0, 1500], [-100, 1510]]})
    scene["interfaces"]["bottom"]["points"] = [[-3000, -100], [6000, -130], [0, -200]]
    scene["interfaces"]["bottom"]["closed"] = True
    with pytest.raises((eigenray.EigenrayError, ValueError), match="interfaces.bottom"):
        eigenray.Scene(scene)


@pytest.mark.parametrize("reflected", [False, True])
def test_gradient_through_a_profile_matches_finite_differences(reflected):
    """Tracer.gradient through a profile (the default mode's ray: a turning direct ray, or
    one reflected off the bottom, then the surface): `profile_speed` (dT/dc of each knot),
    the source, the receiver and the `slowness` entry (w = 1/c of the first knot, the
    profile's shape held) against central differences of re-solved times."""
    if reflected:
        scene = guide({"profile": [[20, 1521], [-35, 1510], [-60, 1497], [-130, 1502]]})
        del scene["search"], scene["receivers"]
        scene["receivers"] = [[2500, -70]]
        scene["paths"] = [{"name": "bs", "steps": [{"reflect": "bottom"}, {"reflect": "surface"}],
                           "media": ["water"] * 3}]
        medium, path, (s, r) = "water", "bs", ((0, -30), (2500, -70))
    else:
        scene = copy.deepcopy(SCENE)
        medium, path, (s, r) = "sea", "direct", ((0, Y0), (receivers()[0], Y0))
    knots = scene["media"][medium]["profile"]

    def gradient(doc, s=s, r=r):
        return eigenray.Tracer(eigenray.Scene(doc)).gradient(s, r, path)

    g = gradient(scene)
    assert g.status == "converged"
    assert set(g.profile_speed) == {medium} and g.profile_speed[medium].shape == (len(knots),)
    assert g.speed_gradient == {}

    def difference(change, h):
        times = []
        for d in (h, -h):
            doc = copy.deepcopy(scene)
            change(doc, d)
            times.append(gradient(doc).time)
        return (times[0] - times[1]) / (2 * h)

    for k in range(len(knots)):
        def change(doc, d, k=k):
            doc["media"][medium]["profile"][k][1] += d
        fd = difference(change, 1e-3)
        assert abs(g.profile_speed[medium][k] - fd) < 1e-9, (k, g.profile_speed[medium][k], fd)

    def shift(doc, d):
        for knot in doc["media"][medium]["profile"]:
            knot[1] += d
    c0 = knots[0][1]
    assert abs(g.slowness[medium] - (-c0 * c0 * difference(shift, 1e-3))) < 1e-9 * c0 * c0
    for i in range(2):
        for end, d in (("source", g.source), ("receiver", g.receiver)):
            def moved(h, i=i, end=end):
                a, b = list(s), list(r)
                (a if end == "source" else b)[i] += h
                return gradient(scene, tuple(a), tuple(b)).time
            fd = (moved(1e-2) - moved(-1e-2)) / 2e-2
            assert abs(d[i] - fd) < 1e-9, (end, i, d[i], fd)
    if reflected:
        assert {v["interface"] for v in g.vertices} == {"surface", "bottom"}
        assert all(v["d"][0] == 0.0 for v in g.vertices)


def munk(n):
    """The Munk profile at n knots from 0 to 5000 m depth (y = -z)."""
    knots = []
    for z in np.linspace(0.0, 5000.0, n):
        eta = 2.0 * (z - 1300.0) / 1300.0
        knots.append([-float(z), 1500.0 * (1.0 + 0.00737 * (eta - 1.0 + math.exp(-eta)))])
    return knots


def test_gradients_of_a_batch_are_each_rays_own():
    """`Tracer.gradients(rays)` through a profile: of the three rays `"stationary": "all"`
    finds between the same points in the Munk profile at 60 km, each row is the ray of its
    own `launch_angle`: its receiver gradient and its knots' `profile_speed` against central
    differences of that ray's re-solved time (found again by its turns and nearest launch
    angle)."""
    scene = {
        "media": {"ocean": {"profile": munk(11)}},
        "sources": [[0, -1000]],
        "receivers": [[60000, -800]],
        "paths": [{"steps": [], "media": ["ocean"]}],
    }

    def rays_of(doc):
        return eigenray.Tracer(eigenray.Scene(doc)).trace_stationary()

    rays = rays_of(scene)
    n = len(rays.time)
    assert n == 3
    grads = eigenray.Tracer(eigenray.Scene(scene)).gradients(rays)
    assert grads.speed_gradient == {}
    assert grads.profile_speed["ocean"].shape == (n, 11)

    def time_of(doc, i):
        again = rays_of(doc)
        same = [j for j in range(len(again.time)) if again.turns[j] == rays.turns[i]]
        j = min(same, key=lambda j: abs(again.launch_angle[j] - rays.launch_angle[i]))
        return again.time[j]

    for i in range(n):
        for axis in range(2):
            times = []
            for h in (1e-2, -1e-2):
                doc = copy.deepcopy(scene)
                doc["receivers"][0][axis] += h
                times.append(time_of(doc, i))
            fd = (times[0] - times[1]) / 2e-2
            assert abs(grads.receiver[i, axis] - fd) < 1e-9, (i, axis, grads.receiver[i], fd)
        for k in (0, 2, 5, 10):
            times = []
            for h in (1e-3, -1e-3):
                doc = copy.deepcopy(scene)
                doc["media"]["ocean"]["profile"][k][1] += h
                times.append(time_of(doc, i))
            fd = (times[0] - times[1]) / 2e-3
            assert abs(grads.profile_speed["ocean"][i, k] - fd) < 2e-9, (i, k)
    # The rows are of different rays: their receiver gradients differ.
    assert len({tuple(np.round(grads.receiver[i], 12)) for i in range(n)}) == n
