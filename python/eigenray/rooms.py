"""Extruded rooms in a few lines, as pyroomacoustics builds them.

A floor plan of vertical walls (its corners, each wall absorbing its own share of the
energy) extruded to a height, with a flat floor and ceiling of their own absorption:
eigenray's `"extrusion"` scene, whose 3-D arrivals are exact (every plan path found by the
search, with its floor and ceiling reflections in closed form).

pyroomacoustics::

    room = pra.Room.from_corners(corners, fs=16000, max_order=8,
                                 materials=pra.Material(0.2))
    room.extrude(3.0, materials=pra.Material(0.3))
    room.add_source([1.0, 1.5, 1.2]); room.add_microphone([4.0, 2.0, 1.6])
    room.compute_rir()

eigenray::

    from eigenray import rooms
    room = rooms.from_corners(corners, 3.0, absorption=0.2, floor=0.3, ceiling=0.3,
                              fs=16000, max_order=8)
    room.add_source([1.0, 1.5, 1.2]); room.add_microphone([4.0, 2.0, 1.6])
    rir = room.compute_rir()            # [sources, microphones, samples]
    parameters = room.room_parameters()  # T20, T30, EDT, C50, C80, D50 per pair
    level = room.level_map((0.1, 5.9, 59), (0.1, 3.9, 39), z=1.6, frequency=500)

`corners` is an array of shape ``(2, N)`` as pyroomacoustics takes it (or ``(N, 2)``);
`absorption` one energy absorption coefficient for every wall, or one per wall (wall ``k``
from corner ``k`` to corner ``k + 1``). Responses are eigenray's: a unit point source's
pressure ``1/(4πR)`` per path, each pulse centred on its arrival's time (pyroomacoustics
leaves out the ``1/(4π)`` and delays its responses by 40 samples).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ._eigenray import Scene, Tracer

__all__ = ["ExtrudedRoom", "from_corners"]


def _corners(corners: Any) -> np.ndarray:
    c = np.asarray(corners, dtype=float)
    if c.ndim != 2 or 2 not in c.shape:
        raise ValueError("corners: expected an array of shape (2, N) or (N, 2)")
    if c.shape[0] == 2 and c.shape[1] != 2:
        c = c.T
    if len(c) < 3:
        raise ValueError("corners: a floor plan needs at least 3 corners")
    return c


def _absorption(name: str, a: float) -> dict[str, Any]:
    a = float(a)
    if not 0.0 <= a <= 1.0:
        raise ValueError(f"{name}: an absorption lies from 0 to 1, not {a}")
    return {"absorption": a}


class ExtrudedRoom:
    """An extruded room: its floor plan, height, absorptions, sources and microphones."""

    def __init__(
        self,
        corners: Any,
        height: float,
        *,
        absorption: float | Sequence[float] = 0.0,
        floor: float = 0.0,
        ceiling: float = 0.0,
        fs: float = 16000.0,
        max_order: int | None = None,
        max_time: float | None = None,
        speed: float = 343.0,
    ) -> None:
        self.corners = _corners(corners)
        self.height = float(height)
        n = len(self.corners)
        walls = np.asarray(absorption, dtype=float)
        if walls.ndim == 0:
            walls = np.full(n, float(walls))
        if walls.shape != (n,):
            raise ValueError(f"absorption: one per wall ({n}), or one for all")
        self.absorption = [float(a) for a in walls]
        self.floor = float(floor)
        self.ceiling = float(ceiling)
        self.fs = float(fs)
        if max_order is None and max_time is None:
            raise ValueError("give max_order (reflections), max_time (s), or both")
        self.max_order = max_order
        self.max_time = max_time
        self.speed = float(speed)
        self.sources: list[list[float]] = []
        self.microphones: list[list[float]] = []

    def add_source(self, position: Sequence[float]) -> "ExtrudedRoom":
        """Adds a source at ``[x, y, z]``."""
        self.sources.append([float(v) for v in position])
        return self

    def add_microphone(self, position: Sequence[float]) -> "ExtrudedRoom":
        """Adds a microphone (a receiver) at ``[x, y, z]``."""
        self.microphones.append([float(v) for v in position])
        return self

    def duration(self) -> float:
        """The responses' duration (s): `max_time`, else the latest arrival's time bound
        (the longest path of `max_order` reflections across the room's bounding box)."""
        if self.max_time is not None:
            return float(self.max_time)
        span = np.ptp(self.corners, axis=0)
        diagonal = float(np.hypot(np.hypot(span[0], span[1]), self.height))
        return (int(self.max_order) + 1) * diagonal / self.speed + 0.01

    def scene_dict(self) -> dict[str, Any]:
        """The eigenray scene document of the room."""
        c = self.corners
        n = len(c)
        interfaces = {
            f"wall{k}": {
                "points": [c[k].tolist(), c[(k + 1) % n].tolist()],
                "reflection": _absorption(f"absorption[{k}]", self.absorption[k]),
            }
            for k in range(n)
        }
        search: dict[str, Any] = {"refract": False}
        if self.max_order is not None:
            search["max_steps"] = int(self.max_order)
        if self.max_time is not None:
            search["max_time"] = float(self.max_time)
        return {
            "media": {"air": {"speed": self.speed}},
            "background": "air",
            "interfaces": interfaces,
            "extrusion": {
                "height": self.height,
                "floor": _absorption("floor", self.floor),
                "ceiling": _absorption("ceiling", self.ceiling),
            },
            "sources": self.sources,
            "receivers": self.microphones,
            "search": search,
            "amplitudes": {"source": "point"},
            "impulse_response": {"rate": self.fs, "duration": self.duration()},
        }

    def scene(self) -> Scene:
        """The room as an eigenray `Scene`."""
        return Scene(self.scene_dict())

    def tracer(self) -> Tracer:
        """A `Tracer` of the room."""
        return Tracer(self.scene())

    def arrivals(self):
        """Every 3-D arrival (`Tracer.search`): points ``(x, y, z)``, steps naming the walls,
        the floor and the ceiling."""
        return self.tracer().search()

    def compute_rir(self) -> np.ndarray:
        """The impulse responses, float64 ``[sources, microphones, samples]`` at `fs`."""
        return self.tracer().impulse_response()

    def room_parameters(self) -> list[dict[str, Any]]:
        """EDT, T20, T30, C50, C80 and D50 of each (source, microphone)
        (`Tracer.room_parameters`)."""
        return self.tracer().room_parameters()


    def level_map(
        self,
        x: Sequence[float],
        y: Sequence[float],
        z: float,
        frequency: float,
        mode: str = "incoherent",
    ) -> np.ndarray:
        """The level of each source over a grid of listeners at height `z`: ``20 log10(4π|p|)``
        dB (0 dB at 1 m in free field; minus the transmission loss), float64 ``[sources, nx,
        ny]``. `x` and `y` are ``(first, last, count)`` as `numpy.linspace`; `mode`
        ``"incoherent"`` (the energy sum of the arrivals, the usual room map) or
        ``"coherent"`` (their sum at `frequency`). A listener outside the plan (or that no
        path reaches) gets ``-inf``. The room's microphones play no part."""
        doc = self.scene_dict()
        doc["receivers"] = {
            "grid": {"x": [float(v) for v in x], "y": [float(v) for v in y], "z": float(z)}
        }
        doc["amplitudes"]["frequency"] = float(frequency)
        doc.pop("impulse_response")
        return -Tracer(Scene(doc)).transmission_loss(mode=mode)


def from_corners(corners: Any, height: float, **kwargs: Any) -> ExtrudedRoom:
    """An extruded room from its floor plan's corners and its height (see `ExtrudedRoom`)."""
    return ExtrudedRoom(corners, height, **kwargs)
