"""Records beside images: ``out/front.png`` → ``out/front.meta.json``, saying how a view's
image was made, made, written and read back by the command line's own code
(``penumbra::products::record``), so that both write the same layout (docs/spec.md §10 has
the conventions of K and the poses):

- ``settings``: ``penumbra`` (the version), ``scene_digest`` (:attr:`penumbra.Scene.scene_digest`,
  the command line's for the same file), ``camera`` (the scene camera's name; None for an
  explicit camera), ``frame`` (None: a view has no frame), ``render`` (the resolved render
  settings by name: ``camera`` (``{"named": NAME}``, ``"first"``, ``{"pinhole": {...}}`` or, for a
  :class:`penumbra.Camera` with K, a lens model or an aperture, ``{"explicit": {...}}`` with
  its ``K`` on the film and its ``lens``),
  ``width``, ``height``, ``sampler``, ``spp``, ``light_samples``, ``seed``, ``shading``,
  ``light_model``, ``ambient``, ``background``; every number to the bit), ``region``
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
from typing import Any, Dict, Mapping, Optional, Union

from . import _core
from ._camera import Camera
from .views import RENDER_KEYS, view as normalized

#: The largest record read back: far more than any record penumbra writes.
MAX_RECORD_BYTES = _core.MAX_RECORD_BYTES


def record_path(image: Union[str, "os.PathLike[str]"]) -> str:
    """Where the record of the image at ``image`` goes: its extension replaced by
    ``.meta.json``, as the command line names it."""
    return os.fspath(_core.record_path(os.fspath(image)))


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
    v = normalized(view)
    settings: Dict[str, Any] = {k: v[k] for k in RENDER_KEYS if v[k] is not None}
    camera = v["camera"]
    if isinstance(camera, Camera):
        settings["camera"] = camera._args()
    elif camera is not None:
        scene.camera(camera)  # an unknown name raises, naming the scene's cameras
        settings["camera"] = camera
    text = scene._core.record(
        os.fspath(image), view=v["name"], scene_digest=scene_digest, aovs=list(v["aovs"]),
        **settings,
    )
    value: Dict[str, Any] = json.loads(text)
    return value


def write_record(image: Union[str, "os.PathLike[str]"], value: Mapping[str, Any]) -> str:
    """Writes the record ``value`` beside ``image`` (at :func:`record_path`), whole or not at
    all (a temporary file renamed into place); returns its path."""
    image = os.fspath(image)
    if image != value.get("image"):
        raise ValueError(f"{image}: the record is of another image, {value.get('image')!r}")
    return os.fspath(_core.write_record(json.dumps(dict(value))))


def digest(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """A file's entry in a record's ``digests``: ``bytes`` (its size) and ``fnv1a64`` (the
    64-bit FNV-1a of its bytes, 16 hex digits), as the command line computes them."""
    size, fnv = _core.file_digest(os.fspath(path))
    return {"bytes": size, "fnv1a64": fnv}


def read_record(path: Union[str, "os.PathLike[str]"]) -> Optional[Dict[str, Any]]:
    """The record at ``path`` (a ``.meta.json``), or None when there is none that can be read:
    missing, not a regular file (a named pipe there is never opened: opening it would wait for
    a writer), larger than :data:`MAX_RECORD_BYTES`, or not a JSON object."""
    text = _core.read_record(os.fspath(path))
    value = None if text is None else json.loads(text)
    return value if isinstance(value, dict) else None


def intact(value: Mapping[str, Any]) -> bool:
    """True when every file the record ``value`` lists (``files``) is a regular file of the
    size and digest its ``digests`` keep: False for an image cut short or changed after its
    record was written, and for a record without digests (from before penumbra kept them)."""
    try:
        text = json.dumps(dict(value))
    except (TypeError, ValueError):  # not a record of JSON values
        return False
    return bool(_core.record_intact(text))


def done(image: Union[str, "os.PathLike[str]"], settings: Mapping[str, Any]) -> bool:
    """True when the image at ``image`` is done, as ``penumbra render --resume`` decides: its
    record lists it first, was made with exactly ``settings`` (the ``settings`` of the record
    it would be written with now: the scene's digest, penumbra's version, the camera, the
    render settings, the AOVs, the gamma and the format), and every file it lists (the
    image, then its ``.aovs.npz``) still has the size and digest it was written with. A
    missing, unreadable or different record (or one of an older layout), or a file cut short
    or changed, is not done."""
    return _core.record_finished(os.fspath(image), json.dumps(dict(settings))) is not None
