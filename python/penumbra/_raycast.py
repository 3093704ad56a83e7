"""Ray casting against triangle meshes with the names and semantics of Open3D's
``open3d.t.geometry.RaycastingScene``: code written for it runs by changing the import.

Results are :class:`penumbra.Tensor` arrays (dicts of them for the queries that return
several): numpy arrays that also have Open3D's ``.numpy()``, ``.cpu()``, ``.isfinite()``,
``.isinf()`` and ``.isnan()``, so ``ans["t_hit"].numpy()`` works as with Open3D. Inputs may be
numpy arrays, lists or Open3D tensors. Differences from Open3D: float64 (or integer) rays
and points are converted to float32 rather than refused; an index out of range in
``add_triangles`` is a ``ValueError``; the ray test is watertight: a ray aimed exactly at
an edge shared by two triangles, or at a vertex, hits the surface; vertices and ray origins
beyond ±1e12 (where 32-bit ray tests overflow) are refused with a ``ValueError``; and a
result too large for memory raises ``MemoryError`` naming the call.

>>> import numpy as np, penumbra
>>> scene = penumbra.RaycastingScene()
>>> square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)
>>> scene.add_triangles(square, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32))
0
>>> ans = scene.cast_rays(np.array([[0.5, 0.5, 2, 0, 0, -1], [3, 3, 2, 0, 0, -1]]))
>>> ans["t_hit"].numpy().tolist(), ans["t_hit"].isfinite().tolist()
([2.0, inf], [True, False])
>>> ans["geometry_ids"].tolist() == [0, penumbra.INVALID_ID]
True
"""

from __future__ import annotations

import math
from typing import Any, Dict, Sequence, Tuple

import numpy as np

from . import _args, _core
from ._camera import Camera
from ._tensor import Tensor, tensor

#: The geometry and primitive id of a miss (Open3D's ``RaycastingScene.INVALID_ID``).
INVALID_ID: int = _core.INVALID_ID


#: Containers whose order is arbitrary, or that are not sequences of values at all: taken as
#: arrays, their elements would land in an arbitrary order (or become one opaque object).
_UNORDERED = (set, frozenset, dict, type({}.keys()), type({}.values()))


def _numpy(value: Any, call: str, name: str) -> np.ndarray:
    """``value`` as a numpy array; Open3D tensors (anything with a ``numpy()`` method that is
    not an array) are converted through it, after ``cpu()`` when they have one. Sets and
    dicts, at any depth of nested lists, are refused with a TypeError naming ``call`` and
    ``name``."""
    if not isinstance(value, np.ndarray) and callable(getattr(value, "numpy", None)):
        if callable(getattr(value, "cpu", None)):
            value = value.cpu()
        value = value.numpy()
    if _holds_unordered(value):
        raise TypeError(
            f"{call}: {name} must be an array or a list of numbers, not a "
            f"{type(_holds_unordered(value)).__name__} (its order is arbitrary)"
        )
    try:
        return np.asarray(value)
    except MemoryError:
        raise MemoryError(f"{call}: {name} is too large to convert to an array") from None


def _holds_unordered(value: Any, depth: int = 0) -> Any:
    """The first set or dict in ``value`` or its nested lists and tuples (not arrays), or
    None."""
    if isinstance(value, _UNORDERED):
        return value
    if isinstance(value, (list, tuple)) and depth < 4:
        for item in value[:64] if len(value) > 64 else value:
            found = _holds_unordered(item, depth + 1)
            if found is not None:
                return found
    return None


#: Values converted between two chances for Ctrl-C to stop a conversion: about 10 ms.
_PIECE = 1 << 22


def _copy(dst: np.ndarray, src: np.ndarray) -> None:
    """``dst[...] = src`` (converting the dtype), a piece of about :data:`_PIECE` values at a
    time: a KeyboardInterrupt is raised between two pieces, not only after hundreds of
    megabytes of rays are converted."""
    if src.size <= _PIECE or src.ndim == 1:
        dst[...] = src
        return
    per = src.size // src.shape[0]
    step = max(1, _PIECE // max(per, 1))
    for i in range(0, src.shape[0], step):
        if step == 1:
            _copy(dst[i], src[i])
        else:
            dst[i : i + step] = src[i : i + step]


def _rows(value: Any, width: int, call: str, name: str) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """A (..., width) array of reals as C-contiguous float32 rows, and its leading shape."""
    array = _numpy(value, call, name)
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{call}: {name} must be an array of real numbers, not dtype {array.dtype}"
        )
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{call}: {name} must have shape (..., {width}), not {array.shape}")
    lead = array.shape[:-1]
    if array.dtype != np.float32 or not array.flags.c_contiguous:
        try:
            converted = np.empty(array.shape, np.float32)
        except MemoryError:
            gib = array.size * 4 / 2**30
            raise MemoryError(
                f"{call}: {name} needs {gib:.1f} GiB as float32, more memory than this "
                "process can have"
            ) from None
        _copy(converted, array)
        array = converted
    return array.reshape(-1, width), lead


def _shaped(result: Dict[str, np.ndarray], lead: Tuple[int, ...]) -> Dict[str, Tensor]:
    """Each array of ``result`` as a :class:`Tensor` with its first axis reshaped to
    ``lead``."""
    return {k: tensor(v.reshape(lead + v.shape[1:])) for k, v in result.items()}


#: The surface attributes ``cast_rays`` can add.
ATTRIBUTES = ("albedo", "shading_normal", "uv", "object_id")


def _attributes(call: str, attributes: Any, world: Any) -> Tuple[str, ...]:
    """The attribute names asked for, checked: known, and a scene that has them."""
    names = (attributes,) if isinstance(attributes, str) else tuple(attributes)
    for name in names:
        if name not in ATTRIBUTES:
            raise ValueError(f"{call}: unknown attribute {name!r}; expected any of {', '.join(ATTRIBUTES)}")
    if names and world is None:
        raise ValueError(f"{call}: attributes need a scene made by penumbra.Scene.raycasting_scene(), "
                         "which knows the materials")
    return names


def _threads(nthreads: Any, call: str) -> int:
    """Open3D's ``nthreads``: 0 (one per core) to ``MAX_THREADS``."""
    return _args.integer(call, "nthreads", nthreads, 0, _core.MAX_THREADS)


def _samples(nsamples: Any, call: str) -> int:
    n = _args.integer(call, "nsamples", nsamples, 1, 255)
    if n % 2 == 0:
        raise ValueError(f"{call}: nsamples must be odd (a majority vote), not {n}")
    return n


class RaycastingScene:
    """Triangle meshes to cast rays against and to query closest points on.

    ``nthreads`` is the number of worker threads of queries whose own ``nthreads`` is 0 (0:
    one per core this process may use). Queries release the GIL, run on a pool of the
    scene's own (never a global one), and stop within about 0.1 s on Ctrl-C with
    ``KeyboardInterrupt``. Rays are ``(..., 6)`` arrays ``[ox, oy, oz, dx, dy, dz]`` and
    points ``(..., 3)`` arrays, of any leading shape, which the results keep; float64 or
    integer arrays are converted to float32, non-contiguous ones copied. Results are
    :class:`penumbra.Tensor` arrays: numpy arrays with Open3D's ``.numpy()``, ``.cpu()``,
    ``.isfinite()``, ``.isinf()`` and ``.isnan()``.
    """

    __slots__ = ("_core", "_world", "_objects")

    #: The geometry and primitive id of a miss: 4294967295.
    INVALID_ID: int = _core.INVALID_ID

    def __init__(self, nthreads: int = 0) -> None:
        self._core = _core.CoreRaycastingScene(_threads(nthreads, "RaycastingScene"))
        self._world: Any = None
        self._objects = 0

    @classmethod
    def _wrap(cls, core: "_core.CoreRaycastingScene", world: Any = None) -> "RaycastingScene":
        """A scene around ``core``; ``world``, the core of the :class:`penumbra.Scene` it was
        made from (``Scene.raycasting_scene()``), answers ``cast_rays``' ``attributes`` for
        the geometries ``core`` has now, the world's objects (those added later are none)."""
        scene = cls.__new__(cls)
        scene._core = core
        scene._world = world
        scene._objects = core.geometry_count if world is not None else 0
        return scene

    def __repr__(self) -> str:
        c = self._core
        return f"<penumbra.RaycastingScene: {c.geometry_count} geometries, {c.triangle_count} triangles>"

    def add_triangles(self, vertex_positions: Any, triangle_indices: Any = None) -> int:
        """Adds a mesh: ``vertex_positions`` (N, 3) float32 and ``triangle_indices`` (M, 3)
        uint32 (other real or integer dtypes are converted). Returns its geometry id: 0 for
        the first mesh, then 1, 2, ... . Primitive ids in results index ``triangle_indices``.

        Like Open3D, also takes an ``open3d.t.geometry.TriangleMesh`` alone (its
        ``vertex.positions`` and ``triangle.indices``). An index out of range, or a vertex
        that is not finite, raises ``ValueError`` and adds nothing.
        """
        if triangle_indices is None:
            mesh = vertex_positions
            try:
                vertex_positions = mesh.vertex.positions
                triangle_indices = mesh.triangle.indices
            except AttributeError:
                raise TypeError(
                    "add_triangles takes (vertex_positions, triangle_indices) or an "
                    "open3d.t.geometry.TriangleMesh"
                ) from None
        call = "add_triangles"
        vertices, _ = _rows(vertex_positions, 3, call, "vertex_positions")
        indices = _numpy(triangle_indices, call, "triangle_indices")
        if indices.dtype.kind not in "iu":
            raise TypeError(
                f"{call}: triangle_indices must be integers, not dtype {indices.dtype}"
            )
        if indices.ndim != 2 or indices.shape[1] != 3:
            raise ValueError(
                f"{call}: triangle_indices must have shape (M, 3), not {indices.shape}"
            )
        if indices.size and (indices.min() < 0 or indices.max() > INVALID_ID):
            raise ValueError(
                f"{call}: triangle_indices must be in [0, {len(vertices)}), "
                f"not from {indices.min()} to {indices.max()}"
            )
        indices = np.ascontiguousarray(indices, dtype=np.uint32)
        return self._core.add_triangles(vertices, indices)

    def add_instance(self, geometry_id: Any, transform: Any) -> int:
        """Places geometry ``geometry_id`` by ``transform``, a (4, 4) row-major
        object-to-world matrix (numpy array of any real dtype, nested list or Open3D tensor)
        whose last row is ``[0, 0, 0, 1]``; mirrors and non-uniform scales are allowed.
        Returns the placement's geometry id, which the queries report for its triangles;
        its primitive ids are those of ``geometry_id``'s triangles.

        An extension of Open3D's API (Open3D has no instances). The triangles are not
        copied: the geometry is built once into a tree of its own and each placement (about
        150 bytes) enters it through its inverse; answers are the copied triangles' with
        ``t`` and barycentrics within 1e-5. A ``geometry_id`` that is not a
        geometry, a matrix entry that is not finite, a last row that is not
        ``[0, 0, 0, 1]``, a matrix that cannot be inverted, or a placed vertex beyond
        ±1e12 raises ``ValueError`` and adds nothing.
        """
        call = "add_instance"
        geometry_id = _args.integer(call, "geometry_id", geometry_id, 0, _args.U32_MAX)
        matrix = _matrix(transform, (4, 4), call, "transform")
        return self._core.add_instance(geometry_id, matrix)

    def set_transform(self, geometry_id: Any, transform: Any) -> None:
        """Moves placement ``geometry_id`` (an id :meth:`add_instance` returned) to
        ``transform``, a (4, 4) row-major object-to-world matrix taken as
        :meth:`add_instance` takes it. It replaces the placement's transform (it does not
        compose with it); for a placement of a placement, ``transform`` places the placed
        geometry as it did in :meth:`add_instance`. Nothing is built again but the top level
        (on the next query), and the queries then answer as a fresh :meth:`add_instance`
        with that transform would. Placements made on this one keep their place until they
        are moved themselves. An id that is no placement (a geometry of ``add_triangles``, or
        an object of the scene ``raycasting_scene()`` made, whose surface attributes come from
        that scene) and a matrix :meth:`add_instance` would refuse raise ``ValueError`` and
        change nothing."""
        call = "set_transform"
        geometry_id = _args.integer(call, "geometry_id", geometry_id, 0, _args.U32_MAX)
        if geometry_id < self._objects:
            raise ValueError(
                f"{call}: geometry_id: geometry {geometry_id} is an object of the scene "
                "raycasting_scene() made (its surface attributes come from that scene): only "
                "placements add_instance returned move"
            )
        matrix = _matrix(transform, (4, 4), call, "transform")
        self._core.set_transform(geometry_id, matrix)

    def cast_rays(
        self,
        rays: Any,
        nthreads: int = 0,
        tnear: float = 0.0,
        tfar: float = math.inf,
        attributes: Sequence[str] = (),
    ) -> Dict[str, Tensor]:
        """The closest hit (``tnear <= t <= tfar``; Open3D's ``cast_rays`` has no bounds and
        takes t >= 0, penumbra's defaults) of each ray: a dict of :class:`Tensor` arrays, ``t_hit``
        (...) float32 in units of
        the direction's length, inf on a miss; ``geometry_ids`` and ``primitive_ids`` (...)
        uint32, ``INVALID_ID`` on a miss; ``primitive_uvs`` (..., 2) float32, the weights of
        the triangle's vertices 1 and 2; ``primitive_normals`` (..., 3) float32, the unit
        normal e1 x e2 of the triangle hit (not flipped toward the ray; zero on a miss).

        Rays shaped (height, width, 6), as ``create_rays_pinhole`` makes them, are traced as
        an image: square packets of neighbouring rays, the same results, faster.

        ``attributes`` (penumbra's extension, for a scene made by
        :meth:`penumbra.Scene.raycasting_scene`) adds what the renderer sees at each hit, for
        sensor models such as LiDAR intensity: any of ``albedo`` (..., 3), the diffuse
        reflectance k_d times the texture and vertex colour; ``shading_normal`` (..., 3), the
        interpolated vertex normal of a smooth triangle, else the geometric one, as the mesh
        orients it; ``uv`` (..., 2), the texture coordinates; ``object_id`` (...) uint32, the
        object's id (``geometry_ids``). All zero (``INVALID_ID``) on a miss, and on a geometry
        added after ``raycasting_scene()`` (``add_triangles``, ``add_instance``), which is no
        object of the scene."""
        call = "cast_rays"
        wanted = _attributes(call, attributes, self._world)
        r, lead = _rows(rays, 6, call, "rays")
        row_length = lead[-1] if len(lead) >= 2 else 0
        near, far = _real(call, "tnear", tnear), _real(call, "tfar", tfar)
        hits = self._core.cast_rays(r, _threads(nthreads, call), row_length, near, far)
        if wanted:
            g, p = hits["geometry_ids"], hits["primitive_ids"]
            # The scene's objects are its first geometries; the rest have no object.
            g = np.where(g < self._objects, g, np.uint32(INVALID_ID)).astype(np.uint32)
            found = {"object_id": g}
            if set(wanted) - {"object_id"}:  # the surface's own, looked up in the scene
                found.update(self._world.surface_attributes(
                    g.reshape(-1, 1), p.reshape(-1, 1), hits["primitive_uvs"]))
            hits.update({k: found[k] for k in wanted})
        return _shaped(hits, lead)

    def test_occlusions(
        self, rays: Any, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0
    ) -> Tensor:
        """Whether each ray meets a triangle with ``tnear <= t <= tfar``: a (...) bool
        array."""
        call = "test_occlusions"
        r, lead = _rows(rays, 6, call, "rays")
        near, far = _real(call, "tnear", tnear), _real(call, "tfar", tfar)
        hit = self._core.test_occlusions(r, near, far, _threads(nthreads, call))
        return tensor(hit.reshape(lead))

    def count_intersections(
        self, rays: Any, nthreads: int = 0, tnear: float = 0.0, tfar: float = math.inf
    ) -> Tensor:
        """How many times each ray crosses the surface with ``tnear <= t <= tfar`` (Open3D
        counts t >= 0, penumbra's defaults; the bounds are penumbra's extension): a (...)
        int32 array. A ray through an edge shared by two triangles, or through a vertex,
        crosses once; from outside a closed mesh the count is even."""
        call = "count_intersections"
        r, lead = _rows(rays, 6, call, "rays")
        near, far = _real(call, "tnear", tnear), _real(call, "tfar", tfar)
        counts = self._core.count_intersections(r, _threads(nthreads, call), near, far)
        return tensor(counts.reshape(lead))

    def list_intersections(self, rays: Any, nthreads: int = 0) -> Dict[str, Tensor]:
        """Every crossing of every ray, as ``count_intersections`` counts them, sorted by t
        within each ray, as Open3D lists them: ``ray_splits`` (n + 1,) uint32 (the hits of
        ray i are ``ray_splits[i]:ray_splits[i + 1]``, rays numbered in C order of the
        leading shape), and per hit ``ray_ids``, ``t_hit``, ``geometry_ids``,
        ``primitive_ids`` and ``primitive_uvs`` (k, 2)."""
        call = "list_intersections"
        r, _ = _rows(rays, 6, call, "rays")
        listed = self._core.list_intersections(r, _threads(nthreads, call))
        return {k: tensor(v) for k, v in listed.items()}

    def compute_closest_points(self, query_points: Any, nthreads: int = 0) -> Dict[str, Tensor]:
        """The closest surface point of each query point: a dict of ``points`` (..., 3),
        ``geometry_ids``, ``primitive_ids`` (...) uint32, ``primitive_uvs`` (..., 2) and
        ``primitive_normals`` (..., 3). An empty scene gives NaN points and INVALID_ID."""
        call = "compute_closest_points"
        p, lead = _rows(query_points, 3, call, "query_points")
        return _shaped(self._core.compute_closest_points(p, _threads(nthreads, call)), lead)

    def compute_distance(self, query_points: Any, nthreads: int = 0) -> Tensor:
        """The distance of each query point to the surface: (...) float32 (inf for an empty
        scene)."""
        call = "compute_distance"
        p, lead = _rows(query_points, 3, call, "query_points")
        return tensor(self._core.compute_distance(p, _threads(nthreads, call)).reshape(lead))

    def compute_signed_distance(
        self, query_points: Any, nthreads: int = 0, nsamples: int = 1
    ) -> Tensor:
        """The distance to the surface, negative inside (as ``compute_occupancy`` decides,
        with ``nsamples`` rays): (...) float32. Meaningful for closed meshes."""
        call = "compute_signed_distance"
        p, lead = _rows(query_points, 3, call, "query_points")
        n = _samples(nsamples, call)
        d = self._core.compute_signed_distance(p, _threads(nthreads, call), n)
        return tensor(d.reshape(lead))

    def compute_occupancy(
        self, query_points: Any, nthreads: int = 0, nsamples: int = 1
    ) -> Tensor:
        """1.0 for points inside the closed surface, 0.0 outside: (...) float32, as Open3D.
        A point is inside when most of ``nsamples`` (odd) rays from it cross the surface an
        odd number of times; crossings are counted exactly, so 1 is enough for a closed
        mesh."""
        call = "compute_occupancy"
        p, lead = _rows(query_points, 3, call, "query_points")
        n = _samples(nsamples, call)
        occ = self._core.compute_occupancy(p, _threads(nthreads, call), n)
        return tensor(occ.reshape(lead))

    @staticmethod
    def create_rays_camera(camera: Camera, width_px: int, height_px: int) -> Tensor:
        """The exact rays of any :class:`penumbra.Camera` (each lens model of the scene
        format), one per pixel center: (height_px, width_px, 6) float32 origin and unit
        direction, as the renderer makes the rays of its one-ray AOVs, so ``t_hit`` is the
        ``depth`` AOV. ``K`` counts pixels of this width and height. Where the lens model sees
        nothing (beyond a distortion's valid radius or a fisheye's ``max_angle``) the row is
        NaN, which ``cast_rays`` reports as a miss. A thin lens's rays leave its centre."""
        call = "create_rays_camera"
        if not isinstance(camera, Camera):
            raise TypeError(f"{call}: camera must be a penumbra.Camera, "
                            f"not {type(camera).__name__}")
        w = _args.size(call, "width_px", width_px)
        h = _args.size(call, "height_px", height_px)
        return tensor(_core.camera_rays(camera._args(), w, h))

    @staticmethod
    def create_rays_pinhole(*args: Any, **kwargs: Any) -> Tensor:
        """The rays of a pinhole camera, one per pixel center: (height_px, width_px, 6)
        float32, as Open3D makes them, in either of its forms::

            create_rays_pinhole(intrinsic_matrix, extrinsic_matrix, width_px, height_px)
            create_rays_pinhole(fov_deg, center, eye, up, width_px, height_px)

        ``intrinsic_matrix`` is 3x3 ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`` and
        ``extrinsic_matrix`` 4x4 world-to-camera. Ray ``[y, x]`` starts at the camera center
        with direction ``R^T K^-1 (x + 0.5, y + 0.5, 1)`` (not normalized: its depth along
        the optical axis is 1, so ``t_hit`` is the depth). In the second form the camera at
        ``eye`` looks at ``center`` with a horizontal field of view of ``fov_deg`` degrees
        and the row index grows toward ``up``."""
        return tensor(_pinhole(*args, **kwargs))


def _pinhole(*args: Any, **kwargs: Any) -> np.ndarray:
    """Both forms of ``create_rays_pinhole``, told apart by their argument names or count."""
    fov_names = ("fov_deg", "center", "eye", "up", "width_px", "height_px")
    matrix_names = ("intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px")
    use_fov = "fov_deg" in kwargs or len(args) + len(kwargs) == 6
    names = fov_names if use_fov else matrix_names
    if len(args) > len(names):
        raise TypeError(f"create_rays_pinhole takes at most {len(names)} arguments")
    bound = dict(zip(names, args))
    for key, value in kwargs.items():
        if key not in names or key in bound:
            raise TypeError(f"create_rays_pinhole: unexpected or repeated argument {key!r}")
        bound[key] = value
    missing = [n for n in names if n not in bound]
    if missing:
        raise TypeError(f"create_rays_pinhole: missing arguments {missing}")
    call = "create_rays_pinhole"
    w = _args.integer(call, "width_px", bound["width_px"], 0, _args.U32_MAX)
    h = _args.integer(call, "height_px", bound["height_px"], 0, _args.U32_MAX)
    if use_fov:
        vec = [_matrix(bound[n], (3,), call, n) for n in ("center", "eye", "up")]
        fov = _real(call, "fov_deg", bound["fov_deg"])
        return _core.create_rays_pinhole_fov(fov, *vec, w, h)
    k = _matrix(bound["intrinsic_matrix"], (3, 3), call, "intrinsic_matrix")
    e = _matrix(bound["extrinsic_matrix"], (4, 4), call, "extrinsic_matrix")
    return _core.create_rays_pinhole(k, e, w, h)


def _matrix(value: Any, shape: Tuple[int, ...], call: str, name: str) -> Any:
    """A vector or matrix of real numbers of exactly ``shape`` (an array, nested lists or an
    Open3D tensor) as nested lists of floats."""
    array = _numpy(value, call, name)
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{call}: {name} must be an array of real numbers, not dtype {array.dtype}"
        )
    if array.shape != shape:
        raise ValueError(f"{call}: {name} must have shape {shape}, not {array.shape}")
    return array.astype(np.float64).tolist()


def _real(call: str, name: str, value: Any) -> float:
    """:func:`_args.real`, taking a 0-d array (a scalar tensor's ``numpy()``) as its value."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    return _args.real(call, name, value)
