"""An explicit camera, for rendering a scene from a view its file does not name: a pinhole or
any of the scene format's lens models, with the keys of a ``[camera]`` table."""

from __future__ import annotations

import json
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from . import _args, _core

Vector = Tuple[float, float, float]

#: The keyword-only keys, in the order ``repr`` lists them.
_LENS_KEYS = (
    "camera_to_world",
    "K",
    "model",
    "distortion",
    "max_angle",
    "height",
    "aperture_radius",
    "focus_distance",
)


def _matrix(name: str, value: Any, shape: Tuple[int, int]) -> list:
    """``value`` as rows of finite floats of ``shape`` (a ``ValueError`` naming ``name``)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"Camera: {name} must be a {shape[0]}x{shape[1]} matrix of numbers, "
                        f"not {value!r}") from None
    if a.shape != shape:
        raise ValueError(f"Camera: {name} must be {shape[0]}x{shape[1]}, not shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"Camera: {name} must hold finite numbers")
    return a.tolist()


def _finite(name: str, value: Any) -> float:
    return _args.finite("Camera", name, value)


class Camera:
    """A camera: the keys of a scene file's ``[camera]`` table (docs/scene-format.md,
    "Camera models"). The pinhole of old is ``position``, ``look_at``, ``up`` (default
    ``(0, 1, 0)``) and ``fov``, the vertical field of view in degrees inside (0, 180)::

        Camera((0, 1, 5), (0, 0, 0), (0, 1, 0), 45)

    Keyword-only keys give the rest, exactly as a scene file does:

    - ``camera_to_world``: a 4×4 rigid transform in OpenCV's axes (x right, y down, z
      forward), instead of ``position``/``look_at``/``up``;
    - ``K``: 3×3 intrinsics in pixels of the film rendered (OpenCV's pixel centres at integer
      coordinates), instead of ``fov``;
    - ``model``: ``"pinhole"``, ``"opencv"``, ``"fisheye"``, ``"equirectangular"`` or
      ``"orthographic"``, with ``distortion`` (OpenCV's order), ``max_angle`` (a fisheye's,
      degrees) and ``height`` (an orthographic image's, world units);
    - ``aperture_radius`` and ``focus_distance``: a thin lens.

    A vector is a list, tuple or array of 3 numbers and a matrix anything numpy reads as one;
    anything else (a set, a string, a dict) raises ``TypeError``. A camera that cannot exist
    (``look_at`` equal to ``position``, a view direction parallel to ``up``, a NaN, the fov out
    of range, a bad K or distortion, keys that do not go together) raises ``ValueError``
    naming the key, as a scene file's error does.

    >>> Camera(position=(0, 1, 5), look_at=(0, 0, 0), up=(0, 1, 0), fov=45)
    Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov=45.0)
    >>> Camera((0, 0, 0), (0, 0, -1), model="equirectangular").model
    'equirectangular'
    """

    __slots__ = ("_table",)

    def __init__(
        self,
        position: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        up: Optional[Sequence[float]] = None,
        fov: Optional[float] = None,
        *,
        camera_to_world: Any = None,
        K: Any = None,
        model: Optional[str] = None,
        distortion: Optional[Sequence[float]] = None,
        max_angle: Optional[float] = None,
        height: Optional[float] = None,
        aperture_radius: Optional[float] = None,
        focus_distance: Optional[float] = None,
    ) -> None:
        table: Dict[str, Any] = {}
        for name, value in (("position", position), ("look_at", look_at), ("up", up)):
            if value is not None:
                table[name] = _args.vector("Camera", name, value)
        if fov is not None:
            table["fov"] = _args.real("Camera", "fov", fov)
        if camera_to_world is not None:
            table["camera_to_world"] = _matrix("camera_to_world", camera_to_world, (4, 4))
        if K is not None:
            table["K"] = _matrix("K", K, (3, 3))
        if model is not None:
            if not isinstance(model, str):
                raise TypeError(f"Camera: model must be a name, not {type(model).__name__}")
            table["model"] = model
        if distortion is not None:
            items = np.asarray(distortion, dtype=np.float64).reshape(-1)
            table["distortion"] = [_finite(f"distortion[{i}]", c) for i, c in enumerate(items)]
        for name, number in (
            ("max_angle", max_angle),
            ("height", height),
            ("aperture_radius", aperture_radius),
            ("focus_distance", focus_distance),
        ):
            if number is not None:
                table[name] = _finite(name, number)
        self._table = table
        self._check()

    def _check(self) -> None:
        if not self._is_pinhole():
            # A table goes as JSON, which has no NaN: refused here, naming the key.
            for name in ("position", "look_at", "up"):
                if name in self._table:
                    _args.finite_vector("Camera", name, self._table[name])
            if "fov" in self._table:
                _finite("fov", self._table["fov"])
        try:
            _core.check_camera(self._args())
        except ValueError as e:
            raise ValueError(f"Camera: {e}") from None

    def _is_pinhole(self) -> bool:
        """True for the plain pinhole: position, look_at, fov (and up), nothing else."""
        return {"position", "look_at", "fov"} <= set(self._table) <= {
            "position", "look_at", "up", "fov"}

    def _args(self) -> tuple:
        """The camera as the core takes it: a pinhole's (position, look_at, up, fov), else
        its table as JSON in a 1-tuple."""
        if self._is_pinhole():
            up = self._table.get("up", (0.0, 1.0, 0.0))
            return (self._table["position"], self._table["look_at"], up, self._table["fov"])
        return (json.dumps(self._table, sort_keys=True),)

    @property
    def position(self) -> Optional[Vector]:
        """The eye point, in world space (None when ``camera_to_world`` gives it)."""
        return self._table.get("position")

    @property
    def look_at(self) -> Optional[Vector]:
        """The point the camera looks at (None when ``camera_to_world`` gives the pose)."""
        return self._table.get("look_at")

    @property
    def up(self) -> Vector:
        """The direction that appears upward in the image (need not be perpendicular)."""
        return self._table.get("up", (0.0, 1.0, 0.0))

    @property
    def fov(self) -> Optional[float]:
        """The vertical field of view in degrees (None when ``K`` or the model sets it)."""
        return self._table.get("fov")

    @property
    def model(self) -> str:
        """The lens model's name."""
        return self._table.get("model", "pinhole")

    def table(self) -> Dict[str, Any]:
        """The keys of the ``[camera]`` table this camera is, as given (a copy)."""
        return json.loads(json.dumps(self._table))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Camera) and self._args() == other._args()

    def __hash__(self) -> int:
        return hash(self._args())

    def __repr__(self) -> str:
        if self._is_pinhole():
            return (
                f"Camera(position={self.position}, look_at={self.look_at}, "
                f"up={self.up}, fov={self.fov})"
            )
        keys = ("position", "look_at", "up", "fov") + _LENS_KEYS
        given = ", ".join(f"{k}={self._table[k]!r}" for k in keys if k in self._table)
        return f"Camera({given})"
