"""The Python package gives the command-line tool's answers bit for bit: every field of
every ray of every fixture and benchmark scene, and the same refusals."""

import json
import math
import subprocess

import numpy as np
import pytest

import eigenray

from conftest import ROOT

SCENES = sorted(
    p
    for pattern in (
        "fixtures/cases/*.json",
        "fixtures/bench/*.json",
        "fixtures/fuzz/*.json",
        "fixtures/pyroomacoustics/*.json",
        "fixtures/every_stationary.json",
        "examples/scenes/*.json",
    )
    for p in ROOT.glob(pattern)
    if not p.name.endswith((".expected.json", ".ref.json")) and p.name != "rooms.json"
)


def run_cli(cli, scene, *extra):
    out = subprocess.run(
        [cli, "solve", str(scene), "--format", "json", *extra],
        capture_output=True,
        text=True,
        check=False,
    )
    return out


def same_number(a, b):
    return a == b or (math.isnan(a) and math.isnan(b))


def check_rays(expected, rays, tracer_scene, stationary):
    assert len(rays) == len(expected)
    names = rays.status_names
    for i, e in enumerate(expected):
        where = f"ray {i}: {e}"
        assert rays.source[i] == e["source"], where
        assert rays.receiver[i] == e["receiver"], where
        assert rays.path[i] == e["path"], where
        assert rays.path_names[rays.path[i]] == e.get("path_name"), where
        assert names[rays.status[i]] == e["status"], where
        assert same_number(rays.time[i], e.get("time", math.nan)), where
        assert rays.iterations[i] == e["iterations"], where
        assert same_number(rays.residual[i], e.get("residual", math.nan)), where
        assert rays.reason[i] == e.get("reason"), where
        k = rays.num_points[i]
        if "points" in e:
            assert rays.points[i, :k].tolist() == e["points"], where
        else:
            assert np.isnan(rays.points[i]).all(), where
        assert np.isnan(rays.points[i, k:]).all(), where
        media = [rays.media_names[m] for m in rays.media[i] if m >= 0]
        assert media == e.get("media", []), where
        if stationary:
            assert rays.arrival[i] == e["arrival"], where
            assert rays.kink[i] == e.get("kink"), where
            assert rays.complete[i] == e["complete"], where
        else:
            assert rays.arrival is None and rays.kink is None and rays.complete is None


def check_arrivals(expected, arrivals):
    assert len(arrivals) == len(expected)
    for a, e in zip(arrivals, expected):
        assert a["source"] == e["source"] and a["receiver"] == e["receiver"]
        assert a["steps"] == e["steps"]
        assert a["media"] == e["media"]
        assert a["status"] == e["status"]
        assert a["time"] == e["time"]
        assert a["points"].tolist() == e["points"]
        assert a["iterations"] == e["iterations"]
        assert a["complete"] == e["complete"]
        assert a["reason"] == e.get("reason")
        assert a["kink"] == e.get("kink")


@pytest.mark.parametrize("scene_file", SCENES, ids=lambda p: str(p.relative_to(ROOT)))
@pytest.mark.parametrize("warm_start", [True, False])
def test_the_package_gives_the_cli_output(cli, scene_file, warm_start):
    extra = () if warm_start else ("--no-warm-start",)
    out = run_cli(cli, scene_file, *extra)
    assert out.returncode == 0, out.stderr
    expected = json.loads(out.stdout)
    scene = eigenray.Scene(scene_file)
    tracer = eigenray.Tracer(scene)
    stationary = json.loads(scene_file.read_text()).get("solver", {}).get("stationary") == "all"
    if stationary:
        rays = tracer.trace_stationary()
    else:
        rays = tracer.trace(warm_start=warm_start)
    check_rays(expected["rays"], rays, scene, stationary)
    if not stationary:
        # Into the arrays of an earlier result (of the other start), rewritten in place.
        earlier = tracer.trace(warm_start=not warm_start)
        rays = tracer.trace(warm_start=warm_start, out=earlier)
        check_rays(expected["rays"], rays, scene, stationary)
    if "arrivals" in expected:
        check_arrivals(expected["arrivals"], tracer.search())


INVALID = sorted((ROOT / "fixtures/invalid").glob("*.json"))


@pytest.mark.parametrize("scene_file", INVALID, ids=lambda p: p.name)
def test_invalid_scenes_raise_the_cli_message(cli, scene_file):
    out = run_cli(cli, scene_file)
    assert out.returncode == 2
    message = out.stderr.strip().removeprefix("error: ")
    stationary = "\"stationary\": \"all\"" in scene_file.read_text()
    with pytest.raises(eigenray.EigenrayError) as caught:
        tracer = eigenray.Tracer(eigenray.Scene(scene_file))
        if stationary:
            tracer.trace_stationary()
    error = caught.value
    assert str(error) == message
    # `key` and `message` hold the scene's text as it is; the message escapes control
    # characters.
    if error.message.isprintable():
        assert message == f"{error.key}: {error.message}"
    # Each fixture's .key file holds what its message must name.
    assert scene_file.with_suffix(".key").read_text().strip() in str(caught.value)
