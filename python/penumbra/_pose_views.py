"""The views of a poses file, as ``penumbra render --poses`` writes it (and
:func:`penumbra.poses.write_poses`): penumbra's layout, ``{"frames": [{"file", "position",
"look_at", "up", "fov", "width", "height", ...}]}``, or NeRF's ``transforms.json``
(``--poses-format nerf``), whose frames give a ``transform_matrix`` (camera to world, OpenGL
axes) and the intrinsics. Each frame becomes a view named by its image's file name without
the extension (``out/front.png`` gives ``front``), of its explicit camera and its size.
"""

from __future__ import annotations

import math
import os
from typing import Any, Dict, List, Mapping, Optional

import numpy as np

#: NeRF camera models a penumbra camera is (a centred pinhole without distortion).
NERF_MODELS = ("OPENCV", "PINHOLE")
#: NeRF's distortion coefficients, which must be 0.
DISTORTION = ("k1", "k2", "k3", "k4", "p1", "p2")


def pose_views(data: Mapping[str, Any], where: str) -> List[Dict[str, Any]]:
    """The views of a poses file's JSON ``data`` (its top-level object), ``where`` naming the
    file in messages. Raises ``ValueError`` naming the frame and key for what penumbra's
    pinhole camera cannot be (a NeRF camera with distortion, an off-centre principal point,
    pixels that are not square) or a frame without its camera."""
    frames = data.get("frames")
    if not isinstance(frames, list):
        raise ValueError(f"{where}: frames must be a list of frames, not {frames!r}")
    nerf = any(isinstance(f, Mapping) and "transform_matrix" in f for f in frames)
    if nerf:
        model = data.get("camera_model", "OPENCV")
        if model not in NERF_MODELS:
            raise ValueError(
                f"{where}: camera_model {model!r}: penumbra's camera is a pinhole "
                f"({' or '.join(NERF_MODELS)})"
            )
    out = []
    for i, frame in enumerate(frames):
        at = f"{where}: frames[{i}]"
        if not isinstance(frame, Mapping):
            raise ValueError(f"{at}: a frame is an object, not {frame!r}")
        view = _nerf_view(data, frame, at) if nerf else _penumbra_view(frame, at)
        file = frame.get("file_path" if nerf else "file")
        if isinstance(file, str) and file:
            view["name"] = os.path.splitext(os.path.basename(file))[0]
        out.append(view)
    return out


def _need(frame: Mapping[str, Any], key: str, at: str) -> Any:
    if key not in frame:
        raise ValueError(f"{at}: missing {key!r}")
    return frame[key]


def _penumbra_view(frame: Mapping[str, Any], at: str) -> Dict[str, Any]:
    """A frame of penumbra's layout: its camera as written, and its size."""
    view = {key: _need(frame, key, at) for key in ("position", "look_at", "up", "fov")}
    for key in ("width", "height"):
        if frame.get(key) is not None:
            view[key] = frame[key]
    return view


def _nerf_view(data: Mapping[str, Any], frame: Mapping[str, Any], at: str) -> Dict[str, Any]:
    """A frame of ``transforms.json``: the camera of its ``transform_matrix`` (camera to world
    in OpenGL axes: +x right, +y up, looking along -z) and the vertical field of view of its
    intrinsics (the frame's, else the file's)."""

    def intrinsic(key: str) -> Optional[float]:
        value = frame.get(key, data.get(key))
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{at}: {key} must be a number, not {value!r}")
        if not math.isfinite(value):
            raise ValueError(f"{at}: {key} must be finite, not {value!r}")
        return float(value)

    try:
        m = np.array(_need(frame, "transform_matrix", at), dtype=np.float64)
    except (TypeError, ValueError):
        m = np.zeros(0)
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise ValueError(f"{at}: transform_matrix must be 4 rows of 4 finite numbers")
    for key in DISTORTION:
        if intrinsic(key) not in (None, 0.0):
            raise ValueError(f"{at}: {key} is not 0: penumbra's camera has no lens distortion")
    w, h = intrinsic("w"), intrinsic("h")
    fl_x, fl_y = intrinsic("fl_x"), intrinsic("fl_y")
    cx, cy = intrinsic("cx"), intrinsic("cy")
    if w is not None and h is not None and fl_y is not None:
        if fl_x is not None and not math.isclose(fl_x, fl_y, rel_tol=1e-6):
            raise ValueError(f"{at}: fl_x {fl_x} and fl_y {fl_y} differ: pixels must be square")
        for key, c, side in (("cx", cx, w), ("cy", cy, h)):
            if c is not None and abs(c - side / 2) > 1e-3:
                raise ValueError(
                    f"{at}: {key} {c} is not the image's centre ({side / 2}): penumbra's "
                    f"camera looks through the centre"
                )
        fov = math.degrees(2.0 * math.atan(h / (2.0 * fl_y)))
    else:
        angle = intrinsic("camera_angle_y")
        if angle is None:
            raise ValueError(
                f"{at}: no vertical field of view (give w, h and fl_y, or camera_angle_y)"
            )
        fov = math.degrees(angle)
    position = m[:3, 3]
    view: Dict[str, Any] = {
        "position": position.tolist(),
        "look_at": (position - m[:3, 2]).tolist(),
        "up": m[:3, 1].tolist(),
        "fov": fov,
    }
    if w is not None and h is not None:
        if not (w.is_integer() and h.is_integer()):
            raise ValueError(f"{at}: w and h must be whole numbers of pixels, not {w} and {h}")
        view["width"], view["height"] = int(w), int(h)
    return view
