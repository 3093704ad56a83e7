"""Camera poses and intrinsics of views, as ``penumbra render --poses`` writes them
(docs/spec.md §10): ``K`` in OpenCV's convention (pixel centres at integer coordinates, so a
centred camera has cx = (W - 1)/2), ``camera_to_world`` in OpenCV axes (+x right, +y down,
+z forward), ``camera_to_world_opengl`` (+x right, +y up, +z backward) and
``world_to_camera``. The numbers are the command line's, computed by the same code.

>>> from penumbra import Camera
>>> pose = camera_pose(Camera((0, 0, 5), (0, 0, 0), (0, 1, 0), 90), 64, 48)
>>> float(pose["K"][0, 2]), float(pose["K"][1, 2])
(31.5, 23.5)
>>> pose["camera_to_world"][:3, 3].tolist()
[0.0, 0.0, 5.0]
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Mapping, Sequence, Union

import numpy as np

from . import _args, _core
from ._camera import Camera
from ._staged import write_json
from .views import output_path, views as normalized

#: The layouts :func:`write_poses` writes.
FORMATS = ("penumbra", "nerf")


def camera_pose(camera: Camera, width: int, height: int) -> Dict[str, np.ndarray]:
    """``K`` (3×3), ``camera_to_world``, ``camera_to_world_opengl`` and ``world_to_camera``
    (4×4, float64) of ``camera`` on a ``width`` × ``height`` film."""
    if not isinstance(camera, Camera):
        raise TypeError(f"camera_pose takes a penumbra.Camera, not {type(camera).__name__}")
    width = _args.size("camera_pose", "width", width)
    height = _args.size("camera_pose", "height", height)
    k, c2w, gl, w2c = _core.camera_pose(
        camera.position, camera.look_at, camera.up, camera.fov, width, height
    )
    return {
        "K": np.array(k),
        "camera_to_world": np.array(c2w),
        "camera_to_world_opengl": np.array(gl),
        "world_to_camera": np.array(w2c),
    }


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
    width = _args.size("poses", "width", width)
    height = _args.size("poses", "height", height)
    frames = []
    for i, v in enumerate(normalized(specs)):
        camera = v["camera"]
        if not isinstance(camera, Camera):
            raise ValueError(
                f"views[{i}]: poses need an explicit camera (a penumbra.Camera or "
                f"position/look_at), not {camera!r}"
            )
        w, h = v["width"] or width, v["height"] or height
        pose = camera_pose(camera, w, h)
        frames.append(
            {
                "frame": i,
                "camera": v["name"],
                "file": output_path(output, v, i),
                "width": w,
                "height": h,
                "fov": float(np.float32(camera.fov)),
                **{key: m.tolist() for key, m in pose.items()},
                "position": [float(c) for c in np.float32(camera.position)],
                "look_at": [float(c) for c in np.float32(camera.look_at)],
                "up": [float(c) for c in np.float32(camera.up)],
            }
        )
    return {"frames": frames}


def nerf(frames: Dict[str, List[Dict[str, Any]]], folder: str = ".") -> Dict[str, Any]:
    """The ``transforms.json`` of :func:`poses`' result, as instant-ngp and nerfstudio read
    it: ``camera_model`` "OPENCV", ``fl_x``, ``fl_y``, ``cx``, ``cy`` (NeRF's pixel centres
    at +1/2: K's plus 1/2), ``w``, ``h``, ``camera_angle_x``/``_y``, zero distortion, and
    per frame ``file_path`` (relative to ``folder``, where the file goes) and
    ``transform_matrix`` (``camera_to_world_opengl``), with the intrinsics repeated."""
    out: Dict[str, Any] = {"camera_model": "OPENCV"}
    listed = []
    for f in frames["frames"]:
        k = f["K"]
        w, h = f["width"], f["height"]
        intrinsics = {
            "fl_x": k[0][0],
            "fl_y": k[1][1],
            "cx": k[0][2] + 0.5,
            "cy": k[1][2] + 0.5,
            "w": w,
            "h": h,
            "camera_angle_x": 2.0 * float(np.arctan(w / (2.0 * k[0][0]))),
            "camera_angle_y": 2.0 * float(np.arctan(h / (2.0 * k[1][1]))),
        }
        if not listed:
            out.update(intrinsics)
            out.update({"k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0})
        rel = os.path.relpath(os.path.abspath(f["file"]), os.path.abspath(folder))
        listed.append(
            {
                "file_path": rel,
                "transform_matrix": f["camera_to_world_opengl"],
                **intrinsics,
                "camera": f["camera"],
                "frame": f["frame"],
            }
        )
    out["frames"] = listed
    return out


def write_poses(
    path: Union[str, "os.PathLike[str]"],
    specs: Sequence[Union[Camera, Mapping[str, Any]]],
    width: int,
    height: int,
    output: str = "{name}.png",
    format: str = "penumbra",
) -> None:
    """Writes the :func:`poses` of ``specs`` to ``path`` (JSON) as ``penumbra render --poses``
    does, or with ``format="nerf"`` as ``--poses-format nerf`` does (:func:`nerf`); the file
    appears complete or not at all."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, not {format!r}")
    value: Any = poses(specs, width, height, output)
    if format == "nerf":
        value = nerf(value, os.path.dirname(os.fspath(path)) or ".")
    path = os.fspath(path)
    write_json(path, value, indent=2)
