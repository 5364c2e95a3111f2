"""Attenuation per wavelength (`{"db_per_wavelength": a}`) given in a scene dict: the same
amplitudes as the scene written in dB per unit length (a·f/c), its refusals naming the key, its
document, and a change of speed that moves it."""

import json
import math

import numpy as np
import pytest

import eigenray


def layered(sediment):
    """Water over a sediment attenuating as `sediment` gives it, at 250 Hz."""
    return {
        "media": {
            "water": {"speed": 1500, "attenuation": 0.002, "at": [10, -5]},
            "sediment": {"speed": 1700, "density": 1.8, "attenuation": sediment, "at": [10, -150]},
        },
        "domain": [[-1, -300], [3001, 1]],
        "interfaces": {
            "surface": {"points": [[-1, 0], [3001, 0]], "reflection": "pressure-release"},
            "bottom": {"points": [[-1, -100], [1500, -110], [3001, -100]], "reflection": "media"},
        },
        "sources": [[0, -30]],
        "receivers": [[1000, -60], [2500, -200], [2900, -20]],
        "paths": [
            {"steps": []},
            {"steps": [{"reflect": "bottom"}]},
            {"steps": [{"refract": "bottom"}]},
        ],
        "search": {"max_steps": 3, "refract": False},
        "amplitudes": {"source": "axisymmetric", "frequency": 250},
    }


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def columns(tracer):
    rays, arrivals = tracer.trace(), tracer.search()
    return [
        rays.amplitude, rays.attenuation_db, rays.spreading,
        arrivals.amplitude, arrivals.attenuation_db,
    ]


def test_per_wavelength_is_a_f_over_c_per_metre():
    per_wavelength = eigenray.Tracer(eigenray.Scene(layered({"db_per_wavelength": 0.5})))
    per_metre = eigenray.Tracer(eigenray.Scene(layered(0.5 * 250 / 1700)))
    got, want = columns(per_wavelength), columns(per_metre)
    # Ray 5 (the second receiver's refracted ray) ends in the sediment.
    assert np.isfinite(got[1][5]) and got[1][5] > 0.002 * 100
    for g, w in zip(got, want):
        assert same_bits(g, w)


def test_per_wavelength_refusals_name_the_key():
    without = layered({"db_per_wavelength": 0.5})
    del without["amplitudes"]["frequency"]
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Scene(without)
    assert caught.value.key == "media.sediment.attenuation"
    for bad, key in [
        ({"db_per_wavelength": -1}, "media.sediment.attenuation.db_per_wavelength"),
        ({"db_per_wavelenght": 1}, "media.sediment.attenuation"),
        (1e308, "media.sediment.attenuation"),
    ]:
        with pytest.raises(eigenray.EigenrayError) as caught:
            eigenray.Scene(layered(bad))
        assert caught.value.key == key


def test_the_document_keeps_it_and_a_new_speed_moves_it():
    scene = eigenray.Scene(layered({"db_per_wavelength": 0.5}))
    document = json.loads(scene.to_json())
    assert document["media"]["sediment"]["attenuation"] == {"db_per_wavelength": 0.5}
    tracer = eigenray.Tracer(scene)
    tracer.set_medium_speed("sediment", 1650)
    fresh = layered({"db_per_wavelength": 0.5})
    fresh["media"]["sediment"]["speed"] = 1650
    for g, w in zip(columns(tracer), columns(eigenray.Tracer(eigenray.Scene(fresh)))):
        assert same_bits(g, w)
    rays = tracer.trace()
    ray = 5  # the refracted ray to the second receiver, in the sediment
    points = rays.points[ray][: rays.num_points[ray]]
    legs = np.linalg.norm(np.diff(points, axis=0), axis=1)
    want = 0.002 * legs[0] + 0.5 * 250 / 1650 * legs[1]
    assert math.isclose(rays.attenuation_db[ray], want, rel_tol=1e-13)
