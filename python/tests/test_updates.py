"""Cheap updates in a layout loop: after each, the tracer's rays are bit for bit those of a
tracer built from the edited scene; a refused update raises naming the key and changes
nothing."""

import copy

import numpy as np
import pytest

import eigenray

BENT = {
    "media": {"air": {"speed": 343.0}, "water": {"speed": 1500.0}},
    "interfaces": {
        "surface": {"points": [[-10, 0], [-3, 0.4], [2, -0.3], [10, 0.2]]},
        "wall": {"points": [[-10, -8], [10, -9]]},
    },
    "sources": [[-2, 3], [1, 4]],
    "receivers": [[x, -4] for x in np.linspace(-6, 6, 12)],
    "paths": [
        {"name": "down", "steps": [{"refract": "surface"}], "media": ["air", "water"]},
        {"name": "echo", "steps": [{"refract": "surface"}, {"reflect": "wall"},
                                   {"refract": "surface"}],
         "media": ["air", "water", "water", "air"]},
    ],
}


def same_rays(a, b):
    for name in ("source", "receiver", "path", "status", "num_points", "media", "iterations"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for name in ("time", "points", "residual"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.reason == b.reason


def test_random_updates_give_the_rebuilt_tracers_rays():
    rng = np.random.default_rng(20)
    spec = copy.deepcopy(BENT)
    tracer = eigenray.Tracer(eigenray.Scene(spec))
    rays = tracer.trace()
    for step in range(60):
        kind = step % 5
        if kind == 0:
            i = int(rng.integers(len(spec["receivers"])))
            p = [float(rng.uniform(-6, 6)), float(rng.uniform(-6, -1))]
            tracer.set_receiver(i, p)
            spec["receivers"][i] = p
        elif kind == 1:
            i = int(rng.integers(2))
            p = [float(rng.uniform(-4, 4)), float(rng.uniform(1, 5))]
            tracer.set_source(i, p)
            spec["sources"][i] = p
        elif kind == 2:
            points = [list(v) for v in spec["interfaces"]["surface"]["points"]]
            j = int(rng.integers(1, 3))
            points[j][1] = float(rng.uniform(-0.6, 0.6))
            tracer.set_interface_points("surface", points)
            spec["interfaces"]["surface"]["points"] = points
        elif kind == 3:
            speed = float(rng.uniform(1000, 2000))
            tracer.set_medium_speed("water", speed)
            spec["media"]["water"] = {"speed": speed}
        else:
            receivers = np.column_stack(
                [np.sort(rng.uniform(-6, 6, 12)), rng.uniform(-6, -1, 12)]
            )
            tracer.set_receivers(receivers)
            spec["receivers"] = receivers.tolist()
        tracer.trace(out=rays)
        same_rays(rays, eigenray.Tracer(eigenray.Scene(spec)).trace())
        one = tracer.solve(spec["sources"][0], spec["receivers"][3], "echo")
        fresh = eigenray.Tracer(eigenray.Scene(spec)).solve(
            spec["sources"][0], spec["receivers"][3], "echo"
        )
        assert one.status == fresh.status
        assert np.array_equal(one.points, fresh.points)


@pytest.mark.parametrize(
    "update, key",
    [
        (lambda t: t.set_receiver(0, (0, float("nan"))), "receivers[0]"),
        (lambda t: t.set_receiver(99, (0, -1)), "receivers"),
        (lambda t: t.set_source(0, (0, 1, 2)), "sources[0]"),
        (lambda t: t.set_receivers(np.zeros((3, 2))), "receivers"),
        (lambda t: t.set_receivers(np.vstack([np.full((5, 2), -2.0), [[0, np.nan]],
                                              np.full((6, 2), -3.0)])), "receivers[5]"),
        (lambda t: t.set_interface_points("surface", [[-10, 0]]), "interfaces.surface.points"),
        (lambda t: t.set_interface_points("surface", [[-10, 0], [10, -20]]),
         "interfaces.surface.points"),
        (lambda t: t.set_medium_speed("water", -1.0), "media.water"),
        (lambda t: t.set_medium_index("air", float("inf")), "media.air"),
    ],
)
def test_a_refused_update_names_the_key_and_changes_nothing(update, key):
    tracer = eigenray.Tracer(eigenray.Scene(BENT))
    before = tracer.trace()
    with pytest.raises(eigenray.EigenrayError) as caught:
        update(tracer)
    assert caught.value.key.startswith(key), str(caught.value)
    same_rays(tracer.trace(), before)


def test_unknown_names_and_indices():
    tracer = eigenray.Tracer(eigenray.Scene(BENT))
    with pytest.raises(KeyError):
        tracer.set_interface_points("floor", [[0, 0], [1, 0]])
    with pytest.raises(KeyError):
        tracer.set_medium_speed("glass", 1.0)
    with pytest.raises(IndexError):
        tracer.set_medium_speed(5, 1.0)


def test_the_scene_a_tracer_was_made_from_does_not_change():
    scene = eigenray.Scene(BENT)
    tracer = eigenray.Tracer(scene)
    tracer.set_receiver(0, (0.5, -2))
    assert scene.receivers[0].tolist() == BENT["receivers"][0]
    assert tracer.scene.receivers[0].tolist() == [0.5, -2]
