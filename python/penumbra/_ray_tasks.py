"""What runs on Ray's workers, and how a scene gets there: the scene is packed and put in the
object store once per driver (:func:`ship`), and each worker process builds a scene's world
once and keeps it for its next tasks (a cache keyed by the pack's digest, at most
:data:`CACHED_WORLDS`). A task renders with as many threads as CPUs Ray gave it, and is
retried by Ray (up to :data:`MAX_RETRIES` times) when its worker dies.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from typing import Any, Dict, List, Optional, Tuple

import ray

from . import _core
from ._scene import Scene, load_pack

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
def render_task(
    digest: str,
    boxed_pack: List[Any],
    camera: Any,
    settings: Dict[str, Any],
    region: Optional[Tuple[int, int, int, int]],
    aovs: Tuple[str, ...],
) -> Dict[str, Any]:
    """Renders ``region`` (None: the whole film) of ``camera`` with ``settings`` and
    ``aovs`` on this worker: the image, its AOVs, the render's stats, and where and how it
    ran (``built``: whether this task built the world). The pack comes boxed in a list so
    that Ray does not fetch it for tasks whose process has the world already."""
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
        # As the command line's manifest has them.
        "host": _core.host_name(),
        "peak_memory_bytes": _core.peak_memory_bytes(),
    }


# What the driver has shipped in the current Ray session: each scene's pack digest (the pack is
# made, reading every file, once per scene) and each digest's pack in the object store (put
# once). A new session (ray.shutdown() then ray.init()) ships again.
_shipped: Dict[str, Any] = {"session": None, "digests": {}, "refs": {}}


def ship(scene: Scene) -> Tuple[str, List[Any]]:
    """The pack digest of ``scene`` and its pack in Ray's object store, boxed in a list for
    :func:`render_task`: packed and put once per scene and Ray session."""
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
