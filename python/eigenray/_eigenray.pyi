"""Type stubs of the compiled core (`eigenray._eigenray`); the package re-exports these."""

import os
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

PointLike = Union[Sequence[float], npt.ArrayLike]

STATUS_NAMES: list[str]

class EigenrayError(ValueError):
    """An invalid scene or argument; `str(error)` is ``"key: message"``."""

    key: str
    message: str

class Scene:
    """A validated scene: from a JSON string, a dict of the JSON's shape, or a file path."""

    def __init__(self, source: Union[str, dict[str, Any], os.PathLike[str]]) -> None: ...
    @staticmethod
    def from_json(text: str) -> Scene: ...
    @staticmethod
    def from_dict(scene: dict[str, Any]) -> Scene: ...
    @staticmethod
    def from_file(path: Union[str, os.PathLike[str]]) -> Scene: ...
    @property
    def media_names(self) -> list[str]: ...
    @property
    def slowness(self) -> npt.NDArray[np.float64]: ...
    @property
    def interface_names(self) -> list[str]: ...
    @property
    def interfaces(self) -> dict[str, npt.NDArray[np.float64]]: ...
    @property
    def closed(self) -> dict[str, bool]: ...
    @property
    def path_names(self) -> list[Optional[str]]: ...
    @property
    def sources(self) -> npt.NDArray[np.float64]: ...
    @property
    def receivers(self) -> npt.NDArray[np.float64]: ...
    @property
    def num_rays(self) -> int: ...
    def to_json(self) -> str: ...

class Ray:
    """One ray: status, time (NaN without one), points `(k + 2, 2)`, leg media's names."""

    status: str
    time: float
    points: npt.NDArray[np.float64]
    media: list[str]
    iterations: int
    residual: float
    reason: Optional[str]
    arrival: Optional[int]
    kink: Optional[str]
    # With "amplitudes" (None without): NaN where there is no value (see amplitude_reason).
    amplitude: Optional[complex]
    spreading: Optional[float]
    coefficient: Optional[complex]
    attenuation_db: Optional[float]
    amplitude_reason: Optional[str]

class Gradient:
    """Derivatives of one ray's time: source, receiver, slowness per medium, touched vertices."""

    status: str
    time: float
    source: npt.NDArray[np.float64]
    receiver: npt.NDArray[np.float64]
    slowness: dict[str, float]
    vertices: list[dict[str, Any]]

class PointSensitivities:
    """How one ray's points move: `d[i]` is d(points)/d(parameters[i]), shape (points, 2)."""

    status: str
    time: float
    parameters: list[tuple[Any, ...]]
    d: npt.NDArray[np.float64]

class Gradients:
    """Derivatives of many rays' times, one row per ray (NaN and -1 without a time)."""

    source: npt.NDArray[np.float64]
    receiver: npt.NDArray[np.float64]
    slowness: npt.NDArray[np.float64]
    vertex_interface: npt.NDArray[np.int32]
    vertex: npt.NDArray[np.int32]
    vertex_d: npt.NDArray[np.float64]
    media_names: list[str]
    interface_names: list[str]
    def __len__(self) -> int: ...

class Rays:
    """Rays as numpy arrays, in ray order (source-major, then receiver, then path)."""

    source: npt.NDArray[np.int64]
    receiver: npt.NDArray[np.int64]
    path: npt.NDArray[np.int64]
    status: npt.NDArray[np.uint8]
    time: npt.NDArray[np.float64]
    points: npt.NDArray[np.float64]
    num_points: npt.NDArray[np.int64]
    media: npt.NDArray[np.int32]
    iterations: npt.NDArray[np.uint32]
    residual: npt.NDArray[np.float64]
    reason: list[Optional[str]]
    status_names: list[str]
    path_names: list[Optional[str]]
    media_names: list[str]
    arrival: Optional[npt.NDArray[np.int64]]
    kink: Optional[list[Optional[str]]]
    complete: Optional[npt.NDArray[np.bool_]]
    # With "amplitudes" (None without): NaN where there is no value (see amplitude_reason).
    amplitude: Optional[npt.NDArray[np.complex128]]
    spreading: Optional[npt.NDArray[np.float64]]
    coefficient: Optional[npt.NDArray[np.complex128]]
    attenuation_db: Optional[npt.NDArray[np.float64]]
    amplitude_reason: Optional[list[Optional[str]]]
    def __len__(self) -> int: ...

class Tracer:
    """Traces the rays of a scene (prepared once, reused by every call)."""

    def __init__(self, scene: Scene) -> None: ...
    @property
    def scene(self) -> Scene: ...
    def trace(
        self,
        *,
        warm_start: bool = True,
        progress: Union[None, bool, Callable[[int, int], Any]] = None,
        out: Optional[Rays] = None,
    ) -> Rays: ...
    def trace_stationary(
        self, *, progress: Union[None, bool, Callable[[int, int], Any]] = None
    ) -> Rays: ...
    def solve(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> Ray: ...
    def time(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> float: ...
    def amplitude(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> complex: ...
    def solve_pairs(
        self,
        sources: npt.ArrayLike,
        receivers: npt.ArrayLike,
        path: Union[int, str, None] = None,
    ) -> Rays: ...
    def stationary_paths(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> tuple[list[Ray], bool]: ...
    def gradient(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> Gradient: ...
    def gradients(self, rays: Rays) -> Gradients: ...
    def point_sensitivities(
        self, source: PointLike, receiver: PointLike, path: Union[int, str, None] = None
    ) -> PointSensitivities: ...
    def search(self) -> list[dict[str, Any]]: ...
    def echoes(self) -> dict[str, npt.NDArray[Any]]: ...
    def impulse_response(
        self,
        rate: float | None = None,
        duration: float | None = None,
        taps: int | None = None,
    ) -> npt.NDArray[np.float64]: ...
    def pressure(self, frequency: float | None = None) -> npt.NDArray[np.complex128]: ...
    def transmission_loss(self, frequency: float | None = None) -> npt.NDArray[np.float64]: ...
    def set_source(self, index: int, point: PointLike) -> None: ...
    def set_receiver(self, index: int, point: PointLike) -> None: ...
    def set_receivers(self, points: npt.ArrayLike) -> None: ...
    def set_interface_points(self, interface: Union[int, str], points: npt.ArrayLike) -> None: ...
    def set_medium_speed(self, medium: Union[int, str], speed: float) -> None: ...
    def set_medium_index(self, medium: Union[int, str], index: float) -> None: ...
