"""The lens models against OpenCV itself (docs/scene-format.md, "Camera models"): every hit a
pixel's centre ray finds, projected by ``cv2.projectPoints`` or ``cv2.fisheye.projectPoints``
with the scene's K, distortion and pose, lands within 1e-3 px of that pixel's centre; and the
COLMAP and nerfstudio files carry the coefficients as the scene gives them."""

from __future__ import annotations

import cv2  # the test extra's reference for lens models (opencv-python-headless)
import numpy as np
import pytest

import penumbra
import penumbra.poses
import penumbra.record

W, H = 96, 64
K = np.array([[42.0, 0.0, 49.3], [0.0, 40.5, 30.9], [0.0, 0.0, 1.0]])


def pose() -> np.ndarray:
    """Camera to world in OpenCV's axes: at (0.5, 0.3, 2.5), turned 20° about y and 10° about
    x from looking down −z."""
    a, b = np.radians(20.0), np.radians(10.0)
    ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    flip = np.diag([1.0, -1.0, -1.0])
    m = np.eye(4)
    m[:3, :3] = ry @ rx @ flip
    m[:3, 3] = [0.5, 0.3, 2.5]
    return m


def room(camera: dict) -> penumbra.Scene:
    quad = lambda corner, u, v: {"type": "quad", "corner": corner, "u": u, "v": v}  # noqa: E731
    return penumbra.load_dict({
        "film": {"width": W, "height": H},
        "camera": camera,
        "render": {"sampler": "center"},
        "lights": [{"type": "point", "position": [0, 2, 2]}],
        "objects": [
            quad([-4, -2, -3], [8, 0, 0], [0, 5, 0]),
            quad([-4, -2, 4], [8, 0, 0], [0, 0, -7]),
            quad([-4, 3, -3], [8, 0, 0], [0, 0, 9]),
            {"type": "sphere", "center": [0.7, -0.5, 0], "radius": 0.8},
        ],
    })


def hits_and_pixels(scene: penumbra.Scene):
    """The hit positions of the pixel centres that hit, and those pixels' (x, y)."""
    _, aov = scene.render(aovs=["position", "depth"])
    ys, xs = np.nonzero(np.isfinite(aov["depth"]))
    return aov["position"][ys, xs].astype(np.float64), np.stack([xs, ys], axis=1).astype(np.float64)


def world_to_camera(m: np.ndarray):
    r = m[:3, :3].T
    return cv2.Rodrigues(r)[0], -r @ m[:3, 3]


@pytest.mark.parametrize("distortion", [
    [-0.28, 0.07, 0.0002, -0.0001],
    [-0.28, 0.07, 0.0002, -0.0001, 0.01],
    [0.1, -0.05, 0.001, 0.002, 0.01, 0.05, -0.02, 0.003],
    [-0.2, 0.05, 0.001, -0.002, 0.0, 0.02, 0.01, 0.0, 0.002, -0.001, 0.001, 0.0005],
])
def test_opencv_lenses_project_back_onto_their_pixels(distortion):
    m = pose()
    scene = room({"model": "opencv", "K": K.tolist(), "distortion": distortion,
                  "camera_to_world": m.tolist()})
    points, pixels = hits_and_pixels(scene)
    assert len(points) > W * H // 2
    rvec, tvec = world_to_camera(m)
    projected, _ = cv2.projectPoints(points, rvec, tvec, K, np.array(distortion))
    error = np.abs(projected.reshape(-1, 2) - pixels).max()
    assert error < 1e-3, f"a hit projects {error} px from its pixel centre"


def test_fisheye_lenses_project_back_onto_their_pixels():
    m = pose()
    k = [0.02, -0.01, 0.003, -0.0005]
    # OpenCV's fisheye projects points in front of the camera: max_angle 85° keeps to them.
    scene = room({"model": "fisheye", "K": K.tolist(), "distortion": k, "max_angle": 85,
                  "camera_to_world": m.tolist()})
    points, pixels = hits_and_pixels(scene)
    assert len(points) > W * H // 2
    rvec, tvec = world_to_camera(m)
    projected, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), rvec, tvec, K, np.array(k))
    error = np.abs(projected.reshape(-1, 2) - pixels).max()
    assert error < 1e-3, f"a hit projects {error} px from its pixel centre"


PINHOLE = {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40}
DISTORTION = [-0.28, 0.07, 0.0002, -0.0001, 0.01]


def test_a_python_camera_renders_any_lens_exactly():
    m = pose()
    scene = room(PINHOLE)
    camera = penumbra.Camera(model="opencv", K=K, distortion=DISTORTION, camera_to_world=m)
    _, aov = scene.render(camera=camera, sampler="center", aovs=["position", "depth"])
    ys, xs = np.nonzero(np.isfinite(aov["depth"]))
    points = aov["position"][ys, xs].astype(np.float64)
    assert len(points) > W * H // 2
    rvec, tvec = world_to_camera(m)
    projected, _ = cv2.projectPoints(points, rvec, tvec, K, np.array(DISTORTION))
    error = np.abs(projected.reshape(-1, 2) - np.stack([xs, ys], axis=1)).max()
    assert error < 1e-3, f"a hit projects {error} px from its pixel centre"
    # The same camera as a scene file's table renders the same bytes.
    table = {"model": "opencv", "K": K.tolist(), "distortion": DISTORTION,
             "camera_to_world": m.tolist()}
    assert camera.table() == table
    np.testing.assert_array_equal(scene.render(camera=camera), room(table).render())


def test_create_rays_camera_gives_the_rays_of_each_model():
    m = pose()
    k = [0.02, -0.01, 0.003, -0.0005]
    fisheye = penumbra.Camera(model="fisheye", K=K, distortion=k, max_angle=70,
                              camera_to_world=m)
    rays = np.asarray(penumbra.RaycastingScene.create_rays_camera(fisheye, W, H).numpy())
    assert rays.shape == (H, W, 6) and rays.dtype == np.float32
    blind = np.isnan(rays).any(axis=-1)
    assert 0 < blind.sum() < W * H // 4, "the film's corners lie beyond 70°"
    np.testing.assert_allclose(np.linalg.norm(rays[~blind][:, 3:], axis=-1), 1, atol=1e-6)
    cast = room(PINHOLE).raycasting_scene().cast_rays(rays)
    t = np.asarray(cast["t_hit"].numpy())
    assert np.isinf(t[blind]).all()
    ys, xs = np.nonzero(np.isfinite(t))
    points = (rays[ys, xs, :3] + t[ys, xs, None] * rays[ys, xs, 3:]).astype(np.float64)
    rvec, tvec = world_to_camera(m)
    projected, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), rvec, tvec, K, np.array(k))
    # float32 hits 2-3 m away: well within 1e-2 px of their pixel centres.
    error = np.abs(projected.reshape(-1, 2) - np.stack([xs, ys], axis=1)).max()
    assert error < 1e-2, f"a hit projects {error} px from its pixel centre"


@pytest.mark.parametrize("keys, message", [
    ({"K": [[0, 0, 1], [0, 1, 1], [0, 0, 1]]}, "K: "),
    ({"K": K, "fov": 40}, "fov"),
    ({"K": K, "model": "opencv", "distortion": [0.1, 0.2, 0.3]}, "distortion"),
    ({"fov": 40, "model": "fisheye"}, "fov"),
    ({"fov": 40, "aperture_radius": 0.1}, "focus_distance"),
])
def test_python_cameras_are_refused_at_their_key(keys, message):
    with pytest.raises(ValueError, match=f"^Camera: .*{message}"):
        penumbra.Camera((0, 0, 3), (0, 0, 0), **keys)


def test_a_lens_cameras_record_and_pose_carry_its_lens(tmp_path):
    scene = room(PINHOLE)
    camera = penumbra.Camera(model="opencv", K=K, distortion=DISTORTION, camera_to_world=pose())
    rec = penumbra.record.record(scene, camera, tmp_path / "a.png")
    explicit = rec["settings"]["render"]["camera"]["explicit"]
    assert explicit["lens"]["model"] == "opencv" and explicit["lens"]["distortion"] == DISTORTION
    np.testing.assert_allclose(explicit["K"], K)
    np.testing.assert_allclose(penumbra.poses.camera_pose(camera, W, H)["K"], K)
    plain = penumbra.record.record(scene, penumbra.Camera((0, 0, 3), (0, 0, 0), fov=40), "b.png")
    assert "pinhole" in plain["settings"]["render"]["camera"]


def test_a_batch_view_takes_a_cameras_lens_keys():
    from penumbra.views import ViewError, view

    m = pose()
    keys = {"camera_to_world": m.tolist(), "K": K.tolist(), "model": "opencv",
            "distortion": DISTORTION}
    camera = view({"name": "left", **keys})["camera"]
    assert camera == penumbra.Camera(**keys)
    ortho = view({"camera_to_world": m.tolist(), "model": "orthographic",
                  "orthographic_height": 3.0, "height": 20})
    assert ortho["camera"].table()["height"] == 3.0 and ortho["height"] == 20
    with pytest.raises(ViewError, match="distortion is a key of an explicit camera"):
        view({"camera": "front", "distortion": DISTORTION})
    with pytest.raises(ViewError, match="Camera: distortion"):
        view({**keys, "distortion": [0.1, 0.2, 0.3]})


def test_a_lens_camera_renders_by_name_and_is_not_passed_off_as_a_pinhole():
    # Scene.camera gives the fov's pinhole: a lens model is rendered by its name.
    scene = room({"model": "equirectangular", "camera_to_world": pose().tolist()})
    image = scene.render()
    assert image.shape == (H, W, 3) and image.max() > 0
    with pytest.raises(ValueError, match="lens model"):
        scene.camera()
