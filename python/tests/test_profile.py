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
    "receivers": [[8000, -500], [15000, -500]],
    "paths": [{"name": "direct", "steps": [], "media": ["sea"]}],
    "amplitudes": {"source": "point"},
}


def speed(y):
    ys = [k[0] for k in KNOTS][::-1]
    cs = [k[1] for k in KNOTS][::-1]
    return float(np.interp(y, ys, cs))


def down_and_back(p, y0):
    """Range and time of the ray of parameter p from y0 down to its turning point and back."""
    y_turn = brentq(lambda y: speed(y) - 1.0 / p, -3000.0, -1000.0, xtol=1e-14)
    top = math.sqrt(y0 - y_turn)
    # The knot at -1000 in the substitution's variable u (y = y_turn + u²).
    cut = math.sqrt(-1000.0 - y_turn)

    def integrand(u, f):
        y = y_turn + u * u
        c = speed(y)
        s = math.sqrt(max(1.0 - p * p * c * c, 0.0))
        return f(c, s) * 2.0 * u

    def both(f):
        # The integrand ~ u / √u² stays finite at u = 0: divide analytically near it.
        a = quad(lambda u: integrand(u, f) if u > 0 else 0.0, 0.0, cut, epsabs=0, epsrel=1e-13, limit=200)[0]
        b = quad(lambda u: integrand(u, f), cut, top, epsabs=0, epsrel=1e-13, limit=200)[0]
        return 2.0 * (a + b)

    x = both(lambda c, s: p * c / s)
    t = both(lambda c, s: 1.0 / (c * s))
    return x, t


def test_turning_rays_match_quadrature():
    tracer = eigenray.Tracer(eigenray.Scene(SCENE))
    y0 = -500.0
    p_hi = 1.0 / speed(y0) * (1 - 1e-9)  # below: the ray leaves the source's height
    p_lo = 1.0 / 1530.0 * (1 + 1e-9)  # above: it turns above the last knot
    grid = np.linspace(p_lo, p_hi, 400)
    for rx in (8000.0, 15000.0):
        values = [down_and_back(p, y0)[0] - rx for p in grid]
        roots = [
            brentq(lambda p: down_and_back(p, y0)[0] - rx, grid[i], grid[i + 1], xtol=1e-20, rtol=1e-15)
            for i in range(len(grid) - 1)
            if values[i] * values[i + 1] < 0
        ]
        expected = sorted(down_and_back(p, y0)[1] for p in roots)
        rays, complete = tracer.stationary_paths((0, y0), (rx, y0), "direct")
        assert not complete
        ours = sorted(r.time for r in rays if r.turns == 1 and r.launch_angle < 0)
        assert len(ours) == len(expected) >= 1, (ours, expected)
        for a, b in zip(ours, expected):
            assert abs(a - b) < 1e-9 * b, (a, b)
        # Every ray has its columns, and amplitudes with a caustic phase of -π/2 each.
        for r in rays:
            assert r.turns >= 0 and r.caustics >= 0
            phase = math.atan2(r.amplitude.imag, r.amplitude.real)
            expect = math.remainder(-math.pi / 2 * r.caustics, 2 * math.pi)
            assert abs(math.remainder(phase - expect, 2 * math.pi)) < 1e-9


def test_columns_of_a_batch():
    scene = dict(SCENE, solver={"stationary": "all"})
    rays = eigenray.Tracer(eigenray.Scene(scene)).trace()
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
