"""Records beside images: ``out/front.png`` → ``out/front.meta.json``, saying how a view's
image was made, in the layout ``penumbra render --meta`` writes (docs/spec.md §10 has the
conventions of K and the poses):

- ``settings``: ``penumbra`` (the version), ``scene_digest`` (:attr:`penumbra.Scene.scene_digest`,
  the command line's for the same file), ``camera`` (the scene camera's name; None for an
  explicit camera), ``frame`` (None: a view has no frame), ``render`` (the resolved render
  settings as the command line's record writes them, every number to the bit), ``region``
  (None), ``aovs`` (the AOV names), ``gamma`` (the scene's ``film.gamma``; None: the sRGB curve)
  and ``format`` (``png``, ``jpg``, ``exr`` or ``pfm``);
- ``image``, ``files`` (the image, then its ``.aovs.npz`` when the view has AOVs),
  ``digests`` (for each file, as written: ``bytes``, its size, and ``fnv1a64``, the 64-bit
  FNV-1a of its bytes as 16 hex digits; :func:`intact` checks them), ``width``, ``height``;
- ``K`` (3×3, OpenCV: pixel centres at integer coordinates), ``camera_to_world`` (OpenCV
  axes), ``camera_to_world_opengl`` and ``world_to_camera`` (4×4), as lists of rows;
- ``objects``: each ``[[objects]]`` entry's ``key``, ``type`` and ``ids`` (``[first, end)``
  object ids), which name the values of an ``object_id`` AOV (:attr:`penumbra.Scene.objects`);
- ``view``: the view's name (Python's only key).

>>> import penumbra
>>> scene = penumbra.loads('''
... [film]
... width = 8
... height = 6
... [camera]
... position = [0, 0, 3]
... look_at = [0, 0, 0]
... fov = 40
... [[objects]]
... type = "sphere"
... center = [0, 0, 0]
... radius = 1
... ''')
>>> r = record(scene, "camera", "out/a.png")
>>> r["K"][0][2], r["camera_to_world"][2][3], r["objects"]
(3.5, 3.0, [{'key': 'objects[0]', 'type': 'sphere', 'ids': [0, 1]}])
>>> record_path("out/a.png")
'out/a.meta.json'
"""

from __future__ import annotations

import json
import os
import stat
from typing import Any, Dict, Mapping, Optional, Union

from . import _core
from ._camera import Camera
from ._staged import commit, stage_json
from .poses import camera_pose
from .views import RENDER_KEYS, aov_path, view as normalized

#: The format names records give, by image extension (as the command line names them).
FORMATS = {".png": "png", ".jpg": "jpg", ".jpeg": "jpg", ".exr": "exr", ".pfm": "pfm"}

#: The largest record read back: far more than any record penumbra writes.
MAX_RECORD_BYTES = 1 << 20


def record_path(image: Union[str, "os.PathLike[str]"]) -> str:
    """Where the record of the image at ``image`` goes: its extension replaced by
    ``.meta.json``, as the command line names it."""
    stem, _ = os.path.splitext(os.fspath(image))
    return stem + ".meta.json"


def record(
    scene: Any,
    view: Union[str, Camera, Mapping[str, Any]],
    image: Union[str, "os.PathLike[str]"],
    scene_digest: Optional[str] = None,
) -> Dict[str, Any]:
    """The record of ``view`` (a camera name, a :class:`penumbra.Camera` or a view dict, see
    :mod:`penumbra.views`) of ``scene`` rendered to ``image``, as a dict of JSON values (see
    the module's docs). ``scene_digest`` saves computing ``scene.scene_digest`` again for
    each view of a batch. Raises ``ValueError`` for a view the scene cannot render (an
    unknown camera, bad settings) and for an image whose extension names no format."""
    image = os.fspath(image)
    ext = os.path.splitext(image)[1].lower()
    if ext not in FORMATS:
        raise ValueError(
            f"{image}: a record's image is .png, .jpg, .jpeg, .exr or .pfm, not {ext or 'none'!r}"
        )
    v = normalized(view)
    settings = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
    camera = v["camera"]
    if isinstance(camera, Camera):
        name, view_arg = None, camera._args()
    else:
        # No camera is the scene's first, by name, as the command line records it.
        name = camera if camera is not None else next(iter(scene.cameras), None)
        camera, view_arg = scene.camera(name), name
    render = scene._core.settings_record(camera=view_arg, **settings)
    width = int(v["width"] or scene.settings["width"])
    height = int(v["height"] or scene.settings["height"])
    files = [image] + ([aov_path(image)] if v["aovs"] else [])
    pose = camera_pose(camera, width, height)
    return {
        "settings": {
            "penumbra": _core.__version__,
            "scene_digest": scene_digest if scene_digest is not None else scene.scene_digest,
            "camera": name,
            "frame": None,
            "render": render,
            "region": None,
            "aovs": list(v["aovs"]),
            "gamma": scene.gamma,
            "format": FORMATS[ext],
        },
        "image": image,
        "files": files,
        "width": width,
        "height": height,
        **{key: m.tolist() for key, m in pose.items()},
        "objects": scene.objects,
        "view": v["name"],
    }


def write_record(image: Union[str, "os.PathLike[str]"], value: Mapping[str, Any]) -> str:
    """Writes the record ``value`` beside ``image`` (at :func:`record_path`), whole or not at
    all (a temporary file renamed into place); returns its path."""
    path = record_path(image)
    commit(stage_record(path, value), path)
    return path


def stage_record(path: str, value: Mapping[str, Any]) -> str:
    """Writes ``value`` as JSON to a temporary file beside ``path`` (flushed to disk) and
    returns its name, for the caller to rename into place; nothing is left on failure, and an
    ``OSError`` names ``path``."""
    return stage_json(path, value, separators=(",", ":"))


def digest(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """A file's entry in a record's ``digests``: ``bytes`` (its size) and ``fnv1a64`` (the
    64-bit FNV-1a of its bytes, 16 hex digits), as the command line computes them."""
    size, fnv = _core.file_digest(os.fspath(path))
    return {"bytes": size, "fnv1a64": fnv}


def read_record(path: Union[str, "os.PathLike[str]"]) -> Optional[Dict[str, Any]]:
    """The record at ``path`` (a ``.meta.json``), or None when there is none that can be read:
    missing, not a regular file (a named pipe there is never opened: opening it would wait for
    a writer), larger than :data:`MAX_RECORD_BYTES`, or not a JSON object."""
    path = os.fspath(path)
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_RECORD_BYTES:
            return None
        with open(path, "rb") as f:
            value = json.loads(f.read(MAX_RECORD_BYTES + 1))
    except (OSError, ValueError):
        return None
    return value if isinstance(value, dict) else None


def intact(value: Mapping[str, Any]) -> bool:
    """True when every file the record ``value`` lists (``files``) is a regular file of the
    size and digest its ``digests`` keep: False for an image cut short or changed after its
    record was written, and for a record without digests (from before penumbra kept them)."""
    files, digests = value.get("files"), value.get("digests")
    if not isinstance(files, list) or not isinstance(digests, list) or not files:
        return False
    if len(files) != len(digests):
        return False
    for f, d in zip(files, digests):
        try:
            if not isinstance(f, str) or digest(f) != d:
                return False
        except OSError:
            return False
    return True
