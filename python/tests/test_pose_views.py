"""views.from_json reads the poses files the command line writes (issue 62): penumbra's
layout gives each frame's camera and size exactly, so the views render the command line's
images again, bit for bit; NeRF's transforms.json gives the same camera, pose for pose; what
penumbra's pinhole cannot be is refused naming the frame and the key."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

import penumbra
from penumbra import poses, views

from conftest import SCENES, read_pfm, run_cli, same_bits


def cli_poses(tmp_path, fmt: str):
    """The room's path camera ``turn`` (frames 0 to 2) rendered to PFM files, and its poses
    file in ``fmt``."""
    path = tmp_path / f"{fmt}.json"
    run_cli(
        "render", SCENES / "cornell.toml", "--width", 16, "--height", 12, "--spp", 1,
        "--set", 'cameras.turn = { fov = 60, path = { type = "orbit", center = [0, 1, -3], '
        'radius = 2.6, height = 4.2, frames = 3 } }',
        "--camera", "turn", "-o", tmp_path / "img" / "turn{frame:04}.pfm",
        "--poses", path, "--poses-format", fmt, "--quiet",
    )
    return path


def test_a_penumbra_poses_file_gives_the_views_that_render_its_images(tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    read = views.from_json(cli_poses(tmp_path, "penumbra"))
    assert [v["name"] for v in read] == ["turn0000", "turn0001", "turn0002"]
    for v in views.views(read):
        assert (v["width"], v["height"]) == (16, 12)
        image = scene.render(camera=v["camera"], width=v["width"], height=v["height"], spp=1)
        assert same_bits(image, read_pfm(tmp_path / "img" / f"{v['name']}.pfm")), v["name"]


def test_a_nerf_transforms_file_gives_the_same_cameras(tmp_path):
    from_penumbra = views.views(views.from_json(cli_poses(tmp_path, "penumbra")))
    written = json.loads(cli_poses(tmp_path, "nerf").read_text())
    from_nerf = views.views(views.from_json(tmp_path / "nerf.json"))
    assert [v["name"] for v in from_nerf] == [v["name"] for v in from_penumbra]
    for frame, a, b in zip(written["frames"], from_penumbra, from_nerf):
        assert (b["width"], b["height"]) == (16, 12)
        assert b["camera"].fov == pytest.approx(a["camera"].fov, abs=1e-4)
        pose = poses.camera_pose(b["camera"], 16, 12)
        assert np.allclose(pose["camera_to_world_opengl"], frame["transform_matrix"], atol=1e-5)
        assert np.allclose(pose["K"], poses.camera_pose(a["camera"], 16, 12)["K"], atol=1e-4)


def test_python_written_poses_read_back_as_their_views(tmp_path):
    cams = [penumbra.Camera((0, 1, 4), (0, 1, 0), (0, 1, 0), 40),
            penumbra.Camera((3, 2, 0), (0, 1, 0), (0, 1, 0), 55)]
    specs = [{"name": "a", "camera": cams[0]}, {"name": "b", "camera": cams[1], "width": 8}]
    poses.write_poses(tmp_path / "p.json", specs, 32, 24, output="out/{name}.png")
    read = views.views(views.from_json(tmp_path / "p.json"))
    assert [(v["name"], v["camera"], v["width"], v["height"]) for v in read] == [
        ("a", cams[0], 32, 24), ("b", cams[1], 8, 24)
    ]
    # One layout, written and returned by the same code: the file is poses()'s value, and
    # NeRF's file nerf()'s of it, every number to the bit.
    assert json.loads((tmp_path / "p.json").read_text()) == poses.poses(
        specs, 32, 24, output="out/{name}.png")
    poses.write_poses(tmp_path / "sub" / "t.json", specs, 32, 24, output="out/{name}.png",
                      format="nerf")
    written = json.loads((tmp_path / "sub" / "t.json").read_text())
    frames = poses.poses(specs, 32, 24, output="out/{name}.png")
    assert written == poses.nerf(frames, str(tmp_path / "sub"))
    assert written["frames"][0]["file_path"] == os.path.relpath("out/a.png", tmp_path / "sub")
    # COLMAP's model: a folder of three files, by the command line's code.
    poses.write_poses(tmp_path / "sparse" / "0", specs, 32, 24, output="out/{name}.png",
                      format="colmap")
    assert sorted(os.listdir(tmp_path / "sparse" / "0")) == [
        "cameras.txt", "images.txt", "points3D.txt"]
    images = (tmp_path / "sparse" / "0" / "images.txt").read_text().splitlines()
    assert [line.split(" ")[-1] for line in images if line and not line.startswith("#")] == [
        "a.png", "b.png"]
    with pytest.raises(ValueError, match=r'unknown poses format "bundler"'):
        poses.write_poses(tmp_path / "c.json", specs, 32, 24, format="bundler")


def nerf_file(tmp_path, **change):
    frame = {
        "file_path": "img/a.png",
        "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 1], [0, 0, 1, 4], [0, 0, 0, 1]],
    }
    top = {"camera_model": "OPENCV", "fl_x": 20.0, "fl_y": 20.0, "cx": 8.0, "cy": 6.0,
           "w": 16, "h": 12, "frames": [frame]}
    for key, value in change.items():
        (frame if key in frame else top)[key] = value
    path = tmp_path / "transforms.json"
    path.write_text(json.dumps(top))
    return path


@pytest.mark.parametrize(
    "change, words",
    [
        ({"k1": 0.1}, "frames[0]: k1 is not 0"),
        ({"cx": 7.0}, "frames[0]: cx 7.0 is not the image's centre (8.0)"),
        ({"fl_x": 30.0}, "frames[0]: fl_x 30.0 and fl_y 20.0 differ"),
        ({"camera_model": "OPENCV_FISHEYE"}, "camera_model 'OPENCV_FISHEYE'"),
        ({"transform_matrix": [[1, 0, 0]]}, "frames[0]: transform_matrix must be 4 rows"),
        ({"fl_y": float("nan")}, "frames[0]: fl_y must be finite"),
    ],
)
def test_what_a_pinhole_cannot_be_is_refused_naming_the_frame(tmp_path, change, words):
    path = nerf_file(tmp_path, **change)
    with pytest.raises(ValueError) as info:
        views.from_json(path)
    assert str(path) in str(info.value) and words in str(info.value), str(info.value)


def test_a_nerf_frame_becomes_a_camera_looking_along_minus_z(tmp_path):
    (v,) = views.views(views.from_json(nerf_file(tmp_path)))
    assert v["name"] == "a" and (v["width"], v["height"]) == (16, 12)
    assert v["camera"].position == (0.0, 1.0, 4.0) and v["camera"].look_at == (0.0, 1.0, 3.0)
    assert v["camera"].fov == pytest.approx(2 * np.degrees(np.arctan(6 / 20)))


def test_other_json_is_refused_saying_what_is_read(tmp_path):
    path = tmp_path / "x.json"
    path.write_text('{"views": []}')
    with pytest.raises(ValueError, match="expected a list of views or a poses file"):
        views.from_json(path)
