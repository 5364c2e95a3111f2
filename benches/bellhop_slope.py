"""eigenray's rays through a sound-speed profile over a sloping bottom, against BELLHOP.

The scene (examples/scenes/profile_slope.json's): a five-knot summer profile (C-linear),
a pressure-release surface, a bottom sloping from 100 m at -100 m to 118 m at 2 km and
130 m at 5 km over a fluid half-space of 1700 m/s, density 1.8 (no shear, no loss), a
source at 30 m, receivers at 60 m depth 1.5, 3 and 4 km away, 200 Hz.

BELLHOP (Porter's Fortran; not in this repository: build the A-New-BellHope sources with
gfortran and pass the path of `bellhop.exe`) runs it as 'CVF' with an 'A*' bottom and a
piecewise-linear ('L') bathymetry file, run type 'A' (arrivals), 20,001 beams over +-80
degrees, STEP 1 m. eigenray solves one prescribed path per sequence of surface and bottom
reflections (`reflection_sequences`: 65 of 0 to 12 reflections), `"stationary": "all"`.

The arrivals are matched per receiver by their numbers of surface and bottom reflections
and their launch angles (BELLHOP's are positive downward, eigenray's in radians positive
upward); BELLHOP's phase is the conjugate of eigenray's, its delays single precision.
eigenray's loss is -20 log10 |4 pi A| (BELLHOP's amplitude is |p| with |p| = 1/R at 1 m).
Two eigenrays BELLHOP lists as one (`merge_as_bellhop`) are merged as it merges them.

What it prints: the matched arrivals (a Markdown table); for each matched loss more than
1 dB apart, the geometric loss of BELLHOP's own ray fan at that launch angle
(`ray_fan_loss`); per receiver the counts, the worst differences and the arrivals only one
lists, with, for each arrival only BELLHOP lists of at most 12 reflections, the depths at
which BELLHOP's own rays of its sequence launched within 0.01 degrees cross the receiver's
range (`fan_depths`). BELLHOP's files are left in a temporary directory.

How to run:
  cargo build --profile test-opt --bin eigenray
  python3 benches/bellhop_slope.py /path/to/bellhop.exe [path/to/eigenray] [--receiver-depth M]
"""

import json
import math
import os
import subprocess
import sys
import tempfile

PROFILE = [[0, 1500], [-20, 1497], [-50, 1490], [-80, 1488], [-150, 1489]]
BOTTOM = [[-100, -100], [2000, -118], [5000, -130]]
SOURCE_DEPTH = 30.0
RECEIVER_DEPTH = 60.0
RANGES = [1500.0, 3000.0, 4000.0]
FREQUENCY = 200.0
MAX_REFLECTIONS = 12  # eigenray's "stationary": "all" takes at most 12 steps
MAX_BOTTOM_RUN_LENGTH = 6
BEAMS = 20001
MAX_ANGLE = 80.0
STEP = 1.0
ANGLE_MATCH = 0.5  # degrees
PHASE_TOL = 0.05  # BELLHOP's ArrMod.f90: arrivals within this (rad, and omega * delay) merge


def bellhop_files(root):
    knots = "\n".join(f"{-y:.1f} {c:.1f} /" for y, c in PROFILE)
    ranges = " ".join(f"{r / 1000:.3f}" for r in RANGES)
    env = f"""'eigenray profile over a slope'
{FREQUENCY:.1f}
1
'CVF'
0 0.0 {-PROFILE[-1][0]:.1f}
{knots}
'A*' 0.0
{-PROFILE[-1][0]:.1f} 1700.0 0.0 1.8 0.0 0.0 /
1
{SOURCE_DEPTH:.1f} /
1
{RECEIVER_DEPTH:.1f} /
{len(RANGES)}
{ranges} /
'A'
{BEAMS}
{-MAX_ANGLE:.1f} {MAX_ANGLE:.1f} /
{STEP:.1f} {-PROFILE[-1][0] + 5:.1f} {BOTTOM[-1][0] / 1000 + 0.05:.2f}
"""
    bty = "'L'\n{}\n{}\n".format(
        len(BOTTOM), "\n".join(f"{x / 1000:.3f} {-y:.1f}" for x, y in BOTTOM)
    )
    with open(root + ".env", "w") as f:
        f.write(env)
    with open(root + ".bty", "w") as f:
        f.write(bty)


def speed(depth):
    for (y0, c0), (y1, c1) in zip(PROFILE, PROFILE[1:]):
        if depth <= -y1:
            return c0 + (c1 - c0) * (depth + y0) / (y0 - y1)
    return PROFILE[-1][1]


def bottom_depth(x):
    for (x0, y0), (x1, y1) in zip(BOTTOM, BOTTOM[1:]):
        if x <= x1:
            return -(y0 + (y1 - y0) * (x - x0) / (x1 - x0))
    return -BOTTOM[-1][1]


def bellhop_rays(bellhop, root, first, last, count):
    """BELLHOP's own rays (run type 'R'), `count` launch angles from `first` to `last`
    (degrees, positive down): a list of (launch, [(range, depth), ...])."""
    with open(root + ".env") as f:
        lines = f.read().split("\n")
    i = lines.index("'A'")
    lines[i : i + 3] = ["'R'", str(count), f"{first:.6f} {last:.6f} /"]
    fan = root + "_fan"
    with open(fan + ".env", "w") as f:
        f.write("\n".join(lines))
    with open(root + ".bty") as f, open(fan + ".bty", "w") as g:
        g.write(f.read())
    subprocess.run(
        [bellhop, os.path.basename(fan)], cwd=os.path.dirname(root), capture_output=True, check=True
    )
    with open(fan + ".ray") as f:
        rows = f.read().split("\n")
    k, rays = 7, []
    while k < len(rows) and rows[k].strip():
        n = int(rows[k + 1].split()[0])
        points = [tuple(map(float, row.split())) for row in rows[k + 2 : k + 2 + n]]
        rays.append((float(rows[k]), points))
        k += 2 + n
    return rays


def crossing(points, range_m):
    """(depth, angle below the horizontal, reflections "s"/"b" before) where a ray's
    polyline crosses range_m, or None."""
    walls, heading = "", 0
    for (r0, z0), (r1, z1) in zip(points, points[1:]):
        if r0 <= range_m < r1:
            depth = z0 + (z1 - z0) * (range_m - r0) / (r1 - r0)
            return depth, math.atan2(z1 - z0, r1 - r0), walls
        step = (z1 > z0) - (z1 < z0)
        if step and heading and step != heading:
            if z0 < 1e-3:
                walls += "s"
            elif abs(z0 - bottom_depth(r0)) < 0.05:
                walls += "b"
        heading = step or heading
    return None


def ray_fan_loss(bellhop, root, range_m, launch, half_step=0.0005):
    """The geometric loss of the ray BELLHOP traces from `launch` (degrees, positive down),
    from its own ray file (three rays `half_step` degrees apart): |p|^2 =
    c_r cos(theta_s) / (c_s r |dz/dtheta_s| cos(theta_r)), the reflection coefficients left
    out (1 in magnitude for these rays: the surface's and the bottom's below its critical
    angle). Independent of BELLHOP's beams and of eigenray's amplitudes."""
    rays = bellhop_rays(bellhop, root, launch - half_step, launch + half_step, 3)
    (z_minus, _, _), (_, arrival, _), (z_plus, _, _) = (crossing(p, range_m) for _, p in rays)
    dz_dtheta = (z_plus - z_minus) / math.radians(2 * half_step)
    pressure_sq = (
        speed(RECEIVER_DEPTH)
        * math.cos(math.radians(launch))
        / (speed(SOURCE_DEPTH) * range_m * abs(dz_dtheta) * math.cos(arrival))
    )
    return -10 * math.log10(pressure_sq)


def fan_roots(bellhop, root, range_m, launch, walls, half_width=0.1, count=201):
    """The launch angles (degrees, positive down) within half_width of `launch` at which
    BELLHOP's own rays reflecting `walls` pass the receiver: sign changes of the depth miss
    between neighbouring rays (0.001 degrees apart), jumps of more than 1 m (a reflection
    crossing a bottom vertex) left out. Where BELLHOP's beams merge two eigenrays, these
    show both."""
    rays = bellhop_rays(bellhop, root, launch - half_width, launch + half_width, count)
    roots, last = [], None
    for angle, points in rays:
        hit = crossing(points, range_m)
        if hit is None or hit[2] != walls:
            last = None
            continue
        miss = hit[0] - RECEIVER_DEPTH
        if last is not None and (last[1] > 0) != (miss > 0) and abs(miss - last[1]) < 1:
            roots.append(last[0] + (angle - last[0]) * last[1] / (last[1] - miss))
        last = (angle, miss)
    return roots


def fan_depths(bellhop, root, range_m, launch, walls, half_width=0.01, count=201):
    """The depths at range_m of BELLHOP's rays launched within half_width degrees of
    `launch` whose reflections before it are `walls` (for an arrival only BELLHOP lists:
    does a ray of its sequence pass the receiver at all?)."""
    rays = bellhop_rays(bellhop, root, launch - half_width, launch + half_width, count)
    hits = [crossing(p, range_m) for _, p in rays]
    return [h[0] for h in hits if h is not None and h[2] == walls]


def read_arrivals(path):
    """BELLHOP's ASCII .arr: per receiver (depth-major, then range) a list of
    (amplitude, phase deg, delay s, launch deg, top bounces, bottom bounces)."""
    with open(path) as f:
        lines = [line.split() for line in f if line.strip()]
    i = 6  # '2D', freq, sources, receiver depths, ranges, max count
    out = []
    for _ in RANGES:
        count = int(lines[i][0])
        i += 1
        arrivals = []
        for row in lines[i : i + count]:
            a, phase, delay, _, launch, _, top, bottom = (float(v) for v in row)
            arrivals.append(
                dict(
                    amp=a, phase=phase % 360, delay=delay, launch=launch, s=int(top), b=int(bottom)
                )
            )
        i += count
        out.append(arrivals)
    return out


def reflection_sequences():
    """Every sequence of surface and bottom reflections eigenray is asked for: no two
    surface reflections in a row (a ray leaving the surface has a phase speed of at least
    1500 m/s, faster than the water anywhere below, so it never turns back up before the
    bottom), two or more bottom reflections in a row allowed (a ray leaving the bottom
    flatter than about 7 degrees turns below the surface) up to MAX_BOTTOM_RUN_LENGTH
    reflections in all, and the alternating sequences up to MAX_REFLECTIONS."""
    seqs = {""}
    frontier = [""]
    for n in range(1, MAX_REFLECTIONS + 1):
        grown = []
        for seq in frontier:
            for wall in "sb":
                if seq.endswith("s") and wall == "s":
                    continue
                candidate = seq + wall
                if n > MAX_BOTTOM_RUN_LENGTH and "bb" in candidate:
                    continue
                grown.append(candidate)
        seqs.update(grown)
        frontier = grown
    return sorted(seqs, key=lambda q: (len(q), q))


def eigenray_scene():
    walls = {"s": "surface", "b": "bottom"}
    paths = [
        {"name": seq or "direct", "steps": [{"reflect": walls[w]} for w in seq]}
        for seq in reflection_sequences()
    ]
    return {
        "media": {
            "water": {"profile": PROFILE, "density": 1, "at": [0, -50]},
            "sand": {"speed": 1700, "density": 1.8, "at": [0, -200]},
            "air": {"speed": 340, "density": 0.0012, "at": [0, 50]},
        },
        "domain": [[-100, -300], [5000, 100]],
        "interfaces": {
            "surface": {"points": [[-100, 0], [5000, 0]], "reflection": "pressure-release"},
            "bottom": {"points": BOTTOM, "reflection": "media"},
        },
        "sources": [[0, -SOURCE_DEPTH]],
        "receivers": [[r, -RECEIVER_DEPTH] for r in RANGES],
        "paths": paths,
        "solver": {"stationary": "all"},
        "amplitudes": {"source": "point", "frequency": FREQUENCY},
    }


def eigenray_arrivals(binary, root):
    with open(root + ".json", "w") as f:
        json.dump(eigenray_scene(), f)
    run = subprocess.run([binary, "solve", root + ".json"], capture_output=True, check=True)
    out = [[] for _ in RANGES]
    for ray in json.loads(run.stdout)["rays"]:
        if ray["status"] != "converged":
            continue
        re, im = ray["amplitude"]
        name = ray["path_name"]
        out[ray["receiver"]].append(
            dict(
                time=ray["time"],
                launch=-math.degrees(ray["launch_angle"]),
                s=name.count("s"),
                b=name.count("b"),
                name="-" if name == "direct" else name,
                tl=-20 * math.log10(4 * math.pi * math.hypot(re, im)),
                phase=(-math.degrees(math.atan2(im, re))) % 360,
            )
        )
    return out


def merge_as_bellhop(arrivals):
    """BELLHOP adds each beam's contribution to the last arrival it listed when their
    delays differ by less than PHASE_TOL / omega and their phases by less than PHASE_TOL
    (rad): two eigenrays of one sequence that close (a fold's pair) are one arrival there,
    its amplitude their sum, its delay and angle their amplitude-weighted means. The same
    merge of eigenray's list, so that the pair compares with BELLHOP's one arrival."""
    omega = 2 * math.pi * FREQUENCY
    out = []
    for e in sorted(arrivals, key=lambda e: (e["name"], e["launch"])):
        last = out[-1] if out else None
        if (
            last is not None
            and last["name"] == e["name"]
            and omega * abs(last["time"] - e["time"]) < PHASE_TOL
            and math.radians(abs(phase_difference(last["phase"], e["phase"]))) < PHASE_TOL
        ):
            a1, a2 = 10 ** (-last["tl"] / 20), 10 ** (-e["tl"] / 20)
            w1, w2 = a1 / (a1 + a2), a2 / (a1 + a2)
            last["time"] = w1 * last["time"] + w2 * e["time"]
            last["launch"] = w1 * last["launch"] + w2 * e["launch"]
            last["tl"] = -20 * math.log10(a1 + a2)
            last["merged"] += 1
        else:
            out.append(dict(e, merged=1))
    return out


def phase_difference(a, b):
    return (a - b + 180) % 360 - 180


def main():
    global RECEIVER_DEPTH
    args = sys.argv[1:]
    if "--receiver-depth" in args:
        i = args.index("--receiver-depth")
        RECEIVER_DEPTH = float(args[i + 1])
        del args[i : i + 2]
    bellhop = os.path.abspath(args[0])
    here = os.path.dirname(os.path.abspath(__file__))
    default = os.path.join(here, "..", "target", "test-opt", "eigenray")
    binary = args[1] if len(args) > 1 else default
    work = tempfile.mkdtemp(prefix="bellhop_slope_")
    root = os.path.join(work, "slope")
    bellhop_files(root)
    subprocess.run([bellhop, "slope"], cwd=work, capture_output=True, check=True)
    bh_all = read_arrivals(root + ".arr")
    er_raw = eigenray_arrivals(binary, root)
    er_all = [merge_as_bellhop(er) for er in er_raw]
    print(
        "| range | eigenray time (s) | BELLHOP delay − eigenray (µs) "
        "| launch eigenray / BELLHOP | reflections | eigenray TL (dB) "
        "| BELLHOP − eigenray (dB) | phase eigenray / BELLHOP (°) |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    summary = []
    for r, bh, er in zip(RANGES, bh_all, er_all):
        used = set()
        rows, only_er = [], []
        for e in sorted(er, key=lambda e: e["time"]):
            best = None
            for j, a in enumerate(bh):
                if j in used or (a["s"], a["b"]) != (e["s"], e["b"]):
                    continue
                d = abs(a["launch"] - e["launch"])
                if d < ANGLE_MATCH and (best is None or d < best[0]):
                    best = (d, j)
            if best is None:
                only_er.append(e)
                continue
            used.add(best[1])
            a = bh[best[1]]
            dtl = -20 * math.log10(a["amp"]) - e["tl"]
            rows.append((e, a, dtl))
            merged = f" ({e['merged']} merged)" if e["merged"] > 1 else ""
            print(
                f"| {r / 1000:g} km | {e['time']:.9f} | {1e6 * (a['delay'] - e['time']):+.1f} | "
                f"{e['launch']:+.3f}° / {a['launch']:+.3f}° | {e['name']}{merged} | "
                f"{e['tl']:.2f} | "
                f"{dtl:+.2f} | {e['phase']:.2f} / {a['phase']:.2f} |"
            )
        only_bh = [a for j, a in enumerate(bh) if j not in used]
        summary.append((r, len(er), len(bh), rows, only_er, only_bh))
    for r, _, _, rows, _, _ in summary:
        for e, a, dtl in rows:
            if abs(dtl) > 1:
                fan = ray_fan_loss(bellhop, root, r, e["launch"])
                print(
                    f"{r / 1000:g} km {e['name']} {e['launch']:+.3f}°: eigenray TL {e['tl']:.2f}, "
                    f"BELLHOP's beams {e['tl'] + dtl:.2f}, BELLHOP's ray fan {fan:.2f} dB"
                )
                walls = "" if e["name"] == "-" else e["name"]
                roots = fan_roots(bellhop, root, r, a["launch"], walls, half_width=0.2, count=401)
                listed = [x["launch"] for x in er_raw[RANGES.index(r)] if x["name"] == e["name"]]
                missed = [x for x in roots if min(abs(x - y) for y in listed) > 0.002]
                print(
                    f"  BELLHOP's {walls} rays within 0.2° pass the receiver at "
                    + (", ".join(f"{x:+.4f}°" for x in roots) or "none (over 1 m per 0.001°)")
                    + (f"; {len(missed)} of them eigenray does not list" if missed else "")
                )
    print()
    for r, n_er, n_bh, rows, only_er, only_bh in summary:
        worst_t = max((abs(a["delay"] - e["time"]) for e, a, _ in rows), default=0)
        worst_db = max((abs(d) for _, _, d in rows), default=0)
        worst_ph = max(
            (abs(phase_difference(e["phase"], a["phase"])) for e, a, _ in rows), default=0
        )
        print(
            f"{r / 1000:g} km: eigenray {n_er}, BELLHOP {n_bh}, matched {len(rows)}; worst "
            f"{1e6 * worst_t:.1f} µs, {worst_db:.2f} dB, {worst_ph:.2f}°"
        )
        for e in only_er:
            print(
                f"  eigenray only: {e['name']} {e['launch']:+.3f}° t {e['time']:.6f} "
                f"TL {e['tl']:.1f}"
            )
        beyond = [a for a in only_bh if a["s"] + a["b"] > MAX_REFLECTIONS]
        if beyond:
            print(
                f"  BELLHOP only, more than {MAX_REFLECTIONS} reflections: {len(beyond)} "
                f"(launched {min(abs(a['launch']) for a in beyond):.1f}° or steeper, TL "
                f"{min(-20 * math.log10(a['amp']) for a in beyond):.1f} dB or more)"
            )
        for a in only_bh:
            if a in beyond:
                continue
            print(
                f"  BELLHOP only: s{a['s']} b{a['b']} {a['launch']:+.3f}° t {a['delay']:.6f} "
                f"TL {-20 * math.log10(a['amp']):.1f} phase {a['phase']:.1f}"
            )
            counts = (a["s"], a["b"])
            sequences = [
                q for q in reflection_sequences() if (q.count("s"), q.count("b")) == counts
            ]
            for walls in sequences:
                depths = fan_depths(bellhop, root, r, a["launch"], walls)
                if depths:
                    print(
                        f"    BELLHOP's {len(depths)} {walls} rays within 0.01° of it cross "
                        f"{r / 1000:g} km at {min(depths):.2f} to {max(depths):.2f} m depth"
                    )


if __name__ == "__main__":
    main()
