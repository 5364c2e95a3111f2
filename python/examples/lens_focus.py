"""The focal spot of a biconvex glass lens: a line source far in front of it, every ray
through both faces to each receiver of a grid around the focus (every stationary path, so that
the rays through different zones of the lens interfere), summed coherently at a wavelength of
0.05 length units and drawn as the intensity relative to its peak. Beside it, rays through
the lens to the focal plane.

Checked against an independent computation: the thick-lens (lensmaker's) paraxial focus and
the marginal ray's crossing of the axis, traced through the two circular faces by Snell's law
in this file; the brightest point lies on the axis between the two (spherical aberration
pulls the best focus from the paraxial one towards the lens).

    python lens_focus.py [lens_focus.png]
"""

import math
import sys

import numpy as np

import eigenray

N_GLASS, RADIUS, THICKNESS, HALF_APERTURE = 1.5, 10.0, 2.0, 2.0
SOURCE_X, WAVELENGTH = -1000.0, 0.05
SEGMENTS = 200


def face(sign):
    """A face of the lens, digitised: the arc of radius RADIUS through the vertex at
    x = sign * THICKNESS / 2, its centre on the axis on the other side, from y = -h to h."""
    vertex = sign * THICKNESS / 2
    centre = vertex - sign * RADIUS
    ys = np.linspace(-HALF_APERTURE, HALF_APERTURE, SEGMENTS + 1)
    xs = centre + sign * np.sqrt(RADIUS**2 - ys**2)
    return np.column_stack([xs, ys]).tolist()


def scene(receivers):
    return eigenray.Scene({
        "media": {"air": {"index": 1.0}, "glass": {"index": N_GLASS}},
        "interfaces": {"front": {"points": face(-1)}, "back": {"points": face(1)}},
        "sources": [[SOURCE_X, 0.0]],
        "receivers": np.asarray(receivers).tolist(),
        "paths": [{"steps": [{"refract": "front"}, {"refract": "back"}],
                   "media": ["air", "glass", "air"]}],
        "solver": {"stationary": "all"},
        "amplitudes": {"source": "line", "frequency": 1.0 / WAVELENGTH},
    })


def paraxial_focus():
    """The image of the source by the thick-lens formulas: its x."""
    r1, r2, n, d = RADIUS, -RADIUS, N_GLASS, THICKNESS
    power = (n - 1) * (1 / r1 - 1 / r2 + (n - 1) * d / (n * r1 * r2))
    f = 1 / power
    front_principal = -d / 2 - f * (n - 1) * d / (n * r2)
    back_principal = d / 2 - f * (n - 1) * d / (n * r1)
    s = front_principal - SOURCE_X
    return back_principal + 1 / (1 / f - 1 / s)


def refract(d, normal, n1, n2):
    """Snell's law in vector form: the unit direction after refraction of unit `d` at a
    surface of unit `normal` (facing the incoming ray), from index n1 into n2."""
    cos_i = -float(np.dot(d, normal))
    eta = n1 / n2
    k = 1 - eta**2 * (1 - cos_i**2)
    return eta * d + (eta * cos_i - math.sqrt(k)) * normal


def sphere_hit(p, d, centre, outer):
    """Where the ray p + t d meets the circle of radius RADIUS about `centre` (the nearer
    crossing when `outer`, else the farther), and the circle's outward normal there."""
    w = p - centre
    b = float(np.dot(w, d))
    c = float(np.dot(w, w)) - RADIUS**2
    t = -b - math.sqrt(b * b - c) if outer else -b + math.sqrt(b * b - c)
    x = p + t * d
    return x, (x - centre) / RADIUS


def marginal_focus(height):
    """Where the ray from the source through the front face at `height` crosses the axis
    behind the lens, traced through the exact circular faces."""
    front_centre = np.array([-THICKNESS / 2 + RADIUS, 0.0])
    back_centre = np.array([THICKNESS / 2 - RADIUS, 0.0])
    source = np.array([SOURCE_X, 0.0])
    # Aim at the front face's point at `height`.
    x_face = front_centre[0] - math.sqrt(RADIUS**2 - height**2)
    d = np.array([x_face, height]) - source
    d /= np.linalg.norm(d)
    # The front face's outward normal faces the incoming ray; the back face's faces away.
    p, n = sphere_hit(source, d, front_centre, outer=True)
    d = refract(d, n, 1.0, N_GLASS)
    p, n = sphere_hit(p, d, back_centre, outer=False)
    d = refract(d, -n, N_GLASS, 1.0)
    return float(p[0] - p[1] * d[0] / d[1])


def focal_grid(nx, ny):
    x = np.linspace(8.6, 11.6, nx)
    y = np.linspace(-0.4, 0.4, ny)
    gx, gy = np.meshgrid(x, y)
    return np.column_stack([gx.ravel(), gy.ravel()])


def intensity_db(receivers):
    """The intensity at each receiver relative to the brightest, dB."""
    tl = eigenray.Tracer(scene(receivers)).transmission_loss()[0]
    return -(tl - tl[np.isfinite(tl)].min())


def main():
    picture = sys.argv[1] if len(sys.argv) > 1 else "lens_focus.png"
    receivers = focal_grid(241, 81)
    level = intensity_db(receivers)
    peak = receivers[np.argmax(np.where(np.isfinite(level), level, -np.inf))]
    paraxial = paraxial_focus()
    marginal = marginal_focus(0.98 * HALF_APERTURE)
    print(f"paraxial focus x = {paraxial:.4f}, marginal focus x = {marginal:.4f}, "
          f"brightest point ({peak[0]:.4f}, {peak[1]:.4f})")
    assert marginal < peak[0] < paraxial, (marginal, peak, paraxial)
    assert abs(peak[1]) <= WAVELENGTH

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (rays_ax, spot_ax) = plt.subplots(1, 2, figsize=(13, 4.6), layout="constrained",
                                           gridspec_kw={"width_ratios": [1.1, 1]})
    # Left: the lens and every stationary path from the source to the brightest point.
    tracer = eigenray.Tracer(scene([peak]))
    for name in ("front", "back"):
        pts = np.array(face(-1 if name == "front" else 1))
        rays_ax.plot(pts[:, 0], pts[:, 1], color="tab:blue", linewidth=2)
    paths, complete = tracer.stationary_paths([SOURCE_X, 0.0], peak)
    # Near the focus each pair of facets sends its own ray: a dozen of them, by height.
    paths.sort(key=lambda ray: ray.points[1][1])
    shown = paths[:: max(1, len(paths) // 12)]
    for ray in shown:
        p = np.asarray(ray.points)
        # The first leg comes from 1,000 units away: drawn from x = -4.
        t = (-4.0 - p[0, 0]) / (p[1, 0] - p[0, 0])
        p[0] = p[0] + t * (p[1] - p[0])
        rays_ax.plot(p[:, 0], p[:, 1], color="tab:orange", linewidth=0.6)
    rays_ax.axvline(paraxial, color="black", linestyle=":", linewidth=1,
                    label=f"paraxial focus (lensmaker), x = {paraxial:.2f}")
    rays_ax.axvline(marginal, color="tab:red", linestyle="--", linewidth=1,
                    label=f"marginal ray's focus, x = {marginal:.2f}")
    rays_ax.set_xlim(-4, 12.5)
    rays_ax.set_aspect("equal")
    rays_ax.set_xlabel("x (length units)")
    rays_ax.set_ylabel("y (length units)")
    rays_ax.set_title(f"Biconvex lens, n = {N_GLASS}, R = {RADIUS:g}, aperture "
                      f"{2 * HALF_APERTURE:g}\n{len(shown)} of the {len(paths)} rays from the "
                      f"source (x = {SOURCE_X:g}) to the brightest point", fontsize=10)
    rays_ax.legend(fontsize=8, loc="lower left")
    # Right: the focal spot.
    xs, ys = np.unique(receivers[:, 0]), np.unique(receivers[:, 1])
    grid = level.reshape(len(ys), len(xs))
    cmap = plt.get_cmap("inferno").with_extremes(bad="0.8")
    grid = np.where(np.isfinite(grid), grid, np.nan)
    image = spot_ax.pcolormesh(xs, ys, grid, cmap=cmap, vmin=-30, vmax=0, shading="nearest")
    bar = fig.colorbar(image, ax=spot_ax)
    bar.set_label("intensity relative to the peak (dB)")
    spot_ax.axvline(paraxial, color="tab:blue", linestyle=":", linewidth=1.2,
                    label="paraxial focus")
    spot_ax.axvline(marginal, color="cyan", linestyle="--", linewidth=1,
                    label="marginal ray's focus")
    spot_ax.plot(*peak, marker="+", color="lime", markersize=12, linestyle="none",
                 label=f"brightest point, x = {peak[0]:.2f}")
    spot_ax.set_xlabel("x (length units)")
    spot_ax.set_ylabel("y (length units)")
    spot_ax.set_title(f"Focal spot: every ray summed coherently, wavelength {WAVELENGTH:g} "
                      "(grey: no ray arrives)", fontsize=10)
    spot_ax.legend(fontsize=8, loc="lower left")
    fig.savefig(picture, dpi=110)
    print(f"wrote {picture}: {len(receivers)} receivers")


if __name__ == "__main__":
    main()
