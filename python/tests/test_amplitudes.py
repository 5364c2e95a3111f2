"""Amplitudes from Python: the arrays of `Rays` are the command-line tool's `.npy` fields bit
for bit; every call (`trace`, `solve`, `amplitude`, `solve_pairs`, `stationary_paths`,
`trace_stationary`, `search`) gives the same numbers; a missing amplitude is NaN with a reason,
never 0; a scene without `"amplitudes"` has none; bad calls raise."""

import json
import math
import subprocess

import numpy as np
import pytest

import eigenray

from conftest import ROOT

SCENES = sorted((ROOT / "fixtures/amplitudes").glob("*.json"))

# A word of each `.npy` reason name's sentence (the names table of `--names`).
REASON_WORDS = {
    "vertex": "vertex (edge-diffracted)",
    "obstructed": "obstructed",
    "converted": "converted wave",
    "on_axis": "axis of symmetry",
}


def same_bits(a, b):
    """Whether two float arrays are equal bit for bit, NaN where the other is NaN."""
    a, b = np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float)
    nan = np.isnan(a)
    return (
        a.shape == b.shape
        and (nan == np.isnan(b)).all()
        and (a[~nan].view(np.uint64) == b[~nan].view(np.uint64)).all()
    )


def pairs(z):
    """Complex numbers as `(re, im)` rows, as the `.npy` output holds them."""
    return np.column_stack([z.real, z.imag])


@pytest.mark.parametrize("scene_file", SCENES, ids=lambda p: p.name)
def test_the_arrays_are_the_cli_npy_fields(cli, scene_file, tmp_path):
    names_file = tmp_path / "names.json"
    command = [cli, "solve", str(scene_file), "--format", "npy", "--names", str(names_file)]
    if "search" in json.loads(scene_file.read_text()):
        # (A search's arrivals are a table of their own, in a file of their own.)
        command += ["--arrivals", str(tmp_path / "arrivals.npy")]
    with open(tmp_path / "rays.npy", "wb") as out:
        subprocess.run(command, stdout=out, check=True)
    expected = np.load(tmp_path / "rays.npy")
    names = json.loads(names_file.read_text())["amplitude_reasons"]
    tracer = eigenray.Tracer(eigenray.Scene(scene_file))
    stationary = "arrival" in expected.dtype.names
    rays = tracer.trace_stationary() if stationary else tracer.trace()
    assert len(rays) == len(expected)
    assert same_bits(pairs(rays.amplitude), expected["amplitude"])
    assert same_bits(rays.spreading, expected["spreading"])
    assert same_bits(pairs(rays.coefficient), expected["coefficient"])
    assert same_bits(rays.attenuation_db, expected["attenuation_db"])
    for code, words in zip(expected["amplitude_reason"], rays.amplitude_reason):
        assert (words is None) == (code == 0)
        if names[code] in REASON_WORDS:
            assert REASON_WORDS[names[code]] in words
    # Rays with a time and an amplitude have a finite one; no missing one is 0.
    missing = np.isnan(rays.amplitude)
    assert (rays.amplitude[missing] != 0).all()
    assert (missing == (expected["amplitude_reason"] != 0) | np.isnan(rays.time)).all()


def test_every_call_gives_the_same_amplitude():
    scene = eigenray.Scene(ROOT / "fixtures/amplitudes/waveguide.json")
    tracer = eigenray.Tracer(scene)
    rays = tracer.trace(warm_start=False)
    sources, receivers = scene.sources, scene.receivers
    for path in range(len(scene.path_names)):
        pairs_of_path = tracer.solve_pairs(np.repeat(sources, len(receivers), axis=0),
                                           receivers, path)
        for r, receiver in enumerate(receivers):
            i = r * len(scene.path_names) + path
            one = tracer.solve(sources[0], receiver, path)
            a = tracer.amplitude(sources[0], receiver, path)
            assert same_bits(pairs(np.array([one.amplitude, a, pairs_of_path.amplitude[r]])),
                             pairs(np.repeat(rays.amplitude[i], 3)))
            assert same_bits(np.array([one.spreading, pairs_of_path.spreading[r]]),
                             np.repeat(rays.spreading[i], 2))
            assert same_bits(np.array([one.attenuation_db, pairs_of_path.attenuation_db[r]]),
                             np.repeat(rays.attenuation_db[i], 2))
            assert same_bits(pairs(np.array([one.coefficient, pairs_of_path.coefficient[r]])),
                             pairs(np.repeat(rays.coefficient[i], 2)))
            assert one.amplitude_reason == rays.amplitude_reason[i]
    # Warm starts end elsewhere in the solver's tolerance: the same to its worth.
    warm = tracer.trace()
    timed = ~np.isnan(rays.amplitude)
    assert np.allclose(warm.amplitude[timed], rays.amplitude[timed], rtol=1e-10, atol=0)


def test_every_stationary_path_has_the_amplitude_of_its_ray():
    scene = eigenray.Scene(ROOT / "fixtures/amplitudes/kinds.json")
    tracer = eigenray.Tracer(scene)
    table = tracer.trace_stationary()
    found, complete = tracer.stationary_paths(scene.sources[0], scene.receivers[0], "valley")
    assert complete and [r.status for r in found] == ["converged", "converged", "vertex"]
    rows = np.flatnonzero((table.receiver == 0) & (table.path == 0))
    for ray, row in zip(found, rows):
        assert same_bits(pairs(np.array([ray.amplitude])), pairs(table.amplitude[[row]]))
        assert ray.amplitude_reason == table.amplitude_reason[row]
    # The two specular reflections off the floor (absorption 0.36): sqrt(0.64) / (4 pi L).
    for ray in found[:2]:
        length = np.linalg.norm(np.diff(ray.points, axis=0), axis=1).sum()
        assert ray.amplitude == pytest.approx(0.8 / (4 * math.pi * length), rel=1e-13)
        assert ray.coefficient == 0.8 and ray.spreading > 0
    # The vertex (edge-held) path: no ray-theory amplitude, NaN and a reason, never 0.
    vertex = found[2]
    assert math.isnan(vertex.amplitude.real) and math.isnan(vertex.spreading)
    assert "diffraction coefficients" in vertex.amplitude_reason


def test_missing_amplitudes_are_nan_with_a_reason():
    scene = eigenray.Scene(ROOT / "fixtures/amplitudes/kinds.json")
    rays = eigenray.Tracer(scene).trace_stationary()
    names = rays.status_names
    reasons = rays.amplitude_reason
    for i in range(len(rays)):
        status, value = names[rays.status[i]], rays.amplitude[i]
        if status in ("no_path", "not_converged"):
            assert math.isnan(value.real) and reasons[i] is None
        elif reasons[i] is not None:
            assert math.isnan(value.real) and math.isnan(value.imag)
        else:
            assert np.isfinite(value) and value != 0
    converted = [i for i in range(len(rays)) if reasons[i] and "converted" in reasons[i]]
    assert converted
    # A converted reflection: its geometry's spreading and attenuation, no coefficient.
    assert (rays.spreading[converted] > 0).all() and (rays.attenuation_db[converted] > 0).all()
    assert np.isnan(rays.coefficient[converted]).all()


def test_search_arrivals_carry_amplitudes():
    scene = eigenray.Scene(ROOT / "fixtures/amplitudes/room_search.json")
    arrivals = eigenray.Tracer(scene).search()
    statuses = {a["status"] for a in arrivals}
    assert statuses == {"converged", "obstructed"}
    for a in arrivals:
        assert isinstance(a["amplitude"], complex)
        if a["status"] == "obstructed":
            assert math.isnan(a["amplitude"].real) and "obstructed" in a["amplitude_reason"]
            continue
        assert a["amplitude_reason"] is None
        # 0.01 dB per metre of air along the path.
        length = np.linalg.norm(np.diff(a["points"], axis=0), axis=1).sum()
        assert a["attenuation_db"] == pytest.approx(0.01 * length, rel=1e-13)
        assert abs(a["amplitude"]) == pytest.approx(
            a["spreading"] * abs(a["coefficient"]) * 10 ** (-a["attenuation_db"] / 20), rel=1e-14
        )


def test_rewriting_an_earlier_result_rewrites_its_amplitudes():
    scene = eigenray.Scene(ROOT / "fixtures/amplitudes/lens_line.json")
    tracer = eigenray.Tracer(scene)
    fresh = tracer.trace()
    earlier = tracer.trace()
    amplitude, reasons = earlier.amplitude, earlier.amplitude_reason
    tracer.set_medium_index("glass", 1.7)
    moved = tracer.trace(out=earlier)
    assert moved is earlier and moved.amplitude is not None
    # The same arrays, new numbers: those of a tracer of the changed scene.
    assert np.shares_memory(moved.amplitude, amplitude)
    again = eigenray.Tracer(tracer.scene).trace()
    assert same_bits(pairs(moved.amplitude), pairs(again.amplitude))
    assert same_bits(moved.spreading, again.spreading)
    assert moved.amplitude_reason == again.amplitude_reason
    assert not same_bits(pairs(moved.amplitude), pairs(fresh.amplitude))
    assert reasons == fresh.amplitude_reason


def test_a_scene_without_amplitudes_has_none():
    scene = eigenray.Scene(ROOT / "examples/scenes/room.json")
    tracer = eigenray.Tracer(scene)
    rays = tracer.trace()
    assert rays.amplitude is None and rays.spreading is None and rays.coefficient is None
    assert rays.attenuation_db is None and rays.amplitude_reason is None
    ray = tracer.solve(scene.sources[0], scene.receivers[0])
    assert ray.amplitude is None and ray.spreading is None and ray.amplitude_reason is None
    with pytest.raises(eigenray.EigenrayError) as caught:
        tracer.amplitude(scene.sources[0], scene.receivers[0])
    assert caught.value.key == "amplitudes"
    # Rays with and without amplitudes do not rewrite each other.
    asking = eigenray.Tracer(eigenray.Scene(ROOT / "examples/scenes/sea_surface.json"))
    without = _without_amplitudes()
    with pytest.raises(eigenray.EigenrayError) as caught:
        asking.trace(out=without)
    assert caught.value.key == "out"
    with pytest.raises(eigenray.EigenrayError) as caught:
        eigenray.Tracer(eigenray.Scene(_without_amplitudes_document())).trace(
            out=asking.trace()
        )
    assert caught.value.key == "out"


def _without_amplitudes_document():
    """The sea-surface example without its `"amplitudes"`."""
    document = json.loads((ROOT / "examples/scenes/sea_surface.json").read_text())
    del document["amplitudes"]
    return document


def _without_amplitudes():
    """The rays of the sea-surface example without its `"amplitudes"`: as many, as wide."""
    return eigenray.Tracer(eigenray.Scene(_without_amplitudes_document())).trace()


@pytest.mark.parametrize(
    "call, key",
    [
        (lambda t: t.amplitude((0, math.nan), (500, -60)), "source"),
        (lambda t: t.amplitude((0, -30), "here"), "receiver"),
        (lambda t: t.amplitude((0, -30), (500, -60), path=7), None),
        (lambda t: t.amplitude((0, -30), (500, -60), path="nowhere"), None),
    ],
)
def test_bad_amplitude_calls_raise(call, key):
    tracer = eigenray.Tracer(eigenray.Scene(ROOT / "examples/scenes/sea_surface.json"))
    with pytest.raises((eigenray.EigenrayError, IndexError, KeyError)) as caught:
        call(tracer)
    if key is not None:
        assert caught.value.key == key


def test_a_ray_without_a_time_has_a_nan_amplitude():
    tracer = eigenray.Tracer(eigenray.Scene(ROOT / "fixtures/amplitudes/kinds.json"))
    ray = tracer.solve((-0.5, 2), (20, 2), "valley")
    assert ray.status == "no_path"
    assert math.isnan(ray.amplitude.real) and math.isnan(ray.spreading)
    assert ray.amplitude_reason is None
    assert math.isnan(tracer.amplitude((-0.5, 2), (20, 2), "valley").real)
