"""Scenes: loading them (from a file, text or a dict) and rendering them to numpy arrays."""

from __future__ import annotations

import json
import os
import sys
import warnings
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np

from . import _args, _core, _display
from ._camera import Camera
from ._pack import PackedScene
from ._raycast import RaycastingScene, _matrix
from ._scene_dict import _scene_error, _to_json, _with_placements

SceneError = _core.SceneError

#: The AOV names ``Scene.render(aovs=...)`` takes.
AOV_NAMES: Tuple[str, ...] = tuple(_core.AOV_NAMES)

PathLike = Union[str, "os.PathLike[str]"]
Progress = Union[None, bool, Callable[[int, int], Any]]


#: What ``progress=True`` says when tqdm is missing.
NO_TQDM = (
    "progress=True needs tqdm, which is not installed: `pip install tqdm` (or install "
    "penumbra with its extra, `pip install .[progress]`); no progress bar is shown"
)


def progress_bar(stacklevel: int, **options: Any) -> Any:
    """A tqdm bar (``tqdm.auto``: a widget in a notebook) with ``options``, or None with a
    warning naming the install command when tqdm is missing (``progress=True`` then shows no
    bar, and says so; the warning points at the caller ``stacklevel`` frames up from the
    caller of this function). The bar is drawn on stderr when it is a terminal, and in
    IPython or a notebook; to a file or a pipe it draws nothing, as tqdm's ``disable=None``
    does, since there each redraw would be one more line."""
    try:
        from tqdm.auto import tqdm
    except ImportError:
        warnings.warn(NO_TQDM, RuntimeWarning, stacklevel=stacklevel + 1)
        return None
    ipython = sys.modules.get("IPython")
    shell = ipython is not None and ipython.get_ipython() is not None
    return tqdm(disable=False if shell else None, **options)


class _Bar:
    """A tqdm progress bar fed with (pixels done, pixels in all); nothing (after a warning)
    when tqdm is not installed."""

    def __init__(self) -> None:
        # _Bar() <- Scene.render <- the caller's line
        options = dict(total=0, unit="px", unit_scale=True, desc="render", leave=False)
        self._bar = progress_bar(stacklevel=3, **options)

    def __call__(self, done: int, total: int) -> None:
        if self._bar is not None:
            self._bar.total = total
            self._bar.update(done - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


class Scene:
    """A built scene: its world (geometry with its BVH, materials, textures, lights and every
    camera) and the scene file's default render settings. Make one with :func:`load`,
    :func:`loads` or :func:`load_dict`. The world is built once; every :meth:`render` call
    reuses it, whatever camera, size, sampler or seed it asks for. :meth:`set_transform`
    moves an object.
    """

    __slots__ = ("_core",)

    def __init__(self, core: "_core.CoreScene") -> None:
        self._core = core

    @property
    def cameras(self) -> List[str]:
        """The names of the scene's cameras, in file order; the first is the default."""
        return self._core.cameras

    def camera(self, name: Optional[str] = None) -> Camera:
        """The scene's camera ``name`` (None: the first, the default) as a :class:`Camera`:
        the camera ``render(camera=name)`` uses, number for number (a camera with keys or a
        path gives its first frame). Raises ``ValueError`` naming the scene's cameras for a
        name it lacks."""
        if name is not None and not isinstance(name, str):
            raise TypeError(f"Scene.camera: name must be a camera name, not {type(name).__name__}")
        got = self._core.camera(name)
        if got is None:
            raise ValueError(
                f"unknown camera {name!r} (the scene's cameras: {', '.join(self.cameras)})"
            )
        p, l, u, fov = got
        return Camera(position=p, look_at=l, up=u, fov=fov)

    def camera_path(self, name: str) -> Optional[Dict[int, Camera]]:
        """The cameras of the camera ``name`` with keys or a path (``[[cameras.NAME.keys]]``,
        ``path = { type = "orbit", ... }``), by frame, first to last: the cameras the command
        line renders for its frames. None for a still camera or a name the scene lacks; raises
        ``ValueError`` for a path with K, a lens model or an aperture (render it by name)."""
        got = self._core.camera_path(name)
        if got is None:
            return None
        first, cameras = got
        return {
            first + k: Camera(position=p, look_at=l, up=u, fov=fov)
            for k, (p, l, u, fov) in enumerate(cameras)
        }

    @property
    def settings(self) -> Dict[str, Any]:
        """The file's default render settings: ``width``, ``height``, ``spp``, ``sampler``,
        ``light_samples`` (None: each light's own), ``seed`` and ``alpha``."""
        return self._core.settings

    @property
    def stats(self) -> Dict[str, Any]:
        """Counts (``triangles``, as rays see them: each instance counts its mesh's;
        ``unique_triangles``, those in memory: each instanced mesh once; ``objects``, every
        copy of an ``instances`` object counted; ``meshes`` built once and placed by
        ``instances``, the ``instances`` placing them, ``lights``, ``materials``,
        ``textures``, ``cameras``, ``bvh_nodes``) and times (``load_seconds``,
        ``bvh_build_seconds``)."""
        return self._core.stats

    @property
    def object_ids(self) -> List[range]:
        """For each entry of the scene's ``objects``, in file order, the object ids it added
        (the ``object_id`` AOV and the geometry ids of :meth:`raycasting_scene`): one each,
        and one per copy for ``type = "instances"``, so ``object_ids[i][k]`` is copy ``k`` of
        entry ``i``."""
        return [range(start, end) for start, end in self._core.object_ids]

    @property
    def objects(self) -> List[Dict[str, Any]]:
        """Each entry of the scene's ``objects``, in file order, as ``penumbra render --meta``
        records it: ``key`` (``"objects[3]"``), ``name`` (when the entry has one), ``type``
        (and the file of a mesh: ``"mesh models/bunny.obj"``) and ``ids``, the ``[first,
        end)`` object ids it added (see :attr:`object_ids`): what the values of an
        ``object_id`` AOV name."""
        return list(json.loads(self._core.objects))

    @property
    def gamma(self) -> Optional[float]:
        """The file's ``film.gamma``: 8-bit images (PNG, JPEG) encode ``c ** (1 / gamma)``;
        None for the sRGB curve. ``penumbra.write_image(path, image, gamma=scene.gamma)``
        writes the bytes ``penumbra render`` writes, as ``render_views`` does."""
        return self._core.gamma

    @property
    def scene_digest(self) -> str:
        """16 hex digits identifying the scene by content: 64-bit FNV-1a of the scene text
        and the bytes of every file its build read (meshes, material libraries, images), the
        ``scene_digest`` that ``penumbra render --meta`` records for the same file."""
        return self._core.scene_digest

    @property
    def files(self) -> List[str]:
        """The files the build read besides the scene file (meshes, MTL libraries, images),
        as the scene resolved their paths, sorted."""
        return [os.fspath(p) for p in self._core.files]

    def pack(self) -> PackedScene:
        """The scene file's text with the bytes of every file in :attr:`files` as the load
        read them (a loaded scene is a snapshot: files edited on disk since change nothing):
        what :func:`load_pack` builds the same scene from in another process or on another
        machine, without those files."""
        return PackedScene(self._core.pack())

    def __reduce__(self):
        # A scene pickles as its pack and is built again when unpickled.
        return (load_pack, (self.pack(),))

    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]:
        """The world's bounding box, ``((min x, y, z), (max x, y, z))``."""
        lo, hi = self._core.bounds
        return tuple(lo), tuple(hi)

    def _repr_html_(self) -> str:
        # Jupyter's view of a scene: its counts, bounds and a small preview render.
        return _display.summary_html(self)

    def __repr__(self) -> str:
        s = self.stats
        return f"<penumbra.Scene: {s['triangles']} triangles, {s['lights']} lights, cameras {self.cameras}>"

    def set_transform(
        self, obj: Union[int, str], matrix: Any, index: Optional[int] = None, threads: int = 0
    ) -> None:
        """Moves object ``obj`` (its position in the file's ``objects``, as :attr:`objects`
        lists them, or its ``name``) to ``matrix``, a (4, 4) row-major object-to-world matrix whose last row is
        ``[0, 0, 0, 1]`` (an array, nested lists or an Open3D tensor). It replaces the
        object's ``translate``, ``rotate`` and ``scale`` (it does not compose with them), as
        the object's ``matrix`` key would in the file. For an ``instances`` object, ``index``
        picks one of its inline placements: ``matrix`` replaces that copy's placement, which
        stays under the object's own transform, as in the file; without ``index`` the whole
        object moves, every copy with it.

        The next :meth:`render` renders the moved scene byte for byte as a fresh load of the
        file with that transform does, and :meth:`pack`, :attr:`scene_digest` and the
        records of :meth:`record` carry the move (a move of the same object or copy replaces
        the last one). The scene is built again, with ``threads`` workers (0: all cores),
        from the bytes its first build read: nothing is read from disk, and a move costs
        about what the load cost without the reading (see docs/python.md). Renders and
        ray-casting scenes made before keep the scene as it was.

        Raises :class:`SceneError` at the object's key for an ``obj`` (a position or a name)
        or ``index`` the scene lacks, a matrix that is not finite, not affine or cannot be inverted, or an
        ``index`` into placements kept in a ``.npy`` file; the scene is then unchanged.
        """
        call = "set_transform"
        if not isinstance(obj, str):
            obj = _args.integer(call, "obj", obj, 0, _args.U32_MAX)
        index = _args.optional_integer(call, "index", index, 0, _args.U32_MAX)
        rows = _matrix(matrix, (4, 4), f"Scene.{call}", "matrix")
        threads = _args.threads(call, threads)
        self._core = self._core.moved(obj, rows, index, threads)

    def raycasting_scene(self) -> RaycastingScene:
        """A :class:`RaycastingScene` of the scene's triangles (spheres tessellated as they
        are rendered), one geometry per object: geometry id = the object's id (its index in
        the file's ``objects``, where every copy of an ``instances`` object counts as one
        object), primitive ids count the object's triangles in order (a copy's: its mesh's).
        Instanced meshes are placed as they are rendered, each mesh's tree shared by all its
        placements (nothing is copied). Its ``cast_rays`` also gives the surface's
        ``attributes`` (albedo, shading normal, uv, object id). Its queries use
        every core unless they pass ``nthreads``."""
        return RaycastingScene._wrap(self._core.raycasting_scene(), self._core)

    def render(
        self,
        camera: Union[None, str, Camera] = None,
        spp: Optional[int] = None,
        sampler: Optional[str] = None,
        light_samples: Optional[int] = None,
        seed: Optional[int] = None,
        width: Optional[int] = None,
        height: Optional[int] = None,
        region: Optional[Tuple[int, int, int, int]] = None,
        threads: int = 0,
        progress: Progress = None,
        aovs: Union[str, Iterable[str]] = (),
        stats: Optional[Dict[str, Any]] = None,
        passes: Optional[Callable[[int, np.ndarray], Any]] = None,
        alpha: Optional[bool] = None,
    ) -> Union[np.ndarray, Tuple[np.ndarray, Dict[str, np.ndarray]]]:
        """Render the scene and return a C-contiguous float32 array of shape
        (height, width, 3): linear RGB, row 0 at the top, the values the command line writes
        to EXR and PFM files, bit for bit; (height, width, 4) with ``alpha``.

        Every argument left as None keeps the scene file's setting:

        - ``camera``: a camera name of the scene, or a :class:`Camera`.
        - ``spp``: samples per pixel, a perfect square (1, 4, 9, ...).
        - ``sampler``: ``"center"``, ``"grid"``, ``"rgss"`` or ``"jittered"``; without
          ``spp`` it takes its own default count (1 for center, else the file's samples).
        - ``light_samples``: N, for N×N samples of every area light.
        - ``seed``: the seed of jittered pixel and light samples.
        - ``width``, ``height``: the film size in pixels.
        - ``alpha``: coverage alpha (the file's ``film.alpha``, the command line's
          ``--alpha``, Blender's transparent film). The result is premultiplied RGBA: channel
          3 is the fraction of each pixel's samples whose camera ray hit geometry, and what
          camera rays miss (the background, a visible environment) adds nothing to the
          colour; environments still light the scene. ``write_image`` writes it as the
          command line does (PNG straight alpha, EXR premultiplied).
        - ``region``: ``(x0, x1, y0, y1)``, render only the pixels [x0, x1) × [y0, y1) of the
          film; the result has the region's size and its pixels equal the full image's.
        - ``threads``: worker threads of a pool of the render's own (0: one per core).
          The image does not depend on it.
        - ``progress``: ``True`` for a tqdm bar on stderr when it is a terminal, or in a
          notebook; none to a file or a pipe, where each redraw would be a line (tqdm is an
          optional dependency: ``pip install tqdm``; without it, a ``RuntimeWarning`` says
          so and no bar shows),
          or a callable receiving (pixels done, pixels in all), called from this thread, or
          ``"notebook"``: in Jupyter or IPython, render progressively (as with ``passes``)
          and show one image that each pass replaces in place, the final image last.
        - ``aovs``: names from :data:`AOV_NAMES`. When given, the result is a tuple
          ``(image, {name: array})`` instead of the image alone; see the Python docs for what
          each AOV holds and how it is filtered.
        - ``stats``: a dict the render fills with its counts and time: ``camera_rays``,
          ``shadow_rays``, ``seconds``, ``rays_per_second`` and ``threads``.
        - ``passes``: render progressively (the command line's ``--progressive``): every
          pixel's samples are taken in passes over the whole image, 1, 2, 4, ... samples, and
          after each pass but the last ``passes(samples, image)`` is called from this thread
          with the image so far (each pixel's mean over its first ``samples`` samples). The
          first call has ``samples`` 0: the preview, the first sample of every second row,
          each shown on the row below too, after half the work of one sample. The result is
          bit for bit the image of a render without ``passes``. Not with ``aovs``.

        The GIL is released while rendering. Ctrl-C stops the render within about 0.1 s and
        raises ``KeyboardInterrupt``. Bad settings raise ``ValueError``.
        """
        call = "Scene.render"
        if isinstance(aovs, str):
            aovs = (aovs,)
        names = [str(a) for a in aovs]
        # A name, or an explicit camera as its (position, look_at, up, fov).
        view: Union[None, str, tuple] = camera
        if isinstance(camera, Camera):
            view = camera._args()
        elif camera is not None and not isinstance(camera, str):
            raise TypeError(
                f"{call}: camera must be a camera name or a penumbra.Camera, "
                f"not {type(camera).__name__}"
            )
        if sampler is not None and not isinstance(sampler, str):
            raise TypeError(f"{call}: sampler must be a name, not {type(sampler).__name__}")
        u32 = _args.U32_MAX
        spp = _args.optional_integer(call, "spp", spp, 0, u32)
        light_samples = _args.optional_integer(call, "light_samples", light_samples, 0, u32)
        seed = _args.optional_integer(call, "seed", seed, 0, _args.U64_MAX)
        width = _args.optional_integer(call, "width", width, 0, u32)
        height = _args.optional_integer(call, "height", height, 0, u32)
        if alpha is not None and not isinstance(alpha, bool):
            raise TypeError(f"{call}: alpha must be True or False, not {type(alpha).__name__}")
        if region is not None:
            corners = _args.sequence(call, "region (x0, x1, y0, y1)", region, 4)
            region = tuple(
                _args.integer(call, f"region {n}", v, 0, u32)
                for n, v in zip(("x0", "x1", "y0", "y1"), corners)
            )
        threads = _args.threads(call, threads)
        bar = None
        callback = None
        live = None
        if isinstance(progress, str) and progress == "notebook":
            if names:
                raise ValueError(f'{call}: progress="notebook" (progressive) does not give aovs')
            live = _display.LiveImage()
            user_passes = passes

            def passes(samples: int, image: np.ndarray) -> None:
                live.show(image)
                if user_passes is not None:
                    user_passes(samples, image)

        elif progress is True:
            bar = _Bar()
            callback = bar
        elif callable(progress):
            callback = progress
        elif progress not in (None, False):
            raise TypeError(
                'progress must be True, False, None, "notebook" or a callable (done, total)'
            )
        if passes is not None and not callable(passes):
            raise TypeError(f"{call}: passes must be a callable (samples, image)")
        if passes is not None and names:
            raise ValueError(f"{call}: passes (a progressive render) does not give aovs")
        try:
            result = self._core.render(
                camera=view,
                spp=spp,
                sampler=sampler,
                light_samples=light_samples,
                seed=seed,
                width=width,
                height=height,
                alpha=alpha,
                region=region,
                threads=threads,
                progress=callback,
                passes=passes,
                aovs=names,
                stats=stats,
            )
            if live is not None:
                live.show(result)
            return result
        finally:
            if bar is not None:
                bar.close()


def load(path: PathLike, threads: int = 0, allow_paths: Sequence[PathLike] = ()) -> Scene:
    """Load and build the ``.toml`` or ``.json`` scene file at ``path`` (meshes and textures
    included), with ``threads`` workers for reading meshes and building the BVH (0: all
    cores). The GIL is released meanwhile.

    A scene file reads only files in its own folder and below, and a model (OBJ, MTL, PLY,
    glTF) only files in its own folder and below; ``allow_paths`` (folders, like the CLI's
    ``--allow-path``) widens that for every file of the scene. A file named outside is a
    :class:`SceneError` naming the file, the reference and the rule.

    A bare ``.obj`` or ``.ply`` mesh is a scene too, as ``penumbra render model.obj`` takes
    it: the mesh (with its MTL materials, or the default one), a camera framing its bounds
    and the default light rig, film 800×600 (see "A model as a scene" in the scene format
    reference).

    Raises :class:`SceneError` (a ``ValueError``) for a mistake in the scene, located by its
    ``file``, ``line``, ``column`` and ``key``; ``OSError`` (``FileNotFoundError``, ...) when
    the file cannot be read.
    """
    threads = _args.threads("load", threads)
    return Scene(_core.load(os.fspath(path), threads, _allow_paths(allow_paths)))


def loads(
    text: str,
    format: str = "toml",
    base_dir: PathLike = ".",
    threads: int = 0,
    allow_paths: Sequence[PathLike] = (),
) -> Scene:
    """Load and build a scene from its text in ``format`` (``"toml"`` or ``"json"``).
    Relative paths in it (meshes, textures) resolve against ``base_dir``, the folder it reads
    in (and below, and in ``allow_paths``, as for :func:`load`). Errors as in :func:`load`,
    with ``file`` ``"<string>"``.
    """
    threads = _args.threads("loads", threads)
    allowed = _allow_paths(allow_paths)
    return Scene(_core.loads(text, format, os.fspath(base_dir), "<string>", threads, allowed))


def load_dict(
    scene: Mapping[str, Any],
    base_dir: PathLike = ".",
    threads: int = 0,
    allow_paths: Sequence[PathLike] = (),
) -> Scene:
    """Load and build a scene from a dict with the scene file's schema (the JSON form of a
    scene file, Mitsuba's ``load_dict`` habit). Tuples and numpy arrays are taken as lists;
    the ``transforms`` of a ``{"type": "instances", "file": ...}`` object may also be an
    (N, 4, 4) array of row-major object-to-world matrices, one per copy (besides a list of
    ``{"translate", "rotate", "scale", "material"}`` or ``{"matrix"}`` dicts, or the path
    of a ``.npy`` file of such matrices). Errors as in :func:`load`, with ``file``
    ``"<dict>"``; their ``key`` names the entry, such as ``objects[2].material`` (or
    ``objects[1].transforms`` for an array of the wrong shape). Files it names are read in
    ``base_dir`` and below, and in ``allow_paths``, as for :func:`load`.

    >>> scene = load_dict({
    ...     "film": {"width": 4, "height": 4},
    ...     "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
    ...     "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
    ... })
    >>> scene.stats["objects"]
    1
    """
    threads = _args.threads("load_dict", threads)
    problem = _args.scene_dict_problem(scene)
    if problem is not None:
        # JSON has no NaN, infinity, set or cycle: reported at its key, as a file's would be.
        key, what = problem
        raise _scene_error(f"<dict>: {key}: {what}", key, "bad_value")
    allowed = _allow_paths(allow_paths)
    text = json.dumps(_with_placements(scene), indent=1, default=_to_json)
    return Scene(_core.loads(text, "json", os.fspath(base_dir), "<dict>", threads, allowed))


def _allow_paths(paths: Sequence[PathLike]) -> List[str]:
    """The ``allow_paths`` argument as a list of paths: one path alone is taken as a list of
    one, as ``--allow-path DIR`` once is."""
    if isinstance(paths, (str, bytes, os.PathLike)):
        paths = [paths]
    return [os.fsdecode(p) for p in paths]


def load_pack(pack: PackedScene, threads: int = 0) -> Scene:
    """Build the scene of a :class:`PackedScene` (from :meth:`Scene.pack`), with ``threads``
    workers (0: all cores). Its meshes and images come from the pack: nothing is read from
    disk. Errors as in :func:`load`.

    >>> import pickle
    >>> scene = load_dict({
    ...     "film": {"width": 4, "height": 4},
    ...     "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
    ...     "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
    ... })
    >>> copy = pickle.loads(pickle.dumps(scene))
    >>> copy.cameras == scene.cameras
    True
    """
    if not isinstance(pack, PackedScene):
        raise TypeError(f"load_pack takes a penumbra.PackedScene, not {type(pack).__name__}")
    return Scene(_core.load_pack(pack._data, _args.threads("load_pack", threads)))
