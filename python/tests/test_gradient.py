"""Derivatives from Python: the seed's named case, central differences of re-solved times
(through the updates), and the command-line tool's "gradient" bit for bit."""

import copy
import json
import subprocess

import numpy as np
import pytest

import eigenray

SEED = {
    "media": {"air": {"index": 1.0}, "water": {"index": 1.333}},
    "interfaces": {"surface": {"points": [[-1, 0], [2, 0]]}},
    "sources": [[0, 1]],
    "receivers": [[1, -1]],
    "paths": [{"steps": [{"refract": "surface"}], "media": ["air", "water"]}],
}

BENT = {
    "media": {"air": {"speed": 1.0}, "glass": {"speed": 0.6}},
    "interfaces": {
        "front": {"points": [[-3, 0.2], [-1, -0.1], [1, 0.15], [3, -0.05]]},
        "back": {"points": [[-3, -2], [3, -2.3]]},
    },
    "sources": [[-0.7, 1.5]],
    "receivers": [[1.2, 1.3]],
    "paths": [{"name": "echo", "steps": [{"refract": "front"}, {"reflect": "back"},
                                         {"refract": "front"}],
               "media": ["air", "glass", "glass", "air"]}],
}


def test_the_seed_case_moves_with_the_legs_directions():
    tracer = eigenray.Tracer(eigenray.Scene(SEED))
    g = tracer.gradient((0, 1), (1, -1))
    ray = tracer.solve((0, 1), (1, -1))
    first = ray.points[1] - ray.points[0]
    last = ray.points[2] - ray.points[1]
    assert np.allclose(g.receiver, 1.333 * last / np.linalg.norm(last), rtol=0, atol=1e-12)
    assert np.allclose(g.source, -1.0 * first / np.linalg.norm(first), rtol=0, atol=1e-12)
    # dT/dw of a medium is the length of the path in it.
    assert g.slowness["air"] == pytest.approx(np.linalg.norm(first), rel=1e-14)
    assert g.slowness["water"] == pytest.approx(np.linalg.norm(last), rel=1e-14)
    assert [(v["interface"], v["vertex"]) for v in g.vertices] == [("surface", 0), ("surface", 1)]
    assert g.time == ray.time


def central(time_of, h=1e-6):
    return (time_of(h) - time_of(-h)) / (2 * h)


def test_central_differences_of_re_solved_times():
    scene = eigenray.Scene(BENT)
    tracer = eigenray.Tracer(scene)
    s, r = BENT["sources"][0], BENT["receivers"][0]
    g = tracer.gradient(s, r, "echo")
    assert g.status == "converged"

    def receiver_x(h):
        return tracer.time(s, (r[0] + h, r[1]), "echo")

    def source_y(h):
        return tracer.time((s[0], s[1] + h), r, "echo")

    assert g.receiver[0] == pytest.approx(central(receiver_x), abs=1e-8)
    assert g.source[1] == pytest.approx(central(source_y), abs=1e-8)

    def glass_slowness(h):
        moved = eigenray.Tracer(scene)
        moved.set_medium_speed("glass", 1 / (1 / 0.6 + h))
        return moved.time(s, r, "echo")

    assert g.slowness["glass"] == pytest.approx(central(glass_slowness), abs=1e-8)
    assert g.slowness["air"] > 0
    touched = {(v["interface"], v["vertex"]) for v in g.vertices}
    front = BENT["interfaces"]["front"]["points"]
    for j in range(len(front)):
        for axis in range(2):

            def vertex(h):
                points = copy.deepcopy(front)
                points[j][axis] += h
                moved = eigenray.Tracer(scene)
                moved.set_interface_points("front", points)
                return moved.time(s, r, "echo")

            expected = central(vertex)
            listed = [v["d"][axis] for v in g.vertices
                      if v["interface"] == "front" and v["vertex"] == j]
            if ("front", j) in touched:
                assert listed[0] == pytest.approx(expected, abs=1e-8), (j, axis)
            else:
                assert abs(expected) < 1e-9, (j, axis)


def test_a_ray_without_a_time_has_nan_derivatives():
    tracer = eigenray.Tracer(eigenray.Scene(SEED))
    g = tracer.gradient((0, 1), (5, -1))  # beyond the surface's end
    assert g.status == "no_path"
    assert np.isnan(g.time) and np.isnan(g.source).all() and g.vertices == []


def test_the_cli_gradient_is_the_packages(cli, tmp_path):
    spec = {**BENT, "solver": {"derivatives": True}}
    path = tmp_path / "bent.json"
    path.write_text(json.dumps(spec))
    out = subprocess.run([cli, "solve", str(path)], capture_output=True, text=True, check=True)
    expected = json.loads(out.stdout)["rays"][0]["gradient"]
    g = eigenray.Tracer(eigenray.Scene(BENT)).gradient(
        BENT["sources"][0], BENT["receivers"][0], "echo"
    )
    assert g.source.tolist() == expected["source"]
    assert g.receiver.tolist() == expected["receiver"]
    assert dict(g.slowness) == expected["slowness"]
    assert [(v["interface"], v["vertex"], v["d"].tolist()) for v in g.vertices] == [
        (v["interface"], v["vertex"], v["d"]) for v in expected["vertices"]
    ]


def test_point_sensitivities_match_differences_of_re_solved_points():
    scene = eigenray.Scene(BENT)
    tracer = eigenray.Tracer(scene)
    s, r = BENT["sources"][0], BENT["receivers"][0]
    sens = tracer.point_sensitivities(s, r, "echo")
    assert sens.status == "converged"
    assert sens.time == tracer.solve(s, r, "echo").time
    rows = {p: i for i, p in enumerate(sens.parameters)}
    assert sens.d.shape == (len(sens.parameters), 5, 2)

    def points_with(h, parameter):
        moved = eigenray.Tracer(scene)
        source, receiver = list(s), list(r)
        kind = parameter[0]
        axis = "xy".index(parameter[-1]) if kind != "slowness" else None
        if kind == "source":
            source[axis] += h
        elif kind == "receiver":
            receiver[axis] += h
        elif kind == "slowness":
            speed = BENT["media"][parameter[1]]["speed"]
            moved.set_medium_speed(parameter[1], 1 / (1 / speed + h))
        else:
            points = copy.deepcopy(BENT["interfaces"][parameter[1]]["points"])
            points[parameter[2]][axis] += h
            moved.set_interface_points(parameter[1], points)
        return moved.solve(source, receiver, "echo").points

    checked = 0
    for parameter, row in rows.items():
        h = 1e-6
        expected = (points_with(h, parameter) - points_with(-h, parameter)) / (2 * h)
        assert np.allclose(sens.d[row], expected, rtol=0, atol=1e-7), parameter
        checked += 1
    # Both ends and both coordinates, both media, and the vertices of both interfaces' segments.
    assert ("source", "x") in rows and ("receiver", "y") in rows
    assert ("slowness", "glass") in rows
    assert any(p[0] == "vertex" and p[1] == "back" for p in rows)
    assert checked >= 10
    # The source's own row moves the source and nothing else at the ends.
    assert sens.d[rows[("source", "x")]][0].tolist() == [1.0, 0.0]
    assert sens.d[rows[("source", "x")]][-1].tolist() == [0.0, 0.0]


def test_a_ray_without_a_time_has_no_sensitivities():
    tracer = eigenray.Tracer(eigenray.Scene(SEED))
    sens = tracer.point_sensitivities((0, 1), (5, -1))
    assert sens.status == "no_path" and np.isnan(sens.time)
    assert sens.parameters == [] and sens.d.shape == (0, 0, 2)


def test_gradients_of_a_batch_are_the_rays_gradients(cli, tmp_path):
    spec = copy.deepcopy(BENT)
    spec["receivers"] = [[x, 1.3] for x in np.linspace(-2.5, 2.5, 9)] + [[40.0, 1.0]]
    spec["paths"].append({"name": "skim", "steps": [{"reflect": "front"}],
                          "media": ["air", "air"]})
    scene = eigenray.Scene(spec)
    tracer = eigenray.Tracer(scene)
    # Each ray from the documented start, as `gradient` solves it.
    rays = tracer.trace(warm_start=False)
    grads = tracer.gradients(rays)
    assert len(grads) == len(rays) == 20
    assert grads.vertex_d.shape == (20, 6, 2) and grads.slowness.shape == (20, 2)
    timed = 0
    for i in range(len(rays)):
        source = spec["sources"][rays.source[i]]
        receiver = spec["receivers"][rays.receiver[i]]
        one = tracer.gradient(source, receiver, int(rays.path[i]))
        if np.isnan(rays.time[i]):
            assert np.isnan(grads.source[i]).all() and (grads.vertex[i] == -1).all()
            continue
        timed += 1
        assert grads.source[i].tolist() == one.source.tolist()
        assert grads.receiver[i].tolist() == one.receiver.tolist()
        assert dict(zip(grads.media_names, grads.slowness[i].tolist())) == dict(one.slowness)
        listed = [(grads.interface_names[grads.vertex_interface[i, j]], int(grads.vertex[i, j]),
                   grads.vertex_d[i, j].tolist())
                  for j in range(grads.vertex.shape[1]) if grads.vertex[i, j] >= 0]
        assert listed == [(v["interface"], v["vertex"], v["d"].tolist()) for v in one.vertices]
    assert 10 <= timed < 20
    # The command-line tool's "gradient" of the same scene (its rays warm-started, as
    # `trace()`'s), bit for bit.
    grads = tracer.gradients(tracer.trace())
    path = tmp_path / "bent.json"
    path.write_text(json.dumps({**spec, "solver": {"derivatives": True}}))
    out = subprocess.run([cli, "solve", str(path)], capture_output=True, text=True, check=True)
    for i, ray in enumerate(json.loads(out.stdout)["rays"]):
        if "gradient" in ray:
            assert grads.source[i].tolist() == ray["gradient"]["source"]
            assert grads.slowness[i].tolist() == [ray["gradient"]["slowness"][m]
                                                  for m in grads.media_names]
    # Rays of another scene are refused, naming the argument.
    other = eigenray.Tracer(eigenray.Scene(SEED)).trace()
    with pytest.raises(eigenray.EigenrayError) as e:
        tracer.gradients(other)
    assert e.value.key == "rays"
