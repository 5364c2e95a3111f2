"""eigenray's `search` in dyadic rooms against exact rational arithmetic (`exact_rooms.py`):
every specular path to order 8 in the comb-shaped room of pyroomacoustics issue #383 (drawn as
one closed polyline and as one interface per wall), and to order 6 in pyroomacoustics' L-shaped
room. Their walls are axis-aligned with coordinates that are multiples of 1/64, so every image
is exact in floating point and eigenray's decisions (a point strictly inside its wall, a leg
through a corner) are exact too: the arrivals must be the exact ones, no more and no fewer,
each time within a few ulps of the exact distance over the speed."""

import json
import math
import os

import eigenray
import exact_rooms

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SPEED = 343.0
COMB = [[0, 0], [0, 5], [1, 5], [1, 2], [2, 2], [2, 5], [3, 5], [3, 0], [2, 0], [2, 1], [1, 1],
        [1, 0]]
COMB_SOURCE = [0.5, 0.5]
COMB_LISTENERS = [[2.5, 4.5], [0.5, 4.5], [0.5, 2.5], [2.5, 2.5], [2.5, 0.5], [1.5, 1.5],
                  [0.25, 1.25], [2.75, 3.75], [1.25, 1.75]]


def l_shape():
    with open(os.path.join(ROOT, "fixtures", "pyroomacoustics", "rooms.json")) as f:
        room = next(r for r in json.load(f)["rooms"] if r["name"] == "l_shape")
    return room["corners"], room["sources"], room["receivers"]


def search(corners, source, receivers, order, polyline):
    """eigenray's arrivals, per receiver: a list of (points, time)."""
    n = len(corners)
    if polyline:
        interfaces = {"room": {"points": corners, "closed": True}}
    else:
        interfaces = {f"w{i}": {"points": [corners[i], corners[(i + 1) % n]]} for i in range(n)}
    scene = eigenray.Scene({
        "media": {"air": {"speed": SPEED, "at": source}},
        "interfaces": interfaces,
        "sources": [source],
        "receivers": receivers,
        "search": {"max_steps": order},
    })
    out = {r: [] for r in range(len(receivers))}
    for a in eigenray.Tracer(scene).search():
        assert a["status"] == "converged" and a["complete"], a
        out[a["receiver"]].append(([tuple(p) for p in a["points"]], a["time"]))
    return out


def compare(exact, ours):
    """The exact paths that eigenray lists (matched by their points, to 1e-12), the ones it
    lists beyond them, and the largest relative time error of the matched ones."""
    missing, worst, extra = [], 0.0, []
    for r, paths in exact.items():
        left = list(ours[r])
        for seq, (d2, points) in paths.items():
            fp = [(float(x), float(y)) for x, y in points]
            hit = next((i for i, (pts, _) in enumerate(left) if len(pts) == len(fp) and all(
                abs(p[0] - q[0]) <= 1e-12 and abs(p[1] - q[1]) <= 1e-12
                for p, q in zip(pts, fp))), None)
            if hit is None:
                missing.append((r, seq))
                continue
            _, time = left.pop(hit)
            exact_time = math.sqrt(d2) / SPEED
            worst = max(worst, abs(time / exact_time - 1))
        extra += [(r, pts) for pts, _ in left]
    return missing, extra, worst


def test_the_beam_enumeration_is_the_exhaustive_one():
    """The reference's pruned enumeration gives the paths of every wall sequence (order 3,
    1,597 sequences, each of the nine listeners)."""
    beams = exact_rooms.exact_paths(COMB, COMB_SOURCE, COMB_LISTENERS, 3)
    every = exact_rooms.exact_paths(COMB, COMB_SOURCE, COMB_LISTENERS, 3, exhaustive=True)
    assert {r: set(p) for r, p in beams.items()} == {r: set(p) for r, p in every.items()}
    assert sum(len(p) for p in beams.values()) > 80


def test_the_comb_room_to_order_8_is_exact():
    exact = exact_rooms.exact_paths(COMB, COMB_SOURCE, COMB_LISTENERS, 8)
    n = sum(len(p) for p in exact.values())
    assert n > 400
    ours = search(COMB, COMB_SOURCE, COMB_LISTENERS, 8, polyline=True)
    missing, extra, worst = compare(exact, ours)
    assert not missing and not extra, (missing[:5], extra[:5])
    assert worst <= 1e-15
    assert any(len(seq) == 8 for p in exact.values() for seq in p)


def test_the_comb_room_drawn_per_wall_is_exact_too():
    """Drawn one interface per wall, each corner is an end of two walls: no free end, so no
    reflection lies there (as the polyline's vertex holds none), and the arrivals are the
    exact ones as well."""
    exact = exact_rooms.exact_paths(COMB, COMB_SOURCE, COMB_LISTENERS, 8)
    ours = search(COMB, COMB_SOURCE, COMB_LISTENERS, 8, polyline=False)
    missing, extra, worst = compare(exact, ours)
    assert not missing and not extra, (missing[:5], extra[:5])
    assert worst <= 1e-15


def test_the_l_shaped_room_to_order_6_is_exact():
    corners, sources, receivers = l_shape()
    for source in sources:
        exact = exact_rooms.exact_paths(corners, source, receivers, 6)
        ours = search(corners, source, receivers, 6, polyline=True)
        missing, extra, worst = compare(exact, ours)
        assert not missing and not extra, (missing[:5], extra[:5])
        assert worst <= 1e-15
