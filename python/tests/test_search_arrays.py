"""`Tracer.search()` gives `Arrivals`: named numpy arrays that agree entry for entry with the
dicts it gives when indexed or iterated (the list of earlier versions) and with the
command-line tool's `arrivals`."""

import json
import math

import numpy as np
import pytest

import eigenray

from conftest import ROOT
from test_agreement import check_amplitude, run_cli, same_number

SQUARE_ROOM = {
    "media": {"air": {"speed": 1.0, "at": [2, 1.5]}},
    "interfaces": {
        "south": {"points": [[0, 0], [4, 0]]},
        "east": {"points": [[4, 0], [4, 3]]},
        "north": {"points": [[4, 3], [0, 3]]},
        "west": {"points": [[0, 3], [0, 0]]},
    },
    "sources": [[1, 1], [2.5, 2]],
    "receivers": [[3, 2], [0.5, 2.5], [3.5, 0.4]],
    "search": {"max_steps": 3, "refract": False},
}

SPEED = 343.0
COMB_ROOM = {
    "media": {"air": {"speed": SPEED}},
    "background": "air",
    "interfaces": {
        "walls": {
            "points": [[0, 0], [0, 5], [1, 5], [1, 2], [2, 2], [2, 5], [3, 5], [3, 0], [2, 0],
                       [2, 1], [1, 1], [1, 0]],
            "closed": True,
        }
    },
    "sources": [[0.5, 0.5]],
    "receivers": [[2.5, 4.5]],
    "search": {"max_steps": 8},
}


def lens_search():
    """A biconvex glass lens in air (Fresnel amplitudes, a line source) searched to three
    steps of both kinds, with `vertex` and `obstructed` arrivals: kinks, reasons, missing
    amplitudes."""
    scene = json.loads((ROOT / "fixtures/amplitudes/lens_line.json").read_text())
    del scene["paths"]
    scene["search"] = {"max_steps": 3, "vertex": True, "obstructed": True}
    return scene


def same_bits(a, b):
    """Two numbers (or complex numbers) equal, NaN equal to NaN."""
    if isinstance(a, complex) or isinstance(b, complex):
        a, b = complex(a), complex(b)
        return same_number(a.real, b.real) and same_number(a.imag, b.imag)
    return same_number(a, b)


def same_dict(a, b):
    """Two arrival dicts with the same keys (in the same order) and values, NaN equal to NaN."""
    assert list(a) == list(b)
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, key
            assert np.array_equal(x, y, equal_nan=True), key
        elif isinstance(x, float) or isinstance(x, complex):
            assert type(x) is type(y) and same_bits(x, y), key
        else:
            assert type(x) is type(y) and x == y, key
    return True


def decoded_steps(arrivals, i):
    """Row `i` of the steps table as the scene writes steps, checking its padding."""
    k = int(arrivals.order[i])
    kinds, interfaces = arrivals.step_kind[i], arrivals.step_interface[i]
    assert (kinds[k:] == 255).all() and (interfaces[k:] == -1).all()
    return [
        {arrivals.step_kind_names[kinds[j]]: arrivals.interface_names[interfaces[j]]}
        for j in range(k)
    ]


def decoded_media(arrivals, i):
    """Row `i` of the media table as names, checking its padding."""
    k = int(arrivals.order[i])
    row = arrivals.media[i]
    assert (row[k + 1 :] == -1).all() and (row[: k + 1] >= 0).all()
    return [arrivals.media_names[m] for m in row[: k + 1]]


def check_shapes(arrivals, asks):
    n = len(arrivals)
    width = int(arrivals.order.max()) + 2 if n else 2
    dtypes = {
        "source": np.int64, "receiver": np.int64, "time": np.float64, "order": np.uint32,
        "status": np.uint8, "complete": np.bool_, "iterations": np.uint32,
        "residual": np.float64,
    }
    for name, dtype in dtypes.items():
        column = getattr(arrivals, name)
        assert column.dtype == dtype and column.shape == (n,), name
    assert arrivals.points.dtype == np.float64 and arrivals.points.shape == (n, width, 2)
    assert arrivals.step_interface.dtype == np.int64
    assert arrivals.step_interface.shape == (n, width - 2)
    assert arrivals.step_kind.dtype == np.uint8 and arrivals.step_kind.shape == (n, width - 2)
    assert arrivals.media.dtype == np.int64 and arrivals.media.shape == (n, width - 1)
    assert arrivals.step_kind_names == ["reflect", "refract"]
    assert arrivals.status_names == eigenray.STATUS_NAMES
    assert len(arrivals.reason) == len(arrivals.kink) == n
    if asks:
        assert arrivals.amplitude.dtype == np.complex128 and arrivals.amplitude.shape == (n,)
        assert arrivals.coefficient.dtype == np.complex128
        assert arrivals.spreading.dtype == np.float64
        assert arrivals.attenuation_db.dtype == np.float64
        assert len(arrivals.amplitude_reason) == n
    else:
        for name in ("amplitude", "spreading", "coefficient", "attenuation_db",
                     "amplitude_reason"):
            assert getattr(arrivals, name) is None, name


def check_arrays_are_the_dicts(arrivals, asks):
    """Every field of every arrival's dict against the arrays, padding and decoding too."""
    check_shapes(arrivals, asks)
    dicts = arrivals.to_dicts()
    assert isinstance(dicts, list) and len(dicts) == len(arrivals)
    reasons, kinks = arrivals.reason, arrivals.kink
    keys = ["source", "receiver", "steps", "media", "status", "time", "points", "iterations",
            "residual", "reason", "kink", "complete"]
    if asks:
        keys += ["amplitude", "spreading", "coefficient", "attenuation_db", "amplitude_reason"]
        amplitude_reasons = arrivals.amplitude_reason
    for i, d in enumerate(dicts):
        assert list(d) == keys
        assert d["source"] == arrivals.source[i] and d["receiver"] == arrivals.receiver[i]
        assert d["steps"] == decoded_steps(arrivals, i)
        assert len(d["steps"]) == arrivals.order[i]
        assert d["media"] == decoded_media(arrivals, i)
        assert d["status"] == arrivals.status_names[arrivals.status[i]]
        assert same_bits(d["time"], arrivals.time[i])
        k = int(arrivals.order[i]) + 2
        assert np.array_equal(d["points"], arrivals.points[i, :k])
        assert d["points"].shape == (k, 2)
        assert np.isnan(arrivals.points[i, k:]).all()
        assert d["iterations"] == arrivals.iterations[i]
        assert same_bits(d["residual"], arrivals.residual[i])
        assert d["reason"] == reasons[i] and d["kink"] == kinks[i]
        assert d["complete"] == arrivals.complete[i]
        if asks:
            assert isinstance(d["amplitude"], complex)
            assert same_bits(d["amplitude"], arrivals.amplitude[i])
            assert same_bits(d["spreading"], arrivals.spreading[i])
            assert same_bits(d["coefficient"], arrivals.coefficient[i])
            assert same_bits(d["attenuation_db"], arrivals.attenuation_db[i])
            assert d["amplitude_reason"] == amplitude_reasons[i]
    # Indexing and iteration give the same dicts.
    assert all(same_dict(a, b) for a, b in zip(arrivals, dicts, strict=True))
    assert all(same_dict(arrivals[i], d) for i, d in enumerate(dicts))


def test_a_rooms_reflections_as_arrays_are_the_dicts():
    tracer = eigenray.Tracer(eigenray.Scene(SQUARE_ROOM))
    arrivals = tracer.search()
    assert isinstance(arrivals, eigenray.Arrivals)
    assert repr(arrivals) == f"Arrivals({len(arrivals)} arrivals)"
    # 2 sources × 3 receivers: the direct sound and the four walls' images each, and at most
    # 8 and 12 images of orders 2 and 3 (a path through a corner is not specular).
    counts = np.bincount(arrivals.order).tolist()
    assert counts[:2] == [6, 24] and 0 < counts[2] <= 48 and 0 < counts[3] <= 72
    assert (arrivals.status == 0).all() and arrivals.complete.all()
    assert arrivals.interface_names == tracer.scene.interface_names
    assert sorted(arrivals.interface_names) == ["east", "north", "south", "west"]
    assert arrivals.media_names == tracer.scene.media_names == ["air"]
    assert (arrivals.step_kind[arrivals.step_interface >= 0] == 0).all()
    check_arrays_are_the_dicts(arrivals, asks=False)


def test_refractions_and_amplitudes_as_arrays_are_the_dicts():
    arrivals = eigenray.Tracer(eigenray.Scene(lens_search())).search()
    statuses = {arrivals.status_names[s] for s in arrivals.status}
    assert statuses == {"converged", "vertex", "obstructed"}
    assert (arrivals.step_kind == 1).sum() > 100 and (arrivals.step_kind == 0).any()
    assert {"minimum", "maximum"} <= set(arrivals.kink)
    # A missing amplitude is NaN with a reason, never 0.
    missing = np.isnan(arrivals.amplitude)
    assert missing.any() and not missing.all()
    reasons = np.array([r is not None for r in arrivals.amplitude_reason])
    assert (reasons == missing).all()
    check_arrays_are_the_dicts(arrivals, asks=True)


def test_the_comb_rooms_times_are_its_unfolded_path_lengths():
    arrivals = eigenray.Tracer(eigenray.Scene(COMB_ROOM)).search()
    # The teeth hide the listener: three reflections at least, eight at most.
    assert len(arrivals) > 10 and arrivals.order.min() == 3 and arrivals.order.max() == 8
    assert arrivals.interface_names == ["walls"] and (arrivals.status == 0).all()
    assert (arrivals.step_kind[arrivals.step_interface >= 0] == 0).all()
    # Each leg's length from the padded points (the padding's NaN legs left out).
    legs = np.linalg.norm(np.diff(arrivals.points, axis=1), axis=2)
    assert (np.isnan(legs).sum(axis=1) == 8 - arrivals.order).all()
    lengths = np.nansum(legs, axis=1)
    np.testing.assert_allclose(arrivals.time, lengths / SPEED, rtol=1e-13)
    assert (np.diff(arrivals.time) >= 0).all()


def test_negative_indices_slices_and_out_of_range():
    arrivals = eigenray.Tracer(eigenray.Scene(SQUARE_ROOM)).search()
    n = len(arrivals)
    dicts = arrivals.to_dicts()
    assert same_dict(arrivals[-1], dicts[n - 1])
    assert same_dict(arrivals[-n], dicts[0])
    assert all(same_dict(a, b) for a, b in zip(arrivals[1:7:2], dicts[1:7:2], strict=True))
    assert all(same_dict(a, b) for a, b in zip(arrivals[::-1], dicts[::-1], strict=True))
    assert arrivals[n:] == [] and isinstance(arrivals[2:4], list)
    for index in (n, -n - 1, 10**6):
        with pytest.raises(IndexError):
            arrivals[index]
    with pytest.raises(TypeError):
        arrivals["time"]
    assert len(list(iter(arrivals))) == n and bool(arrivals)


def test_a_scene_without_arrivals_gives_empty_arrays():
    scene = {**SQUARE_ROOM, "search": {"max_time": 0.1}}
    arrivals = eigenray.Tracer(eigenray.Scene(scene)).search()
    assert len(arrivals) == 0 and not arrivals and arrivals.to_dicts() == []
    assert arrivals.points.shape == (0, 2, 2) and arrivals.step_kind.shape == (0, 0)
    assert arrivals.media.shape == (0, 1) and list(arrivals) == []
    with pytest.raises(IndexError):
        arrivals[0]


@pytest.mark.parametrize("scene", [SQUARE_ROOM, lens_search()], ids=["room", "lens"])
def test_the_arrays_are_the_cli_arrivals(cli, tmp_path, scene):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    out = run_cli(cli, path)
    assert out.returncode == 0, out.stderr
    expected = json.loads(out.stdout)["arrivals"]
    arrivals = eigenray.Tracer(eigenray.Scene(path)).search()
    assert len(arrivals) == len(expected)
    reasons, kinks = arrivals.reason, arrivals.kink
    asks = "amplitudes" in scene
    for i, e in enumerate(expected):
        where = f"arrival {i}: {e}"
        assert arrivals.source[i] == e["source"] and arrivals.receiver[i] == e["receiver"]
        assert decoded_steps(arrivals, i) == e["steps"], where
        assert decoded_media(arrivals, i) == e["media"], where
        assert arrivals.status_names[arrivals.status[i]] == e["status"], where
        assert arrivals.time[i] == e["time"], where
        k = len(e["steps"]) + 2
        assert arrivals.points[i, :k].tolist() == e["points"], where
        assert arrivals.iterations[i] == e["iterations"], where
        assert same_number(arrivals.residual[i], e.get("residual", math.nan)), where
        assert reasons[i] == e.get("reason") and kinks[i] == e.get("kink"), where
        assert arrivals.complete[i] == e["complete"], where
        if asks:
            check_amplitude(
                e, arrivals.amplitude[i], arrivals.spreading[i], arrivals.coefficient[i],
                arrivals.attenuation_db[i], arrivals.amplitude_reason[i], where,
            )


def test_plot_draws_arrivals():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    scene = eigenray.Scene(SQUARE_ROOM)
    arrivals = eigenray.Tracer(scene).search()
    ax = eigenray.plot(scene, arrivals, colour_by="path")
    assert len(ax.collections) >= 1
    matplotlib.pyplot.close("all")
