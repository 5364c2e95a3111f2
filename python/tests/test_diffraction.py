"""Diffraction at vertices from Python: `diffract` steps on paths (times against the straight
legs through the vertex, the UTD amplitude's presence and its reasons), the search's
diffracted arrivals (as dicts and arrays, against the command-line tool's), the errors that
name the key, and a transmission loss without a jump at a corner's shadow edge."""

import json
import math

import numpy as np
import pytest

import eigenray

from test_agreement import run_cli

SCREEN = {
    "media": {"air": {"speed": 343.0}},
    "background": "air",
    "interfaces": {
        "screen": {"points": [[0, -3], [0, 0]]},
        "floor": {"points": [[-10, -4], [10, -4]]},
    },
    "sources": [[-2, -1]],
    "receivers": [[2, -1], [3, 2]],
    "paths": [
        {"steps": [{"diffract": "screen", "vertex": 1}]},
        {"steps": [{"reflect": "floor"}, {"diffract": "screen", "vertex": 1}]},
    ],
    "amplitudes": {"source": "point", "frequency": 500},
}

L_ROOM = {
    "media": {"air": {"speed": 343.0, "at": [1, 1]}},
    "interfaces": {
        "room": {
            "points": [[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]],
            "closed": True,
        }
    },
    "sources": [[1, 3]],
    "receivers": [[3, 1], [1, 1]],
    "search": {"max_steps": 1, "diffraction": True},
    "amplitudes": {"source": "point", "frequency": 500},
}


def test_diffract_steps_hold_the_vertex():
    rays = eigenray.Tracer(eigenray.Scene(SCREEN)).trace()
    s, v = (-2.0, -1.0), (0.0, 0.0)
    assert len(rays) == 4
    for i in range(len(rays)):
        assert rays.status_names[rays.status[i]] == "converged"
        r = SCREEN["receivers"][rays.receiver[i]]
        first = math.dist(s, v) if rays.path[i] == 0 else math.dist((-2.0, -7.0), v)
        want = (first + math.dist(v, r)) / 343.0
        assert abs(rays.time[i] - want) <= 1e-15 * want
        n = rays.num_points[i]
        assert tuple(rays.points[i][n - 2]) == v
        assert np.isfinite(rays.amplitude[i]) and rays.amplitude[i] != 0
        assert rays.amplitude_reason[i] is None


def test_errors_name_the_key():
    bad = json.loads(json.dumps(SCREEN))
    bad["paths"][0]["steps"][0]["vertex"] = 7
    with pytest.raises(ValueError, match=r"paths\[0\]\.steps\[0\]\.vertex"):
        eigenray.Scene(bad)
    bad = json.loads(json.dumps(SCREEN))
    bad["paths"][0]["steps"][0]["diffract"] = "screne"
    with pytest.raises(ValueError, match=r"paths\[0\]\.steps\[0\]\.diffract"):
        eigenray.Scene(bad)


def test_search_lists_the_corner_and_agrees_with_the_cli(cli, tmp_path):
    arrivals = eigenray.Tracer(eigenray.Scene(L_ROOM)).search()
    assert arrivals.step_kind_names == ["reflect", "refract", "diffract"]
    dicts = list(arrivals)
    # Behind the re-entrant corner (vertex 3) there is no direct sound: the corner comes
    # first, then two reflections and the far corner (vertex 0).
    behind = [a for a in dicts if a["receiver"] == 0]
    assert behind[0]["steps"] == [{"diffract": "room", "vertex": 3}]
    assert behind[-1]["steps"] == [{"diffract": "room", "vertex": 0}]
    t = (math.dist((1, 3), (2, 2)) + math.dist((2, 2), (3, 1))) / 343.0
    assert abs(behind[0]["time"] - t) <= 1e-15 * t
    assert behind[0]["amplitude"] is not None
    path = tmp_path / "l_room.json"
    path.write_text(json.dumps(L_ROOM))
    out = run_cli(cli, path)
    assert out.returncode == 0, out.stderr
    listed = json.loads(out.stdout)["arrivals"]
    assert [a["steps"] for a in listed] == [a["steps"] for a in dicts]
    assert [a["time"] for a in listed] == [a["time"] for a in dicts]


def test_transmission_loss_has_no_jump_at_a_shadow_edge():
    phi0, r0, r = math.pi / 3, 30.0, 40.0
    edge = math.pi + phi0
    scene = {
        "media": {"air": {"speed": 343.0}},
        "background": "air",
        "interfaces": {"corner": {"points": [[500, 0], [0, 0], [0, -500]]}},
        "sources": [[r0 * math.cos(phi0), r0 * math.sin(phi0)]],
        "receivers": [[r * math.cos(a), r * math.sin(a)] for a in (edge - 1e-9, edge + 1e-9)],
        "search": {"max_steps": 1, "diffraction": True},
        "amplitudes": {"source": "point", "frequency": 250},
    }
    tl = np.asarray(eigenray.Tracer(eigenray.Scene(scene)).transmission_loss()).ravel()
    assert np.all(np.isfinite(tl))
    assert abs(tl[0] - tl[1]) < 1e-5
    scene["search"]["diffraction"] = False
    tl = np.asarray(eigenray.Tracer(eigenray.Scene(scene)).transmission_loss()).ravel()
    assert not np.isfinite(tl[1]) or tl[1] - tl[0] > 3


def test_echoes_count_diffractions_and_the_echogram_marks_them_apart():
    """The echoes of the example L-shaped room: the listener round the corner hears only the
    diffracted arrivals (counted in `diffractions`), which the echogram draws as diamonds
    keyed "diffracted", apart from the orders' colours; the listener in view hears the direct
    sound and reflections too, and the paths' diffracted rays count as diffracted."""
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from eigenray.plotting import DIFFRACTED_COLOUR, echogram

    from conftest import ROOT

    scene = eigenray.Scene(json.loads((ROOT / "examples/scenes/l_room_diffraction.json").read_text()))
    echoes = eigenray.Tracer(scene).echoes()
    diffractions = np.asarray(echoes["diffractions"])
    assert diffractions.dtype == np.uint32
    behind = np.asarray(echoes["receiver"]) == 0
    assert behind.any() and (diffractions[behind] == 1).all()
    # Every echo's count against the search's steps.
    arrivals = eigenray.Tracer(scene).search()
    want = sorted(
        (a["receiver"], a["time"], sum("diffract" in s for s in a["steps"]))
        for a in arrivals
        if a["status"] == "converged"
    )
    got = sorted(zip(echoes["receiver"].tolist(), echoes["time"].tolist(), diffractions.tolist()))
    assert got == want
    for receiver in (0, 1):
        mine = np.asarray(echoes["receiver"]) == receiver
        ax = echogram(echoes, receiver=receiver)
        marks = [line for line in ax.get_lines() if line.get_gid() == "diffracted"]
        assert len(marks) == 1
        assert len(marks[0].get_xdata()) == int((diffractions[mine] > 0).sum())
        assert marks[0].get_marker() == "D" and marks[0].get_color() == DIFFRACTED_COLOUR
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels[-1] == "diffracted"
        plain_orders = sorted(set(np.asarray(echoes["order"])[mine & (diffractions == 0)].tolist()))
        assert len(labels) == len(plain_orders) + 1
    # A path with a diffract step: its ray's echo counts as diffracted too.
    screen = eigenray.Tracer(eigenray.Scene(SCREEN)).echoes()
    assert (np.asarray(screen["diffractions"]) == 1).all() and len(screen["time"]) > 0
