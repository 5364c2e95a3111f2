"""Media with a speed gradient from Python (curved legs): the design note's caustic example,
a seismic reflection against its closed form, the command-line tool's times bit for bit, and
the refusals naming the key."""

import copy
import json
import math
import subprocess

import pytest

import eigenray

# The design note's caustic example with y up: water over a half-space whose speed grows
# downwards, c = 1500 + 0.1 (-200 - y); source and receiver at the surface, 10 km apart.
CAUSTIC = {
    "media": {
        "water": {"speed": 1500, "at": [5000, -100]},
        "rock": {"speed": 1480, "gradient": [0, -0.1], "at": [5000, -1000]},
    },
    "interfaces": {"floor": {"points": [[-1000, -200], [11000, -200]]}},
    "domain": [[-1000, -5000], [11000, 100]],
    "sources": [[0, 0]],
    "receivers": [[10000, 0]],
    "paths": [
        {"name": "given", "steps": [{"refract": "floor"}, {"refract": "floor"}],
         "media": ["water", "rock", "water"]},
        {"name": "looked up", "steps": [{"refract": "floor"}, {"refract": "floor"}]},
    ],
}


def test_the_caustic_example_times():
    tracer = eigenray.Tracer(eigenray.Scene(CAUSTIC))
    for path in ("given", "looked up"):
        ray = tracer.solve((0, 0), (10000, 0), path)
        assert ray.status == "converged"
        # The ray past the caustic (the design note: 6.672526446116 s, Morse index 1).
        assert abs(ray.time - 6.672526446116) < 1e-11
        assert ray.media == ["water", "rock", "water"]
        # The turning arc's ends are on the floor, symmetric about the middle.
        assert abs(ray.points[1][0] + ray.points[2][0] - 10000) < 1e-6


def test_seismic_reflection_matches_the_closed_form():
    v0, k, h = 2000.0, 0.6, 1500.0
    scene = {
        "media": {"rock": {"speed": v0, "gradient": [0, -k]}},
        "interfaces": {"reflector": {"points": [[-1000, -h], [8000, -h]]}},
        "domain": [[-1000, -3000], [8000, 10]],
        "sources": [[0, 0]],
        "receivers": [[x, 0] for x in range(500, 6001, 500)],
        "paths": [{"steps": [{"reflect": "reflector"}], "media": ["rock", "rock"]}],
    }
    rays = eigenray.Tracer(eigenray.Scene(scene)).trace()
    vh = v0 + k * h
    for i, x in enumerate(range(500, 6001, 500)):
        closed = 2 / k * math.acosh(1 + k * k * (x * x / 4 + h * h) / (2 * v0 * vh))
        assert math.isfinite(rays.time[i])
        assert abs(rays.time[i] - closed) < 1e-12 * closed


def test_the_cli_gives_the_same_times(tmp_path):
    path = tmp_path / "caustic.json"
    path.write_text(json.dumps(CAUSTIC))
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--profile", "test-opt", "--", "solve", str(path)],
        capture_output=True, text=True, check=True,
    )
    cli = json.loads(out.stdout)["rays"]
    rays = eigenray.Tracer(eigenray.Scene(CAUSTIC)).trace()
    assert [r["time"] for r in cli] == list(rays.time)


@pytest.mark.parametrize(
    "change, key",
    [
        (lambda s: s["media"]["rock"].update(gradient=[0, 1]), "media.rock.gradient"),
        (lambda s: s["media"]["rock"].update(gradient=[0, "x"]), "media"),
        (lambda s: s.update(search={"max_steps": 1, "diffraction": True}), "search.diffraction"),
    ],
)
def test_bad_gradients_are_refused_naming_the_key(change, key):
    scene = copy.deepcopy(CAUSTIC)
    change(scene)
    with pytest.raises(eigenray.EigenrayError, match=key.replace(".", r"\.")):
        eigenray.Scene(scene)


def test_every_stationary_path_of_the_caustic_example():
    tracer = eigenray.Tracer(eigenray.Scene(CAUSTIC))
    rays, complete = tracer.stationary_paths((0, 0), (10000, 0), "given")
    # Through arcs the multi-start search is no proof.
    assert not complete
    times = [r.time for r in rays]
    assert len(times) == 2
    assert abs(times[0] - 6.628258089353) < 1e-11
    assert abs(times[1] - 6.672526446116) < 1e-11


def test_gradients_through_arcs_match_finite_differences():
    def solved(scene):
        return eigenray.Tracer(eigenray.Scene(scene)).gradient((0, 0), (10000, 0), "given")

    g = solved(CAUSTIC)
    assert set(g.speed_gradient) == {"rock"}
    h = 1e-7
    for i in range(2):
        times = []
        for d in (h, -h):
            scene = copy.deepcopy(CAUSTIC)
            scene["media"]["rock"]["gradient"][i] += d
            times.append(solved(scene).time)
        fd = (times[0] - times[1]) / (2 * h)
        assert abs(g.speed_gradient["rock"][i] - fd) < 1e-6 * g.time, (i, fd)


def test_search_through_arcs():
    scene = copy.deepcopy(CAUSTIC)
    del scene["paths"]
    scene["search"] = {"max_steps": 2, "reflect": False}
    arrivals = eigenray.Tracer(eigenray.Scene(scene)).search()
    times = sorted(a["time"] for a in arrivals)
    # The direct arc-free ray and both caustic eigenrays, none a proof.
    assert any(abs(t - 6.628258089353) < 1e-9 for t in times), times
    assert any(abs(t - 6.672526446116) < 1e-9 for t in times), times
    assert not any(a["complete"] for a in arrivals)


def test_the_caustic_turns_the_phase_by_a_quarter():
    scene = dict(CAUSTIC, amplitudes={"source": "point"})
    tracer = eigenray.Tracer(eigenray.Scene(scene))
    rays, _ = tracer.stationary_paths((0, 0), (10000, 0), "given")
    phases = [math.atan2(r.amplitude.imag, r.amplitude.real) for r in rays]
    assert abs(phases[0]) < 1e-12
    assert abs(phases[1] + math.pi / 2) < 1e-12


def test_the_caustics_column_is_the_morse_index():
    # The design note's Morse indices: 0 before the caustic (6.628 s), 1 past it (6.673 s).
    tracer = eigenray.Tracer(eigenray.Scene(CAUSTIC))
    rays, _ = tracer.stationary_paths((0, 0), (10000, 0), "given")
    assert [r.caustics for r in rays] == [0, 1]
    ray = tracer.solve((0, 0), (10000, 0), "looked up")
    assert ray.caustics == 1
    batch = tracer.trace()
    assert list(batch.caustics) == [1, 1]


def test_gradients_of_a_batch_give_the_speed_gradients():
    """`Tracer.gradients(rays)` through arcs: each row's `speed_gradient` (by medium) and its
    other entries are those of `Tracer.gradient` for the same ray (checked against finite
    differences above)."""
    tracer = eigenray.Tracer(eigenray.Scene(CAUSTIC))
    rays = tracer.trace(warm_start=False)
    grads = tracer.gradients(rays)
    assert set(grads.speed_gradient) == {"rock"} and grads.profile_speed == {}
    assert grads.speed_gradient["rock"].shape == (len(rays), 2)
    for i in range(len(rays)):
        one = tracer.gradient((0, 0), (10000, 0), int(rays.path[i]))
        assert one.status == "converged"
        assert grads.speed_gradient["rock"][i].tolist() == one.speed_gradient["rock"].tolist()
        assert grads.receiver[i].tolist() == one.receiver.tolist()
        assert dict(zip(grads.media_names, grads.slowness[i].tolist())) == dict(one.slowness)
