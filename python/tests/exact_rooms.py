"""Every specular path of a polygonal room, in exact rational arithmetic: the reference that
`test_exact_rooms.py` and `benches/search_rooms.py` hold eigenray's `search` against.

A path of wall sequence w1 … wk from source S to receiver R is the image method's: the image
of S mirrored in w1, then w2, …; back from R, each point is where the line towards the image
meets its wall. It is kept when every point lies strictly inside its wall (not on a corner),
and no leg touches a wall other than at its own end points (`touches`, as eigenray's
obstruction test: a leg through a corner is obstructed; this also rules out a leg that
reaches a wall from outside the room). Its time is the exact distance from the last image to
R over the speed.

Sequences are enumerated by an exact beam tree (`beam_sequences`): each node holds an image
and the part of its last wall (the window) that rays from the source can reach, clipped to
the wedge of the node before it; a child wall is visited only where the window has a part
strictly inside the room's side of it and the wedge through that part meets it. The pruning
only drops sequences with no valid path (a path's points lie in the windows it passes, its
legs on the room's side of the walls they reach), so the reference is the same as the
exhaustive enumeration, which `exhaustive_sequences` gives for a check on small orders.
"""

from fractions import Fraction


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def at(p, q, t):
    """The point a fraction `t` from `p` to `q`."""
    return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))


def mirror(x, p, q):
    """`x` mirrored in the line through `p` and `q`, exactly."""
    e = sub(q, p)
    w = sub(x, p)
    k = 2 * (w[0] * e[0] + w[1] * e[1]) / (e[0] ** 2 + e[1] ** 2)
    return (p[0] + k * e[0] - w[0], p[1] + k * e[1] - w[1])


def meet(a, b, p, q):
    """Where segment `a -> b` meets the line through `p`, `q`: (t along a->b, u along p->q),
    or None when parallel."""
    d, e = sub(b, a), sub(q, p)
    den = cross(d, e)
    if den == 0:
        return None
    w = sub(p, a)
    return cross(w, e) / den, cross(w, d) / den


def orient(x, y, z):
    c = cross(sub(y, x), sub(z, x))
    return (c > 0) - (c < 0)


def touches(a, b, p, q):
    """Whether segments `a-b` and `p-q` share a point (exact orientation tests): eigenray's
    obstruction test, in which a leg through a wall's end point (a corner) meets that wall."""

    def on(x, y, z):  # z on segment x-y, given collinear
        return (min(x[0], y[0]) <= z[0] <= max(x[0], y[0])
                and min(x[1], y[1]) <= z[1] <= max(x[1], y[1]))

    o1, o2, o3, o4 = orient(a, b, p), orient(a, b, q), orient(p, q, a), orient(p, q, b)
    if o1 != o2 and o3 != o4 and 0 not in (o1, o2, o3, o4):
        return True
    return (o1 == 0 and on(a, b, p)) or (o2 == 0 and on(a, b, q)) or (
        o3 == 0 and on(p, q, a)) or (o4 == 0 and on(p, q, b))


def exact_walls(corners):
    """The walls of a polygon given by its corners, as pairs of exact points, and +1 or -1:
    the sign of the room's side (the interior is where `sign * cross(q - p, x - p) > 0`)."""
    c = [(Fraction(x), Fraction(y)) for x, y in corners]
    walls = [(c[i], c[(i + 1) % len(c)]) for i in range(len(c))]
    area = sum(cross(p, q) for p, q in walls)
    return walls, (1 if area > 0 else -1)


def clip(interval, f0, f1):
    """The part of `interval` (t0, t1) where the linear function with values `f0` at t = 0
    and `f1` at t = 1 is >= 0; None when empty or a single point."""
    t0, t1 = interval
    if f0 >= 0 and f1 >= 0:
        pass
    elif f0 < 0 and f1 < 0:
        return None
    else:
        root = f0 / (f0 - f1)
        if f0 < 0:
            t0 = max(t0, root)
        else:
            t1 = min(t1, root)
    return (t0, t1) if t0 < t1 else None


def beam_sequences(walls, sign, source, max_order):
    """Every wall sequence of up to `max_order` walls that a beam from `source` passes, with
    its image: a list of (sequence, image). See the module's comment."""
    out = [((), source)]
    # (sequence, image, window start, window end) per node.
    stack = [((), source, None, None)]
    while stack:
        seq, image, a, b = stack.pop()
        if len(seq) == max_order:
            continue
        for w, (p, q) in enumerate(walls):
            if seq and seq[-1] == w:
                continue
            side = lambda x: sign * cross(sub(q, p), sub(x, p))  # noqa: E731
            if not seq:
                if side(source) <= 0:
                    continue
                part = (Fraction(0), Fraction(1))
            else:
                # The window's part strictly on the room's side of wall w.
                window = clip((Fraction(0), Fraction(1)), side(a), side(b))
                if window is None:
                    continue
                a2, b2 = at(a, b, window[0]), at(a, b, window[1])
                # The points of w inside the wedge from the image through that part, beyond
                # the last wall (on the room's side of it).
                lp, lq = walls[seq[-1]]
                beyond = lambda x: sign * cross(sub(lq, lp), sub(x, lp))  # noqa: E731
                sigma = 1 if cross(sub(a2, image), sub(b2, image)) > 0 else -1
                part = (Fraction(0), Fraction(1))
                for f in (
                    lambda x: sigma * cross(sub(a2, image), sub(x, image)),
                    lambda x: -sigma * cross(sub(b2, image), sub(x, image)),
                    beyond,
                ):
                    part = clip(part, f(p), f(q))
                    if part is None:
                        break
                if part is None:
                    continue
            child = seq + (w,)
            mirrored = mirror(image, p, q)
            out.append((child, mirrored))
            stack.append((child, mirrored, at(p, q, part[0]), at(p, q, part[1])))
    return out


def exhaustive_sequences(walls, source, max_order):
    """Every wall sequence of up to `max_order` walls (no wall twice in a row), with its
    image: the enumeration the beam tree prunes."""
    out = [((), source)]
    level = [((), source)]
    for _ in range(max_order):
        level = [(s + (w,), mirror(img, *walls[w])) for s, img in level
                 for w in range(len(walls)) if not s or s[-1] != w]
        out += level
    return out


def path(walls, seq, image_of, receiver):
    """The points of sequence `seq`'s path to `receiver` (source first), or None where it is
    not valid; `image_of(i)` is the image after the first `i` walls."""
    points = [receiver]
    to = receiver
    for i in range(len(seq) - 1, -1, -1):
        p, q = walls[seq[i]]
        m = meet(to, image_of(i + 1), p, q)
        if m is None or not (0 < m[0] < 1 and 0 < m[1] < 1):
            return None
        to = at(p, q, m[1])
        points.append(to)
    points.append(image_of(0))
    points.reverse()
    on_wall = [None] + list(seq) + [None]
    for j in range(len(points) - 1):
        for w, (p, q) in enumerate(walls):
            if w not in (on_wall[j], on_wall[j + 1]) and touches(points[j], points[j + 1], p, q):
                return None
    return points


def exact_paths(corners, source, receivers, max_order, exhaustive=False):
    """{receiver index: {wall sequence: (squared length as a Fraction, points)}} of every valid
    path from `source` of up to `max_order` reflections."""
    walls, sign = exact_walls(corners)
    src = (Fraction(source[0]), Fraction(source[1]))
    if exhaustive:
        nodes = exhaustive_sequences(walls, src, max_order)
    else:
        nodes = beam_sequences(walls, sign, src, max_order)
    images = dict(nodes)
    out = {}
    for ri, r in enumerate(receivers):
        rec = (Fraction(r[0]), Fraction(r[1]))
        found = {}
        for seq, image in nodes:
            points = path(walls, seq, lambda i, seq=seq: images[seq[:i]], rec)
            if points is None:
                continue
            d = sub(rec, image)
            found[seq] = (d[0] ** 2 + d[1] ** 2, points)
        out[ri] = found
    return out
