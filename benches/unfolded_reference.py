"""Amplitudes of reflect-only paths in one medium against an independent 50-digit reference.

Each arrival (or ray) of two or more reflections whose legs are all in one medium is the
straight line from the source's image: `eigenray` gives its tube in closed form from the
unfolded length (`walk_reflections` in src/amplitude/ray.rs), where before it swept the
path's Hessian. This script recomputes such paths from the scene alone with mpmath at 50
digits, by the image method (the walls of the arrival's steps, each the segment its point
lies on; the image of the source in each in turn; the reflection points traced back from the
receiver), and from them:

- the length L = |image - receiver|, the spreading of the source model: 1/(4 pi L) for
  `point`; 1/(4 pi sqrt(L Y)) with Y = x_R / |t0x| (t0 the first leg's direction) for
  `axisymmetric`; 1/sqrt(8 pi k L), k = 2 pi f / c, for `line` (whose amplitude also takes
  e^(i pi/4));
- each bounce's cosine of incidence and its law's coefficient as the contract defines them
  (the scene contract: rigid 1, pressure-release -1, absorption sqrt(1 - a),
  coefficient r, `"media"` the fluid Rayleigh coefficient (Z2 cos1 - Z1 cos2) / (Z2 cos1 +
  Z1 cos2), cos2 = +i sqrt((c2/c1)^2 sin^2 - 1) beyond the critical angle, against the
  scene's other medium);
- the attenuation a L dB and the amplitude spreading x coefficients x 10^(-a L / 20).

It runs `eigenray solve SCENE` (one thread, default output) with each binary given and prints,
per scene and binary, the number of such paths and the largest relative error of the complex
amplitude, the spreading and the attenuation against the reference, and how many paths the
binaries give different bits for.

    python benches/unfolded_reference.py --bin new=target/release/eigenray \
        --bin old=/tmp/eigenray-against/a1457c0/release/eigenray SCENE.json ...

With `--max-error E` it exits 1 when a binary's largest error on a scene exceeds E.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import mpmath as mp

mp.mp.dps = 50


def load_scene(path):
    """The scene with every number an exact mpf of its decimal text."""
    with open(path) as f:
        return json.load(f, parse_float=mp.mpf, parse_int=mp.mpf)


def polyline(interface):
    points = [(mp.mpf(x), mp.mpf(y)) for x, y in interface["points"]]
    if interface.get("closed"):
        points.append(points[0])
    return points


def nearest_segment(points, p):
    """The index of the segment of `points` nearest to `p` (float, to pick the wall)."""
    best, best_d = None, None
    px, py = float(p[0]), float(p[1])
    for j in range(len(points) - 1):
        (ax, ay), (bx, by) = [(float(q[0]), float(q[1])) for q in points[j : j + 2]]
        ex, ey = bx - ax, by - ay
        s = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        s = min(1.0, max(0.0, s))
        d = (ax + s * ex - px) ** 2 + (ay + s * ey - py) ** 2
        if best_d is None or d < best_d:
            best, best_d = j, d
    return best


def mirror(p, a, b):
    """`p` mirrored in the line through `a` and `b`."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    n = mp.sqrt(ex * ex + ey * ey)
    tx, ty = ex / n, ey / n
    dx, dy = p[0] - a[0], p[1] - a[1]
    along = dx * tx + dy * ty
    return (a[0] + 2 * along * tx - dx, a[1] + 2 * along * ty - dy)


def meet(p, q, a, b):
    """Where the line through `p` and `q` meets the line through `a` and `b`."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    ex, ey = b[0] - a[0], b[1] - a[1]
    den = dx * ey - dy * ex
    s = ((a[0] - p[0]) * ey - (a[1] - p[1]) * ex) / den
    return (p[0] + s * dx, p[1] + s * dy)


def media_of(scene):
    out = {}
    for name, m in scene["media"].items():
        speed = m.get("speed")
        density = m.get("density", mp.mpf(1))
        attenuation = m.get("attenuation", mp.mpf(0))
        if isinstance(attenuation, dict):
            f = scene["amplitudes"]["frequency"]
            attenuation = attenuation["db_per_wavelength"] * f / speed
        out[name] = {"speed": speed, "density": density, "attenuation": attenuation}
    return out


def coefficient(law, cos1, medium, across):
    """A bounce's coefficient under `law` at the cosine of incidence `cos1`."""
    if law is None or law == "rigid":
        return mp.mpc(1)
    if law == "pressure-release":
        return mp.mpc(-1)
    if isinstance(law, dict) and "absorption" in law:
        return mp.mpc(mp.sqrt(1 - law["absorption"]))
    if isinstance(law, dict) and "coefficient" in law:
        return mp.mpc(law["coefficient"])
    if law == "media":
        c1, c2 = medium["speed"], across["speed"]
        z1, z2 = medium["density"] * c1, across["density"] * c2
        sin2 = 1 - cos1 * cos1
        q = (c2 / c1) ** 2 * sin2
        cos2 = mp.mpc(mp.sqrt(1 - q)) if q <= 1 else mp.mpc(0, mp.sqrt(q - 1))
        return (z2 * cos1 - z1 * cos2) / (z2 * cos1 + z1 * cos2)
    raise ValueError(f"law {law!r} not modelled here")


def reference(scene, steps, media, points):
    """The reference amplitude, spreading and attenuation (dB) of one path, or None where it
    is not a reflect-only path of two or more steps in one medium."""
    if len(steps) < 2 or any("reflect" not in s for s in steps) or len(set(media)) != 1:
        return None
    all_media = media_of(scene)
    medium = all_media[media[0]]
    others = [m for name, m in all_media.items() if name != media[0]]
    source = (mp.mpf(points[0][0]), mp.mpf(points[0][1]))
    # The scene's own source and receiver (exact decimals), matched to the output's floats.
    source = min(
        ((mp.mpf(x), mp.mpf(y)) for x, y in scene["sources"]),
        key=lambda s: abs(float(s[0]) - points[0][0]) + abs(float(s[1]) - points[0][1]),
    )
    receiver = min(
        ((mp.mpf(x), mp.mpf(y)) for x, y in receivers(scene)),
        key=lambda s: abs(float(s[0]) - points[-1][0]) + abs(float(s[1]) - points[-1][1]),
    )
    walls = []
    for j, step in enumerate(steps):
        interface = scene["interfaces"][step["reflect"]]
        line = polyline(interface)
        k = nearest_segment(line, points[j + 1])
        walls.append((line[k], line[k + 1], interface.get("reflection")))
    images = [source]
    for a, b, _ in walls:
        images.append(mirror(images[-1], a, b))
    length = mp.sqrt((images[-1][0] - receiver[0]) ** 2 + (images[-1][1] - receiver[1]) ** 2)
    # The reflection points, from the receiver back.
    bounce = [None] * len(walls)
    target = receiver
    for j in range(len(walls) - 1, -1, -1):
        a, b, _ = walls[j]
        target = meet(images[j + 1], target, a, b)
        bounce[j] = target
    path = [source] + bounce + [receiver]
    coef = mp.mpc(1)
    for j, (a, b, law) in enumerate(walls):
        p, q = path[j], path[j + 1]
        ux, uy = q[0] - p[0], q[1] - p[1]
        lu = mp.sqrt(ux * ux + uy * uy)
        ex, ey = b[0] - a[0], b[1] - a[1]
        le = mp.sqrt(ex * ex + ey * ey)
        cos1 = abs((ux * ey - uy * ex) / (lu * le))
        if law == "media" and len(others) != 1:
            raise ValueError("a 'media' law with more than one other medium")
        coef *= coefficient(law, cos1, medium, others[0] if others else None)
    settings = scene["amplitudes"]
    model = settings.get("source")
    if model == "point":
        spreading = 1 / (4 * mp.pi * length)
        phase = mp.mpc(1)
    elif model == "axisymmetric":
        t0x = (path[1][0] - path[0][0]) / mp.sqrt(
            (path[1][0] - path[0][0]) ** 2 + (path[1][1] - path[0][1]) ** 2
        )
        width = abs(receiver[0]) / abs(t0x)
        spreading = 1 / (4 * mp.pi * mp.sqrt(length * width))
        phase = mp.mpc(1)
    elif model == "line":
        k = 2 * mp.pi * settings["frequency"] / medium["speed"]
        spreading = 1 / mp.sqrt(8 * mp.pi * k * length)
        phase = mp.expjpi(mp.mpf(1) / 4)
    else:
        raise ValueError(f"source model {model!r}")
    attenuation_db = medium["attenuation"] * length
    amplitude = spreading * coef * phase * mp.power(10, -attenuation_db / 20)
    return amplitude, spreading, attenuation_db, coef


def receivers(scene):
    r = scene["receivers"]
    if isinstance(r, dict):
        raise ValueError("receiver grids are not read here")
    return r


def entries(scene, output):
    """(steps, media, points, amplitude, spreading, attenuation_db, coefficient) of each
    timed entry."""
    paths = scene.get("paths", [])
    for kind in ("rays", "arrivals"):
        for e in output.get(kind, []):
            if e.get("amplitude") is None or e.get("status") != "converged":
                continue
            if "steps" in e:
                steps = e["steps"]
            else:
                steps = [
                    {k: v for k, v in s.items() if k in ("reflect", "refract")}
                    for s in paths[e["path"]]["steps"]
                ]
            media = e.get("media")
            if media is None:
                continue
            yield (
                steps,
                media,
                e["points"],
                e["amplitude"],
                e["spreading"],
                e["attenuation_db"],
                e["coefficient"],
            )


def solve(binary, scene_path):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    run = subprocess.run(
        [binary, "solve", scene_path], capture_output=True, text=True, env=env, check=True
    )
    return json.loads(run.stdout)


def relative(x, ref):
    return float(abs(x - ref) / abs(ref)) if ref != 0 else float(abs(x))


def errors(scene, rows):
    """Each reflect-only path of `rows` (from [`entries`]) of two or more steps in one medium:
    its index and the relative errors of its amplitude, spreading, attenuation and
    coefficient against the reference."""
    out = []
    for i, row in enumerate(rows):
        ref = reference(scene, *row[:3])
        if ref is None:
            continue
        out.append(
            (
                i,
                relative(mp.mpc(*row[3]), ref[0]),
                relative(mp.mpf(row[4]), ref[1]),
                relative(mp.mpf(row[5]), ref[2]) if ref[2] != 0 else abs(row[5]),
                relative(mp.mpc(*row[6]), ref[3]),
            )
        )
    return out


def worst_errors(scene_path, binary):
    """The number of such paths `binary` gives for the scene at `scene_path` and the largest
    relative errors of their amplitude, spreading, attenuation and coefficient."""
    scene = load_scene(scene_path)
    found = errors(scene, list(entries(scene, solve(binary, scene_path))))
    return len(found), [max((e[k] for e in found), default=0.0) for k in range(1, 5)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--bin", action="append", required=True, help="NAME=PATH of eigenray")
    parser.add_argument("--max-error", type=float, default=None)
    args = parser.parse_args()
    bins = [b.split("=", 1) for b in args.bin]
    failed = False
    print(
        f"{'scene':<40} {'binary':<8} {'paths':>6} {'amplitude':>10} {'spreading':>10} "
        f"{'atten.':>10} {'coeff.':>10} {'differ':>6}"
    )
    for scene_path in args.scenes:
        scene = load_scene(scene_path)
        outputs = {name: list(entries(scene, solve(path, scene_path))) for name, path in bins}
        first = outputs[bins[0][0]]
        for name, _ in bins:
            rows = outputs[name]
            found = errors(scene, rows)
            worst = [max((e[k] for e in found), default=0.0) for k in range(1, 5)]
            differ = sum(rows[e[0]][3:6] != first[e[0]][3:6] for e in found)
            print(
                f"{scene_path:<40} {name:<8} {len(found):>6} {worst[0]:>10.2e} "
                f"{worst[1]:>10.2e} {worst[2]:>10.2e} {worst[3]:>10.2e} {differ:>6}"
            )
            if args.max_error is not None and max(worst[:3]) > args.max_error:
                failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
