"""Views for batch rendering: what one image of a batch is (a camera, optional settings and
AOVs, a name), and generators of many: an orbit around a point, a list of poses from JSON.

A view is a dict with these keys, all optional:

- ``name``: used in output file names (``output="out/{name}.png"``); without one, a view
  of a named camera is called by the camera's name (``"front"`` gives ``out/front.png``),
  any other ``view0000``, ``view0001``, ... by its index;
- the camera: ``camera`` (a camera name of the scene, or a :class:`penumbra.Camera`), or
  ``position``, ``look_at``, ``up`` (default ``[0, 1, 0]``) and ``fov`` (degrees, default 45)
  of an explicit pinhole camera, or the keys of any :class:`penumbra.Camera`:
  ``camera_to_world`` (for ``position``/``look_at``/``up``), ``K`` (for ``fov``), ``model``,
  ``distortion``, ``max_angle``, ``orthographic_height`` (the camera's ``height``; ``height``
  is the film's), ``aperture_radius`` and ``focus_distance``; none means the scene's default
  camera;
- ``spp``, ``sampler``, ``light_samples``, ``seed``, ``width``, ``height``, ``alpha``: as
  in :meth:`penumbra.Scene.render` (None keeps the scene file's setting);
- ``aovs``: AOV names, written beside the image as ``{stem}.aovs.npz``.

>>> views = orbit(center=(0, 1, 0), radius=4, frames=4, height=1.5, fov=40)
>>> [v["name"] for v in views]
['orbit0000', 'orbit0001', 'orbit0002', 'orbit0003']
>>> [round(c, 6) for c in views[1]["camera"].position]
[4.0, 2.5, 0.0]
>>> view("front")["name"]
'front'
"""

from __future__ import annotations

import json
import math
import numbers
import os
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

from . import _args, _core
from ._camera import Camera
from ._pose_views import pose_views

#: Keys of an explicit camera beyond a pinhole's, as :class:`penumbra.Camera` names them
#: (but ``orthographic_height``, the camera's ``height``).
LENS_KEYS = (
    "camera_to_world",
    "K",
    "model",
    "distortion",
    "max_angle",
    "orthographic_height",
    "aperture_radius",
    "focus_distance",
)
#: Keys passed on to :meth:`penumbra.Scene.render`.
RENDER_KEYS = ("spp", "sampler", "light_samples", "seed", "width", "height", "alpha")
#: Keys a view may have.
VIEW_KEYS = (
    ("name", "camera", "position", "look_at", "up", "fov") + LENS_KEYS + RENDER_KEYS + ("aovs",)
)
#: Settings a batch's defaults (a jobs file's ``[defaults]``) may give every view.
SETTING_KEYS = RENDER_KEYS + ("aovs",)
#: The most frames :func:`orbit` makes (each is a view, with its image).
MAX_FRAMES = 100_000


def setting_problem(key: str, value: Any) -> Union[str, None]:
    """What is wrong with ``value`` for the view setting ``key`` (one of
    :data:`SETTING_KEYS`), as a message naming the key, or None when nothing is. Checks types
    and the simple ranges; :meth:`penumbra.Scene.render` checks the rest (a perfect square
    ``spp``, the largest sizes)."""
    if key in ("spp", "light_samples", "width", "height"):
        if not _is_int(value) or value < 1:
            return f"{key} must be a positive integer, not {value!r}"
    elif key == "seed":
        if not _is_int(value) or not 0 <= value < 2**64:
            return f"seed must be an integer from 0 to 2^64 - 1, not {value!r}"
    elif key == "alpha":
        if not isinstance(value, bool):
            return f"alpha must be true or false, not {value!r}"
    elif key == "sampler":
        if not isinstance(value, str):
            return f"sampler must be a name such as \"rgss\", not {value!r}"
    elif key == "aovs":
        names = (value,) if isinstance(value, str) else value
        if not isinstance(names, (list, tuple)):
            return f"aovs must be a list of AOV names, not {value!r}"
        for a in names:
            if a not in _core.AOV_NAMES:
                return f"unknown AOV {a!r} in aovs (the AOVs are: {', '.join(_core.AOV_NAMES)})"
    else:
        return f"unknown setting {key!r} (known: {', '.join(SETTING_KEYS)})"
    return None


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


class ViewError(ValueError):
    """A mistake in a view of a batch: ``index`` (its place in the batch, from 0), ``name``
    (the name it was given, else None) and ``reason``. The message names it as
    ``views[INDEX]``, with its name when it has one."""

    def __init__(self, index: int, name: Union[str, None], reason: str) -> None:
        self.index, self.name, self.reason = index, name, reason
        super().__init__(f"{label(index, name)}: {reason}")


def label(index: int, name: Union[str, None]) -> str:
    """How messages name the view at ``index`` of a batch: ``views[INDEX]``, with its name
    when it has one."""
    return f"views[{index}]" + (f" ({name!r})" if name else "")


def view(
    spec: Union[str, Camera, Mapping[str, Any]], index: int = 0, **defaults: Any
) -> Dict[str, Any]:
    """The normalized view of ``spec`` (a view dict, a camera name, or a
    :class:`penumbra.Camera`) at position ``index`` of its batch, with ``defaults`` for the
    keys it leaves out. The result has every key of :data:`VIEW_KEYS` but the pose and lens
    keys: the camera is a name, a :class:`Camera` or None. Raises :class:`ViewError` (a ``ValueError``)
    naming the view and key for a mistake."""
    if isinstance(spec, (str, Camera)):
        spec = {"camera": spec}
    if not isinstance(spec, Mapping):
        raise ViewError(index, None, "a view is a dict, a camera name or a penumbra.Camera")
    given = spec.get("name")
    unknown = sorted(set(spec) - set(VIEW_KEYS))
    if unknown:
        raise ViewError(
            index, given, f"unknown key {unknown[0]!r} (known: {', '.join(VIEW_KEYS)})"
        )
    merged = {**{k: v for k, v in defaults.items() if v is not None}, **spec}
    camera = merged.get("camera")
    lens = [k for k in LENS_KEYS if k in merged]
    if any(k in merged for k in ("position", "look_at", "camera_to_world")):
        if camera is not None:
            raise ViewError(index, given, "give either camera or position/look_at, not both")
        camera = _explicit(merged, index, given)
    elif lens:
        raise ViewError(
            index, given, f"{lens[0]} is a key of an explicit camera: give position and "
            "look_at (or camera_to_world) with it"
        )
    elif camera is not None and not isinstance(camera, (str, Camera)):
        raise ViewError(index, given, "camera must be a camera name or a penumbra.Camera")
    if given is not None and not isinstance(given, str):
        raise ViewError(index, None, f"name must be a string, not {given!r}")
    for key in SETTING_KEYS:
        problem = None if merged.get(key) is None else setting_problem(key, merged[key])
        if problem:
            raise ViewError(index, given, problem)
    default_name = camera if isinstance(camera, str) else f"view{index:04d}"
    name = str(merged.get("name") or default_name)
    aovs = merged.get("aovs") or ()
    if isinstance(aovs, str):
        aovs = (aovs,)
    out: Dict[str, Any] = {"name": name, "camera": camera, "aovs": tuple(str(a) for a in aovs)}
    for key in RENDER_KEYS:
        out[key] = merged.get(key)
    return out


def _explicit(merged: Mapping[str, Any], index: int, given: Optional[str]) -> Camera:
    """The :class:`Camera` of a view's explicit camera keys (fov 45 for a pinhole without
    K or fov)."""
    keys = {k: merged[k] for k in ("position", "look_at", "up", "fov") + LENS_KEYS if k in merged}
    if "camera_to_world" not in keys:
        for needed in ("position", "look_at"):
            if needed not in keys:
                raise ViewError(index, given, f"an explicit camera needs {needed!r}")
    if "orthographic_height" in keys:
        keys["height"] = keys.pop("orthographic_height")
    if not {"fov", "K"} & set(keys) and keys.get("model", "pinhole") in ("pinhole", "opencv"):
        keys["fov"] = 45.0
    try:
        return Camera(**keys)
    except (TypeError, ValueError) as e:
        raise ViewError(index, given, str(e)) from None


def views(
    specs: Iterable[Union[str, Camera, Mapping[str, Any]]], **defaults: Any
) -> List[Dict[str, Any]]:
    """Every view of ``specs`` normalized by :func:`view`; names must be unique (two views
    of one camera need names of their own). Raises :class:`ViewError`."""
    out = [view(s, i, **defaults) for i, s in enumerate(specs)]
    seen: Dict[str, int] = {}
    for i, v in enumerate(out):
        if v["name"] in seen:
            raise ViewError(
                i, v["name"], f"views[{seen[v['name']]}] has this name too (names must be unique)"
            )
        seen[v["name"]] = i
    return out


def orbit(
    center: Sequence[float],
    radius: float,
    frames: int,
    height: float = 0.0,
    fov: float = 45.0,
    up: Sequence[float] = (0.0, 1.0, 0.0),
    start_degrees: float = 0.0,
    name: str = "orbit{index:04d}",
    **settings: Any,
) -> List[Dict[str, Any]]:
    """A turntable: ``frames`` views on a circle of ``radius`` around ``center``, ``height``
    above it along ``up`` (which must be an axis: x, y or z), all looking at ``center``; frame
    k at ``start_degrees + 360·k/frames`` degrees, counted from the axis after up (z for y
    up: frame 0 is in front, on +z) toward the next (x): counter-clockwise seen from above.
    ``settings`` (spp, seed, width, ...) go into every view; ``name`` is formatted with
    ``index``."""
    # Checked before anything is made: a typo of 1e8 frames fails at once, in no memory.
    call = "orbit"
    frames = _args.integer(call, "frames", frames, 1, MAX_FRAMES)
    center = _args.finite_vector(call, "center", center)
    radius = _args.finite(call, "radius", radius, positive=True)
    height = _args.finite(call, "height", height)
    fov = _args.finite(call, "fov", fov)
    start_degrees = _args.finite(call, "start_degrees", start_degrees)
    up = _args.finite_vector(call, "up", up)
    axis = [i for i, c in enumerate(up) if c != 0]
    if len(axis) != 1:
        raise ValueError(f"orbit: up must be an axis such as (0, 1, 0), not {up}")
    try:
        name.format(index=0)
    except (AttributeError, IndexError, KeyError, ValueError) as e:
        raise ValueError(f"orbit: name {name!r} is a pattern of {{index}} only: {e}") from None
    a = axis[0]
    sign = 1.0 if up[a] > 0 else -1.0
    # The circle's plane: the two other axes, in right-handed order (for y up: z, then x),
    # so that the frames turn the positive way about up (counter-clockwise seen from above).
    u, v = (a + 1) % 3, (a + 2) % 3
    out = []
    for k in range(frames):
        angle = math.radians(start_degrees + 360.0 * k / frames)
        p = [float(c) for c in center]
        p[u] += radius * math.cos(angle)
        p[v] += radius * math.sin(angle)
        p[a] += sign * height
        out.append(
            {
                "name": name.format(index=k),
                "camera": Camera(position=p, look_at=center, up=up, fov=fov),
                **settings,
            }
        )
    return out


def path(
    scene: Any,
    camera: str,
    frames: Optional[Iterable[int]] = None,
    name: str = "{camera}{frame:04d}",
    **settings: Any,
) -> List[Dict[str, Any]]:
    """The views of a scene file's camera with keys or a path (``[[cameras.NAME.keys]]``,
    ``path = { type = "orbit", ... }``), one per frame: the task list ``penumbra render
    --camera NAME --frames ...`` renders, for :func:`penumbra.distributed.render_views` or
    :meth:`penumbra.Scene.render`. ``frames`` picks frames (default: all, first to last; one
    outside the path raises ``ValueError``); ``name`` is formatted with ``camera`` and
    ``frame``; ``settings`` go into every view."""
    cameras = scene.camera_path(camera)
    if cameras is None:
        raise ValueError(
            f"camera {camera!r} has no keys or path (the scene's cameras: "
            f"{', '.join(scene.cameras)})"
        )
    picked = list(cameras) if frames is None else list(frames)
    picked = [
        _args.integer("path", f"frames[{i}]", f, -(2**63), 2**63 - 1)
        for i, f in enumerate(picked)
    ]
    for f in picked:
        if f not in cameras:
            first, last = min(cameras), max(cameras)
            raise ValueError(f"camera {camera!r} has frames {first} to {last}, not {f!r}")
    return [
        {"name": name.format(camera=camera, frame=f), "camera": cameras[f], **settings}
        for f in picked
    ]


def from_json(path: Union[str, "os.PathLike[str]"]) -> List[Dict[str, Any]]:
    """The views of a JSON file: a list of view objects (see the module's docs), such as
    ``[{"name": "a", "position": [0, 1, 5], "look_at": [0, 1, 0], "fov": 40}, ...]``, or
    a poses file as ``penumbra render --poses`` (or :func:`penumbra.poses.write_poses`)
    writes it, in penumbra's layout or NeRF's ``transforms.json``: one view per frame, of its
    camera and its size, named by its image's file name without the extension
    (``out/front.png`` gives ``front``), so that a batch renders the same images again."""
    where = os.fspath(path)
    with open(path, encoding="utf-8") as f:
        try:
            data = json.load(f)
        except json.JSONDecodeError as e:
            raise ValueError(f"{where}: line {e.lineno}, column {e.colno}: {e.msg}") from None
    if isinstance(data, dict) and "frames" in data:
        return pose_views(data, where)
    if not isinstance(data, list):
        raise ValueError(
            f"{where}: expected a list of views or a poses file (an object with frames, as "
            f"`penumbra render --poses` writes)"
        )
    return [dict(v) if isinstance(v, dict) else v for v in data]


def output_path(pattern: str, v: Mapping[str, Any], index: int) -> str:
    """``pattern`` with the view's ``{name}`` and ``{index}`` (``{index:04d}``, or
    ``{index:04}`` as the command line writes ``{frame:04}``: zeros to a width), by the
    expander the command line's ``-o`` uses. The name stays one file name, by the rule the
    command line's ``{camera}`` follows: path separators, ``:`` and control characters become
    ``_``, and so does a leading ``.`` or ``-`` (``..`` gives ``_.``), so that no view writes
    outside the pattern's folder; a pattern whose ``..`` after a field leaves that folder
    (``out/{name}/../../x.png``), an unknown field or an unclosed brace is a ``ValueError``.

    >>> output_path("out/{name}/{index:03d}.png", {"name": "../up"}, 3)
    'out/_._up/003.png'
    """
    return _core.view_output_path(pattern, str(v["name"]), index)


def output_paths(pattern: str, views: Sequence[Mapping[str, Any]]) -> List[str]:
    """Each view's :func:`output_path` (its ``index`` its place in ``views``); a
    ``ValueError`` when two views would write one file (``f{index}/../x.png``)."""
    paths = [output_path(pattern, v, i) for i, v in enumerate(views)]
    seen: Dict[str, int] = {}
    for i, p in enumerate(paths):
        j = seen.setdefault(os.path.normpath(p), i)
        if j != i:
            raise ValueError(
                f"output pattern {pattern!r} gives views {j} and {i} the same file "
                f"{os.path.normpath(p)}: use {{name}} or {{index}} in it, and no `..` after them"
            )
    return paths


def aov_path(image_path: str) -> str:
    """Where the AOVs of the image at ``image_path`` go: ``out/a.png`` → ``out/a.aovs.npz``,
    as a batch's records list them."""
    return os.fspath(_core.aov_path(image_path))
