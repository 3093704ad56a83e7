"""``cast_rays(..., attributes=...)`` on a loaded scene's ray-casting scene: what the
renderer sees at each hit, checked against its AOVs for the pixel-centre rays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import penumbra
from penumbra import _core

SCENES = Path(__file__).resolve().parents[2] / "scenes"
W, H = 48, 36


def centre_rays(scene: penumbra.Scene) -> np.ndarray:
    """The rays the one-ray AOVs take, through each pixel's centre: (H, W, 6)."""
    return _core.camera_rays(scene.camera(None)._args(), W, H)


@pytest.mark.parametrize("name", ["showcase.toml", "herd.toml"])
def test_attributes_are_what_the_renderer_sees_through_each_pixel_centre(name):
    # showcase: a textured OBJ, a textured sphere, a smooth scan; herd: instances.
    # The shipped scenes read ../assets: allowed, as `--allow-path assets` allows it.
    scene = penumbra.load(SCENES / name, allow_paths=[SCENES.parent / "assets"])
    hits = scene.raycasting_scene().cast_rays(
        centre_rays(scene), attributes=("albedo", "shading_normal", "uv", "object_id"))
    # One sample at the pixel's centre: the filtered albedo AOV is the centre ray's.
    _, aov = scene.render(width=W, height=H, sampler="center", spp=1,
                          aovs=["albedo", "normal", "object_id"])
    ids = hits["object_id"].numpy()
    assert ids.shape == (H, W) and ids.dtype == np.uint32
    np.testing.assert_array_equal(ids, aov["object_id"])
    np.testing.assert_array_equal(ids, hits["geometry_ids"].numpy())
    hit = ids != penumbra.NO_ID
    assert 0.2 < hit.mean() < 1.0
    albedo = hits["albedo"].numpy()
    # Ray casting's barycentrics come from its watertight test, the renderer's from
    # Möller–Trumbore: texture lookups may differ in the last bits, or across a texel edge.
    near = np.isclose(albedo[hit], aov["albedo"][hit], rtol=0, atol=1e-3).all(axis=-1)
    assert near.mean() > 0.99, near.mean()
    assert (albedo[~hit] == 0).all()
    # The AOV turns the normal to the camera's side; the attribute is the mesh's own.
    normal = hits["shading_normal"].numpy()
    dots = np.abs(np.sum(normal[hit] * aov["normal"][hit], axis=-1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-5)
    assert hits["uv"].numpy().shape == (H, W, 2)
    # Textures and materials make the albedo vary: the test sees more than one colour.
    assert len(np.unique(albedo[hit].round(4), axis=0)) > 5


# A unit quad in z = 0 mapped (0, 0) to (1, 1) corner to corner, as object 0.
UNIT_QUAD = """
[film]
width = 8
height = 8
[camera]
position = [0.5, 0.5, 3]
look_at = [0.5, 0.5, 0]
fov = 30
[[lights]]
type = "point"
position = [0, 0, 3]
[[objects]]
type = "quad"
corner = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
"""


def test_uv_is_the_texture_coordinate_the_texture_is_read_at():
    # A quad mapped (0, 0) to (1, 1) corner to corner: uv is the hit's place on it.
    scene = penumbra.loads(UNIT_QUAD)
    rays = np.array([[0.25, 0.75, 1, 0, 0, -1], [0.6, 0.1, 1, 0, 0, -1], [5, 5, 1, 0, 0, -1]],
                    np.float32)
    hits = scene.raycasting_scene().cast_rays(rays, attributes=["uv", "shading_normal"])
    uv = hits["uv"].numpy()
    np.testing.assert_allclose(uv[:2], [[0.25, 0.75], [0.6, 0.1]], atol=1e-6)
    np.testing.assert_array_equal(uv[2], [0, 0])
    np.testing.assert_allclose(hits["shading_normal"].numpy()[:2], [[0, 0, 1]] * 2, atol=1e-6)
    assert set(hits) >= {"t_hit", "uv", "shading_normal"} and "albedo" not in hits


def test_attributes_need_a_loaded_scene_and_known_names():
    plain = penumbra.RaycastingScene()
    plain.add_triangles(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]], np.uint32))
    rays = np.array([[0.2, 0.2, 1, 0, 0, -1]], np.float32)
    with pytest.raises(ValueError, match="Scene.raycasting_scene"):
        plain.cast_rays(rays, attributes=("albedo",))
    scene = penumbra.load(SCENES / "cornell.toml")
    with pytest.raises(ValueError, match="unknown attribute 'colour'"):
        scene.raycasting_scene().cast_rays(rays, attributes=("colour",))
    # Without attributes, the same dict as before.
    assert set(plain.cast_rays(rays)) == {
        "t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}


def test_geometry_added_later_has_no_object_id_nor_surface():
    # A quad as object 0; then a triangle and a placed copy of the quad added to the
    # ray-casting scene: their geometry ids are no object's, so object_id is INVALID_ID and
    # the surface's attributes are zero, as on a miss.
    scene = penumbra.loads(UNIT_QUAD)
    rc = scene.raycasting_scene()
    assert rc.add_triangles(np.array([[2, 0, 0], [3, 0, 0], [2, 1, 0]], np.float32),
                            np.array([[0, 1, 2]], np.uint32)) == 1
    shift = np.eye(4)
    shift[0, 3] = 4
    assert rc.add_instance(0, shift) == 2
    rays = np.array([[x, 0.25, 1, 0, 0, -1] for x in (0.25, 2.25, 4.25, 9.0)], np.float32)
    hits = rc.cast_rays(rays, attributes=("object_id", "albedo", "uv", "shading_normal"))
    invalid = penumbra.RaycastingScene.INVALID_ID
    assert hits["geometry_ids"].numpy().tolist() == [0, 1, 2, invalid]
    assert hits["object_id"].numpy().tolist() == [0, invalid, invalid, invalid]
    assert hits["object_id"].numpy().dtype == np.uint32
    assert (hits["albedo"].numpy()[0] > 0).all()
    for name in ("albedo", "uv", "shading_normal"):
        assert (hits[name].numpy()[1:] == 0).all(), name
