"""The echoes of an extruded room count their floor and ceiling reflections, and the echogram
marks them apart."""

import json

import numpy as np
import pytest

import eigenray
from conftest import ROOT


def test_echoes_count_floor_and_ceiling_reflections_and_the_echogram_marks_them():
    """`Tracer.echoes()`'s `vertical` column is, echo for echo, the number of floor and
    ceiling steps of the search's arrivals; the echogram draws exactly those with one or more
    as squares keyed "floor/ceiling"; a plane room's column is all 0 and has no such mark."""
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from eigenray.plotting import echogram

    doc = json.loads((ROOT / "examples/scenes/extruded_room.json").read_text())
    tracer = eigenray.Tracer(eigenray.Scene(doc))
    echoes = tracer.echoes()
    vertical = np.asarray(echoes["vertical"])
    assert vertical.dtype == np.uint32
    want = sorted(
        (a["source"], a["receiver"], a["time"],
         sum(s.get("reflect") in ("floor", "ceiling") for s in a["steps"]))
        for a in tracer.search()
        if a["status"] == "converged"
    )
    got = sorted(zip(echoes["source"].tolist(), echoes["receiver"].tolist(),
                     echoes["time"].tolist(), vertical.tolist()))
    assert got == want
    assert (vertical == 0).any() and (vertical >= 2).any()
    for receiver in (0, 1):
        mine = np.asarray(echoes["receiver"]) == receiver
        ax = echogram(echoes, receiver=receiver)
        marks = [line for line in ax.get_lines() if line.get_gid() == "vertical"]
        assert len(marks) == 1 and marks[0].get_marker() == "s"
        assert sorted(marks[0].get_xdata().tolist()) == sorted(
            np.asarray(echoes["time"])[mine & (vertical > 0)].tolist())
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert labels[-1] == "floor/ceiling"
    # The same plan without its extrusion: nothing to mark.
    del doc["extrusion"]
    doc["sources"] = [p[:2] for p in doc["sources"]]
    doc["receivers"] = [p[:2] for p in doc["receivers"]]
    plane = eigenray.Tracer(eigenray.Scene(doc)).echoes()
    assert len(plane["time"]) > 0 and (np.asarray(plane["vertical"]) == 0).all()
    ax = echogram(plane)
    assert not [line for line in ax.get_lines() if line.get_gid() == "vertical"]
