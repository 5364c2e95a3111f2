"""Every refracted eigenray of the Munk profile (issue 40's check), as a `profile` medium.

c(z) = 1500 [1 + 0.00737 (eta - 1 + exp(-eta))], eta = 2 (z - 1300) / 1300, z = -y the
depth, 0-5000 m, sampled at N knots (30, then 60 and 120); a source at 1000 m depth,
receivers at 800 m depth, 10, 30 and 60 km away; `"stationary": "all"` on a path without
steps, amplitudes of a point source. Above the top knot and below the bottom one the
speed stays that of the end knot, so only rays that turn inside the water column come
back: the refracted arrivals (no surface or bottom reflections: a scene with a profile
takes no steps yet).

What it prints and checks:
- the arrivals at each range (time, launch angle, turns, caustics, amplitude as
  -20 log10 |4 pi A| dB, BELLHOP's normalisation of |p| = 1/R);
- an independent check of every ray at 60 km: the ray ODE (dx/ds = cos t, dy/ds = sin t,
  dt/ds = -c'(y) cos t / c, dT/ds = 1/c) integrated by scipy's DOP853 from eigenray's launch
  angle through the same piecewise-linear profile, its miss at the receiver's range, its
  time and its number of turning points;
- the times at 30, 60 and 120 knots: their changes against the profile's own change
  (the largest |c_N - c| of the N-knot profile: second order in the knot spacing, as the
  times' changes are);
- docs/munk_eigenrays.png: the eigenrays at 60 km, each drawn from the ODE's dense output
  (arcs, not chords), coloured by time.

The ocean (issue 40's waveguide): the same profile between a pressure-release surface at
0 m and a flat bottom at 5000 m over a fluid half-space (1600 m/s, density 1, BELLHOP's
MunkB bottom without its shear and loss: a `"media"` reflection), `"search"` with
`max_steps` 12 at 60 km: every ray with up to 12 surface and bottom reflections and any
turning points. Checked against
- the ray ODE with reflections (DOP853 again, each wall a terminal event where the ray's
  angle is mirrored), shot from each listed launch angle: its miss, time, turning points
  and sequence of reflections;
- an independent RK4 fan with mirror reflections at the walls: the sign changes of the
  depth miss at 60 km between neighbouring rays with the same reflection sequence, per
  sequence, against the arrivals eigenray lists;
- docs/munk_eigenrays.png: every eigenray at 60 km, refracted and reflected, drawn from
  the ODE.

How to run:
  cargo build --profile test-opt
  python3 benches/munk_profile.py [path/to/eigenray]
"""

import json
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parents[1]
BIN = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target" / "test-opt" / "eigenray")
RANGES = [10000.0, 30000.0, 60000.0]
SOURCE_DEPTH, RECEIVER_DEPTH = 1000.0, 800.0
DEPTH, MAX_STEPS, GUIDE_RANGE = 5000.0, 12, 60000.0


def munk(z):
    eta = 2.0 * (z - 1300.0) / 1300.0
    return 1500.0 * (1.0 + 0.00737 * (eta - 1.0 + np.exp(-eta)))


def knots(n):
    z = np.linspace(0.0, 5000.0, n)
    return [[-float(zi), float(munk(zi))] for zi in z]


def scene(n):
    return {
        "media": {"ocean": {"profile": knots(n)}},
        "sources": [[0.0, -SOURCE_DEPTH]],
        "receivers": [[r, -RECEIVER_DEPTH] for r in RANGES],
        "paths": [{"steps": [], "media": ["ocean"]}],
        "solver": {"stationary": "all"},
        "amplitudes": {"source": "point"},
    }


def solve(n):
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "munk.json"
        path.write_text(json.dumps(scene(n)))
        t0 = time.perf_counter()
        out = subprocess.run([BIN, "solve", str(path)], check=True, capture_output=True)
        wall = time.perf_counter() - t0
    return json.loads(out.stdout)["rays"], wall


def guide_scene(n):
    """The waveguide: the profile between a pressure-release surface and a `"media"`
    bottom over a fluid half-space, searched up to MAX_STEPS reflections at 60 km."""
    return {
        "media": {
            "ocean": {"profile": knots(n), "at": [0.0, -2000.0]},
            "halfspace": {"speed": 1600.0, "density": 1.0, "at": [0.0, -5500.0]},
            "air": {"speed": 340.0, "density": 0.0012, "at": [0.0, 500.0]},
        },
        "domain": [[-1000.0, -6000.0], [100000.0, 1000.0]],
        "interfaces": {
            "surface": {"points": [[-1000.0, 0.0], [100000.0, 0.0]], "reflection": "pressure-release"},
            "bottom": {"points": [[-1000.0, -DEPTH], [100000.0, -DEPTH]], "reflection": "media"},
        },
        "sources": [[0.0, -SOURCE_DEPTH]],
        "receivers": [[GUIDE_RANGE, -RECEIVER_DEPTH]],
        "amplitudes": {"source": "point"},
        "search": {"max_steps": MAX_STEPS},
    }


def solve_guide(n):
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "guide.json"
        arrivals = pathlib.Path(d) / "arrivals.json"
        path.write_text(json.dumps(guide_scene(n)))
        t0 = time.perf_counter()
        subprocess.run(
            [BIN, "solve", str(path), "--arrivals", str(arrivals)], check=True, capture_output=True
        )
        wall = time.perf_counter() - t0
        return json.loads(arrivals.read_text())["arrivals"], wall


def sequence(a):
    """An arrival's reflections as a string: s (surface), b (bottom)."""
    return "".join(s["reflect"][0] for s in a["steps"])


def shoot_guide(n, angle, x_end):
    """The ray ODE between the walls from the source at `angle` to the range x_end, each
    wall a terminal event where the angle is mirrored: (miss in y, time, turns, reflection
    sequence, [dense pieces])."""
    speed, slope = interpolated(n)

    def rhs(_s, u):
        x, y, t, _ = u
        c = speed(y)
        return [np.cos(t), np.sin(t), -slope(y) * np.cos(t) / c, 1.0 / c]

    def reach(_s, u):
        return u[0] - x_end

    def top(_s, u):
        return u[1]

    def bottom(_s, u):
        return u[1] + DEPTH

    for e in (reach, top, bottom):
        e.terminal = True
    top.direction, bottom.direction = 1.0, -1.0
    u = [0.0, -SOURCE_DEPTH, angle, 0.0]
    s0, pieces, seq, turns = 0.0, [], "", 0
    while True:
        sol = solve_ivp(
            rhs,
            [s0, s0 + 3.0 * x_end],
            u,
            method="DOP853",
            rtol=1e-12,
            atol=1e-10,
            max_step=20.0,
            events=(reach, top, bottom),
            dense_output=True,
        )
        pieces.append(sol)
        turns += int(np.sum(np.diff(np.sign(sol.y[2])) != 0))
        if len(sol.t_events[0]):
            end = sol.y_events[0][0]
            return end[1] + RECEIVER_DEPTH, end[3], turns, seq, pieces
        wall = 1 if len(sol.t_events[1]) else 2
        seq += "s" if wall == 1 else "b"
        u = list(sol.y_events[wall][0])
        u[1] = 0.0 if wall == 1 else -DEPTH
        u[2] = -u[2]
        s0 = sol.t_events[wall][0]


def fan_guide(n, count=12000, ds=5.0, max_angle=np.radians(50.0)):
    """An independent count of the eigenrays between the walls at GUIDE_RANGE: a fan of
    `count` launch angles, RK4 in arc length with step `ds`, mirrored at each wall (the
    crossing found by linear interpolation within the step), the depth at the range
    interpolated; each sign change of y - y_receiver between neighbouring rays with the
    same sequence of reflections is one eigenray of that sequence; sign changes of one
    sequence within 0.05 degrees of each other count once (at steep angles, after ten
    reflections, the fan's own error at the mirrored steps makes the miss flicker about 0
    over a few neighbouring rays: three changes 0.02 degrees apart where the ODE shot from
    eigenray's angle lands within centimetres). Returns the merged counts, the raw counts
    and the angles of the changes."""
    speed, slope = interpolated(n)
    angles = np.linspace(-max_angle, max_angle, count)
    u = np.stack([np.zeros(count), np.full(count, -SOURCE_DEPTH), angles])
    # Reflections alternate between the walls: a ray's sequence is its first wall and count.
    first = np.zeros(count, dtype=int)  # 0 none yet, 1 surface, 2 bottom
    nref = np.zeros(count, dtype=int)
    alive = np.ones(count, bool)
    at = np.full(count, np.nan)

    def f(u):
        c = speed(u[1])
        return np.stack([np.cos(u[2]), np.sin(u[2]), -slope(u[1]) * np.cos(u[2]) / c])

    while np.any(alive):
        k1 = f(u)
        k2 = f(u + 0.5 * ds * k1)
        k3 = f(u + 0.5 * ds * k2)
        k4 = f(u + ds * k3)
        v = u + ds / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        for wall, code in ((0.0, 1), (-DEPTH, 2)):
            crossed = alive & ((v[1] > wall) if code == 1 else (v[1] < wall))
            first[crossed & (nref == 0)] = code
            nref[crossed] += 1
            v[1][crossed] = 2.0 * wall - v[1][crossed]
            v[2][crossed] = -v[2][crossed]
        hit = alive & (u[0] < GUIDE_RANGE) & (v[0] >= GUIDE_RANGE)
        w = (GUIDE_RANGE - u[0][hit]) / (v[0][hit] - u[0][hit])
        at[hit] = u[1][hit] + w * (v[1][hit] - u[1][hit])
        alive &= ~hit
        u = v
    d = at + RECEIVER_DEPTH
    raw, where = {}, {}
    for i in range(count - 1):
        same = first[i] == first[i + 1] and nref[i] == nref[i + 1]
        if same and nref[i] <= MAX_STEPS and np.sign(d[i]) != np.sign(d[i + 1]):
            seq = "".join("sb"[(first[i] - 1 + k) % 2] for k in range(nref[i]))
            raw[seq] = raw.get(seq, 0) + 1
            where.setdefault(seq, []).append(np.degrees(angles[i]))
    counts = {
        seq: 1 + int(np.sum(np.diff(sorted(a)) > 0.05)) for seq, a in where.items()
    }
    return counts, raw, where


def interpolated(n):
    k = np.array(knots(n))
    y, c = k[::-1, 0], k[::-1, 1]  # increasing y

    def speed(yy):
        return np.interp(yy, y, c)

    def slope(yy):
        i = np.clip(np.searchsorted(y, yy, side="right") - 1, 0, len(y) - 2)
        inside = (yy > y[0]) & (yy < y[-1])
        return np.where(inside, (c[i + 1] - c[i]) / (y[i + 1] - y[i]), 0.0)

    return speed, slope


def shoot(n, angle, x_end):
    """The ray ODE from the source at `angle`, to the range x_end: (miss in y, time, turns,
    dense curve)."""
    speed, slope = interpolated(n)

    def rhs(_s, u):
        x, y, t, _ = u
        c = speed(y)
        return [np.cos(t), np.sin(t), -slope(y) * np.cos(t) / c, 1.0 / c]

    def reach(_s, u):
        return u[0] - x_end

    reach.terminal = True
    sol = solve_ivp(
        rhs,
        [0.0, 3.0 * x_end],
        [0.0, -SOURCE_DEPTH, angle, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-10,
        max_step=20.0,
        events=reach,
        dense_output=True,
    )
    end = sol.y_events[0][0]
    turns = int(np.sum(np.diff(np.sign(sol.y[2])) != 0))
    return end[1] + RECEIVER_DEPTH, end[3], turns, sol


def fan(n, count=4000, ds=5.0):
    """An independent count of the refracted eigenrays at each range: a fan of `count`
    launch angles (every ray that stays in the water column), RK4 in arc length with step
    `ds` through the N-knot profile, y at each range interpolated; each sign change of
    y - y_receiver between neighbouring rays of the fan is one eigenray."""
    speed, slope = interpolated(n)
    theta_max = np.arccos(speed(-SOURCE_DEPTH) / knots(n)[0][1])
    angles = np.linspace(-theta_max, theta_max, count + 2)[1:-1]
    u = np.stack([np.zeros(count), np.full(count, -SOURCE_DEPTH), angles])
    alive = np.ones(count, bool)
    at = {r: np.full(count, np.nan) for r in RANGES}

    def f(u):
        c = speed(u[1])
        return np.stack([np.cos(u[2]), np.sin(u[2]), -slope(u[1]) * np.cos(u[2]) / c])

    while np.any(alive & (u[0] < RANGES[-1])):
        k1 = f(u)
        k2 = f(u + 0.5 * ds * k1)
        k3 = f(u + 0.5 * ds * k2)
        k4 = f(u + ds * k3)
        v = u + ds / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        for r in RANGES:
            hit = alive & (u[0] < r) & (v[0] >= r)
            w = (r - u[0][hit]) / (v[0][hit] - u[0][hit])
            at[r][hit] = u[1][hit] + w * (v[1][hit] - u[1][hit])
        alive &= (v[1] < 0.0) & (v[1] > -5000.0)
        u = v
    counts = {}
    for r in RANGES:
        d = at[r] + RECEIVER_DEPTH
        ok = np.isfinite(d[:-1]) & np.isfinite(d[1:])
        counts[r] = int(np.sum(ok & (np.sign(d[:-1]) != np.sign(d[1:]))))
    return counts


def main():
    results = {}
    for n in (30, 60, 120):
        rays, wall = solve(n)
        results[n] = [a for a in rays if a.get("time") is not None]
        print(f"{n} knots: {len(rays)} arrivals over {len(RANGES)} receivers, {wall:.2f} s")
    print()
    for i, r in enumerate(RANGES):
        arr = [a for a in results[30] if a["receiver"] == i]
        print(f"30 knots, range {r / 1000:.0f} km: {len(arr)} arrivals")
        print("  time (s)        launch (deg)  turns caustics  TL (dB)")
        for a in arr:
            amp = complex(*a["amplitude"]) if a.get("amplitude") else float("nan")
            tl = -20.0 * np.log10(4.0 * np.pi * abs(amp))
            print(
                f"  {a['time']:.9f}  {np.degrees(a['launch_angle']):+9.4f}  "
                f"{int(a['turns']):5d} {int(a['caustics']):8d}  {tl:7.2f}"
            )
    print()
    # The ODE check at 60 km.
    arr60 = [a for a in results[30] if a["receiver"] == 2]
    worst_miss, worst_dt = 0.0, 0.0
    curves = []
    for a in arr60:
        miss, t, turns, sol = shoot(30, a["launch_angle"], RANGES[2])
        worst_miss = max(worst_miss, abs(miss))
        worst_dt = max(worst_dt, abs(t - a["time"]))
        assert turns == int(a["turns"]), (turns, a)
        curves.append((a, sol))
    print(
        f"ODE check at 60 km ({len(arr60)} rays): worst miss {worst_miss:.2e} m, "
        f"worst time difference {worst_dt:.2e} s, turns all equal"
    )
    t0 = time.perf_counter()
    counts = fan(30)
    for i, r in enumerate(RANGES):
        listed = sum(1 for a in results[30] if a["receiver"] == i)
        print(f"fan of 4000 RK4 rays, {r / 1000:.0f} km: {counts[r]} eigenrays; eigenray lists {listed}")
        assert counts[r] == listed
    print(f"(the fan took {time.perf_counter() - t0:.1f} s)")
    # Knot refinement: the same arrival (same turns, same launch side, same order) at N.
    print()
    z = np.linspace(0.0, 5000.0, 200001)
    for n in (30, 60, 120):
        speed, _ = interpolated(n)
        print(f"{n:4d} knots: max |c_N - c| = {np.max(np.abs(speed(-z) - munk(z))):.4f} m/s")

    def key(a):
        return (a["receiver"], int(a["turns"]), a["launch_angle"] > 0)

    for n, m in ((30, 60), (60, 120)):
        changes = []
        for a in results[n]:
            same = [b for b in results[m] if key(b) == key(a)]
            if same:
                b = min(same, key=lambda b: abs(b["launch_angle"] - a["launch_angle"]))
                changes.append(abs(b["time"] - a["time"]))
        print(
            f"times {n} -> {m} knots: {len(changes)} arrivals matched, "
            f"largest change {max(changes) * 1e3:.3f} ms, median {np.median(changes) * 1e3:.3f} ms"
        )
    # The waveguide: reflected arrivals too.
    print()
    guide, wall = solve_guide(30)
    print(
        f"waveguide (surface, bottom at {DEPTH:.0f} m), 30 knots, {GUIDE_RANGE / 1000:.0f} km, "
        f"up to {MAX_STEPS} reflections: {len(guide)} arrivals, {wall:.2f} s"
    )
    print("  time (s)        launch (deg)  turns caustics  TL (dB)  reflections")
    for a in guide:
        amp = complex(*a["amplitude"]) if a.get("amplitude") else float("nan")
        tl = -20.0 * np.log10(4.0 * np.pi * abs(amp))
        print(
            f"  {a['time']:.9f}  {np.degrees(a['launch_angle']):+9.4f}  "
            f"{int(a['turns']):5d} {int(a['caustics']):8d}  {tl:7.2f}  {sequence(a) or '-'}"
        )
    worst_miss, worst_dt = 0.0, 0.0
    guide_curves = []
    for a in guide:
        miss, t, turns, seq, pieces = shoot_guide(30, a["launch_angle"], GUIDE_RANGE)
        worst_miss = max(worst_miss, abs(miss))
        worst_dt = max(worst_dt, abs(t - a["time"]))
        assert turns == int(a["turns"]) and seq == sequence(a), (turns, seq, a)
        guide_curves.append((a, pieces))
    print(
        f"ODE check ({len(guide)} rays): worst miss {worst_miss:.2e} m, worst time difference "
        f"{worst_dt:.2e} s, turns and reflection sequences all equal"
    )
    t0 = time.perf_counter()
    counts, raw, where = fan_guide(30)
    listed = {}
    for a in guide:
        listed[sequence(a)] = listed.get(sequence(a), 0) + 1
    print(
        f"fan of 12000 RK4 rays with reflections (±50°): {sum(raw.values())} sign changes, "
        f"{sum(counts.values())} eigenrays in "
        f"{len(counts)} sequences; eigenray lists {len(guide)} in {len(listed)} "
        f"({time.perf_counter() - t0:.1f} s)"
    )
    assert counts == listed, (counts, listed, where)
    # The picture.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_c, ax) = plt.subplots(
        1, 2, figsize=(11, 4.5), gridspec_kw={"width_ratios": [1, 5]}, sharey=True
    )
    zz = np.linspace(0.0, 5000.0, 500)
    ax_c.plot(munk(zz), zz, "k-", lw=1, label="Munk")
    k = np.array(knots(30))
    ax_c.plot(k[:, 1], -k[:, 0], "o", ms=3, color="tab:red", label="30 knots")
    ax_c.set_xlabel("c (m/s)")
    ax_c.set_ylabel("depth (m)")
    ax_c.legend(fontsize=7)
    times = [a["time"] for a, _ in guide_curves]
    cmap = plt.get_cmap("viridis")
    lo, hi = min(times), max(times)
    for a, pieces in guide_curves:
        refracted = not a["steps"]
        for sol in pieces:
            s = np.linspace(sol.t[0], sol.t[-1], 1500)
            u = sol.sol(s)
            ax.plot(
                u[0] / 1000.0,
                -u[1],
                lw=1.6 if refracted else 0.7,
                color="tab:red" if refracted else cmap((a["time"] - lo) / (hi - lo + 1e-30)),
            )
    ax.plot([0], [SOURCE_DEPTH], "k*", ms=10)
    ax.plot([RANGES[2] / 1000.0], [RECEIVER_DEPTH], "kv", ms=8)
    ax.set_xlabel("range (km)")
    ax.set_ylim(DEPTH, 0)
    ax.set_title(
        f"Munk profile, 30 knots, pressure-release surface, bottom at {DEPTH:.0f} m: "
        f"{len(guide_curves)} eigenrays at 60 km\n"
        f"(up to {MAX_STEPS} reflections; red: the {len(curves)} refracted; others by time, "
        f"{lo:.2f}-{hi:.2f} s)",
        fontsize=9,
    )
    fig.tight_layout()
    out = ROOT / "docs" / "munk_eigenrays.png"
    fig.savefig(out, dpi=110)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
