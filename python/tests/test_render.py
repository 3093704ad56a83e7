"""Rendering to numpy: the same bits as the command line, for any thread count or region,
and many renders from one built world."""

from __future__ import annotations

import shutil
import sys

import numpy as np
import pytest

import penumbra
from conftest import ROOT, SCENES, read_pfm, run_cli, same_bits

CORNELL = SCENES / "cornell.toml"


@pytest.fixture(scope="module")
def cornell() -> penumbra.Scene:
    return penumbra.load(CORNELL)


@pytest.mark.parametrize(
    "cli_args, kwargs",
    [
        ([], {}),
        (
            ["--camera", "left", "--sampler", "jittered", "--spp", "9", "--seed", "7"],
            {"camera": "left", "sampler": "jittered", "spp": 9, "seed": 7},
        ),
        (["--sampler", "center", "--light-samples", "3"], {"sampler": "center", "light_samples": 3}),
        (["--pixelbounds", "5,29,3,17"], {"region": (5, 29, 3, 17)}),
    ],
)
def test_the_image_is_the_command_lines_bit_for_bit(tmp_path, cornell, cli_args, kwargs):
    out = tmp_path / "cli.pfm"
    size = ["--width", 40, "--height", 30]
    run_cli("render", CORNELL, *size, *cli_args, "--quiet", "-o", out)
    image = cornell.render(width=40, height=30, **kwargs)
    assert image.dtype == np.float32 and image.flags["C_CONTIGUOUS"]
    expected = read_pfm(out)
    assert same_bits(image, expected)
    # And written back by penumbra.write_image, the very same file.
    mine = tmp_path / "mine.pfm"
    penumbra.write_image(mine, image)
    assert mine.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("ext", ["png", "exr", "jpg"])
def test_image_files_match_the_command_lines(tmp_path, cornell, ext):
    out = tmp_path / f"cli.{ext}"
    run_cli("render", CORNELL, "--width", 24, "--height", 16, "--quiet", "-o", out)
    mine = tmp_path / f"mine.{ext}"
    penumbra.write_image(mine, cornell.render(width=24, height=16))
    assert mine.read_bytes() == out.read_bytes()


def test_to_srgb8_is_the_srgb_curve(cornell):
    image = cornell.render(width=24, height=16)
    srgb = penumbra.to_srgb8(image)
    assert srgb.dtype == np.uint8 and srgb.shape == image.shape
    # The sRGB curve by hand, in float64.
    c = np.clip(image.astype(np.float64), 0, 1)
    curve = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    assert np.abs(srgb.astype(int) - np.round(255 * curve)).max() <= 1


def test_threads_and_regions_give_identical_arrays(cornell):
    args = dict(width=37, height=23, spp=4, sampler="jittered", seed=3)
    one = cornell.render(threads=1, **args)
    for threads in (2, 3, 8):
        assert same_bits(cornell.render(threads=threads, **args), one)
    part = cornell.render(region=(9, 30, 4, 21), threads=2, **args)
    assert same_bits(part, one[4:21, 9:30])


def test_an_explicit_camera_equals_the_named_one(cornell):
    view = penumbra.Camera(position=(-2.2, 3.8, 5.5), look_at=(0.4, 2.0, -3.5), up=(0, 1, 0), fov=55)
    a = cornell.render(camera=view, width=20, height=20, spp=1)
    b = cornell.render(camera="left", width=20, height=20, spp=1)
    assert same_bits(a, b)
    assert not same_bits(a, cornell.render(width=20, height=20, spp=1))


def test_the_world_is_built_once(tmp_path):
    # A scene with a mesh and a texture, whose files are deleted after loading: every later
    # render, with any camera, size, sampler or seed, still works, so nothing is reread.
    scene_dir = tmp_path / "scene"
    scene_dir.mkdir()
    shutil.copy(ROOT / "assets/textures/spot_texture.png", scene_dir / "tex.png")
    (scene_dir / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0.5 1\nf 1/1 2/2 3/3\n")
    (scene_dir / "s.toml").write_text(
        """
[film]
width = 16
height = 16
[cameras.a]
position = [0, 0, 3]
look_at = [0, 0, 0]
fov = 50
[cameras.b]
position = [1, 1, 3]
look_at = [0, 0, 0]
fov = 40
[textures.t]
type = "image"
file = "tex.png"
[materials.m]
texture = "t"
[[lights]]
type = "point"
position = [0, 0, 3]
[[objects]]
type = "mesh"
file = "tri.obj"
material = "m"
"""
    )
    scene = penumbra.load(scene_dir / "s.toml")
    before = scene.render(camera="b", width=12, height=10, spp=4, seed=1)
    shutil.rmtree(scene_dir)
    assert same_bits(scene.render(camera="b", width=12, height=10, spp=4, seed=1), before)
    for kwargs in ({}, {"camera": "b"}, {"width": 7, "height": 5}, {"sampler": "jittered", "seed": 9}):
        assert scene.render(**kwargs).any()


def test_loads_and_load_dict_give_the_files_image(cornell):
    if sys.version_info < (3, 11):
        pytest.skip("tomllib is in Python 3.11 and later")
    import tomllib

    text = CORNELL.read_text()
    from_text = penumbra.loads(text, base_dir=SCENES)
    from_dict = penumbra.load_dict(tomllib.loads(text), base_dir=SCENES)
    expected = cornell.render(width=16, height=12)
    assert same_bits(from_text.render(width=16, height=12), expected)
    assert same_bits(from_dict.render(width=16, height=12), expected)
    json = penumbra.loads((SCENES / "cornell.json").read_text(), format="json", base_dir=SCENES)
    assert same_bits(json.render(width=16, height=12), expected)


def test_scene_properties(cornell):
    assert cornell.cameras == ["front", "left", "high"]
    assert cornell.settings == {
        "width": 512,
        "height": 512,
        "spp": 4,
        "sampler": "rgss",
        "light_samples": None,  # the file's 5 is each light's own, not an override
        "seed": 0,
        "alpha": False,
    }
    stats = cornell.stats
    assert stats["objects"] > 0 and stats["triangles"] >= 12 * 2 and stats["lights"] == 1
    assert "cameras ['front', 'left', 'high']" in repr(cornell)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"spp": 3}, "perfect square"),
        ({"sampler": "center", "spp": 4}, "center sampler"),
        ({"sampler": "sobol"}, "unknown sampler"),
        ({"camera": "top"}, "front, left, high"),
        ({"width": 0}, "at least 1x1"),
        ({"region": (0, 100, 0, 4)}, "pixel bounds"),
        ({"light_samples": 0}, "light samples"),
        ({"aovs": ("depth", "speed")}, "unknown AOV"),
        ({"threads": penumbra.MAX_THREADS + 1}, "1024"),
    ],
)
def test_bad_settings_are_value_errors(cornell, kwargs, message):
    with pytest.raises(ValueError, match=message):
        cornell.render(**{"width": 8, "height": 8, **kwargs})


def test_bad_arguments_are_refused(cornell):
    with pytest.raises(TypeError):
        cornell.render(camera=5)
    with pytest.raises(ValueError, match="degenerate"):
        penumbra.Camera((0, 0, 0), (0, 0, 0), (0, 1, 0), 40)
    for nan_or_inf in (float("nan"), float("inf"), 1e39):
        with pytest.raises(ValueError, match="must be finite"):
            penumbra.Camera((nan_or_inf, 0, 1), (0, 0, 0), (0, 1, 0), 40)
    with pytest.raises(ValueError, match="fov"):
        penumbra.Camera((0, 0, 1), (0, 0, 0), (0, 1, 0), 180)
    with pytest.raises(ValueError, match="position must have 3 items"):
        penumbra.Camera((0, 0), (0, 0, 0), (0, 1, 0), 40)
    with pytest.raises(ValueError, match="Scene.render: spp must be from 0"):
        cornell.render(spp=-1)


def test_write_image_is_atomic_and_reports_failures(tmp_path):
    image = np.zeros((4, 5, 3), np.float32)
    with pytest.raises(ValueError, match="unknown image format"):
        penumbra.write_image(tmp_path / "x.tiff", image)
    with pytest.raises(OSError):
        penumbra.write_image(tmp_path / "missing" / "x.png", image)
    with pytest.raises(ValueError, match="height, width, 3"):
        penumbra.write_image(tmp_path / "x.png", np.zeros((4, 5), np.float32))
    assert list(tmp_path.iterdir()) == []
    # float64 and non-contiguous input are converted, not misread.
    wide = np.random.default_rng(1).random((6, 8, 3))
    penumbra.write_image(tmp_path / "a.pfm", wide[:, ::2])
    assert np.array_equal(read_pfm(tmp_path / "a.pfm"), wide[:, ::2].astype(np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.pfm"]


def test_a_camera_given_by_k_renders_by_name_and_is_not_passed_off_as_a_fov():
    # Python's Camera holds a field of view: a calibrated K is rendered by its name.
    scene = penumbra.load_dict({
        "film": {"width": 32, "height": 24},
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0],
                   "K": [[40.0, 0.0, 12.0], [0.0, 36.0, 11.5], [0.0, 0.0, 1.0]]},
        "lights": [{"type": "point", "position": [0, 3, 5]}],
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
    })
    image = scene.render()
    assert image.shape == (24, 32, 3) and image.max() > 0
    # Off-centre (cx = 12 of 15.5): the sphere's middle lies left of the image's middle.
    columns = np.flatnonzero(image.sum(axis=(0, 2)) > 0)
    assert columns.mean() < 15.5 - 2
    with pytest.raises(ValueError, match="intrinsic matrix K"):
        scene.camera()
