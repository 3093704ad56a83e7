"""Scene dicts (``load_dict``) as scene text: arrays of placements written as the scene format's
inline list, numpy values as plain ones, and errors about the dict with a library error's
attributes."""

from __future__ import annotations

import os
from typing import Any, Mapping

import numpy as np

from . import _core

SceneError = _core.SceneError


def _with_placements(scene: Mapping[str, Any]) -> Mapping[str, Any]:
    """``scene`` with the ``transforms`` of each ``instances`` object that are an (N, 4, 4)
    array written as the scene format's inline list, ``[{"matrix": rows}, ...]``; the dict
    itself when there are none (it is never changed in place)."""
    objects = scene.get("objects") if isinstance(scene, Mapping) else None
    if not isinstance(objects, (list, tuple)):
        return scene
    placed = [_placements(o, f"objects[{i}].transforms") for i, o in enumerate(objects)]
    if all(p is o for p, o in zip(placed, objects)):
        return scene
    return {**scene, "objects": placed}


def _placements(obj: Any, key: str) -> Any:
    """The object ``obj`` with array ``transforms`` (at ``key``) as a list of
    ``{"matrix": rows}`` entries; ``obj`` itself when they are not an array."""
    if not isinstance(obj, Mapping) or obj.get("type") != "instances":
        return obj
    transforms = obj.get("transforms")
    if not isinstance(transforms, np.ndarray):
        return obj
    if transforms.dtype.kind not in "fiu":
        raise _scene_error(
            f"<dict>: {key}: an array of transforms must hold real numbers, not dtype "
            f"{transforms.dtype}",
            key,
            "bad_value",
        )
    if transforms.ndim != 3 or transforms.shape[1:] != (4, 4):
        raise _scene_error(
            f"<dict>: {key}: an array of transforms must have shape (N, 4, 4), one "
            f"row-major 4x4 matrix per copy, not {transforms.shape}",
            key,
            "bad_value",
        )
    rows = transforms.astype(np.float64).tolist()
    return {**obj, "transforms": [{"matrix": m} for m in rows]}


def _scene_error(message: str, key: str, kind: str) -> SceneError:
    """A :class:`SceneError` about the scene dict, with the attributes the library's have."""
    e = SceneError(message)
    e.file, e.line, e.column, e.key, e.kind = "<dict>", None, None, key, kind
    return e


def _to_json(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return list(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"a scene dict cannot hold {type(value).__name__} values")
