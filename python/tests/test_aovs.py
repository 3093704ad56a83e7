"""AOVs against closed forms: a quad facing the camera at a known distance, and a cube, with
every pixel's center ray computed here in float64 from the camera model of docs/spec.md §3."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from conftest import same_bits

W, H, EYE_Z, HALF = 40, 30, 4.0, 1.0


def scene(extra: str = "") -> penumbra.Scene:
    return penumbra.loads(
        f"""
[film]
width = {W}
height = {H}
[camera]
position = [0, 0, {EYE_Z}]
look_at = [0, 0, 0]
fov = 40
[render]
sampler = "jittered"
samples = 16
light_samples = 2
[materials.red]
diffuse = [0.6, 0.2, 0.1]
[[lights]]
type = "area"
center = [0, 3, 3]
u = [1, 0, 0]
v = [0, 0, 1]
[[objects]]
type = "quad"
corner = [-{HALF}, -{HALF}, 0]
u = [{2 * HALF}, 0, 0]
v = [0, {2 * HALF}, 0]
material = "red"
{extra}
"""
    )


def center_rays() -> np.ndarray:
    """Unit directions of the pixel-center rays, (H, W, 3) float64."""
    half = np.tan(np.radians(20.0))
    x = (2 * (np.arange(W) + 0.5) / W - 1) * (W / H) * half
    y = (1 - 2 * (np.arange(H) + 0.5) / H) * half
    d = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -np.ones((H, W))), axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_a_quad_at_a_known_distance():
    image, aov = scene().render(aovs=penumbra.AOV_NAMES)
    assert set(aov) == set(penumbra.AOV_NAMES)
    d = center_rays()
    t = EYE_Z / -d[..., 2]
    p = np.array([0, 0, EYE_Z]) + t[..., None] * d
    inside = (np.abs(p[..., 0]) < HALF - 0.02) & (np.abs(p[..., 1]) < HALF - 0.02)
    # More than half a pixel's diagonal (0.05 here) off the quad: every sample misses.
    outside = (np.abs(p[..., 0]) > HALF + 0.06) | (np.abs(p[..., 1]) > HALF + 0.06)
    assert inside.sum() > 300 and outside.sum() > 300

    assert np.allclose(aov["depth"][inside], t[inside], rtol=1e-6)
    assert np.allclose(aov["position"][inside], p[inside], atol=1e-5)
    assert np.all(aov["normal"][inside] == [0, 0, 1])
    assert np.all(aov["object_id"][inside] == 0)
    assert set(np.unique(aov["primitive_id"][inside])) == {0, 1}
    # Every sample of an inner pixel sees the red quad.
    assert np.allclose(aov["albedo"][inside], [0.6, 0.2, 0.1], atol=1e-6)

    assert np.all(np.isinf(aov["depth"][outside])) and np.all(aov["depth"][outside] > 0)
    for name in ("position", "normal", "albedo"):
        assert np.all(aov[name][outside] == 0)
    for name in ("object_id", "primitive_id"):
        assert np.all(aov[name][outside] == penumbra.NO_ID)
    assert penumbra.NO_ID == 4294967295


def test_shapes_dtypes_and_the_unchanged_colour():
    s = scene()
    plain = s.render()
    image, aov = s.render(aovs=("depth", "normal", "albedo", "position", "object_id", "primitive_id"))
    assert same_bits(image, plain)
    for name, shape, dtype in [
        ("depth", (H, W), np.float32),
        ("normal", (H, W, 3), np.float32),
        ("albedo", (H, W, 3), np.float32),
        ("position", (H, W, 3), np.float32),
        ("object_id", (H, W), np.uint32),
        ("primitive_id", (H, W), np.uint32),
    ]:
        a = aov[name]
        assert (a.shape, a.dtype, a.flags["C_CONTIGUOUS"]) == (shape, dtype, True), name
    # Only what was asked for; a single name may be a string.
    _, only = s.render(aovs="depth")
    assert list(only) == ["depth"]
    assert same_bits(only["depth"], aov["depth"])
    _, region = s.render(aovs=("object_id",), region=(3, 20, 5, 9))
    assert np.array_equal(region["object_id"], aov["object_id"][5:9, 3:20])


def test_geometric_aovs_come_from_the_center_ray_and_albedo_is_filtered():
    s = scene()
    _, a = s.render(aovs=penumbra.AOV_NAMES, spp=16, seed=1)
    _, b = s.render(aovs=penumbra.AOV_NAMES, spp=1, sampler="center", seed=2)
    for name in ("depth", "position", "normal", "object_id", "primitive_id"):
        assert np.array_equal(a[name], b[name]), name
    # At the quad's edge some samples miss: the filtered albedo lies strictly between.
    red = np.array([0.6, 0.2, 0.1], np.float32)
    partial = (a["albedo"][..., 0] > 0) & (a["albedo"][..., 0] < 0.6 - 1e-6)
    assert partial.sum() >= 2 * (W // 4)
    ratio = a["albedo"][partial] / red
    assert np.allclose(ratio, ratio[:, :1], atol=1e-6)  # a fraction of the same colour


def test_ids_name_objects_and_triangles_within_them():
    # A cube in front of the quad's lower-left part: object 1, triangles 0..11 of its own.
    _, aov = scene(
        """
[[objects]]
type = "cube"
center = [-0.5, -0.5, 0.5]
size = 0.6
rotate = [20, 30, 0]
"""
    ).render(aovs=("object_id", "primitive_id", "normal", "depth"))
    ids = aov["object_id"]
    assert set(np.unique(ids)) == {0, 1, penumbra.NO_ID}
    cube = ids == 1
    prims = np.unique(aov["primitive_id"][cube])
    assert prims.max() < 12 and len(prims) >= 4
    n = aov["normal"][cube]
    assert np.allclose(np.linalg.norm(n, axis=-1), 1, atol=1e-6)
    # Seen faces point toward the camera.
    d = center_rays()[cube]
    assert np.all(np.sum(n * d, axis=-1) < 0)
    assert np.all(aov["depth"][cube] < EYE_Z)


@pytest.mark.parametrize("threads", [1, 3])
def test_aovs_do_not_depend_on_threads(threads):
    s = scene()
    _, a = s.render(aovs=penumbra.AOV_NAMES, threads=threads)
    _, b = s.render(aovs=penumbra.AOV_NAMES, threads=2)
    for name in penumbra.AOV_NAMES:
        assert a[name].tobytes() == b[name].tobytes(), name


def test_z_is_planar_depth_and_depth_the_distance_along_the_ray():
    # The quad faces the camera EYE_Z away: z is EYE_Z all over it, depth is z over the
    # cosine of each center ray to the optical axis, and both are inf off it.
    _, aov = scene().render(aovs=("depth", "z"))
    assert aov["z"].shape == (H, W) and aov["z"].dtype == np.float32
    hit = np.isfinite(aov["depth"])
    assert hit.sum() > W * H // 10
    assert np.array_equal(hit, np.isfinite(aov["z"]))
    assert np.allclose(aov["z"][hit], EYE_Z, rtol=1e-6)
    cosine = -center_rays()[..., 2]
    assert np.allclose(aov["depth"][hit] * cosine[hit], aov["z"][hit], rtol=1e-5)
    assert aov["depth"][hit].max() > EYE_Z * 1.01
