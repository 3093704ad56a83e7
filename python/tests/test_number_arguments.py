"""Numbers given to the pure-Python calls (issue 63, class 6): a NaN, an infinity, a negative
or a fraction where a size or a count is meant is refused in one line naming the call and the
argument, never truncated (``int(2.5)`` was 2) or failing somewhere inside; integers are
integers as numpy takes them (2.0 is refused, numpy integers are taken). A scene dict that
contains itself, or gives a set where a vector is meant, is a SceneError at its key path."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import penumbra
from penumbra import coco, poses, views

SCENE = {
    "film": {"width": 8, "height": 6},
    "cameras": {
        "main": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
        "turn": {"fov": 40, "path": {"type": "orbit", "center": [0, 0, 0], "radius": 3, "frames": 4}},
    },
    "lights": [{"type": "point", "position": [0, 2, 3]}],
    "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
}

CAMERA = penumbra.Camera((0, 0, 3), (0, 0, 0), (0, 1, 0), 40)
IMAGE = np.zeros((6, 8, 3), np.float32)


@pytest.fixture(scope="module")
def scene() -> penumbra.Scene:
    return penumbra.load_dict(SCENE)


def orbit(**change):
    return views.orbit(**{"center": (0, 1, 0), "radius": 2, "frames": 3, **change})


# (the call, its mistake, the error, words of the message)
CASES = [
    (lambda s: penumbra.picture(IMAGE, max_side=math.nan), TypeError, "picture: max_side must be an integer, not float nan"),
    (lambda s: penumbra.picture(IMAGE, max_side=2.5), TypeError, "picture: max_side must be an integer, not float 2.5"),
    (lambda s: penumbra.picture(IMAGE, max_side=0), ValueError, "picture: max_side must be from 1"),
    (lambda s: penumbra.display(IMAGE, max_side=-4), ValueError, "picture: max_side must be from 1 to 4294967295, not -4"),
    (lambda s: coco.amodal_areas(s, None, -4, 6), ValueError, "amodal_areas: width must be from 1 to 4294967295, not -4"),
    (lambda s: coco.amodal_areas(s, None, 2.5, 6), TypeError, "amodal_areas: width must be an integer, not float 2.5"),
    (lambda s: coco.amodal_areas(s, None, 8, math.inf), TypeError, "amodal_areas: height must be an integer"),
    (lambda s: coco.amodal_areas(s, None, 8, 0), ValueError, "amodal_areas: height must be from 1"),
    (lambda s: poses.camera_pose(CAMERA, 64.0, 48), TypeError, "camera_pose: width must be an integer, not float 64.0"),
    (lambda s: poses.camera_pose(CAMERA, 64, -48), ValueError, "camera_pose: height must be from 1"),
    (lambda s: poses.poses([CAMERA], 64, 2.5), TypeError, "poses: height must be an integer, not float 2.5"),
    (lambda s: orbit(radius=math.nan), ValueError, "orbit: radius must be a finite number, not nan"),
    (lambda s: orbit(radius=-2), ValueError, "orbit: radius must be positive, not -2"),
    (lambda s: orbit(height=math.inf), ValueError, "orbit: height must be a finite number, not inf"),
    (lambda s: orbit(start_degrees=math.nan), ValueError, "orbit: start_degrees must be a finite number"),
    (lambda s: orbit(frames=2.5), TypeError, "orbit: frames must be an integer, not float 2.5"),
    (lambda s: orbit(frames=-1), ValueError, "orbit: frames must be from 1 to 100000, not -1"),
    (lambda s: orbit(center={0, 1, 2}), TypeError, "orbit: center must be a list, tuple or array of 3 items"),
    (lambda s: orbit(center=(0, math.nan, 0)), ValueError, "orbit: center[1] must be a finite number, not nan"),
    (lambda s: orbit(up={0, 1, 2}), TypeError, "orbit: up must be a list, tuple or array"),
    (lambda s: orbit(fov=math.nan), ValueError, "orbit: fov must be a finite number, not nan"),
    (lambda s: orbit(fov=200), ValueError, "Camera: fov must be between 0 and 180 degrees"),
    (lambda s: penumbra.Camera((0, 0, 1), (0, 0, 0), (0, 1, 0), math.nan), ValueError, "Camera: fov"),
    (lambda s: penumbra.to_srgb8(IMAGE, gamma="2.2"), TypeError, "to_srgb8: gamma must be a number, not str '2.2'"),
    (lambda s: penumbra.write_image("x.png", IMAGE, gamma=[2.2]), TypeError, "write_image: gamma must be a number"),
    (lambda s: penumbra.picture(IMAGE, gamma=math.nan), ValueError, "picture: gamma must be a finite number, not nan"),
    (lambda s: penumbra.picture(IMAGE, gamma=-1), ValueError, "picture: gamma must be positive, not -1"),
    (lambda s: views.path(s, "turn", frames=[1.0]), TypeError, "path: frames[0] must be an integer, not float 1.0"),
]


@pytest.mark.parametrize("call, error, words", CASES, ids=[c[2].split(" must")[0] for c in CASES])
def test_a_bad_number_is_refused_naming_the_call_and_the_argument(scene, call, error, words):
    with pytest.raises(error) as info:
        call(scene)
    text = str(info.value)
    assert "\n" not in text and words in text, text


def test_the_same_calls_take_integers_of_any_kind(scene):
    assert penumbra.picture(IMAGE, max_side=np.int64(4)).width == 4
    assert sum(coco.amodal_areas(scene, None, np.uint16(8), 6).values()) > 0
    assert poses.camera_pose(CAMERA, np.int32(8), 6)["K"].shape == (3, 3)
    assert len(orbit(frames=np.int64(2), center=np.array([0.0, 1.0, 0.0]))) == 2
    assert [v["name"] for v in views.path(scene, "turn", frames=[np.int64(1)])] == ["turn0001"]


def scene_error(d) -> penumbra.SceneError:
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load_dict(d)
    e = info.value
    assert (e.kind, e.file) == ("bad_value", "<dict>") and "\n" not in str(e), str(e)
    return e


def test_a_scene_dict_that_contains_itself_is_named_at_its_key():
    d = copy.deepcopy(SCENE)
    d["objects"][0]["material"] = d["objects"][0]
    e = scene_error(d)
    assert e.key == "objects[0].material" and "objects[0].material: contains itself" in str(e)
    d = copy.deepcopy(SCENE)
    d["objects"].append(d["objects"])
    assert scene_error(d).key == "objects[1]"
    d = copy.deepcopy(SCENE)
    d["film"]["scene"] = d
    assert scene_error(d).key == "film.scene"


def test_one_dict_used_twice_is_not_a_cycle():
    d = copy.deepcopy(SCENE)
    ball = d["objects"][0]
    d["objects"] = [ball, ball, {"type": "sphere", "center": ball["center"], "radius": 0.5}]
    assert penumbra.load_dict(d).stats["objects"] == 3


@pytest.mark.parametrize(
    "change, key",
    [
        (lambda d: d["cameras"]["main"].__setitem__("position", {0, 0, 3}), "cameras.main.position"),
        (lambda d: d["objects"][0].__setitem__("center", frozenset((0.0, 1.0, 2.0))), "objects[0].center"),
        (lambda d: d["lights"].__setitem__(0, {**d["lights"][0], "color": {1, 2, 3}}), "lights[0].color"),
    ],
)
def test_a_set_in_a_scene_dict_is_refused_at_its_key(change, key):
    d = copy.deepcopy(SCENE)
    change(d)
    e = scene_error(d)
    assert e.key == key and "a set has no order" in str(e), str(e)


def test_a_scene_dict_nested_past_any_use_is_refused_not_a_recursion_error():
    d = copy.deepcopy(SCENE)
    deep: list = []
    d["objects"][0]["extra"] = deep
    for _ in range(5000):
        deep.append([])
        deep = deep[0]
    e = scene_error(d)
    assert e.key.startswith("objects[0].extra[0][0]") and "nests deeper than" in str(e)
