"""Arguments of the rendering API under abuse (issue 30, classes 7 and 8): every mistake is one
line naming the call and the argument, a ``TypeError`` for the wrong kind of value (a float
where an integer is meant, a set where a vector is) and a ``ValueError`` for one out of range,
never a bare ``OverflowError``, a silently truncated value or a failure after the work."""

from __future__ import annotations

import math

import numpy as np
import pytest

import penumbra

SCENE = {
    "film": {"width": 8, "height": 6},
    "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"type": "point", "position": [0, 2, 3]}],
    "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
}

MAX = penumbra.MAX_THREADS


@pytest.fixture(scope="module")
def scene() -> penumbra.Scene:
    return penumbra.load_dict(SCENE)


def one_line(e: BaseException) -> str:
    text = str(e)
    assert "\n" not in text, text
    return text


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        ({"spp": -1}, ValueError, "spp"),
        ({"spp": 2**40}, ValueError, "spp"),
        ({"spp": 4.0}, TypeError, "spp"),
        ({"spp": "4"}, TypeError, "spp"),
        ({"spp": True}, TypeError, "spp"),
        ({"width": -8}, ValueError, "width"),
        ({"width": 2**40}, ValueError, "width"),
        ({"width": 0}, ValueError, "1x1"),
        ({"height": 2**33}, ValueError, "height"),
        ({"height": 6.5}, TypeError, "height"),
        ({"light_samples": -1}, ValueError, "light_samples"),
        ({"seed": -1}, ValueError, "seed"),
        ({"seed": 2**64}, ValueError, "seed"),
        ({"seed": 0.5}, TypeError, "seed"),
        ({"threads": -1}, ValueError, "threads"),
        ({"threads": 2**70}, ValueError, "threads"),
        ({"threads": MAX + 1}, ValueError, "threads"),
        ({"threads": 2.0}, TypeError, "threads"),
        ({"region": (-1, 4, 0, 4)}, ValueError, "region x0"),
        ({"region": (0, 2**40, 0, 4)}, ValueError, "region x1"),
        ({"region": (0.5, 4.7, 0, 4)}, TypeError, "region x0"),
        ({"region": (0, 4, 0, 4.0)}, TypeError, "region y1"),
        ({"region": np.array([0, 4, 0, 2.5])}, TypeError, "region x0"),
        ({"region": {0, 1, 2, 3}}, TypeError, "region"),
        ({"region": "0123"}, TypeError, "region"),
        ({"region": (0, 4, 0)}, ValueError, "region"),
        ({"sampler": 3}, TypeError, "sampler"),
    ],
)
def test_bad_render_arguments_name_the_call_and_the_argument(scene, kwargs, error, words):
    with pytest.raises(error) as info:
        scene.render(**kwargs)
    assert type(info.value) is error, repr(info.value)
    text = one_line(info.value)
    assert words in text, text
    if "1x1" not in words:
        assert text.startswith("Scene.render: "), text


@pytest.mark.parametrize(
    "kwargs", [{"spp": np.int64(4)}, {"width": np.uint16(4)}, {"region": np.array([1, 3, 0, 2])}]
)
def test_numpy_integers_are_integers(scene, kwargs):
    assert scene.render(**kwargs).ndim == 3


def outcome(call):
    try:
        call()
    except Exception as e:  # noqa: BLE001 - the outcome is the exception's type
        return type(e)
    return None


@pytest.mark.parametrize("threads", [0, 1, MAX, MAX + 1, -1, 2**70, 2.0, "2"])
def test_load_and_render_take_the_same_threads(scene, threads, tmp_path):
    """One check: what load takes, render takes, and the other way round."""
    rendered = outcome(lambda: scene.render(width=2, height=2, threads=threads))
    path = tmp_path / "s.json"
    path.write_text(__import__("json").dumps(SCENE))
    loads = [
        lambda: penumbra.load(path, threads=threads),
        lambda: penumbra.loads(path.read_text(), format="json", threads=threads),
        lambda: penumbra.load_dict(SCENE, threads=threads),
        lambda: penumbra.load_pack(scene.pack(), threads=threads),
    ]
    for load in loads:
        assert outcome(load) is rendered, threads
    assert (rendered is None) == (isinstance(threads, int) and 0 <= threads <= MAX)


@pytest.mark.parametrize(
    "change, key",
    [
        (lambda d: d["camera"]["position"].__setitem__(2, math.nan), "camera.position[2]"),
        (lambda d: d["camera"].__setitem__("fov", math.inf), "camera.fov"),
        (lambda d: d["objects"][0].__setitem__("radius", -math.inf), "objects[0].radius"),
        (
            lambda d: d["objects"][0].__setitem__("center", np.array([0.0, np.nan, 0.0])),
            "objects[0].center[1]",
        ),
        (lambda d: d["lights"][0].__setitem__("position", (0, np.float32("nan"), 3)), "lights[0].position[1]"),
    ],
)
def test_nan_in_a_scene_dict_is_a_bad_value_at_its_key(change, key):
    d = __import__("copy").deepcopy(SCENE)
    change(d)
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load_dict(d)
    e = info.value
    assert (e.kind, e.key, e.file) == ("bad_value", key, "<dict>")
    text = one_line(e)
    assert key in text and "not a finite number" in text, text
    assert "syntax" not in text and "expected value" not in text, text


@pytest.mark.parametrize("name", ["a\0b", "front\nback", "\x1b[31mred"])
def test_camera_names_with_control_characters_render_and_are_printed_safely(name):
    """A camera name with a NUL or another control character is a name like any other: it
    renders (file names made of it are sanitized where they are made), and messages show it
    escaped, on one line."""
    d = {**SCENE, "cameras": {name: SCENE["camera"]}}
    del d["camera"]
    scene = penumbra.load_dict(d)
    assert scene.cameras == [name]
    assert scene.render(camera=name, width=2, height=2).shape == (2, 2, 3)
    with pytest.raises(ValueError) as info:
        scene.render(camera=name + "?")
    text = one_line(info.value)
    assert "no camera named" in text and "\x00" not in text and "\x1b" not in text, text


def test_an_unknown_camera_name_is_refused_before_rendering_and_printed_safely(scene):
    with pytest.raises(ValueError) as info:
        scene.render(camera="a\0b\x1b[31m")
    text = one_line(info.value)
    assert "no camera named" in text and "a\\u{0}b" in text, text
    assert "\x00" not in text and "\x1b" not in text, text


@pytest.mark.parametrize("name", ["x.png", "x.jpg"])
@pytest.mark.parametrize("gamma", [0.0, -0.0, -2.2, math.nan, math.inf, -math.inf, 1e-40])
def test_gamma_must_be_a_positive_finite_number(tmp_path, name, gamma):
    image = np.full((2, 3, 3), 0.5, np.float32)
    with pytest.raises(ValueError) as info:
        penumbra.write_image(tmp_path / name, image, gamma=gamma)
    text = one_line(info.value)
    assert text.startswith("write_image: ") and "gamma" in text, text
    with pytest.raises(ValueError) as info:
        penumbra.to_srgb8(image, gamma=gamma)
    text = one_line(info.value)
    assert text.startswith("to_srgb8: ") and "gamma" in text, text
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("shape", [(1, 65536, 3), (65536, 1, 3)])
def test_a_jpeg_beyond_its_size_limit_is_a_value_error_naming_the_limit(tmp_path, shape):
    with pytest.raises(ValueError) as info:
        penumbra.write_image(tmp_path / "wide.jpg", np.zeros(shape, np.float32))
    text = one_line(info.value)
    assert "65535" in text and "JPEG" in text, text
    assert list(tmp_path.iterdir()) == []


GOOD_CAMERA = {"position": (0, 1, 5), "look_at": (0, 0, 0), "up": (0, 1, 0), "fov": 45}


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("position", {0, 1, 5}, "position"),
        ("look_at", frozenset((0, 1, 2)), "look_at"),
        ("up", {"x": 0, "y": 1, "z": 0}, "up"),
        ("position", "015", "position"),
        ("position", iter((0, 1, 5)), "position"),
        ("position", (0, "1", 5), "position[1]"),
        ("fov", "45", "fov"),
    ],
)
def test_a_camera_takes_ordered_vectors_of_numbers(key, value, words):
    with pytest.raises(TypeError) as info:
        penumbra.Camera(**{**GOOD_CAMERA, key: value})
    text = one_line(info.value)
    assert text.startswith("Camera: ") and words in text, text


def test_a_camera_without_a_field_of_view_names_it():
    # None is a key left out, as in a scene file: a pinhole needs fov (or K).
    with pytest.raises(ValueError, match="^Camera: missing field `fov`"):
        penumbra.Camera(**{**GOOD_CAMERA, "fov": None})


@pytest.mark.parametrize(
    "value", [[0, 1, 5], (0, 1, 5), np.array([0, 1, 5]), np.array([0.0, 1, 5], np.float32), range(3)]
)
def test_a_camera_takes_lists_tuples_and_arrays(value):
    camera = penumbra.Camera(**{**GOOD_CAMERA, "position": value})
    assert camera.position == tuple(float(v) for v in value)
