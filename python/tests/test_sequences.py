"""Camera paths of scene files against Python (issue 28): an orbit in a scene file, rendered
frame by frame by the command line, gives the cameras and images of ``penumbra.views.orbit``;
``--poses`` writes them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import penumbra
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
