"""The plotting helpers' pictures, by their matplotlib artists: the echogram's time axis and
key, the named axes, `plot`'s aspect and the map's scene."""

import numpy as np
import pytest

import eigenray

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from eigenray.plotting import echogram, plot, tl_map  # noqa: E402


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def rectangle_room(order):
    """A 6 × 4 room whose walls absorb 10 % of the energy, every path up to `order` walls."""
    corners = [[0, 0], [6, 0], [6, 4], [0, 4]]
    walls = {
        f"w{i}": {"points": [corners[i], corners[(i + 1) % 4]], "reflection": {"absorption": 0.1}}
        for i in range(4)
    }
    return eigenray.Scene({
        "media": {"air": {"speed": 343.0}},
        "background": "air",
        "interfaces": walls,
        "sources": [[1.5, 1.2]],
        "receivers": [[4.5, 2.8]],
        "search": {"max_steps": order, "refract": False},
        "amplitudes": {"source": "point"},
    })


def waveguide(receivers):
    """Shallow water: a surface, a bottom sloping from 100 to 130 below it, a source 25 down."""
    return eigenray.Scene({
        "media": {"water": {"speed": 1500.0}},
        "background": "water",
        "interfaces": {
            "surface": {"points": [[-10, 0], [5100, 0]], "reflection": "pressure-release"},
            "seabed": {"points": [[-10, -100], [1500, -100], [3500, -130], [5100, -130]]},
        },
        "sources": [[0.0, -25.0]],
        "receivers": receivers,
        "search": {"max_steps": 2, "refract": False},
        "amplitudes": {"source": "point", "frequency": 100.0},
    })


def test_an_echogram_of_30_orders_keys_them_by_a_colour_bar_without_squashing_the_plot():
    echoes = eigenray.Tracer(rectangle_room(30)).echoes()
    orders = np.asarray(echoes["order"])
    assert orders.max() == 30
    ax = echogram(echoes)
    fig = ax.figure
    fig.canvas.draw()
    assert ax.get_legend() is None
    bars = [a for a in fig.axes if a is not ax]
    assert len(bars) == 1 and bars[0].get_ylabel() == "order (interactions; 0: direct)"
    # The plot keeps most of the figure: not a strip under a legend.
    box = ax.get_window_extent()
    assert box.height > 0.6 * fig.bbox.height and box.width > 0.6 * fig.bbox.width
    # One colour per order, every one of the 31 different ("20" is not "direct").
    stems = ax.collections[0]
    colours = stems.get_colors()
    assert len(colours) == len(orders)
    times = np.asarray(echoes["time"])
    by_level = np.argsort(20 * np.log10(np.abs(echoes["amplitude"])))
    order_of_stem = orders[by_level]
    assert np.allclose(stems.get_segments()[0][0][0], times[by_level][0])
    per_order = {}
    for o, c in zip(order_of_stem, colours):
        per_order.setdefault(int(o), set()).add(tuple(np.round(c, 6)))
    assert all(len(c) == 1 for c in per_order.values())
    distinct = {next(iter(c)) for c in per_order.values()}
    assert len(distinct) == 31


def test_a_few_orders_keep_a_legend_beside_the_plot():
    echoes = eigenray.Tracer(rectangle_room(3)).echoes()
    ax = echogram(echoes)
    ax.figure.canvas.draw()
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()][:2] == ["direct", "1 interaction"]
    # Beside the plot, not over its data.
    assert legend.get_window_extent().x0 >= ax.get_window_extent().x1


def test_the_echogram_starts_just_before_the_first_arrival_or_at_zero():
    echoes = {
        "source": np.zeros(3, int), "receiver": np.zeros(3, int), "order": np.array([0, 2, 5]),
        "time": np.array([2.667, 2.9, 3.231]),
        "amplitude": np.array([1e-4, -5e-5, 1e-5], dtype=complex),
    }
    lo, hi = echogram(echoes).get_xlim()
    assert 2.6 < lo < 2.667 and 3.231 < hi < 3.3
    lo, hi = echogram(echoes, from_zero=True).get_xlim()
    assert lo == 0.0 and 3.231 < hi < 3.3


def test_plot_takes_an_aspect_and_named_axes():
    scene = waveguide([[4000.0, -50.0]])
    ax = plot(scene)
    assert ax.get_aspect() == 1.0
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x", "y")
    ax = plot(scene, aspect="auto", x_axis=("range", "km", 1e-3), y_axis=("depth", "m", -1))
    assert ax.get_aspect() == "auto"
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("range (km)", "depth (m)")
    ax.figure.canvas.draw()
    # A 5 km × 130 m waveguide fills the axes rather than a sliver.
    lo, hi = ax.get_ylim()
    assert hi - lo < 400
    depth = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    ticks = ax.get_yticks()
    shown = [(v, t) for v, t in zip(ticks, ax.get_yticklabels()) if lo <= v <= hi]
    assert shown and all(float(t.get_text().replace("−", "-")) == pytest.approx(-v) for v, t in shown)
    assert "100" in depth
    rng = [t.get_text() for t in ax.get_xticklabels()]
    assert "1" in rng and "4" in rng
    with pytest.raises(ValueError, match="scale"):
        plot(scene, x_axis=("range", "km", 0))


def test_the_map_draws_the_surface_the_bottom_and_the_source():
    xs, ys = np.linspace(250.0, 5000.0, 20), np.linspace(-5.0, -95.0, 10)
    grid = np.array([[x, y] for y in ys for x in xs])
    scene = waveguide(grid.tolist())
    tl = eigenray.Tracer(scene).transmission_loss()[0]
    ax = tl_map(grid, tl, scene=scene, x_axis=("range", "km", 1e-3), y_axis=("depth", "m", -1))
    labels = {artist.get_label() for artist in ax.get_children()}
    assert {"surface", "seabed", "seabed (bottom)", "source 0"} <= labels
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("range (km)", "depth (m)")
    # The source at range 0 is inside the map's extent.
    lo, hi = ax.get_xlim()
    assert lo < 0.0 < hi
    assert ax.figure.axes[1].get_ylabel() == "transmission loss (dB)"
    # Without a scene, the map alone as before.
    ax = tl_map(grid, tl)
    assert not any(artist.get_label() == "source 0" for artist in ax.get_children())
