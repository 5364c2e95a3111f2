"""Amplitudes against pyroomacoustics' image sources: in polygon rooms with absorbing walls,
every arrival of eigenray's `search` has pyroomacoustics' image amplitude
`damping / (4 pi distance)` (float32's rounding apart), and the closed form
prod(sqrt(1 - alpha_i)) / (4 pi L) over the walls it reflects off (to round-off).

pyroomacoustics (2-D, no ray tracing, no air absorption) lists every image source to
`max_order` reflections with its damping (the product of sqrt(1 - absorption) of its walls,
float32) and whether each microphone sees it. The same room in eigenray is one interface per
wall with `"reflection": {"absorption": alpha}`, a `search` of up to `max_order` reflections
and `"amplitudes": {"source": "point"}`. Each arrival is matched to the visible image it comes
from: the image lies behind the receiver along the last leg, at the path's length. Coordinates
are multiples of 1/64, exact in float32.
"""

import math

import numpy as np
import pyroomacoustics as pra
import pytest

import eigenray

SPEED = 343.0
ORDER = 3


def q(x):
    """`x` rounded to a multiple of 1/64 (exact in float32)."""
    return round(x * 64.0) / 64.0


# Counter-clockwise corners, one absorption per wall (wall i from corner i to corner i + 1).
ROOMS = {
    # Not convex: the re-entrant corner hides images and blocks paths.
    "l_shape": {
        "corners": [[0, 0], [6, 0], [6, 2.5], [2.5, 2.5], [2.5, 5], [0, 5]],
        "alphas": [0.2, 0.4, 0.1, 0.3, 0.25, 0.15],
        "source": [1.0, 1.0],
        "receivers": [[5.0, 1.5], [1.5, 4.0], [4.0, 0.5], [0.5, 2.75]],
    },
    # Convex, no two walls parallel.
    "pentagon": {
        "corners": [
            [q(3.1 * math.cos(a)), q(2.6 * math.sin(a))]
            for a in np.linspace(0.0, 2.0 * math.pi, 5, endpoint=False) + 0.3
        ],
        "alphas": [0.05, 0.3, 0.5, 0.12, 0.36],
        "source": [q(-0.7), q(0.4)],
        "receivers": [[q(1.3), q(-0.9)], [q(-1.1), q(-1.2)], [q(0.6), q(1.5)]],
    },
}


def pra_images(room, receiver):
    """pyroomacoustics' images visible from `receiver`: positions (n, 2) and dampings (n,)."""
    materials = [pra.Material(energy_absorption=a) for a in room["alphas"]]
    corners = np.array(room["corners"], dtype=float).T
    model = pra.Room.from_corners(
        corners, fs=16000, max_order=ORDER, materials=materials,
        ray_tracing=False, air_absorption=False,
    )
    model.add_source(room["source"])
    model.add_microphone(receiver)
    model.image_source_model()
    source = model.sources[0]
    visible = np.asarray(model.visibility[0][0], dtype=bool)
    return source.images[:, visible].T.astype(float), source.damping[0, visible].astype(float)


def eigenray_scene(room):
    """The room as an eigenray scene with a `search` to `ORDER` reflections."""
    corners, n = room["corners"], len(room["corners"])
    return {
        "media": {"air": {"speed": SPEED}},
        "background": "air",
        "interfaces": {
            f"w{i}": {
                "points": [corners[i], corners[(i + 1) % n]],
                "reflection": {"absorption": room["alphas"][i]},
            }
            for i in range(n)
        },
        "sources": [room["source"]],
        "receivers": room["receivers"],
        "search": {"max_steps": ORDER, "refract": False},
        "amplitudes": {"source": "point"},
    }


def image_of(arrival):
    """The image source an arrival comes from: behind the receiver along its last leg, at the
    path's length."""
    points = arrival["points"]
    legs = np.diff(points, axis=0)
    length = np.linalg.norm(legs, axis=1).sum()
    back = points[-2] - points[-1]
    return points[-1] + length * back / np.linalg.norm(back), length


@pytest.mark.parametrize("name", sorted(ROOMS))
def test_arrival_amplitudes_are_pyroomacoustics_image_amplitudes(name):
    room = ROOMS[name]
    alphas = room["alphas"]
    arrivals = eigenray.Tracer(eigenray.Scene(eigenray_scene(room))).search()
    assert all(a["status"] == "converged" for a in arrivals)
    worst_pra, worst_closed, count = 0.0, 0.0, 0
    for r, receiver in enumerate(room["receivers"]):
        images, damping = pra_images(room, receiver)
        mine = [a for a in arrivals if a["receiver"] == r]
        # The same arrivals: one visible image each, none left over.
        assert len(mine) == len(images), (name, r, len(mine), len(images))
        matched = set()
        for a in mine:
            image, length = image_of(a)
            gaps = np.linalg.norm(images - image, axis=1)
            j = int(np.argmin(gaps))
            assert gaps[j] < 1e-5 and j not in matched, (name, r, a["steps"], gaps[j])
            matched.add(j)
            distance = np.linalg.norm(images[j] - receiver)
            assert abs(distance - length) < 1e-6 * length
            assert abs(a["time"] * SPEED - length) < 1e-12 * length
            amplitude = a["amplitude"]
            assert amplitude.imag == 0.0 and amplitude.real > 0.0
            # pyroomacoustics' image amplitude (float32 damping and images).
            theirs = damping[j] / (4.0 * math.pi * distance)
            worst_pra = max(worst_pra, abs(amplitude.real - theirs) / theirs)
            # The closed form over the walls the arrival reflects off.
            walls = [int(step["reflect"][1:]) for step in a["steps"]]
            closed = math.prod(math.sqrt(1.0 - alphas[w]) for w in walls)
            closed /= 4.0 * math.pi * length
            worst_closed = max(worst_closed, abs(amplitude.real - closed) / closed)
            assert a["spreading"] == pytest.approx(1.0 / (4.0 * math.pi * length), rel=1e-13)
            assert a["coefficient"].imag == 0.0 and a["attenuation_db"] == 0.0
            count += 1
    print(f"{name}: {count} arrivals, largest relative difference from pyroomacoustics "
          f"{worst_pra:.2e}, from the closed form {worst_closed:.2e}")
    # Reflections of every order up to ORDER, and float32-level agreement.
    assert {len(a["steps"]) for a in arrivals} == set(range(ORDER + 1))
    assert worst_pra < 1e-6
    assert worst_closed < 1e-13
