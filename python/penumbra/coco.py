"""COCO-style instance annotations from the ``object_id`` AOV: one annotation per object id
seen in an image, with its bounding box, its mask as COCO's compressed RLE, its area and
the fraction of it that is visible.

:func:`instances` finds the boxes and areas with numpy alone; :func:`amodal_areas` counts,
per object, the pixels whose center ray meets it whether or not something nearer hides it
(so ``visible_fraction`` = area / amodal area); :func:`annotations` assembles the COCO dict,
and its masks need ``pycocotools`` (``pip install pycocotools``; not a dependency of
penumbra: without it, :func:`annotations` raises ``ImportError`` saying so).

Conventions: ``bbox`` is COCO's ``[x, y, width, height]`` in pixels, x to the right and y
down from the image's top-left corner, covering whole pixels (a one-pixel object at column 3,
row 5 has ``[3, 5, 1, 1]``); ``area`` counts the object's pixels, as pycocotools'
``mask.area`` does. Each ``[[objects]]`` entry of the scene is a category (``id`` its index
plus 1, ``name`` its key ``objects[i]``, ``type`` its type), and each object id an instance
of it (every copy of an ``instances`` entry is one). The id AOV takes one ray through each
pixel's center, so masks have hard edges.

>>> import numpy as np
>>> ids = np.full((4, 5), NO_ID, dtype=np.uint32)
>>> ids[1:3, 2:5] = 7
>>> instances(ids)
[{'object_id': 7, 'bbox': [2, 1, 3, 2], 'area': 6}]
>>> instances(ids, amodal={7: 8})[0]["visible_fraction"]
0.75
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _args, _core
from ._camera import Camera

#: The id of pixels that show no object.
NO_ID = _core.NO_ID

#: What :func:`annotations` says when pycocotools is missing.
NO_PYCOCOTOOLS = (
    "COCO annotations need pycocotools for their RLE masks, and it is not installed: "
    "`pip install pycocotools` (penumbra does not depend on it)"
)


def _ids(object_id: Any) -> np.ndarray:
    a = np.asarray(object_id)
    if a.ndim != 2 or a.dtype != np.uint32:
        raise ValueError(
            f"object_id must be the (height, width) uint32 object_id AOV, not a {a.dtype} "
            f"array of shape {a.shape}"
        )
    return a


def instances(
    object_id: Any, amodal: Optional[Mapping[int, int]] = None
) -> List[Dict[str, Any]]:
    """The objects an ``object_id`` AOV shows, by id (ascending): ``object_id``, ``bbox``
    (``[x, y, width, height]``, whole pixels) and ``area`` (pixels), and with ``amodal``
    (object id → its amodal area, from :func:`amodal_areas`) ``visible_fraction``, area /
    amodal area. Pixels of :data:`NO_ID` show nothing."""
    ids = _ids(object_id)
    seen = ids != NO_ID
    ys, xs = np.nonzero(seen)
    values = ids[ys, xs]
    out = []
    for obj in np.unique(values):
        mine = values == obj
        x, y = xs[mine], ys[mine]
        x0, y0 = int(x.min()), int(y.min())
        entry: Dict[str, Any] = {
            "object_id": int(obj),
            "bbox": [x0, y0, int(x.max()) - x0 + 1, int(y.max()) - y0 + 1],
            "area": int(mine.sum()),
        }
        if amodal is not None:
            whole = int(amodal.get(int(obj), 0))
            if whole < entry["area"]:
                raise ValueError(
                    f"object {int(obj)}: its amodal area ({whole} pixels) is less than its "
                    f"visible area ({entry['area']}): amodal areas of another image or camera?"
                )
            entry["visible_fraction"] = entry["area"] / whole
        out.append(entry)
    return out


def amodal_areas(
    scene: Any,
    camera: Union[None, str, Camera],
    width: int,
    height: int,
    object_id: Any = None,
) -> Dict[int, int]:
    """For each object of ``scene`` in view, how many pixels of a ``width`` × ``height``
    image from ``camera`` (a :class:`penumbra.Camera`, a camera name, or None for the
    default) it would cover with nothing in front of it: the pixels whose center ray (the ray
    the id AOV takes) meets it at any distance, counted by ray casting
    (:meth:`penumbra.Scene.raycasting_scene`). With ``object_id`` (the image's id AOV) its
    visible pixels count too, so that an amodal area is never less than the visible one
    where ray casting and rendering disagree at a silhouette's edge."""
    width = _args.size("amodal_areas", "width", width)
    height = _args.size("amodal_areas", "height", height)
    if not isinstance(camera, Camera):
        camera = scene.camera(camera)
    rays = _core.camera_rays(camera._args(), width, height)
    pixels = width * height
    hits = scene.raycasting_scene().list_intersections(rays.reshape(-1, 6))
    keys = np.asarray(hits["geometry_ids"], np.int64) * pixels + np.asarray(
        hits["ray_ids"], np.int64
    )
    if object_id is not None:
        ids = _ids(object_id)
        if ids.shape != (height, width):
            raise ValueError(
                f"object_id has shape {ids.shape}, not the image's ({height}, {width})"
            )
        flat = ids.reshape(-1)
        seen = np.nonzero(flat != NO_ID)[0]
        keys = np.concatenate([keys, flat[seen].astype(np.int64) * pixels + seen])
    objects, counts = np.unique(np.unique(keys) // pixels, return_counts=True)
    return {int(o): int(c) for o, c in zip(objects, counts)}


def _mask_api() -> Any:
    try:
        from pycocotools import mask
    except ImportError:
        raise ImportError(NO_PYCOCOTOOLS) from None
    return mask


def check_available() -> None:
    """Raises ``ImportError`` saying how to install pycocotools when it is missing: call it
    before a long batch whose annotations need it."""
    _mask_api()


def annotations(scene: Any, images: Sequence[Mapping[str, Any]]) -> Dict[str, Any]:
    """The COCO dict (``info``, ``images``, ``categories``, ``annotations``) of ``images``
    of ``scene``, each a mapping with ``file_name``, ``object_id`` (its id AOV) and,
    optionally, ``camera`` (a :class:`penumbra.Camera` or a camera name of the scene; None is
    the default camera) for ``visible_fraction``: without the key, annotations have no
    ``visible_fraction``. Annotations list per image its objects by id, each with ``id``,
    ``image_id``, ``category_id``, ``object_id``, ``bbox``, ``area``, ``segmentation``
    (compressed RLE: ``{"size": [h, w], "counts": "..."}``, as pycocotools encodes it),
    ``iscrowd`` 0 and ``visible_fraction``. Raises ``ImportError`` without pycocotools."""
    mask = _mask_api()
    entries = scene.objects
    entry_of = {}
    for i, e in enumerate(entries):
        for obj in range(*e["ids"]):
            entry_of[obj] = i
    coco: Dict[str, Any] = {
        "info": {
            "description": "object_id annotations written by penumbra",
            "version": _core.__version__,
            "scene_digest": scene.scene_digest,
        },
        "images": [],
        "categories": [
            {"id": i + 1, "name": e["key"], "type": e["type"]} for i, e in enumerate(entries)
        ],
        "annotations": [],
    }
    for k, image in enumerate(images):
        ids = _ids(image["object_id"])
        h, w = ids.shape
        coco["images"].append(
            {"id": k + 1, "file_name": os.fspath(image["file_name"]), "width": w, "height": h}
        )
        amodal = None
        if "camera" in image:
            amodal = amodal_areas(scene, image["camera"], w, h, ids)
        for inst in instances(ids, amodal):
            obj = inst["object_id"]
            if obj not in entry_of:
                raise ValueError(
                    f"{image['file_name']}: object id {obj} is none of the scene's objects "
                    f"(it has {sum(e['ids'][1] - e['ids'][0] for e in entries)} object ids)"
                )
            rle = mask.encode(np.asfortranarray(ids == obj, dtype=np.uint8))
            coco["annotations"].append(
                {
                    "id": len(coco["annotations"]) + 1,
                    "image_id": k + 1,
                    "category_id": entry_of[obj] + 1,
                    **inst,
                    "segmentation": {"size": [h, w], "counts": rle["counts"].decode("ascii")},
                    "iscrowd": 0,
                }
            )
    return coco


def write_annotations(
    path: Union[str, "os.PathLike[str]"], scene: Any, images: Sequence[Mapping[str, Any]]
) -> None:
    """Writes the :func:`annotations` of ``images`` to ``path`` (JSON), whole or not at all
    (a temporary file renamed into place). Raises ``ImportError`` without pycocotools."""
    value = annotations(scene, images)
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    _core.write_bytes(path, (json.dumps(value) + "\n").encode("utf-8"))
