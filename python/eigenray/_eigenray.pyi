"""Type stubs of the compiled core (`eigenray._eigenray`); the package re-exports these."""

import os
from typing import Any, Callable, Iterator, Literal, Optional, Sequence, Union, overload

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
    @property
    def curved(self) -> bool:
        """Whether a medium has a `gradient` or a `profile` (some legs are curved)."""
    def to_json(self) -> str: ...
    def curve(
        self,
        points: npt.ArrayLike,
        media: Optional[Sequence[Union[str, int]]] = None,
        *,
        launch_angle: Optional[float] = None,
        n: int = 100,
    ) -> npt.NDArray[np.float64]:
        """The curve of the ray through `points` (source, interaction points, receiver) with
        leg media `media` (names or indices; None or -1: unknown, straight), sampled at `n`
        points on the ray, `(n, 2)`; through a `profile`, the ray leaving at `launch_angle`."""

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
    # turns, launch_angle with a `profile` medium, caustics with a `profile` or `gradient`
    # medium (None without; NaN for a ray through another medium).
    turns: Optional[float]
    caustics: Optional[float]
    launch_angle: Optional[float]
    def curve(self, n: int = 100) -> npt.NDArray[np.float64]:
        """The ray's curve sampled at `n` points on the ray, `(n, 2)`: arcs through `gradient`
        and `profile` media, the first point the source, the last the receiver, every
        interaction point among them, each leg's points evenly spaced along it."""

class Gradient:
    """Derivatives of one ray's time: source, receiver, slowness per medium, touched vertices."""

    status: str
    time: float
    source: npt.NDArray[np.float64]
    receiver: npt.NDArray[np.float64]
    slowness: dict[str, float]
    vertices: list[dict[str, Any]]
    speed_gradient: dict[str, npt.NDArray[np.float64]]
    profile_speed: dict[str, npt.NDArray[np.float64]]

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
    speed_gradient: dict[str, npt.NDArray[np.float64]]
    profile_speed: dict[str, npt.NDArray[np.float64]]
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
    # turns, launch_angle with a `profile` medium, caustics with a `profile` or `gradient`
    # medium (None without; NaN for a ray through another medium).
    turns: Optional[npt.NDArray[np.float64]]
    caustics: Optional[npt.NDArray[np.float64]]
    launch_angle: Optional[npt.NDArray[np.float64]]
    def curve(self, i: int, n: int = 100) -> npt.NDArray[np.float64]:
        """Ray `i`'s curve sampled at `n` points on the ray, `(n, 2)` (as `Ray.curve`)."""
    def __len__(self) -> int: ...

class Arrivals:
    """A search's arrivals (`Tracer.search`) as numpy arrays, ordered as the search lists
    them: source-major, then receiver, then by time. `len(arrivals)`, `arrivals[i]`
    (negative indices and slices too), iteration and `to_dicts()` give each arrival as a dict
    (`source`, `receiver`, `steps`, `media`, `status`, `time`, `points`, `iterations`,
    `residual`, `reason`, `kink`, `complete`, and with "amplitudes" `amplitude`,
    `spreading`, `coefficient`, `attenuation_db`, `amplitude_reason`), made from the arrays.
    K below is the largest `order`."""

    source: npt.NDArray[np.int64]
    """Source index of each arrival, `(n,)`."""
    receiver: npt.NDArray[np.int64]
    """Receiver index of each arrival, `(n,)`."""
    time: npt.NDArray[np.float64]
    """Travel time, `(n,)` (every arrival has one)."""
    order: npt.NDArray[np.uint32]
    """Steps (reflections and refractions) of each arrival, `(n,)`: 0 for the direct ray."""
    status: npt.NDArray[np.uint8]
    """Status code, `(n,)`: `status_names[code]` is `converged`, `vertex` or `obstructed`."""
    complete: npt.NDArray[np.bool_]
    """Whether the search of the arrival's (source, receiver) pair was complete, `(n,)`."""
    iterations: npt.NDArray[np.uint32]
    """Newton steps of the arrival's solve, `(n,)`."""
    residual: npt.NDArray[np.float64]
    """Final relative residual, `(n,)` (NaN where there is none)."""
    points: npt.NDArray[np.float64]
    """Source, interaction points and receiver, `(n, K + 2, 2)`; NaN past the arrival's own
    `order + 2` points."""
    step_interface: npt.NDArray[np.int64]
    """The interface of each step, `(n, K)`: indices into `interface_names`, -1 past the
    arrival's own `order` steps."""
    step_kind: npt.NDArray[np.uint8]
    """The kind of each step, `(n, K)`: 0 reflect, 1 refract, 2 diffract
    (`step_kind_names[code]`), 255 past the arrival's own steps."""
    media: npt.NDArray[np.int64]
    """Leg media, `(n, K + 1)`: indices into `media_names`, -1 past the arrival's own
    `order + 1` legs."""
    status_names: list[str]
    """The status names, by code."""
    step_kind_names: list[str]
    """`["reflect", "refract"]` (and `"diffract"` when the search lists diffracted arrivals):
    the step kinds, by code."""
    interface_names: list[str]
    """The scene's interface names, by index."""
    media_names: list[str]
    """The scene's medium names, by index."""
    reason: list[Optional[str]]
    """Why an arrival is not `converged` (`None` where it is), naming interfaces."""
    kink: list[Optional[str]]
    """`minimum`, `maximum` or `mixed` on `vertex` arrivals, else `None`."""
    # With "amplitudes" (None without): NaN where there is no value (see amplitude_reason).
    amplitude: Optional[npt.NDArray[np.complex128]]
    """The complex pressure amplitude for a unit source, without the travel-time phase."""
    spreading: Optional[npt.NDArray[np.float64]]
    """The geometric spreading factor."""
    coefficient: Optional[npt.NDArray[np.complex128]]
    """The product of the reflection and transmission coefficients."""
    attenuation_db: Optional[npt.NDArray[np.float64]]
    """The attenuation of the media along the path, dB."""
    amplitude_reason: Optional[list[Optional[str]]]
    """Why an amplitude has no value (`None` where it has one)."""
    # turns, launch_angle with a `profile` medium, caustics with a `profile` or `gradient`
    # medium (None without).
    turns: Optional[npt.NDArray[np.float64]]
    """Turning points on the arrival's legs."""
    caustics: Optional[npt.NDArray[np.float64]]
    """Caustics the arrival's ray tube passed (each −π/2 of phase)."""
    launch_angle: Optional[npt.NDArray[np.float64]]
    """The arrival's direction at the source, radians from +x."""
    def curve(self, i: int, n: int = 100) -> npt.NDArray[np.float64]:
        """Arrival `i`'s curve sampled at `n` points on the ray, `(n, 2)` (as `Ray.curve`):
        the first point the source, the last the receiver, every interaction among them."""
    def to_dicts(self) -> list[dict[str, Any]]:
        """Every arrival as a dict: the list `search` gave before it gave arrays."""
    def __len__(self) -> int: ...
    @overload
    def __getitem__(self, index: int) -> dict[str, Any]: ...
    @overload
    def __getitem__(self, index: slice) -> list[dict[str, Any]]: ...
    def __iter__(self) -> Iterator[dict[str, Any]]: ...

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
    def search(self) -> Arrivals: ...
    def echoes(self) -> dict[str, npt.NDArray[Any]]: ...
    def impulse_response(
        self,
        rate: float | None = None,
        duration: float | None = None,
        taps: int | None = None,
    ) -> npt.NDArray[np.float64]: ...
    def room_parameters(
        self, rate: float | None = None, duration: float | None = None
    ) -> list[dict[str, Any]]: ...
    def pressure(self, frequency: float | None = None) -> npt.NDArray[np.complex128]: ...
    def transmission_loss(
        self,
        frequency: float | None = None,
        mode: Literal["coherent", "incoherent"] | None = None,
    ) -> npt.NDArray[np.float64]: ...
    def set_source(self, index: int, point: PointLike) -> None: ...
    def set_receiver(self, index: int, point: PointLike) -> None: ...
    def set_receivers(self, points: npt.ArrayLike) -> None: ...
    def set_interface_points(self, interface: Union[int, str], points: npt.ArrayLike) -> None: ...
    def set_medium_speed(self, medium: Union[int, str], speed: float) -> None: ...
    def set_medium_index(self, medium: Union[int, str], index: float) -> None: ...
