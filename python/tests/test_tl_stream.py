"""Transmission loss and streamed responses from Python (`Tracer.transmission_loss`,
`Tracer.pressure`, `Tracer.impulse_response`): closed forms (the free field, Lloyd's
mirror, a waveguide's image sum), coherent against incoherent, a grid's shape, and the
streamed sums against the echoes listed by `Tracer.echoes()`."""

import json
import math

import numpy as np
import pytest

import eigenray


def lloyd(mode=None, y=(-5, -95, 10)):
    doc = {
        "media": {"water": {"speed": 1500}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[-5000, 0], [5000, 0]], "reflection": "pressure-release"}
        },
        "sources": [[0, -25]],
        "receivers": {"grid": {"x": [50, 1000, 20], "y": list(y)}},
        "search": {"max_steps": 1, "refract": False},
        "amplitudes": {"source": "point", "frequency": 100},
    }
    if mode is not None:
        doc["transmission_loss"] = {"mode": mode}
    return eigenray.Tracer(eigenray.Scene.from_json(json.dumps(doc)))


def lloyd_closed_form():
    k = 2 * math.pi * 100 / 1500
    x = np.linspace(50, 1000, 20)[:, None]
    y = np.linspace(-5, -95, 10)[None, :]
    r1 = np.hypot(x, y + 25)
    r2 = np.hypot(x, y - 25)
    p = np.exp(1j * k * r1) / r1 - np.exp(1j * k * r2) / r2
    coherent = -20 * np.log10(np.abs(p))
    incoherent = -10 * np.log10(1 / r1**2 + 1 / r2**2)
    return coherent, incoherent


def test_lloyds_mirror_both_modes_in_the_grids_shape():
    coherent, incoherent = lloyd_closed_form()
    tracer = lloyd()
    tl = tracer.transmission_loss()
    assert tl.shape == (1, 20, 10) and tl.dtype == np.float64
    np.testing.assert_allclose(tl[0], coherent, atol=1e-9, rtol=0)
    np.testing.assert_allclose(
        tracer.transmission_loss(mode="incoherent")[0], incoherent, atol=1e-9, rtol=0
    )
    # The scene's mode is the default; the argument overrides it.
    scene_incoherent = lloyd("incoherent")
    np.testing.assert_array_equal(
        scene_incoherent.transmission_loss(), tracer.transmission_loss(mode="incoherent")
    )
    np.testing.assert_array_equal(
        scene_incoherent.transmission_loss(mode="coherent"), tl
    )
    # The incoherent loss never lies below the stronger path's alone.
    assert np.all(tracer.transmission_loss(mode="incoherent") <= tl.max() + 1e-9)
    p = tracer.pressure()
    assert p.shape == (1, 20, 10)
    np.testing.assert_allclose(-20 * np.log10(4 * np.pi * np.abs(p)), tl, atol=1e-12, rtol=0)


def test_the_streamed_sums_equal_the_listed_echoes():
    tracer = lloyd()
    e = tracer.echoes()
    f = 100.0
    want = np.zeros(200, complex)
    np.add.at(want, e["receiver"], e["amplitude"] * np.exp(2j * np.pi * np.mod(f * e["time"], 1)))
    p = tracer.pressure().reshape(-1)
    scale = np.zeros(200)
    np.add.at(scale, e["receiver"], np.abs(e["amplitude"]))
    assert np.all(np.abs(p - want) <= 1e-12 * scale)


def test_nothing_arrives_gives_inf_never_nan():
    tracer = lloyd(y=(5, -85, 10))
    for mode in ("coherent", "incoherent"):
        tl = tracer.transmission_loss(mode=mode)
        assert not np.isnan(tl).any()
        assert np.sum(np.isinf(tl)) == 20 and np.all(tl[0, :, 0] == np.inf)


def test_free_field_is_twenty_log_r():
    doc = {
        "media": {"water": {"speed": 1500}},
        "background": "water",
        "sources": [[0, 0]],
        "receivers": [[1, 0], [30, 40], [0, -250]],
        "search": {"max_steps": 0},
        "amplitudes": {"source": "point", "frequency": 50},
    }
    tracer = eigenray.Tracer(eigenray.Scene.from_json(json.dumps(doc)))
    for mode in ("coherent", "incoherent"):
        tl = tracer.transmission_loss(mode=mode)
        assert tl.shape == (1, 3)
        np.testing.assert_allclose(tl[0], 20 * np.log10([1, 50, 250]), atol=1e-12, rtol=0)


def test_bad_arguments_name_their_key():
    tracer = lloyd()
    with pytest.raises(ValueError, match="mode"):
        tracer.transmission_loss(mode="loud")
    with pytest.raises(ValueError, match="frequency"):
        tracer.transmission_loss(frequency=-1)
    with pytest.raises(ValueError, match="transmission_loss"):
        doc = json.loads(json.dumps({
            "media": {"w": {"speed": 1500}}, "sources": [[0, 0]], "receivers": [[1, 0]],
            "paths": [{"steps": []}], "transmission_loss": {"mode": "coherent"},
        }))
        eigenray.Scene.from_json(json.dumps(doc))


def test_a_grids_impulse_response_has_the_grids_shape():
    doc = {
        "media": {"air": {"speed": 343}},
        "background": "air",
        "interfaces": {"floor": {"points": [[-10, 0], [10, 0]]}},
        "sources": [[0, 1]],
        "receivers": {"grid": {"x": [1, 3, 3], "y": [0.5, 2, 2]}},
        "search": {"max_steps": 1, "refract": False},
        "amplitudes": {"source": "point"},
        "impulse_response": {"rate": 8000, "duration": 0.05},
    }
    tracer = eigenray.Tracer(eigenray.Scene.from_json(json.dumps(doc)))
    ir = tracer.impulse_response()
    assert ir.shape == (1, 3, 2, 400)
    # The direct and the floor's echo at each receiver: the peaks near their times.
    x, y = 3.0, 2.0
    t = math.hypot(x, y - 1) / 343
    assert abs(np.argmax(ir[0, 2, 1]) - t * 8000) <= 1
