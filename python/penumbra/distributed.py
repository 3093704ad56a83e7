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
  and gives the same bytes. Images are written by the driver, atomically; a view whose image
  exists is skipped unless ``force``. Ctrl-C cancels the outstanding tasks.

Call ``ray.init(...)`` first (or let :func:`connect` do it).
"""

from __future__ import annotations

import itertools
import os
import re
import signal
import socket
import threading
from collections import OrderedDict
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import ray

from ._image import write_image
from ._scene import Scene, load_pack, tqdm_class
from .views import (
    RENDER_KEYS,
    ViewError,
    aov_path,
    label,
    output_path,
    setting_problem,
    views as normalize_views,
)

#: Worlds a worker process keeps built, the most recently used first.
CACHED_WORLDS = 2
#: Times Ray retries a task whose worker process died.
MAX_RETRIES = 3

# One world per pack digest in each worker process, and how many were built here.
_worlds: "OrderedDict[str, Scene]" = OrderedDict()
_builds = 0


def _world(digest: str, boxed_pack: List[Any], threads: int) -> Tuple[Scene, bool]:
    """The built scene of the pack, from this process's cache or built now (True)."""
    global _builds
    scene = _worlds.get(digest)
    if scene is not None:
        _worlds.move_to_end(digest, last=False)
        return scene, False
    pack = boxed_pack[0]
    if isinstance(pack, ray.ObjectRef):
        pack = ray.get(pack)
    scene = load_pack(pack, threads=threads)
    _builds += 1
    _worlds[digest] = scene
    _worlds.move_to_end(digest, last=False)
    while len(_worlds) > CACHED_WORLDS:
        _worlds.popitem()
    return scene, True


def _task_threads() -> int:
    """The CPUs Ray assigned to the running task (at least 1)."""
    cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1.0)
    return max(1, int(cpus))


@ray.remote(max_retries=MAX_RETRIES)
def _render_task(
    digest: str,
    boxed_pack: List[Any],
    camera: Any,
    settings: Dict[str, Any],
    region: Optional[Tuple[int, int, int, int]],
    aovs: Tuple[str, ...],
) -> Dict[str, Any]:
    # The pack comes boxed in a list so that Ray does not fetch it for tasks whose process
    # has the world already.
    threads = _task_threads()
    scene, built = _world(digest, boxed_pack, threads)
    stats: Dict[str, Any] = {}
    out = scene.render(
        camera=camera, region=region, threads=threads, aovs=aovs, stats=stats, **settings
    )
    image, passes = out if aovs else (out, {})
    return {
        "image": image,
        "aovs": passes,
        "stats": stats,
        "built": built,
        "builds": _builds,
        "pid": os.getpid(),
        "node": ray.get_runtime_context().get_node_id(),
        "host": socket.gethostname(),
        "peak_memory_bytes": _peak_memory(),
    }


def _peak_memory() -> Optional[int]:
    """This process's peak resident memory in bytes (Linux counts ru_maxrss in KiB)."""
    try:
        import resource
    except ImportError:  # not on Windows
        return None
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


# What the driver has shipped in the current Ray session: each scene's pack digest (the pack is
# made, reading every file, once per scene) and each digest's pack in the object store (put
# once). A new session (ray.shutdown() then ray.init()) ships again.
_shipped: Dict[str, Any] = {"session": None, "digests": {}, "refs": {}}


def _ship(scene: Scene) -> Tuple[str, List[Any]]:
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a penumbra.Scene, not {type(scene).__name__}")
    context = ray.get_runtime_context()
    session = (context.gcs_address, context.get_job_id())
    if _shipped["session"] != session:
        _shipped.update(session=session, digests={}, refs={})
    # Keyed by id, with the scene kept alive beside its digest so the id is not reused.
    known = _shipped["digests"].get(id(scene))
    if known is None:
        pack = scene.pack()
        if pack.digest not in _shipped["refs"]:
            _shipped["refs"][pack.digest] = ray.put(pack)
        known = _shipped["digests"][id(scene)] = (scene, pack.digest)
    digest = known[1]
    return digest, [_shipped["refs"][digest]]


def _gather(
    refs: List["ray.ObjectRef"],
    on_result: Callable[[int, Dict[str, Any]], None],
    progress: Any,
    unit: str,
    label: Callable[[int], str],
    on_failure: Optional[Callable[[int, Exception], None]] = None,
) -> None:
    """Waits for every task, calling ``on_result(index, result)`` as each finishes (with a
    progress bar cleared meanwhile, so that what it prints stays readable); cancels the rest
    on any error or Ctrl-C. A task that failed (after Ray's retries) raises one line naming
    it by ``label(index)`` (see :func:`_task_failure`), not Ray's remote traceback; with
    ``on_failure``, that error, or one ``on_result`` raised, goes to ``on_failure(index,
    error)`` instead and the other tasks go on."""
    index = {ref: i for i, ref in enumerate(refs)}
    pending = list(refs)
    bar = _bar(progress, len(refs), unit)
    interrupted, previous = _defer_ctrl_c()
    try:
        while pending:
            if interrupted.is_set():
                raise KeyboardInterrupt
            done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
            for ref in done:
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as e:
                    failure = _task_failure(e, label(index[ref]))
                    if on_failure is None:
                        raise failure from None
                    on_failure(index[ref], failure)
                    continue
                try:
                    if bar is None:
                        on_result(index[ref], result)
                    else:
                        with bar.external_write_mode():
                            on_result(index[ref], result)
                except Exception as e:
                    if on_failure is None:
                        raise
                    on_failure(index[ref], e)
                if bar is not None:
                    bar.update(1)
                elif callable(progress):
                    progress(len(refs) - len(pending), len(refs))
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if bar is not None:
            bar.close()


def _defer_ctrl_c() -> Tuple[threading.Event, Any]:
    """An event that Ctrl-C sets while tasks are awaited, instead of raising
    KeyboardInterrupt wherever the main thread happens to be: raised inside Ray's calls, it
    made Ray's core worker abort now and then ("Tried to complete task that was not pending"),
    so the batch died with a crash report instead of exiting 130. :func:`_gather` raises it
    itself between waits (within 0.5 s). Only Python's default handler is replaced, and only on
    the main thread, where handlers live; the handler it replaced is returned (or None)."""
    event = threading.Event()
    if (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    ):
        return event, signal.signal(signal.SIGINT, lambda *_: event.set())
    return event, None


# Terminal escape sequences (colours) in Ray's messages.
_ESCAPES = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|[\x00-\x08\x0b-\x1f\x7f]")


def _task_failure(e: "ray.exceptions.RayError", what: str) -> Exception:
    """One line for a failed task: ``WHAT: message`` of the exception the task raised (of its
    type when it is a ValueError, MemoryError or OSError, else a RuntimeError), or the first
    line of Ray's own error (a worker that died more often than it was retried), without
    Ray's remote traceback or terminal escape codes."""
    cause = getattr(e, "cause", None)
    err = cause if isinstance(cause, Exception) else e
    lines = [line.strip() for line in _ESCAPES.sub("", str(err)).splitlines() if line.strip()]
    message = f"{what}: {type(err).__name__}: {lines[0] if lines else 'failed'}"
    kind = type(err) if isinstance(err, (ValueError, MemoryError, OSError)) else RuntimeError
    try:
        return kind(message)
    except TypeError:  # a subclass with other arguments
        return RuntimeError(message)


def check_num_cpus(num_cpus: float, what: str = "num_cpus") -> None:
    """Raises ``ValueError`` naming ``what`` unless ``num_cpus`` is a positive number of CPUs
    that some live node of the cluster has: a task asking for more than any node has would
    wait forever (Ray queues it silently)."""
    if isinstance(num_cpus, bool) or not isinstance(num_cpus, (int, float)):
        raise ValueError(f"{what} must be a positive number of CPUs, not {num_cpus!r}")
    if not 0 < num_cpus < float("inf"):
        raise ValueError(f"{what} must be a positive number of CPUs, not {num_cpus!r}")
    most = max(
        (n["Resources"].get("CPU", 0) for n in ray.nodes() if n.get("Alive")), default=0
    )
    if num_cpus > most:
        raise ValueError(
            f"{what} is {num_cpus:g} CPUs per task, more than any node of the cluster has "
            f"(at most {most:g}): its tasks would wait forever"
        )


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


def _bar(progress: Any, total: int, unit: str) -> Any:
    if progress is not True:
        return None
    # _bar <- _gather <- render_frame or render_views <- the caller's line.
    tqdm = tqdm_class(stacklevel=4)
    if tqdm is None:
        return None
    return tqdm(total=total, unit=unit, desc="penumbra", leave=False)


def tile_regions(
    width: int, height: int, tiles: Union[int, Tuple[int, int]]
) -> List[Tuple[int, int, int, int]]:
    """The regions ``(x0, x1, y0, y1)`` of ``tiles``: an int n gives n horizontal bands of
    (nearly) equal height, ``(columns, rows)`` a grid. Tiles are never empty: there are at
    most as many bands as rows and columns as pixels."""
    cols, rows = (1, tiles) if isinstance(tiles, int) else tiles
    cols, rows = int(cols), int(rows)
    if cols < 1 or rows < 1:
        raise ValueError(f"tiles must be at least 1, not {tiles!r}")
    for name, side in (("width", width), ("height", height)):
        if side < 1:
            raise ValueError(f"{name} must be at least 1 pixel, not {side}")
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
    digest, boxed = _ship(scene)
    task = _render_task.options(num_cpus=num_cpus, scheduling_strategy="SPREAD")
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

    _gather(refs, place, progress, "tile", lambda i: f"render_frame: tile {regions[i]}")
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
) -> List[Dict[str, Any]]:
    """Render every view (see :mod:`penumbra.views`: camera names, :class:`penumbra.Camera`
    objects, view dicts, :func:`penumbra.views.orbit`) as one task each and write its image to
    ``output`` formatted with the view's ``name`` and ``index`` (PNG, JPEG, EXR or PFM by
    extension, written atomically by this process; AOVs beside it as ``.aovs.npz``). The
    keyword settings are defaults for views that do not set their own.

    A view whose image exists already is skipped (not rendered again) unless ``force``: an
    interrupted batch, run again, does only what is missing. Returns one dict per view, in
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
    paths = [output_path(output, v, i) for i, v in enumerate(batch)]
    if len(set(paths)) != len(paths):
        raise ValueError(f"output pattern {output!r} gives two views the same file")
    summary: List[Dict[str, Any]] = [
        {"name": v["name"], "path": p, "skipped": True} for v, p in zip(batch, paths)
    ]
    todo = [
        i
        for i, (v, p) in enumerate(zip(batch, paths))
        if force or not _complete(p, bool(v["aovs"]))
    ]
    if on_view is not None:
        skipped = set(range(len(batch))) - set(todo)
        for i in sorted(skipped):
            on_view(summary[i])
    if not todo:
        return summary
    digest, boxed = _ship(scene)
    task = _render_task.options(num_cpus=num_cpus, scheduling_strategy="SPREAD")
    refs = []
    for i in todo:
        v = batch[i]
        settings = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
        refs.append(task.remote(digest, boxed, v["camera"], settings, None, v["aovs"]))

    def save(k: int, result: Dict[str, Any]) -> None:
        i = todo[k]
        _write_view(paths[i], result["image"], result["aovs"])
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
    _gather(refs, save, progress, "view", name, failed if keep_going else None)
    return summary


def check_views(scene: Scene, batch: Sequence[Mapping[str, Any]]) -> None:
    """Raises :class:`penumbra.views.ViewError` for the first view of ``batch`` (normalized,
    see :func:`penumbra.views.views`) that ``scene`` cannot render: an unknown camera name,
    or settings the render refuses (checked once per distinct camera name and settings, on
    this process, before anything is shipped)."""
    checked: Dict[Any, Optional[str]] = {}
    for i, v in enumerate(batch):
        camera = v["camera"]
        if isinstance(camera, str) and camera not in scene.cameras:
            raise ViewError(i, v["name"], unknown_camera(scene, camera))
        settings = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
        key = (camera if isinstance(camera, str) else None, tuple(sorted(settings.items())))
        if key not in checked:
            checked[key] = _check_render(scene, camera, settings)
        if checked[key]:
            raise ViewError(i, v["name"], checked[key])


def unknown_camera(scene: Scene, camera: str) -> str:
    """What is wrong with a view of ``camera``, a name ``scene`` does not have."""
    return f"unknown camera {camera!r} (the scene's cameras: {', '.join(scene.cameras)})"


def _complete(path: str, with_aovs: bool) -> bool:
    return os.path.isfile(path) and (not with_aovs or os.path.isfile(aov_path(path)))


_writes = itertools.count()


def _write_view(path: str, image: np.ndarray, aovs: Mapping[str, np.ndarray]) -> None:
    """Writes a view's image to ``path`` and its AOVs (if any) beside it, together or not at
    all, as the command line writes an image and its AOV files: each file is written whole
    under a temporary name in its folder first (where a full disk fails), and only then are
    they renamed into place, the image last (a rename takes no space). A failure leaves the
    old files as they were and no temporary file."""
    folder, name = os.path.split(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    tag = f".tmp-{os.getpid()}-{next(_writes)}"
    staged: List[Tuple[str, str]] = []
    try:
        if aovs:
            final = aov_path(path)
            tmp = os.path.join(folder, f".{os.path.basename(final)}{tag}")
            staged.append((tmp, final))
            with open(tmp, "wb") as f:
                np.savez(f, **aovs)
                f.flush()
                os.fsync(f.fileno())
        # The same extension, which names the image's format.
        tmp = os.path.join(folder, f".{name}{tag}{os.path.splitext(name)[1]}")
        staged.append((tmp, path))
        write_image(tmp, image)
        for tmp, final in staged:
            os.replace(tmp, final)
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.remove(tmp)


def connect(address: str = "local", num_cpus: Optional[int] = None, timeout: float = 5.0) -> None:
    """Start or join Ray: ``"local"`` starts a private instance on this machine (with
    ``num_cpus`` CPUs, default all), ``"auto"`` joins the cluster this machine is part of, and
    ``"HOST:PORT"`` the cluster whose head listens there. An address that does not answer
    within ``timeout`` seconds raises ``ConnectionError`` at once, naming it."""
    if ray.is_initialized():
        return
    if address == "local":
        ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)
        return
    if address != "auto":
        host, sep, port = address.rpartition(":")
        if not sep or not host or not port.isdigit():
            raise ValueError(f"a Ray address is local, auto or HOST:PORT, not {address!r}")
        try:
            socket.create_connection((host, int(port)), timeout=timeout).close()
        except OSError as e:
            raise ConnectionError(f"no Ray cluster answers at {address}: {e}") from None
    try:
        ray.init(address=address, log_to_driver=False)
    except ConnectionError as e:
        raise ConnectionError(f"cannot join the Ray cluster at {address}: {e}") from None
