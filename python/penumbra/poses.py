"""Camera poses and intrinsics of views, as ``penumbra render --poses`` writes them
(docs/spec.md §10): ``K`` in OpenCV's convention (pixel centres at integer coordinates, so a
centred camera has cx = (W - 1)/2), ``camera_to_world`` in OpenCV axes (+x right, +y down,
+z forward), ``camera_to_world_opengl`` (+x right, +y up, +z backward) and
``world_to_camera``. The numbers are the command line's, computed by the same code, and the
poses files are written by it (``penumbra::products::poses``).

>>> from penumbra import Camera
>>> pose = camera_pose(Camera((0, 0, 5), (0, 0, 0), (0, 1, 0), 90), 64, 48)
>>> float(pose["K"][0, 2]), float(pose["K"][1, 2])
(31.5, 23.5)
>>> pose["camera_to_world"][:3, 3].tolist()
[0.0, 0.0, 5.0]
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Sequence, Union

import numpy as np

from . import _args, _core
from ._camera import Camera
from .views import output_path, views as normalized


def camera_pose(camera: Camera, width: int, height: int) -> Dict[str, np.ndarray]:
    """``K`` (3×3), ``camera_to_world``, ``camera_to_world_opengl`` and ``world_to_camera``
    (4×4, float64) of ``camera`` on a ``width`` × ``height`` film."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera_pose takes a penumbra.Camera, not {type(camera).__name__}")
    width = _args.size("camera_pose", "width", width)
    height = _args.size("camera_pose", "height", height)
    k, c2w, gl, w2c = _core.camera_pose(camera._args(), width, height)
    return {
        "K": np.array(k),
        "camera_to_world": np.array(c2w),
        "camera_to_world_opengl": np.array(gl),
        "world_to_camera": np.array(w2c),
    }


def _frames(
    call: str,
    specs: Sequence[Union[Camera, Mapping[str, Any]]],
    width: int,
    height: int,
    output: str,
) -> str:
    """The frames of penumbra's layout (JSON text) of the views ``specs``, each with an
    explicit camera, as :func:`poses` describes them."""
    width = _args.size(call, "width", width)
    height = _args.size(call, "height", height)
    frames = []
    for i, v in enumerate(normalized(specs)):
        camera = v["camera"]
        if not isinstance(camera, Camera):
            raise ValueError(
                f"views[{i}]: poses need an explicit camera (a penumbra.Camera or "
                f"position/look_at), not {camera!r}"
            )
        size = (v["width"] or width, v["height"] or height)
        frames.append((i, v["name"], output_path(output, v, i), camera._args(), *size))
    return str(_core.pose_frames(frames))


def poses(
    specs: Sequence[Union[Camera, Mapping[str, Any]]],
    width: int,
    height: int,
    output: str = "{name}.png",
) -> Dict[str, List[Dict[str, Any]]]:
    """``{"frames": [...]}`` for the views ``specs`` (as :func:`penumbra.views.views` takes
    them, each with an explicit camera: a :class:`Camera` or ``position``/``look_at``), in the
    layout of ``penumbra render --poses``: per view its ``frame`` (its index), ``camera`` (its
    name), ``file`` (``output`` formatted as :func:`penumbra.views.output_path` does),
    ``width``, ``height`` (the view's own, else these), ``fov``, ``K`` and the poses as lists
    of rows, and the camera's ``position``, ``look_at`` and ``up``."""
    frames = _frames("poses", specs, width, height, output)
    value: Dict[str, List[Dict[str, Any]]] = json.loads(
        _core.poses_layout("penumbra", frames, "poses.json")
    )
    return value


def nerf(frames: Dict[str, List[Dict[str, Any]]], folder: str = ".") -> Dict[str, Any]:
    """The ``transforms.json`` of :func:`poses`' result, as instant-ngp and nerfstudio read
    it: ``camera_model`` "OPENCV", ``fl_x``, ``fl_y``, ``cx``, ``cy`` (NeRF's pixel centres
    at +1/2: K's plus 1/2), ``w``, ``h``, ``camera_angle_x``/``_y``, zero distortion, and
    per frame ``file_path`` (relative to ``folder``, where the file goes) and
    ``transform_matrix`` (``camera_to_world_opengl``), with the intrinsics repeated."""
    listed = json.dumps(frames["frames"])
    where = os.path.join(folder, "transforms.json")
    value: Dict[str, Any] = json.loads(_core.poses_layout("nerf", listed, where))
    return value


def write_poses(
    path: Union[str, "os.PathLike[str]"],
    specs: Sequence[Union[Camera, Mapping[str, Any]]],
    width: int,
    height: int,
    output: str = "{name}.png",
    format: str = "penumbra",
) -> None:
    """Writes the :func:`poses` of ``specs`` to ``path`` (JSON) as ``penumbra render --poses``
    does, or with ``format="nerf"`` as ``--poses-format nerf`` does (:func:`nerf`), or with
    ``format="colmap"`` COLMAP's text model into the folder ``path`` (``cameras.txt``,
    ``images.txt``, ``points3D.txt``), with the command line's code; the files appear
    complete or not at all (the folder is made when missing)."""
    frames = _frames("write_poses", specs, width, height, output)
    _core.write_poses(os.fspath(path), format, frames)
