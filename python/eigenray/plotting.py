"""Drawing a scene and its rays with matplotlib (an optional dependency:
``pip install matplotlib``)."""

from __future__ import annotations

import numpy as np

__all__ = ["plot"]


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
    # A list of rays (Ray objects or search arrivals as dicts).
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
    `Ray` (from `Tracer.stationary_paths`), or the list of arrivals from `Tracer.search`.
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
