"""A model is a scene: penumbra.load("model.obj") (or .ply) builds the scene of a bare mesh,
with a camera framing its bounds and the default light rig, as `penumbra render` does."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra

# A unit cube centred at (5, 5, 5): only a camera that frames the bounds sees it.
CORNERS = "4.5 4.5 4.5\n5.5 4.5 4.5\n5.5 5.5 4.5\n4.5 5.5 4.5\n" \
    "4.5 4.5 5.5\n5.5 4.5 5.5\n5.5 5.5 5.5\n4.5 5.5 5.5\n"
OBJ = "mtllib cube.mtl\n" + "".join(f"v {line}\n" for line in CORNERS.splitlines()) + \
    "usemtl red\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n"
PLY = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n" \
    "property float z\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n" \
    + CORNERS + "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 3 7 6 2\n4 0 4 7 3\n4 1 2 6 5\n"


@pytest.fixture
def models(tmp_path):
    (tmp_path / "cube.obj").write_text(OBJ)
    (tmp_path / "cube.mtl").write_text("newmtl red\nKd 0.9 0.1 0.1\n")
    (tmp_path / "cube.ply").write_text(PLY)
    return tmp_path


@pytest.mark.parametrize("name", ["cube.obj", "cube.ply"])
def test_a_mesh_file_loads_as_a_framed_lit_scene(models, name):
    scene = penumbra.load(models / name, threads=1)
    s = scene.settings
    assert (s["width"], s["height"], s["spp"], s["sampler"]) == (800, 600, 4, "rgss")
    assert scene.stats["triangles"] == 12
    assert scene.stats["lights"] == 1
    read = [name] + (["cube.mtl"] if name.endswith(".obj") else [])
    assert scene.files == sorted(str(models / f) for f in read)
    image = np.asarray(scene.render(spp=1, light_samples=1, width=40, height=30))
    assert image.shape[:2] == (30, 40)
    centre = image[15, 20, :3]
    assert centre.max() > 0.1, centre
    assert not image[0, 0, :3].any() and not image[-1, -1, :3].any()
    if name.endswith(".obj"):
        assert centre[0] > 2 * max(centre[1], centre[2]), centre  # the MTL's red


def test_raycasting_works_on_a_model(models):
    rays_scene = penumbra.load(models / "cube.ply", threads=1).raycasting_scene()
    # A ray down the z axis through the cube's centre hits its near face at z = 5.5.
    rays = np.array([[5.0, 5.0, 10.0, 0.0, 0.0, -1.0]], np.float32)
    hit = rays_scene.cast_rays(rays)
    assert np.allclose(np.asarray(hit["t_hit"]), [4.5])


def test_a_missing_or_bad_model_names_the_file(models):
    with pytest.raises(FileNotFoundError):
        penumbra.load(models / "missing.obj")
    (models / "empty.obj").write_text("v 0 0 0\n")
    with pytest.raises(penumbra.SceneError, match="empty.obj: .*no faces"):
        penumbra.load(models / "empty.obj")


def test_a_model_packs_and_loads_back_as_the_same_scene(models):
    scene = penumbra.load(models / "cube.obj", threads=1)
    again = penumbra.load_pack(scene.pack(), threads=1)
    assert again.stats["triangles"] == 12
    assert again.settings == scene.settings


def test_camera_auto_frames_any_scene_as_a_model_is_framed(models):
    model = penumbra.load(models / "cube.obj", threads=1)
    small = dict(spp=1, light_samples=1, width=40, height=30)
    assert np.array_equal(model.render(**small), model.render(camera="auto", **small))
    assert model.camera("auto") == model.camera()
    # A scene whose own camera looks away from the cube: auto frames it all the same.
    away = penumbra.load_dict({
        "film": {"width": 40, "height": 30},
        "camera": {"position": [0, 0, 0], "look_at": [-1, 0, 0], "fov": 40},
        "lights": [{"type": "point", "position": [5, 9, 5]}],
        "objects": [{"type": "cube", "center": [5, 5, 5], "size": 1}],
    })
    assert away.camera("auto").look_at == pytest.approx((5, 5, 5))
    assert away.render(camera="auto", **small).max() > 0
    from penumbra import distributed, views
    distributed.check_views(away, [{"name": "a", "camera": "auto",
                                    **{k: None for k in views.RENDER_KEYS}}])


def test_a_vcglib_ply_with_extra_face_values_and_no_texture_file_loads(tmp_path):
    # As VCGlib writes it: a TextureFile that is not there, and values after each face's list.
    faces = "".join(f"{line} 0 0 0\n" for line in PLY.split("end_header\n")[1].splitlines()[8:])
    text = PLY.replace("format ascii 1.0\n",
                       "format ascii 1.0\ncomment TextureFile gone.png\n")
    text = text.split("end_header\n")[0] + "end_header\n" + CORNERS + faces
    (tmp_path / "vcg.ply").write_text(text)
    scene = penumbra.load(tmp_path / "vcg.ply", threads=1)
    assert scene.stats["triangles"] == 12
    assert scene.files == [str(tmp_path / "vcg.ply")]
