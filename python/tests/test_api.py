"""The package's calls: one ray, pairs, every stationary path, search, progress, and every
error path (bad scenes, bad arguments, wrong shapes, NaN)."""

import json
import math

import numpy as np
import pytest

import eigenray

AIR_WATER = {
    "media": {"air": {"index": 1.0}, "water": {"index": 1.333}},
    "interfaces": {"surface": {"points": [[-1, 0], [2, 0]]}},
    "sources": [[0, 1]],
    "receivers": [[1, -1]],
    "paths": [{"name": "down", "steps": [{"refract": "surface"}], "media": ["air", "water"]}],
}

VALLEY = {
    "media": {"air": {"speed": 1.0}},
    "interfaces": {"valley": {"points": [[-3, 0], [0, -2], [3, 0]]}},
    "sources": [[-0.5, 2]],
    "receivers": [[0.5, 2], [20, 2]],
    "paths": [{"name": "floor", "steps": [{"reflect": "valley"}], "media": ["air", "air"]}],
}


def snell_time(source, receiver, n1=1.0, n2=1.333):
    """The refracted time at the surface y = 0 by bisection on the crossing's x (Fermat)."""
    (sx, sy), (rx, ry) = source, receiver
    lo, hi = min(sx, rx), max(sx, rx)
    for _ in range(200):
        x = 0.5 * (lo + hi)
        d = n1 * (x - sx) / math.hypot(x - sx, sy) + n2 * (x - rx) / math.hypot(x - rx, ry)
        lo, hi = (x, hi) if d < 0 else (lo, x)
    x = 0.5 * (lo + hi)
    return n1 * math.hypot(x - sx, sy) + n2 * math.hypot(rx - x, ry)


def test_one_ray_between_any_two_points_obeys_snell():
    tracer = eigenray.Tracer(eigenray.Scene(AIR_WATER))
    ray = tracer.solve((0, 1), (1, -1), "down")
    assert ray.status == "converged"
    assert ray.media == ["air", "water"]
    assert ray.points.shape == (3, 2)
    assert abs(ray.time - snell_time((0, 1), (1, -1))) < 1e-14
    assert tracer.time([0.3, 2.0], np.array([1.5, -0.5])) == pytest.approx(
        snell_time((0.3, 2.0), (1.5, -0.5)), rel=1e-14
    )


def test_pairs_are_the_one_by_one_rays():
    tracer = eigenray.Tracer(eigenray.Scene(AIR_WATER))
    rng = np.random.default_rng(7)
    sources = np.column_stack([rng.uniform(-1, 2, 50), rng.uniform(0.1, 2, 50)])
    receivers = np.column_stack([rng.uniform(-1, 2, 50), rng.uniform(-2, -0.1, 50)])
    rays = tracer.solve_pairs(sources, receivers)
    assert len(rays) == 50
    for i in range(50):
        one = tracer.solve(sources[i], receivers[i])
        assert rays.time[i] == one.time
        assert (rays.points[i] == one.points).all()


def test_a_ray_without_a_time_has_nan_and_a_reason():
    scene = eigenray.Scene(VALLEY)
    rays = eigenray.Tracer(scene).trace()
    assert rays.status_names[rays.status[1]] == "no_path"
    assert math.isnan(rays.time[1])
    assert np.isnan(rays.points[1]).all()
    assert "no stationary path" in rays.reason[1]
    assert rays.reason[0] is None


def test_every_stationary_path_of_the_valley():
    tracer = eigenray.Tracer(eigenray.Scene(VALLEY))
    near, complete = tracer.stationary_paths((-0.5, 2), (0.5, 2), "floor")
    assert complete
    assert [r.status for r in near] == ["converged", "converged", "vertex"]
    assert [r.arrival for r in near] == [0, 1, 2]
    assert near[2].kink == "maximum"
    assert near[0].time == pytest.approx(math.sqrt(45), rel=1e-14)
    assert near[2].time == pytest.approx(2 * math.hypot(0.5, 4), rel=1e-14)
    far, complete = tracer.stationary_paths((-0.5, 2), (20, 2))
    assert far == [] and complete
    rays = tracer.trace_stationary()
    assert rays.arrival.tolist() == [0, 1, 2, 0]
    assert rays.kink == [None, None, "maximum", None]
    assert rays.complete.all()


def test_search_lists_a_square_rooms_reflections_by_time():
    scene = eigenray.Scene({
        "media": {"air": {"speed": 1.0, "at": [2, 1.5]}},
        "interfaces": {
            "south": {"points": [[0, 0], [4, 0]]},
            "east": {"points": [[4, 0], [4, 3]]},
            "north": {"points": [[4, 3], [0, 3]]},
            "west": {"points": [[0, 3], [0, 0]]},
        },
        "sources": [[1, 1]],
        "receivers": [[3, 2]],
        "search": {"max_steps": 1, "refract": False},
    })
    arrivals = eigenray.Tracer(scene).search()
    assert [a["steps"] for a in arrivals][0] == []
    assert {list(a["steps"][0].values())[0] for a in arrivals[1:]} == {
        "north", "south", "east", "west"
    }
    # The image method: the source mirrored in each wall, to the receiver.
    images = {"north": (1, 5), "south": (1, -1), "east": (7, 1), "west": (-1, 1)}
    for a in arrivals[1:]:
        wall = a["steps"][0]["reflect"]
        x, y = images[wall]
        assert a["time"] == pytest.approx(math.hypot(3 - x, 2 - y), rel=1e-14)
    times = [a["time"] for a in arrivals]
    assert times == sorted(times)


def test_progress_reports_every_ray():
    scene = eigenray.Scene({**AIR_WATER, "receivers": [[x, -1] for x in np.linspace(-1, 2, 5000)]})
    seen = []
    rays = eigenray.Tracer(scene).trace(progress=lambda done, total: seen.append((done, total)))
    assert len(rays) == 5000
    assert seen and seen[-1] == (5000, 5000)
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))


def test_a_failing_progress_callback_raises_after_the_batch():
    scene = eigenray.Scene(AIR_WATER)

    def broken(done, total):
        raise RuntimeError("callback failed")

    with pytest.raises(RuntimeError, match="callback failed"):
        eigenray.Tracer(scene).trace(progress=broken)


@pytest.mark.parametrize(
    "scene, key",
    [
        ("{", "invalid JSON"),
        ({**AIR_WATER, "sources": [[0, "x"]]}, "sources"),
        ({**AIR_WATER, "media": {"air": {"index": -1.0}, "water": {"index": 1.333}}}, "media.air"),
        ({**AIR_WATER, "paths": [{"steps": [{"refract": "nowhere"}], "media": ["air", "water"]}]},
         "paths[0].steps[0]"),
    ],
)
def test_bad_scenes_raise_naming_the_key(scene, key):
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Scene(scene)
    assert key in str(caught.value)


@pytest.mark.parametrize(
    "change, key, words",
    [
        ({"sources": [[0, "x"]]}, "sources[0][1]", "invalid type: string"),
        ({"sources": [[0, 1, 2]]}, "sources[0]", "too many elements"),
        ({"solver": {"max_iterations": -3}}, "solver.max_iterations", "invalid value"),
        ({"paths": [{"media": ["air"]}]}, "paths[0].steps", "missing"),
    ],
)
def test_a_dict_scenes_errors_name_the_key_path_not_a_place_in_json(change, key, words):
    # The dict becomes JSON text inside the package; the user never saw that text, so no
    # line and column of it may appear (the same scene as JSON text keeps them where serde
    # has them: the user wrote that text).
    scene = {**AIR_WATER, **change}
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Scene(scene)
    error = caught.value
    assert error.key == key and words in error.message, str(error)
    assert "line" not in str(error) and "column" not in str(error), str(error)
    with pytest.raises(eigenray.EigenrayError) as written:
        eigenray.Scene(json.dumps(scene, indent=1))
    assert written.value.key == key
    if words != "missing":
        assert " at line " in written.value.message, str(written.value)


def test_nan_in_a_dict_scene_is_refused():
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Scene({**AIR_WATER, "sources": [[0, float("nan")]]})
    assert caught.value.key == "scene"


def test_a_missing_file_raises_oserror(tmp_path):
    with pytest.raises(OSError):
        eigenray.Scene(tmp_path / "missing.json")


def test_something_else_is_not_a_scene():
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Scene(42)
    assert caught.value.key == "scene"


@pytest.mark.parametrize(
    "call, key",
    [
        (lambda t: t.solve((0, float("nan")), (1, -1)), "source"),
        (lambda t: t.solve((0, 1), (1, float("inf"))), "receiver"),
        (lambda t: t.solve((0, 1, 2), (1, -1)), "source"),
        (lambda t: t.solve("ab", (1, -1)), "source"),
        (lambda t: t.solve((0, 1), (1e300, 0)), "receiver"),
        (lambda t: t.solve_pairs(np.zeros((3, 3)), np.zeros((3, 2))), "sources"),
        (lambda t: t.solve_pairs(np.zeros((3, 2)), np.zeros((2, 2))), "receivers"),
        (lambda t: t.solve_pairs(np.zeros(4), np.zeros((2, 2))), "sources"),
        (lambda t: t.solve_pairs([[0, 1], [0, float("nan")]], [[1, -1], [1, -1]]), "sources[1]"),
        (lambda t: t.solve_pairs([[0, 1]], [["a", 1]]), "receivers"),
        (lambda t: t.solve((0, 1), (1, -1), 1.5), "path"),
    ],
)
def test_bad_arguments_raise_naming_the_argument(call, key):
    tracer = eigenray.Tracer(eigenray.Scene(AIR_WATER))
    with pytest.raises(eigenray.EigenrayError) as caught:
        call(tracer)
    assert caught.value.key == key, str(caught.value)


def test_bad_path_indices_and_names():
    tracer = eigenray.Tracer(eigenray.Scene(AIR_WATER))
    with pytest.raises(IndexError):
        tracer.solve((0, 1), (1, -1), 3)
    with pytest.raises(IndexError):
        tracer.solve((0, 1), (1, -1), -1)
    with pytest.raises(KeyError):
        tracer.solve((0, 1), (1, -1), "up")


def test_scene_properties():
    scene = eigenray.Scene(AIR_WATER)
    assert scene.media_names == ["air", "water"]
    assert scene.slowness.tolist() == [1.0, 1.333]
    assert scene.interface_names == ["surface"]
    assert scene.interfaces["surface"].tolist() == [[-1.0, 0.0], [2.0, 0.0]]
    assert scene.closed == {"surface": False}
    assert scene.path_names == ["down"]
    assert scene.sources.tolist() == [[0.0, 1.0]]
    assert scene.num_rays == 1


def test_trace_into_an_earlier_result_rewrites_it_in_place():
    scene = eigenray.Scene(VALLEY)
    tracer = eigenray.Tracer(scene)
    first = tracer.trace()
    time_array, points_array = first.time, first.points
    time_array[:] = -1.0
    points_array[:] = 0.0
    again = tracer.trace(out=first)
    assert again is first
    assert first.time is time_array  # the same arrays, rewritten
    fresh = tracer.trace()
    for name in ("source", "receiver", "path", "status", "num_points", "media", "iterations"):
        assert (getattr(first, name) == getattr(fresh, name)).all(), name
    assert np.array_equal(first.time, fresh.time, equal_nan=True)
    assert np.array_equal(first.points, fresh.points, equal_nan=True)
    assert np.array_equal(first.residual, fresh.residual, equal_nan=True)
    assert first.reason == fresh.reason


def test_trace_into_an_earlier_result_rewrites_its_reasons():
    # Rays with a reason, then the same arrays for rays without one, then with one again.
    tracer = eigenray.Tracer(eigenray.Scene(VALLEY))
    rays = tracer.trace()
    assert rays.reason[0] is None and rays.reason[1] is not None
    tracer.set_receiver(1, [1.0, 2.0])
    tracer.trace(out=rays)
    assert rays.reason == [None, None] == tracer.trace().reason
    tracer.set_receiver(1, [20.0, 2.0])
    tracer.trace(out=rays)
    assert rays.reason == tracer.trace().reason and rays.reason[1] is not None


def test_trace_into_rays_of_another_shape_is_refused():
    small = eigenray.Tracer(eigenray.Scene(AIR_WATER)).trace()
    valley = eigenray.Tracer(eigenray.Scene(VALLEY))
    with pytest.raises(eigenray.EigenrayError) as caught:
        valley.trace(out=small)
    assert caught.value.key == "out"
    with pytest.raises(eigenray.EigenrayError):
        valley.trace(out=valley.trace_stationary())
    rays = valley.trace()
    rays.time.flags.writeable = False
    with pytest.raises(eigenray.EigenrayError) as caught:
        valley.trace(out=rays)
    assert "not writeable" in str(caught.value)
