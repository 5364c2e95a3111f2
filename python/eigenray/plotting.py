"""Drawing a scene and its rays with matplotlib (an optional dependency:
``pip install matplotlib``)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot", "echogram", "tl_map"]

#: Most orders an echogram keys by a legend; with more, a colour bar of orders.
MAX_ORDER_LEGEND = 10

#: The colour of a diffracted arrival's stem and diamond in an echogram.
DIFFRACTED_COLOUR = "#111111"


def _axis_spec(spec, default):
    """An axis's title and scale from `spec`: None (`default`, scale 1), a name, or a tuple
    (name, unit) or (name, unit, scale). Tick numbers are scale × coordinate; a negative scale
    numbers the axis downwards (("depth", "m", -1): depth positive down below y = 0)."""
    if spec is None:
        return default, 1.0
    if isinstance(spec, str):
        return spec, 1.0
    parts = tuple(spec)
    if not 1 <= len(parts) <= 3:
        raise ValueError(f"an axis is a name or (name, unit[, scale]), not {spec!r}")
    name = str(parts[0])
    unit = parts[1] if len(parts) > 1 else None
    scale = float(parts[2]) if len(parts) > 2 else 1.0
    if not np.isfinite(scale) or scale == 0.0:
        raise ValueError(f"an axis's scale must be a finite number other than 0, not {scale!r}")
    return (f"{name} ({unit})" if unit else name), scale


def _name_axes(ax, x_axis, y_axis, default_x="x", default_y="y"):
    """Titles `ax`'s axes and numbers their ticks as `x_axis` and `y_axis` say: ticks at round
    numbers of the axis (scale × coordinate), the data left in the scene's coordinates."""
    from matplotlib.ticker import FuncFormatter

    for spec, default, axis, set_label in (
        (x_axis, default_x, ax.xaxis, ax.set_xlabel),
        (y_axis, default_y, ax.yaxis, ax.set_ylabel),
    ):
        title, scale = _axis_spec(spec, default)
        set_label(title)
        if scale != 1.0:
            axis.set_major_locator(_scaled_locator(scale))
            axis.set_major_formatter(FuncFormatter(lambda v, _pos, s=scale: f"{v * s:.10g}"))


def _scaled_locator(scale):
    """A matplotlib locator of ticks at round numbers of scale × coordinate, placed in
    coordinates."""
    from matplotlib.ticker import Locator, MaxNLocator

    round_numbers = MaxNLocator(nbins="auto", steps=[1, 2, 2.5, 5, 10])

    class ScaledLocator(Locator):
        def __call__(self):
            lo, hi = self.axis.get_view_interval()
            return self.tick_values(lo, hi)

        def tick_values(self, vmin, vmax):
            a, b = sorted((vmin * scale, vmax * scale))
            return np.asarray(round_numbers.tick_values(a, b)) / scale

    return ScaledLocator()


def _nearest_interface(scene, source, side):
    """Of the open interfaces that pass over or under `source` (a segment spanning its x), the
    name of the one nearest to it on the side of `side` (+1 above: the surface; -1 below: the
    bottom of the water it lies in), or None."""
    best, best_distance = None, np.inf
    for name, v in scene.interfaces.items():
        if scene.closed[name]:
            continue
        for a, b in zip(v[:-1], v[1:]):
            lo, hi = min(a[0], b[0]), max(a[0], b[0])
            if not (lo <= source[0] <= hi) or hi <= lo:
                continue
            y = a[1] + (b[1] - a[1]) * (source[0] - a[0]) / (b[0] - a[0])
            distance = side * (y - source[1])
            if 0 < distance < best_distance:
                best, best_distance = name, distance
    return best


def _y_within(vertices, x0, x1):
    """The heights of a polyline over x0 <= x <= x1: its vertices there and its crossings of
    x0 and x1."""
    ys = [p[1] for p in vertices if x0 <= p[0] <= x1]
    for a, b in zip(vertices[:-1], vertices[1:]):
        if a[0] != b[0]:
            for x in (x0, x1):
                t = (x - a[0]) / (b[0] - a[0])
                if 0 <= t <= 1:
                    ys.append(a[1] + t * (b[1] - a[1]))
    return np.asarray(ys, dtype=float)


#: Points a curved ray is drawn through: this many, and more per leg (`CURVE_PER_LEG`).
CURVE_POINTS = 200

#: Points a curved ray is drawn through per leg, besides `CURVE_POINTS`.
CURVE_PER_LEG = 32


def _curve_or_points(curve, points):
    """A ray's polyline: `curve(n)` (its curve sampled on the ray, in a scene with curved
    legs), or its points where the curve cannot be had (a scene changed since)."""
    points = np.asarray(points, dtype=float)
    if curve is None:
        return points
    try:
        return curve(CURVE_POINTS + CURVE_PER_LEG * (len(points) - 1))
    except (ValueError, IndexError):
        return points


def _rays_polylines(rays, max_rays, scene=None):
    """The drawn rays' polylines (each ray's curve in a scene with curved legs: its arcs
    through `gradient` and `profile` media, sampled on the ray), their times and path
    labels, and how many were left out."""
    curved = scene is not None and getattr(scene, "curved", False)
    if hasattr(rays, "points") and hasattr(rays, "num_points"):  # Rays
        has_time = ~np.isnan(rays.time)
        chosen = np.flatnonzero(has_time)
        left_out = 0
        if len(chosen) > max_rays:
            left_out = len(chosen) - max_rays
            chosen = chosen[np.linspace(0, len(chosen) - 1, max_rays).astype(int)]
        lines = [
            _curve_or_points(
                (lambda n, i=i: rays.curve(int(i), n)) if curved else None,
                rays.points[i, : rays.num_points[i]],
            )
            for i in chosen
        ]
        times = rays.time[chosen]
        labels = [
            rays.path_names[rays.path[i]] or f"path {rays.path[i]}" for i in chosen
        ]
        return lines, times, labels, left_out
    if hasattr(rays, "step_interface") and hasattr(rays, "curve"):  # Arrivals
        chosen = np.arange(len(rays))
        left_out = max(0, len(chosen) - max_rays)
        if left_out:
            chosen = chosen[np.linspace(0, len(chosen) - 1, max_rays).astype(int)]
        lines, labels = [], []
        for i in chosen:
            item = rays[int(i)]
            lines.append(
                _curve_or_points(
                    (lambda n, i=i: rays.curve(int(i), n)) if curved else None,
                    np.asarray(item["points"])[:, :2],
                )
            )
            labels.append(
                " → ".join(f"{kind} {name}" for s in item["steps"] for kind, name in s.items())
                or "direct"
            )
        return lines, np.asarray(rays.time)[chosen], labels, left_out
    # A list of rays (Ray objects or search arrivals as dicts), or `Arrivals` (its dicts).
    items = list(rays)
    left_out = max(0, len(items) - max_rays)
    if left_out:
        items = [items[i] for i in np.linspace(0, len(items) - 1, max_rays).astype(int)]
    lines, times, labels = [], [], []
    for item in items:
        if isinstance(item, dict):
            points, time = item["points"], item["time"]
            steps = item.get("steps", [])
            label = (
                " → ".join(f"{kind} {name}" for s in steps for kind, name in s.items())
                or "direct"
            )
            curve = None
            if curved and item.get("media") is not None:
                curve = lambda n, item=item: scene.curve(  # noqa: E731
                    np.asarray(item["points"])[:, :2],
                    item["media"],
                    launch_angle=item.get("launch_angle"),
                    n=n,
                )
        else:
            points, time = item.points, item.time
            label = item.status
            curve = item.curve if curved and hasattr(item, "curve") else None
        if len(points) and not np.isnan(time):
            lines.append(_curve_or_points(curve, points))
            times.append(time)
            labels.append(label)
    return lines, np.asarray(times, dtype=float), labels, left_out


def plot(scene, rays=None, *, colour_by="time", ax=None, max_rays=2000, labels=True,
         aspect="equal", x_axis=None, y_axis=None):
    """Draws `scene` (its interfaces, sources and receivers) and `rays` on matplotlib axes.

    `rays` is a `Rays` (from `Tracer.trace`, `trace_stationary` or `solve_pairs`), a list of
    `Ray` (from `Tracer.stationary_paths`), or the `Arrivals` from `Tracer.search` (or a list
    of its dicts). In a scene with curved legs (`scene.curved`: a `gradient` or `profile`
    medium) each ray is drawn as its curve (`curve`, sampled on the ray: arcs, turning
    points and all), else through its points.
    `colour_by`: ``"time"`` (a colour bar of travel time) or ``"path"`` (a colour per path
    name, or per step sequence for search arrivals, with a legend). Past `max_rays` rays an
    even sample is drawn and the title says so.
    `aspect`: ``"equal"`` (the default: one unit as long along both axes), ``"auto"`` (the
    axes fill the figure: a 5 km × 120 m waveguide is not a sliver) or a number (y stretched by
    it), as matplotlib's `set_aspect`.
    `x_axis`, `y_axis`: the axes' names and units, as a name or `(name, unit)` or
    `(name, unit, scale)`, tick numbers being scale × coordinate; `("range", "km", 1e-3)` for a
    scene in metres, `("depth", "m", -1)` for depth positive down below y = 0.
    Returns the axes.
    """
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    if colour_by not in ("time", "path"):
        raise ValueError(f"colour_by must be 'time' or 'path', not {colour_by!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    closed = scene.closed
    for name, vertices in scene.interfaces.items():
        v = np.vstack([vertices, vertices[:1]]) if closed[name] else vertices
        ax.plot(v[:, 0], v[:, 1], color="0.25", linewidth=1.6, zorder=3)
        if labels:
            middle = _middle(v)
            ax.annotate(
                name,
                middle,
                xytext=(3, 3),
                textcoords="offset points",
                fontsize=8,
                color="0.2",
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8),
                zorder=5,
            )
    title = None
    if rays is not None:
        lines, times, names, left_out = _rays_polylines(rays, max_rays, scene)
        if colour_by == "time" and len(lines):
            collection = LineCollection(lines, array=times, cmap="viridis", linewidths=0.8)
            ax.add_collection(collection)
            bar = ax.figure.colorbar(collection, ax=ax)
            bar.set_label("travel time")
        elif len(lines):
            order = list(dict.fromkeys(names))
            cmap = plt.get_cmap("tab10" if len(order) <= 10 else "tab20")
            for k, label in enumerate(order):
                chosen = [line for line, n in zip(lines, names) if n == label]
                ax.add_collection(
                    LineCollection(chosen, colors=[cmap(k % cmap.N)], linewidths=0.9, label=label)
                )
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                      fontsize=8, title="path")
        drawn = len(lines)
        title = f"{drawn} rays" if not left_out else f"{drawn} of {drawn + left_out} rays drawn"
    sources, receivers = scene.sources, scene.receivers
    ax.scatter(sources[:, 0], sources[:, 1], marker="*", s=120, c="crimson", zorder=6, label=None)
    ax.scatter(receivers[:, 0], receivers[:, 1], marker="v", s=14, c="black", zorder=6)
    ax.set_aspect(aspect, adjustable="datalim")
    ax.autoscale_view()
    _name_axes(ax, x_axis, y_axis)
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def _middle(vertices):
    """The point halfway along a polyline's length."""
    steps = np.linalg.norm(np.diff(vertices, axis=0), axis=1)
    half = steps.sum() / 2
    cumulative = np.concatenate([[0.0], np.cumsum(steps)])
    i = min(int(np.searchsorted(cumulative, half, side="right")) - 1, len(steps) - 1)
    t = (half - cumulative[i]) / steps[i] if steps[i] > 0 else 0.0
    return vertices[i] + t * (vertices[i + 1] - vertices[i])


def _order_label(order):
    return "direct" if order == 0 else f"{order} interaction" + ("" if order == 1 else "s")


def echogram(echoes, source=0, receiver=0, *, ax=None, range_db=60.0, from_zero=False):
    """Draws the echogram of one (source, receiver): each arrival as a stem at its time, up to
    its level in dB re the free field 1 unit of length from a point source, 20·log10(|a|·4π),
    coloured by its number of interactions. `echoes` is `Tracer.echoes()` (a dict of arrays).
    Stems start `range_db` below the loudest. Up to 10 orders are keyed by a legend beside the
    plot; more by a colour bar of orders (each order its colour). Diffracted arrivals (those
    with `diffractions` > 0) are drawn apart: dashed dark stems ending in diamonds, keyed
    "diffracted" in the legend (their orders not among the colours). In an extruded room, the
    other arrivals that reflect off the floor or the ceiling (`vertical` > 0) end in an outlined
    square, keyed "floor/ceiling". The time axis starts just before the first arrival, or at 0
    with `from_zero`. Returns the axes."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.5), layout="constrained")
    chosen = (np.asarray(echoes["source"]) == source) & (
        np.asarray(echoes["receiver"]) == receiver
    )
    time = np.asarray(echoes["time"])[chosen]
    level = 20 * np.log10(np.abs(np.asarray(echoes["amplitude"])[chosen]) * 4 * np.pi)
    order = np.asarray(echoes["order"])[chosen]
    if "diffractions" in echoes:
        diffracted = np.asarray(echoes["diffractions"])[chosen] > 0
    else:
        diffracted = np.zeros(len(time), dtype=bool)
    top = np.ceil(level.max() / 10) * 10 + 5 if len(level) else 0.0
    floor = top - range_db - 5
    orders = sorted(set(order[~diffracted].tolist()))
    shown = np.maximum(level, floor)
    plain = ~diffracted
    if len(orders) <= MAX_ORDER_LEGEND:
        cmap = plt.get_cmap("tab10")
        for k, o in enumerate(orders):
            mine = plain & (order == o)
            ax.vlines(time[mine], floor, shown[mine], color=cmap(k), linewidth=1.4,
                      label=_order_label(o))
            ax.plot(time[mine], shown[mine], "o", ms=3, color=cmap(k))
    elif orders:
        lo, hi = orders[0], orders[-1]
        # One colour per order, short of viridis's palest yellow.
        cmap = plt.get_cmap("viridis").resampled(256)
        colours = cmap(0.92 * (order - lo) / max(hi - lo, 1))
        # The quietest first, so that the loud ones are on top.
        by_level = np.argsort(level)
        by_level = by_level[plain[by_level]]
        ax.vlines(time[by_level], floor, shown[by_level], colors=colours[by_level], linewidth=1.2)
        ax.scatter(time[by_level], shown[by_level], s=9, c=colours[by_level], zorder=3)
        boundaries = np.arange(lo, hi + 2) - 0.5
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import ListedColormap

        bar_colours = ListedColormap(cmap(0.92 * (np.arange(lo, hi + 1) - lo) / max(hi - lo, 1)))
        mappable = ScalarMappable(norm=BoundaryNorm(boundaries, bar_colours.N), cmap=bar_colours)
        bar = ax.figure.colorbar(mappable, ax=ax)
        bar.set_label("order (interactions; 0: direct)")
        # Whole orders, at the middles of their blocks: about 8 of them.
        step = max(1, int(np.ceil((hi - lo + 1) / 8)))
        step = next(s for s in (1, 2, 5, 10, 20, 25, 50, 100, step) if s >= step)
        bar.set_ticks(np.arange(int(np.ceil(lo / step)) * step, hi + 1, step))
        bar.ax.invert_yaxis()
    if diffracted.any():
        ax.vlines(time[diffracted], floor, shown[diffracted], color=DIFFRACTED_COLOUR,
                  linewidth=1.4, linestyles=(0, (3, 2)), label="diffracted", zorder=4)
        ax.plot(time[diffracted], shown[diffracted], "D", ms=4.5, color=DIFFRACTED_COLOUR,
                zorder=5, gid="diffracted")
    if "vertical" in echoes:
        vertical = plain & (np.asarray(echoes["vertical"])[chosen] > 0)
    else:
        vertical = np.zeros(len(time), dtype=bool)
    if vertical.any():
        ax.plot(time[vertical], shown[vertical], "s", ms=5, mfc="none", mew=0.9,
                color=DIFFRACTED_COLOUR, linestyle="none", label="floor/ceiling", zorder=5,
                gid="vertical")
    if len(time) and (len(orders) <= MAX_ORDER_LEGEND or diffracted.any() or vertical.any()):
        ax.legend(title="order" if len(orders) <= MAX_ORDER_LEGEND else None, fontsize=8,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.set_ylim(floor, top)
    if len(time):
        first, last = time.min(), time.max()
        spread = last - first
        pad = 0.05 * spread if spread > 0 else (0.05 * last if last > 0 else 0.05)
        start = min(0.0, first - pad) if from_zero else max(first - pad, 0.0) if first >= 0 else first - pad
        ax.set_xlim(start, last + pad)
    else:
        ax.set_xlim(0.0, 1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("level (dB re free field at 1 unit)")
    ax.set_title(f"Echogram: source {source} at receiver {receiver}, {len(time)} arrivals",
                 fontsize=10)
    ax.grid(alpha=0.3)
    return ax


def tl_map(receivers, tl, *, ax=None, range_db=60.0, title=None, scene=None, source=0,
           x_axis=None, y_axis=None):
    """Draws a transmission-loss map: `tl` (dB, one per receiver, as a row of
    `Tracer.transmission_loss()`, or a grid scene's `[nx, ny]` of it) at the `receivers` (an (n, 2) array), as an image when they
    form a grid (every pair of their distinct x and y) and as dots otherwise, over `range_db`
    from the lowest loss, loud bright, with a colour bar. Receivers nothing reaches (inf) are
    grey. With `scene`, its interfaces are drawn over the map, the bottom (below the first open
    interface under source `source`) shaded and that source marked with a star.
    `x_axis`, `y_axis`: the axes' names and units, as for `plot` (`("range", "km", 1e-3)`,
    `("depth", "m", -1)`). Returns the axes."""
    import matplotlib.pyplot as plt

    receivers = np.asarray(receivers, dtype=float)
    # A grid scene's loss in the grid's shape, flattened in the receivers' order.
    tl = np.asarray(tl, dtype=float).reshape(-1)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.5), layout="constrained")
    finite = np.isfinite(tl)
    lo = np.floor(tl[finite].min()) if finite.any() else 0.0
    cmap = plt.get_cmap("viridis_r").with_extremes(bad="0.78")
    xs, ys = np.unique(receivers[:, 0]), np.unique(receivers[:, 1])
    shown = np.where(finite, tl, np.nan)
    if len(xs) * len(ys) == len(tl) and len(tl) > 1:
        grid = np.full((len(ys), len(xs)), np.nan)
        grid[np.searchsorted(ys, receivers[:, 1]), np.searchsorted(xs, receivers[:, 0])] = shown
        artist = ax.pcolormesh(xs, ys, grid, cmap=cmap, vmin=lo, vmax=lo + range_db,
                               shading="nearest")
    else:
        artist = ax.scatter(receivers[:, 0], receivers[:, 1], c=shown, cmap=cmap, vmin=lo,
                            vmax=lo + range_db, s=16, plotnonfinite=True)
    bar = ax.figure.colorbar(artist, ax=ax)
    bar.set_label("transmission loss (dB)")
    bar.ax.invert_yaxis()
    if scene is not None:
        _draw_scene_on_map(ax, scene, source)
    _name_axes(ax, x_axis, y_axis)
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def _draw_scene_on_map(ax, scene, source):
    """Draws `scene`'s interfaces, the bottom under source `source` shaded and the source as a
    star over a map, keeping the map's extent (widened to take the source in)."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    at = np.asarray(scene.sources[source], dtype=float)
    if not x0 <= at[0] <= x1:
        margin = 0.02 * (x1 - x0)
        x0, x1 = min(x0, at[0] - margin), max(x1, at[0] + margin)
    if not y0 <= at[1] <= y1:
        margin = 0.04 * (y1 - y0)
        y0, y1 = min(y0, at[1] - margin), max(y1, at[1] + margin)
    bottom = _nearest_interface(scene, at, -1.0)
    # The surface above the source and the bottom below it in view too, where they lie
    # within half the map's height of it.
    reach = 0.5 * (y1 - y0)
    for side in (1.0, -1.0):
        name = _nearest_interface(scene, at, side)
        if name is None:
            continue
        ys = _y_within(scene.interfaces[name], x0, x1)
        if not len(ys):
            continue
        if side < 0 and ys.min() < y0 and y0 - ys.min() <= reach:
            y0 = ys.min() - 0.03 * (y1 - ys.min())
        elif side > 0 and ys.max() > y1 and ys.max() - y1 <= reach:
            y1 = ys.max() + 0.03 * (ys.max() - y0)
    for name, v in scene.interfaces.items():
        v = np.vstack([v, v[:1]]) if scene.closed[name] else v
        ax.plot(v[:, 0], v[:, 1], color="0.2", linewidth=1.6, zorder=3, label=name)
        if name == bottom:
            below = y0 - (y1 - y0)
            ax.fill_between(v[:, 0], v[:, 1], below, color="#b59b6d", alpha=0.8, zorder=2,
                            linewidth=0, label=f"{name} (bottom)")
    ax.scatter([at[0]], [at[1]], marker="*", s=160, c="#e4572e", edgecolors="0.1",
               linewidths=0.8, zorder=4, label=f"source {source}")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
