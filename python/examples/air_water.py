"""The seed case: a source in air over water, 500 receivers under the surface.

    python air_water.py [picture.png]

Three lines trace it; the rest checks Snell's law and draws the rays coloured by time.
"""

import sys

import numpy as np

import eigenray

receivers = np.column_stack([np.linspace(-3, 3, 500), np.full(500, -1.0)])
scene = eigenray.Scene({
    "media": {"air": {"index": 1.0}, "water": {"index": 1.333}},
    "interfaces": {"surface": {"points": [[-4, 0], [4, 0]]}},
    "sources": [[0, 1]],
    "receivers": receivers.tolist(),
    "paths": [{"name": "refracted", "steps": [{"refract": "surface"}], "media": ["air", "water"]}],
})
rays = eigenray.Tracer(scene).trace()  # every ray, in parallel, as numpy arrays

# Snell's law at each refraction point: n1 sin(θ1) = n2 sin(θ2).
source, hit, receiver = rays.points[:, 0], rays.points[:, 1], rays.points[:, 2]
sin_in = (hit - source)[:, 0] / np.linalg.norm(hit - source, axis=1)
sin_out = (receiver - hit)[:, 0] / np.linalg.norm(receiver - hit, axis=1)
mismatch = np.abs(1.0 * sin_in - 1.333 * sin_out).max()
print(f"{len(rays)} rays, all {rays.status_names[rays.status.max()]}; "
      f"times {rays.time.min():.4f} to {rays.time.max():.4f}; Snell mismatch {mismatch:.1e}")

if len(sys.argv) > 1:
    import matplotlib

    matplotlib.use("Agg")
    ax = eigenray.plot(scene, rays, max_rays=100)
    ax.figure.savefig(sys.argv[1], dpi=120)
    print(f"wrote {sys.argv[1]}")
