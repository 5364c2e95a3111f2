"""The Python package gives the command-line tool's answers bit for bit: every field of
every ray of every fixture and benchmark scene (amplitudes too), and the same refusals."""

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
        "fixtures/amplitudes/*.json",
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


def same_complex(z, pair):
    """A complex number against the CLI's `[re, im]` (`null`: NaN), bit for bit."""
    if pair is None:
        return math.isnan(z.real) and math.isnan(z.imag)
    return z.real == pair[0] and z.imag == pair[1]


def check_amplitude(e, amplitude, spreading, coefficient, attenuation_db, reason, where):
    """One entry's amplitude fields against the CLI's JSON entry `e`, which has them when it
    has a time (`null` where there is no number); NaN and no reason without a time."""
    if "time" not in e:
        assert "amplitude" not in e, where
        numbers = [amplitude.real, amplitude.imag, spreading, coefficient.real, attenuation_db]
        assert all(math.isnan(x) for x in numbers) and reason is None, where
        return
    assert same_complex(amplitude, e["amplitude"]), where
    assert same_number(spreading, e["spreading"] if e["spreading"] is not None else math.nan)
    assert same_complex(coefficient, e["coefficient"]), where
    expected_db = e["attenuation_db"] if e["attenuation_db"] is not None else math.nan
    assert same_number(attenuation_db, expected_db), where
    assert reason == e.get("amplitude_reason"), where
    # A missing amplitude is never 0.
    assert (e["amplitude"] is None) == (reason is not None), where


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
    asks = "amplitudes" in tracer_scene
    assert (rays.amplitude is not None) == asks
    if not asks:
        assert rays.spreading is None and rays.coefficient is None
        assert rays.attenuation_db is None and rays.amplitude_reason is None
        return
    assert rays.amplitude.dtype == np.complex128 and rays.coefficient.dtype == np.complex128
    reasons = rays.amplitude_reason
    for i, e in enumerate(expected):
        check_amplitude(
            e, rays.amplitude[i], rays.spreading[i], rays.coefficient[i],
            rays.attenuation_db[i], reasons[i], f"ray {i}: {e}",
        )


def check_arrivals(expected, arrivals, asks):
    assert len(arrivals) == len(expected)
    for a, e in zip(arrivals, expected):
        if asks:
            check_amplitude(
                e, a["amplitude"], a["spreading"], a["coefficient"], a["attenuation_db"],
                a["amplitude_reason"], f"arrival {e}",
            )
        else:
            assert "amplitude" not in a
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
    document = json.loads(scene_file.read_text())
    stationary = document.get("solver", {}).get("stationary") == "all"
    if stationary:
        rays = tracer.trace_stationary()
    else:
        rays = tracer.trace(warm_start=warm_start)
    check_rays(expected["rays"], rays, document, stationary)
    if not stationary:
        # Into the arrays of an earlier result (of the other start), rewritten in place.
        earlier = tracer.trace(warm_start=not warm_start)
        rays = tracer.trace(warm_start=warm_start, out=earlier)
        check_rays(expected["rays"], rays, document, stationary)
    if "arrivals" in expected:
        check_arrivals(expected["arrivals"], tracer.search(), "amplitudes" in document)


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
