"""The examples run, and the plotting helper draws axes, a colour bar or a legend."""

import pathlib
import subprocess
import sys

import numpy as np
import pytest

import eigenray

EXAMPLES = sorted((pathlib.Path(__file__).parents[1] / "examples").glob("*.py"))


# What an example needs beyond the test extras: skipped without it.
NEEDS = {"dask_tl_map.py": "distributed"}


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_the_example_runs_and_draws(example, tmp_path):
    pytest.importorskip("matplotlib")
    if example.name in NEEDS:
        pytest.importorskip(NEEDS[example.name])
    picture = tmp_path / "picture.png"
    out = subprocess.run(
        [sys.executable, str(example), str(picture)], capture_output=True, text=True, check=False
    )
    assert out.returncode == 0, out.stderr
    assert picture.stat().st_size > 10_000
    assert "wrote" in out.stdout


def test_plot_colours_by_time_with_a_colour_bar():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    scene = eigenray.Scene(pathlib.Path(__file__).parents[2] / "examples/scenes/room.json")
    rays = eigenray.Tracer(scene).trace()
    ax = eigenray.plot(scene, rays)
    assert ax.get_xlabel() == "x" and ax.get_ylabel() == "y"
    assert len(ax.figure.axes) == 2  # the colour bar
    assert ax.figure.axes[1].get_ylabel() == "travel time"
    assert ax.get_title() == "15 rays"


def test_plot_colours_by_path_with_a_legend_and_samples_many_rays():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    scene = eigenray.Scene(pathlib.Path(__file__).parents[2] / "examples/scenes/room.json")
    rays = eigenray.Tracer(scene).trace()
    ax = eigenray.plot(scene, rays, colour_by="path", max_rays=10)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert set(legend) <= set(scene.path_names) and len(legend) >= 3
    assert ax.get_title() == "10 of 15 rays drawn"
    with pytest.raises(ValueError):
        eigenray.plot(scene, rays, colour_by="speed")


def python_block(document, heading):
    """The first ```python block after `heading` in a document of the repository."""
    text = (pathlib.Path(__file__).parents[2] / document).read_text()
    section = text[text.index(heading):]
    start = section.index("```python\n") + len("```python\n")
    return section[start:section.index("```", start)]


@pytest.mark.parametrize(
    "document, heading", [("README.md", "## From Python"), ("docs/python.md", "## Use")]
)
def test_the_documented_snippet_runs(document, heading):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    namespace = {}
    exec(compile(python_block(document, heading), document, "exec"), namespace)
    rays = namespace["rays"]
    assert len(rays) == 500 and (rays.status == 0).all()
    assert rays.points.shape == (500, 3, 2)


def test_the_documented_layout_loop_runs():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    namespace = {}
    exec(compile(python_block("docs/python.md", "## Use"), "use", "exec"), namespace)
    loop = python_block("docs/python.md", "### Changing the scene in a loop")
    exec(compile(loop, "loop", "exec"), namespace)
    rays, tracer = namespace["rays"], namespace["tracer"]
    # Through the bent surface some rays cross at its middle vertex (`vertex`, code 1).
    assert np.isin(rays.status, [0, 1]).all() and (rays.status == 0).sum() > 400
    assert np.allclose(rays.points[:, 2, 1], -3.0)
    assert tracer.scene.interfaces["surface"].shape == (3, 2)
