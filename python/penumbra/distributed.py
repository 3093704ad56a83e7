"""Rendering on a Ray cluster: one big frame as tiles (:func:`render_frame`), or many views
(:func:`render_views`), exact and restartable. Needs Ray (``pip install .[ray]``); the rest of
the package does not import it.

- **Exact.** A pixel depends only on the scene, the settings and its place in the full frame,
  so the tiles stitch into the bytes ``scene.render(...)`` gives in one process, and a view
  rendered on any node is the image rendered locally.
- **The scene travels once.** It is packed (its text and every mesh, MTL and image file it
  reads, :meth:`penumbra.Scene.pack`) and ``ray.put`` once per driver; workers need no shared
  file system. Each worker process builds a scene's world once and keeps it for its next
  tasks (a per-process cache keyed by the pack's digest; at most :data:`CACHED_WORLDS`).
- **Spread.** Tasks are scheduled with Ray's ``SPREAD`` strategy: tiles and views go to
  every node, not first to the node that holds the scene.
- **Threads.** A task renders with as many threads as CPUs Ray gave it (``num_cpus``, 1 by
  default), never more, so workers do not oversubscribe their node.
- **Faults.** A task whose worker dies is retried by Ray (up to :data:`MAX_RETRIES` times)
  and gives the same bytes. Images are written by the driver, atomically, each with its
  record; a view whose image and record (the settings it was made with) match what it would
  render now is skipped unless ``force``. Ctrl-C cancels the outstanding tasks.

Call ``ray.init(...)`` first (or let :func:`connect` do it).
"""

from __future__ import annotations

from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import ray

from . import _args
from ._cluster import check_num_cpus, connect
from ._ray_tasks import CACHED_WORLDS, MAX_RETRIES, render_task, ship
from ._ray_wait import gather
from ._scene import Scene
from ._view_files import write_view
from .record import done, record
from .views import (
    RENDER_KEYS,
    ViewError,
    label,
    output_paths,
    setting_problem,
    views as normalize_views,
)

__all__ = [
    "CACHED_WORLDS",
    "MAX_RETRIES",
    "check_num_cpus",
    "check_views",
    "connect",
    "render_frame",
    "render_views",
    "tile_regions",
    "unknown_camera",
]


def _check_render(scene: Scene, camera: Any, settings: Dict[str, Any]) -> Optional[str]:
    """What ``scene.render`` refuses in ``settings`` with ``camera`` (a perfect square spp,
    the largest film, ...), or None: checked on this process by rendering one pixel, so that
    a mistake is found before any task is shipped, by the checks the render itself makes."""
    try:
        scene.render(camera=camera, region=(0, 1, 0, 1), threads=1, **settings)
    except (ValueError, TypeError, OverflowError) as e:
        given = ", ".join(f"{k}={v!r}" for k, v in settings.items())
        return f"{e}" + (f" (with {given})" if given else "")
    return None


def tile_regions(
    width: int, height: int, tiles: Union[int, Tuple[int, int]]
) -> List[Tuple[int, int, int, int]]:
    """The regions ``(x0, x1, y0, y1)`` of ``tiles``: an int n gives n horizontal bands of
    (nearly) equal height, ``(columns, rows)`` a grid. Tiles are never empty: there are at
    most as many bands as rows and columns as pixels."""
    call = "tile_regions"
    width, height = _args.size(call, "width", width), _args.size(call, "height", height)
    if hasattr(tiles, "__len__") and not isinstance(tiles, (str, bytes)):
        cols, rows = _args.sequence(call, "tiles (columns, rows)", tiles, 2)
        cols = _args.size(call, "tiles' columns", cols)
        rows = _args.size(call, "tiles' rows", rows)
    else:
        cols, rows = 1, _args.size(call, "tiles", tiles)
    cols, rows = min(cols, width), min(rows, height)
    xs = [width * i // cols for i in range(cols + 1)]
    ys = [height * j // rows for j in range(rows + 1)]
    return [(xs[i], xs[i + 1], ys[j], ys[j + 1]) for j in range(rows) for i in range(cols)]


def render_frame(
    scene: Scene,
    tiles: Union[None, int, Tuple[int, int]] = None,
    camera: Any = None,
    spp: Optional[int] = None,
    sampler: Optional[str] = None,
    light_samples: Optional[int] = None,
    seed: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    aovs: Union[str, Iterable[str]] = (),
    num_cpus: float = 1,
    progress: Any = None,
) -> Union[np.ndarray, Tuple[np.ndarray, Dict[str, np.ndarray]]]:
    """Render one frame as tiles on the cluster and stitch them: the array (and AOVs) that
    ``scene.render(camera=..., spp=..., ...)`` returns in one process, bit for bit.

    ``tiles``: an int n for n horizontal bands, ``(columns, rows)`` for a grid, or None for
    4 bands per task slot of the cluster (its CPUs / ``num_cpus``), which balances uneven
    tiles. ``num_cpus``: CPUs (and threads) per task. ``progress``: True for a tqdm bar over
    tiles on stderr, or a callable (tiles done, tiles in all). Other arguments as in
    :meth:`penumbra.Scene.render`.
    """
    aovs = (aovs,) if isinstance(aovs, str) else tuple(aovs)
    settings = _settings(locals())
    # Every argument is checked here, before anything is shipped, each named.
    for key, value in {**settings, "aovs": aovs}.items():
        problem = setting_problem(key, value)
        if problem:
            raise ValueError(f"render_frame: {problem}")
    check_num_cpus(num_cpus, "render_frame: num_cpus")
    problem = _check_render(scene, camera, settings)
    if problem:
        raise ValueError(f"render_frame: {problem}")
    w = int(width if width is not None else scene.settings["width"])
    h = int(height if height is not None else scene.settings["height"])
    if tiles is None:
        slots = max(1, int(ray.cluster_resources().get("CPU", 1) // max(num_cpus, 1e-9)))
        tiles = 4 * slots
    regions = tile_regions(w, h, tiles)
    digest, boxed = ship(scene)
    task = render_task.options(num_cpus=num_cpus, scheduling_strategy="SPREAD")
    refs = [task.remote(digest, boxed, camera, settings, r, aovs) for r in regions]
    image = np.empty((h, w, 3), np.float32)
    passes: Dict[str, np.ndarray] = {}

    def place(i: int, result: Dict[str, Any]) -> None:
        x0, x1, y0, y1 = regions[i]
        image[y0:y1, x0:x1] = result["image"]
        for name, tile in result["aovs"].items():
            if name not in passes:
                passes[name] = np.empty((h, w) + tile.shape[2:], tile.dtype)
            passes[name][y0:y1, x0:x1] = tile

    gather(refs, place, progress, "tile", lambda i: f"render_frame: tile {regions[i]}")
    return (image, passes) if aovs else image


def _settings(args: Mapping[str, Any]) -> Dict[str, Any]:
    return {k: args[k] for k in RENDER_KEYS if args.get(k) is not None}


def render_views(
    scene: Scene,
    views: Iterable[Any],
    output: str = "out/{name}.png",
    spp: Optional[int] = None,
    sampler: Optional[str] = None,
    light_samples: Optional[int] = None,
    seed: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    aovs: Union[str, Iterable[str]] = (),
    num_cpus: float = 1,
    force: bool = False,
    progress: Any = None,
    on_view: Optional[Callable[[Dict[str, Any]], Any]] = None,
    keep_going: bool = False,
    meta: bool = True,
) -> List[Dict[str, Any]]:
    """Render every view (see :mod:`penumbra.views`: camera names, :class:`penumbra.Camera`
    objects, view dicts, :func:`penumbra.views.orbit`) as one task each and write its image to
    ``output`` formatted with the view's ``name`` and ``index`` (PNG, JPEG, EXR or PFM by
    extension, written atomically by this process; AOVs beside it as ``.aovs.npz``). The
    keyword settings are defaults for views that do not set their own.

    Each image gets its record beside it (``out/front.png`` → ``out/front.meta.json``, see
    :mod:`penumbra.record`): the layout of ``penumbra render --meta``, with K, the poses, the
    object ids' entries, the scene's digest and the resolved settings; it is renamed into
    place right after the image, and the old one removed before.

    A view is skipped (not rendered again) when its image exists (with its AOVs) and its
    record says it was made with exactly the settings it would be rendered with now: the
    scene's digest (its text and every file it read), penumbra's version, the camera (its
    pose to the bit), the render settings, the AOVs, the gamma and the format. That is the
    rule of ``penumbra render --resume``: an interrupted batch, run again, does only what is
    missing, and a batch of another scene or other settings writing to the same files
    renders them all again. ``force`` renders every view; ``meta=False`` writes no records
    (and removes old ones), so nothing is known to be done and every view renders. Returns
    one dict per view, in
    order: ``name``, ``path``, ``skipped``, and for rendered views ``seconds`` (the render's),
    ``rays_per_second``, ``node`` (Ray node id), ``host``, ``peak_memory_bytes`` (the task's
    process's), ``pid`` and ``built`` (whether that task built
    the world). ``on_view``, when given, is called with each view's dict as soon as it is
    known: at once for a skipped view, when its image is written for the others (in the
    order they finish), so that an interrupted batch has told what it finished.

    A view whose task fails (after Ray's retries, ``MAX_RETRIES``) or whose image cannot be
    written raises at once, the other tasks cancelled; with ``keep_going`` the others go on,
    and the failed view's dict has ``error`` (one line) and ``skipped`` False.
    """
    defaults = _settings(locals())
    defaults["aovs"] = (aovs,) if isinstance(aovs, str) else tuple(aovs)
    batch = normalize_views(views, **defaults)
    check_views(scene, batch)
    check_num_cpus(num_cpus, "render_views: num_cpus")
    paths = output_paths(output, batch)
    summary: List[Dict[str, Any]] = [
        {"name": v["name"], "path": p, "skipped": True} for v, p in zip(batch, paths)
    ]
    records: Dict[int, Dict[str, Any]] = {}
    if meta:
        # Made before any task starts: a view the record cannot describe fails now.
        scene_digest = scene.scene_digest
        for i, (v, p) in enumerate(zip(batch, paths)):
            try:
                records[i] = record(scene, v, p, scene_digest=scene_digest)
            except ValueError as e:
                raise ViewError(i, v["name"], str(e)) from None
    todo = [
        i
        for i, (v, p) in enumerate(zip(batch, paths))
        if force or not meta or not done(p, records[i]["settings"])
    ]
    if on_view is not None:
        skipped = set(range(len(batch))) - set(todo)
        for i in sorted(skipped):
            on_view(summary[i])
    if not todo:
        return summary
    digest, boxed = ship(scene)
    task = render_task.options(num_cpus=num_cpus, scheduling_strategy="SPREAD")
    refs = []
    for i in todo:
        v = batch[i]
        settings = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
        refs.append(task.remote(digest, boxed, v["camera"], settings, None, v["aovs"]))

    def save(k: int, result: Dict[str, Any]) -> None:
        i = todo[k]
        write_view(paths[i], result["image"], result["aovs"], records.get(i), scene.gamma)
        st = result["stats"]
        summary[i].update(
            skipped=False,
            seconds=st["seconds"],
            rays_per_second=st["rays_per_second"],
            node=result["node"],
            host=result["host"],
            peak_memory_bytes=result["peak_memory_bytes"],
            pid=result["pid"],
            built=result["built"],
        )
        if on_view is not None:
            on_view(summary[i])

    def failed(k: int, error: Exception) -> None:
        i = todo[k]
        summary[i].update(skipped=False, error=str(error) or type(error).__name__)
        if on_view is not None:
            on_view(summary[i])

    name = lambda k: label(todo[k], batch[todo[k]]["name"])  # noqa: E731
    gather(refs, save, progress, "view", name, failed if keep_going else None)
    return summary


def check_views(scene: Scene, batch: Sequence[Mapping[str, Any]]) -> None:
    """Raises :class:`penumbra.views.ViewError` for the first view of ``batch`` (normalized,
    see :func:`penumbra.views.views`) that ``scene`` cannot render: an unknown camera name,
    or settings the render refuses (checked once per distinct camera name and settings, on
    this process, before anything is shipped)."""
    checked: Dict[Any, Optional[str]] = {}
    for i, v in enumerate(batch):
        camera = v["camera"]
        if isinstance(camera, str) and not _has_camera(scene, camera):
            raise ViewError(i, v["name"], unknown_camera(scene, camera))
        settings = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
        key = (camera if isinstance(camera, str) else None, tuple(sorted(settings.items())))
        if key not in checked:
            checked[key] = _check_render(scene, camera, settings)
        if checked[key]:
            raise ViewError(i, v["name"], checked[key])


def _has_camera(scene: Scene, camera: str) -> bool:
    """True when ``scene`` renders the camera ``camera``: one of its own, or ``"auto"``."""
    try:
        scene.camera(camera)
    except ValueError:
        return False
    return True


def unknown_camera(scene: Scene, camera: str) -> str:
    """What is wrong with a view of ``camera``, a name ``scene`` does not have."""
    return f"unknown camera {camera!r} (the scene's cameras: {', '.join(scene.cameras)})"
