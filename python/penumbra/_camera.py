"""An explicit pinhole camera, for rendering a scene from a view its file does not name."""

from __future__ import annotations

from typing import Sequence, Tuple

from . import _args, _core

Vector = Tuple[float, float, float]


class Camera:
    """A pinhole camera at ``position`` looking at ``look_at``, with ``up`` giving the vertical
    and ``fov`` the vertical field of view in degrees, inside (0, 180): the scene file's
    ``[camera]`` table. Each vector is a list, tuple or array of 3 numbers: anything else (a
    set, whose order is arbitrary, a string, a dict) raises ``TypeError``, as do a fov that is
    not a number. Raises ``ValueError`` for a camera that cannot exist (``look_at`` equal to
    ``position``, a view direction parallel to ``up``, a NaN or infinite coordinate, or the
    fov out of range).

    >>> Camera(position=(0, 1, 5), look_at=(0, 0, 0), up=(0, 1, 0), fov=45)
    Camera(position=(0.0, 1.0, 5.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov=45.0)
    """

    __slots__ = ("_position", "_look_at", "_up", "_fov")

    def __init__(
        self,
        position: Sequence[float],
        look_at: Sequence[float],
        up: Sequence[float],
        fov: float,
    ) -> None:
        self._position = _args.vector("Camera", "position", position)
        self._look_at = _args.vector("Camera", "look_at", look_at)
        self._up = _args.vector("Camera", "up", up)
        self._fov = _args.real("Camera", "fov", fov)
        try:
            _core.check_camera(self._position, self._look_at, self._up, self._fov)
        except ValueError as e:
            raise ValueError(f"Camera: {e}") from None

    @property
    def position(self) -> Vector:
        """The eye point, in world space."""
        return self._position

    @property
    def look_at(self) -> Vector:
        """The point the camera looks at."""
        return self._look_at

    @property
    def up(self) -> Vector:
        """The direction that appears upward in the image (need not be perpendicular)."""
        return self._up

    @property
    def fov(self) -> float:
        """The vertical field of view in degrees."""
        return self._fov

    def _args(self) -> tuple:
        return (self._position, self._look_at, self._up, self._fov)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Camera) and self._args() == other._args()

    def __hash__(self) -> int:
        return hash(self._args())

    def __repr__(self) -> str:
        return (
            f"Camera(position={self._position}, look_at={self._look_at}, "
            f"up={self._up}, fov={self._fov})"
        )
