"""Camera paths of scene files against Python (issue 28): an orbit in a scene file, rendered
frame by frame by the command line, gives the cameras and images of ``penumbra.views.orbit``;
``--poses`` writes them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import penumbra
import penumbra.poses
from penumbra import views
from conftest import SCENES, read_pfm, run_cli, same_bits

CORNELL = SCENES / "cornell.toml"


def orbit_override(center, radius, height, frames, start, fov, up=(0, 1, 0)) -> str:
    path = (
        f'{{type = "orbit", center = {list(center)}, radius = {radius}, height = {height}, '
        f"frames = {frames}, start_angle = {start}}}"
    )
    return f"cameras.turn={{fov = {fov}, up = {list(up)}, path = {path}}}"


@pytest.mark.parametrize(
    "up, height, start",
    [((0, 1, 0), 0.3, 0), ((0, 1, 0), -0.2, 37.5), ((0, 0, -1), 0.4, 200), ((1, 0, 0), 0.0, 10)],
)
def test_an_orbit_path_has_the_cameras_of_views_orbit(tmp_path, up, height, start):
    center, radius, frames, fov = (0.1, 0.9, -0.2), 2.7, 7, 41
    poses = tmp_path / "poses.json"
    run_cli(
        "render", CORNELL, "--set", orbit_override(center, radius, height, frames, start, fov, up),
        "--camera", "turn", "--width", 4, "--height", 3, "--spp", 1, "--quiet",
        "-o", tmp_path / "f{frame}.png", "--poses", poses,
    )
    written = json.loads(poses.read_text())["frames"]
    expected = views.orbit(
        center=center, radius=radius, frames=frames, height=height, fov=fov, up=up,
        start_degrees=start,
    )
    assert [p["frame"] for p in written] == list(range(frames))
    for pose, view in zip(written, expected):
        camera = view["camera"]
        # The same single-precision numbers (what the renderer uses), to the bit.
        assert np.array_equal(np.float32(pose["position"]), np.float32(camera.position))
        assert np.array_equal(np.float32(pose["look_at"]), np.float32(camera.look_at))
        assert np.array_equal(np.float32(pose["up"]), np.float32(camera.up))
        assert np.float32(pose["fov"]) == np.float32(camera.fov)


def test_an_orbit_paths_frames_are_the_images_of_views_orbit(tmp_path):
    center, radius, height, frames, start, fov = (0.0, 1.0, 0.0), 2.5, 0.4, 5, 15, 45
    run_cli(
        "render", CORNELL, "--set", orbit_override(center, radius, height, frames, start, fov),
        "--camera", "turn", "--width", 24, "--height", 16, "--quiet", "--frames", "1:4:3",
        "-o", tmp_path / "f{frame}.pfm",
    )
    scene = penumbra.load(CORNELL)
    turn = views.orbit(
        center=center, radius=radius, frames=frames, height=height, fov=fov, start_degrees=start
    )
    for frame in (1, 4):
        image = scene.render(camera=turn[frame]["camera"], width=24, height=16)
        assert same_bits(image, read_pfm(tmp_path / f"f{frame}.pfm")), frame


def test_python_poses_are_the_command_lines(tmp_path):
    # The orbit as a path of the scene file (CLI) and as views.orbit (Python): the same K,
    # poses and NeRF transforms, number for number. Both files are written by one function
    # (penumbra::products::poses::write): what differs is where the cameras come from.
    center, radius, height, frames, start, fov = (0.0, 1.0, 0.0), 2.5, 0.4, 5, 15, 45
    for fmt in ("penumbra", "nerf"):
        run_cli(
            "render", CORNELL, "--set", orbit_override(center, radius, height, frames, start, fov),
            "--camera", "turn", "--width", 6, "--height", 4, "--spp", 1, "--quiet",
            "-o", tmp_path / "img" / "turn{frame:04}.png", "--poses", tmp_path / f"cli_{fmt}.json",
            "--poses-format", fmt,
        )
        turn = views.orbit(
            center=center, radius=radius, frames=frames, height=height, fov=fov,
            start_degrees=start, name="turn{index:04d}",
        )
        mine = tmp_path / f"py_{fmt}.json"
        penumbra.poses.write_poses(
            mine, turn, 6, 4, output=str(tmp_path / "img" / "{name}.png"), format=fmt
        )
        cli = json.loads((tmp_path / f"cli_{fmt}.json").read_text())
        py = json.loads(mine.read_text())
        for c, p in zip(cli["frames"], py["frames"]):
            if fmt == "nerf":
                assert c["file_path"] == p["file_path"] == f"img/turn{c['frame']:04d}.png"
                keys = ("transform_matrix", "fl_x", "fl_y", "cx", "cy", "w", "h")
            else:
                keys = ("frame", "file", "width", "height", "fov", "K", "camera_to_world",
                        "camera_to_world_opengl", "world_to_camera", "position", "look_at", "up")
            for key in keys:
                assert c[key] == p[key], (fmt, c["frame"], key)
    pose = penumbra.poses.camera_pose(turn[0]["camera"], 6, 4)
    assert pose["K"][0, 2] == 2.5 and pose["K"][1, 2] == 1.5
    with pytest.raises(ValueError, match="explicit camera"):
        penumbra.poses.poses(["front"], 6, 4)


def test_a_path_cameras_views_are_the_command_lines_frames(tmp_path):
    # The keyframed camera of a scene file as Python views (the task list the command line
    # renders): each frame's image is the command line's, bit for bit.
    keys = """
[cameras.fly]
fov = 40
[[cameras.fly.keys]]
frame = 3
position = [0, 1, 3.5]
look_at = [0, 1, 0]
[[cameras.fly.keys]]
frame = 5
position = [1, 1.5, 3]
look_at = [0, 0.8, 0]
fov = 30
[[cameras.fly.keys]]
frame = 8
position = [-1, 1, 3]
look_at = [0, 1, 0]
"""
    path = tmp_path / "fly.toml"
    path.write_text(CORNELL.read_text() + keys)
    run_cli(
        "render", path, "--camera", "fly", "--frames", "4:8:2", "--width", 20, "--height", 14,
        "--quiet", "-o", tmp_path / "fly{frame}.pfm",
    )
    scene = penumbra.load(path)
    assert scene.camera_path("front") is None
    assert sorted(scene.camera_path("fly")) == list(range(3, 9))
    fly = views.path(scene, "fly", frames=range(4, 9, 2), width=20, height=14)
    assert [v["name"] for v in fly] == ["fly0004", "fly0006", "fly0008"]
    for v, frame in zip(fly, (4, 6, 8)):
        image = scene.render(camera=v["camera"], width=20, height=14)
        assert same_bits(image, read_pfm(tmp_path / f"fly{frame}.pfm")), frame
    with pytest.raises(ValueError, match="frames 3 to 8"):
        views.path(scene, "fly", frames=[9])
    with pytest.raises(ValueError, match="no keys or path"):
        views.path(scene, "front")
