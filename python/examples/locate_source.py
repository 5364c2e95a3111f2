"""Locating a sound source in air from its arrival times at hydrophones under a wavy water
surface: least squares with scipy, on eigenray's exact times and their derivatives.

    python locate_source.py [picture.png]

Each residual is a ray's time minus the observed time; its derivative with respect to the
source position is `Tracer.gradient(...).source`, exact (the envelope theorem), so the
optimiser gets the true Jacobian of rays that refract through the bent surface.
"""

import sys

import numpy as np
from scipy.optimize import least_squares

import eigenray

surface = [[-30, 0.0], [-15, 0.6], [0, -0.4], [15, 0.5], [30, 0.0]]
hydrophones = [[-12, -8], [-4, -10], [5, -9], [13, -7], [0, -15], [-8, -14]]
scene = eigenray.Scene({
    "media": {"air": {"speed": 343.0}, "water": {"speed": 1480.0}},
    "interfaces": {"surface": {"points": surface}},
    "sources": [[0, 10]],
    "receivers": hydrophones,
    "paths": [{"name": "through the surface", "steps": [{"refract": "surface"}],
               "media": ["air", "water"]}],
})
tracer = eigenray.Tracer(scene)

true_source = np.array([6.3, 7.9])
observed = np.array([tracer.time(true_source, h) for h in hydrophones])


def residuals(x):
    return np.array([tracer.time(x, h) for h in hydrophones]) - observed


def jacobian(x):
    return np.array([tracer.gradient(x, h).source for h in hydrophones])


start = np.array([-5.0, 4.0])
fit = least_squares(residuals, start, jac=jacobian, xtol=1e-15, ftol=1e-15, gtol=1e-15)
error = np.linalg.norm(fit.x - true_source)
print(f"start {start}, found {fit.x} after {fit.nfev} evaluations "
      f"({fit.njev} Jacobians); error {error:.1e} m, largest residual "
      f"{np.abs(fit.fun).max():.1e} s")

if len(sys.argv) > 1:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
    tracer.set_source(0, fit.x)
    eigenray.plot(tracer.scene, tracer.trace(), ax=ax)
    ax.scatter(*start, marker="x", s=80, c="tab:red", zorder=7, label="start")
    ax.scatter(*true_source, marker="o", s=90, facecolors="none", edgecolors="black",
               zorder=7, label="true source")
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(f"source located to {error:.0e} m from 6 arrival times "
                 f"({fit.nfev} evaluations)", fontsize=10)
    fig.savefig(sys.argv[1], dpi=120)
    print(f"wrote {sys.argv[1]}")
