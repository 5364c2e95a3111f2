"""Drawing a scene and its rays with matplotlib (an optional dependency:
``pip install matplotlib``)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot", "echogram", "tl_map"]


def _rays_polylines(rays, max_rays):
    """The drawn rays' polylines, their times and path labels, and how many were left out."""
    if hasattr(rays, "points") and hasattr(rays, "num_points"):  # Rays
        has_time = ~np.isnan(rays.time)
        chosen = np.flatnonzero(has_time)
        left_out = 0
        if len(chosen) > max_rays:
            left_out = len(chosen) - max_rays
            chosen = chosen[np.linspace(0, len(chosen) - 1, max_rays).astype(int)]
        lines = [rays.points[i, : rays.num_points[i]] for i in chosen]
        times = rays.time[chosen]
        labels = [
            rays.path_names[rays.path[i]] or f"path {rays.path[i]}" for i in chosen
        ]
        return lines, times, labels, left_out
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
        else:
            points, time = item.points, item.time
            label = item.status
        if len(points) and not np.isnan(time):
            lines.append(np.asarray(points))
            times.append(time)
            labels.append(label)
    return lines, np.asarray(times, dtype=float), labels, left_out


def plot(scene, rays=None, *, colour_by="time", ax=None, max_rays=2000, labels=True):
    """Draws `scene` (its interfaces, sources and receivers) and `rays` on matplotlib axes.

    `rays` is a `Rays` (from `Tracer.trace`, `trace_stationary` or `solve_pairs`), a list of
    `Ray` (from `Tracer.stationary_paths`), or the `Arrivals` from `Tracer.search` (or a list
    of its dicts).
    `colour_by`: ``"time"`` (a colour bar of travel time) or ``"path"`` (a colour per path
    name, or per step sequence for search arrivals, with a legend). Past `max_rays` rays an
    even sample is drawn and the title says so. Returns the axes.
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
        lines, times, names, left_out = _rays_polylines(rays, max_rays)
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
            ax.legend(loc="best", fontsize=8, title="path")
        drawn = len(lines)
        title = f"{drawn} rays" if not left_out else f"{drawn} of {drawn + left_out} rays drawn"
    sources, receivers = scene.sources, scene.receivers
    ax.scatter(sources[:, 0], sources[:, 1], marker="*", s=120, c="crimson", zorder=6, label=None)
    ax.scatter(receivers[:, 0], receivers[:, 1], marker="v", s=14, c="black", zorder=6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x")
    ax.set_ylabel("y")
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


def echogram(echoes, source=0, receiver=0, *, ax=None, range_db=60.0):
    """Draws the echogram of one (source, receiver): each arrival as a stem at its time, up to
    its level in dB re the free field 1 unit of length from a point source, 20·log10(|a|·4π),
    coloured by its number of interactions, with a legend. `echoes` is `Tracer.echoes()` (a
    dict of arrays). Stems start `range_db` below the loudest. Returns the axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4.5), layout="constrained")
    chosen = (np.asarray(echoes["source"]) == source) & (
        np.asarray(echoes["receiver"]) == receiver
    )
    time = np.asarray(echoes["time"])[chosen]
    level = 20 * np.log10(np.abs(np.asarray(echoes["amplitude"])[chosen]) * 4 * np.pi)
    order = np.asarray(echoes["order"])[chosen]
    top = np.ceil(level.max() / 10) * 10 + 5 if len(level) else 0.0
    floor = top - range_db - 5
    cmap = plt.get_cmap("tab10" if len(set(order)) <= 10 else "tab20")
    for k, o in enumerate(sorted(set(order.tolist()))):
        mine = order == o
        ax.vlines(time[mine], floor, np.maximum(level[mine], floor), color=cmap(k % cmap.N),
                  linewidth=1.4, label=_order_label(o))
        ax.plot(time[mine], np.maximum(level[mine], floor), "o", ms=3, color=cmap(k % cmap.N))
    ax.set_ylim(floor, top)
    ax.set_xlim(0, time.max() * 1.05 if len(time) else 1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("level (dB re free field at 1 unit)")
    ax.set_title(f"Echogram: source {source} at receiver {receiver}, {len(time)} arrivals",
                 fontsize=10)
    if len(time):
        ax.legend(title="order", fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    return ax


def tl_map(receivers, tl, *, ax=None, range_db=60.0, title=None):
    """Draws a transmission-loss map: `tl` (dB, one per receiver, as a row of
    `Tracer.transmission_loss()`) at the `receivers` (an (n, 2) array), as an image when they
    form a grid (every pair of their distinct x and y) and as dots otherwise, over `range_db`
    from the lowest loss, loud bright, with a colour bar. Receivers nothing reaches (inf) are
    grey. Returns the axes."""
    import matplotlib.pyplot as plt

    receivers = np.asarray(receivers, dtype=float)
    tl = np.asarray(tl, dtype=float)
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
    ax.set_xlabel("x (range)")
    ax.set_ylabel("y (height)")
    if title:
        ax.set_title(title, fontsize=10)
    return ax
