"""eigenray: exact ray paths (eigenrays) through reflections and refractions on 2-D
piecewise-linear interfaces between media of different speeds.

>>> import eigenray
>>> scene = eigenray.Scene({
...     "media": {"air": {"index": 1.0}, "water": {"index": 1.333}},
...     "interfaces": {"surface": {"points": [[-1, 0], [2, 0]]}},
...     "sources": [[0, 1]], "receivers": [[1, -1]],
...     "paths": [{"steps": [{"refract": "surface"}], "media": ["air", "water"]}],
... })
>>> rays = eigenray.Tracer(scene).trace()
>>> round(float(rays.time[0]), 6)
2.601764
"""

from ._eigenray import (
    STATUS_NAMES,
    Arrivals,
    EigenrayError,
    Gradient,
    Gradients,
    PointSensitivities,
    Ray,
    Rays,
    Scene,
    Tracer,
)

__all__ = [
    "STATUS_NAMES", "Arrivals", "EigenrayError", "Gradient", "Gradients", "PointSensitivities",
    "Ray", "Rays", "Scene", "Tracer", "plot",
]


def plot(*args, **kwargs):
    """Draws a scene and its rays with matplotlib: see `eigenray.plotting.plot`."""
    from .plotting import plot as _plot

    return _plot(*args, **kwargs)
