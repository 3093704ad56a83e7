"""penumbra.RaycastingScene against a brute-force float64 reference on random rays and
points (two meshes, so geometry ids matter), Open3D's dtypes, shapes and miss values, and
watertightness on the shared edges and vertices of a closed mesh."""

from __future__ import annotations

import numpy as np
import pytest

import penumbra
from raycast_ref import MARGIN, closest_points, cube, hits, icosphere, random_rays, soup

MESHES = [icosphere(2), cube((1.2, 0.2, -0.3), (1.8, 0.8, 0.3))]
TRIS = soup(MESHES)
# (geometry id, primitive id) of each row of TRIS.
GEOMETRY = np.concatenate([np.full(len(t), g) for g, (_, t) in enumerate(MESHES)])
PRIMITIVE = np.concatenate([np.arange(len(t)) for _, t in MESHES])
INVALID = 4294967295


@pytest.fixture(scope="module")
def scene() -> penumbra.RaycastingScene:
    s = penumbra.RaycastingScene(nthreads=2)
    assert [s.add_triangles(v, t) for v, t in MESHES] == [0, 1]
    return s


@pytest.fixture(scope="module")
def rays() -> np.ndarray:
    return random_rays(np.random.default_rng(1), 3000)


def test_invalid_id_is_open3ds():
    assert penumbra.INVALID_ID == penumbra.RaycastingScene.INVALID_ID == INVALID


def test_cast_rays_matches_the_reference(scene, rays):
    ans = scene.cast_rays(rays)
    t, u, v, hit, clear = hits(rays, TRIS)
    assert clear.mean() > 0.98
    tt = np.where(hit, t, np.inf)
    best = tt.argmin(axis=1)
    ref_t = tt.min(axis=1)
    missed = ~np.isfinite(ref_t)
    assert 0.2 < missed.mean() < 0.8  # both outcomes are exercised
    c = clear
    assert np.array_equal(np.isinf(ans["t_hit"][c]), missed[c])
    assert np.all(ans["geometry_ids"][c & missed] == INVALID)
    assert np.all(ans["primitive_ids"][c & missed] == INVALID)
    assert np.all(ans["primitive_uvs"][c & missed] == 0)
    h = c & ~missed
    np.testing.assert_allclose(ans["t_hit"][h], ref_t[h], rtol=1e-5, atol=1e-6)
    # Two triangles at the same t (within rounding) are a tie: either id is right.
    got = np.array([np.flatnonzero((GEOMETRY == g) & (PRIMITIVE == p))[0]
                    for g, p in zip(ans["geometry_ids"][h], ans["primitive_ids"][h])])
    rows = np.flatnonzero(h)
    assert np.mean(got == best[h]) > 0.999
    np.testing.assert_allclose(t[rows, got], ref_t[h], rtol=1e-5, atol=1e-6)
    uv = np.stack([u[rows, got], v[rows, got]], axis=1)
    np.testing.assert_allclose(ans["primitive_uvs"][h], uv, atol=1e-4)
    n = np.cross(TRIS[got, 1] - TRIS[got, 0], TRIS[got, 2] - TRIS[got, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    np.testing.assert_allclose(ans["primitive_normals"][h], n, atol=1e-5)


def test_result_dtypes_and_shapes_follow_the_leading_shape(scene, rays):
    r = rays[:24].reshape(2, 3, 4, 6)
    ans = scene.cast_rays(r)
    want = {"t_hit": ((2, 3, 4), np.float32), "geometry_ids": ((2, 3, 4), np.uint32),
            "primitive_ids": ((2, 3, 4), np.uint32), "primitive_uvs": ((2, 3, 4, 2), np.float32),
            "primitive_normals": ((2, 3, 4, 3), np.float32)}
    assert {k: (a.shape, a.dtype) for k, a in ans.items()} == want
    flat = scene.cast_rays(rays[:24])
    for k in want:
        assert np.array_equal(ans[k].reshape(flat[k].shape), flat[k])
    assert scene.test_occlusions(r).dtype == np.bool_
    assert scene.test_occlusions(r).shape == (2, 3, 4)
    assert scene.count_intersections(r).dtype == np.int32
    assert scene.count_intersections(r).shape == (2, 3, 4)
    one = scene.cast_rays(rays[0])
    assert one["t_hit"].shape == () and one["primitive_uvs"].shape == (2,)
    empty = scene.cast_rays(np.zeros((0, 6), np.float32))
    assert empty["t_hit"].shape == (0,) and empty["primitive_normals"].shape == (0, 3)


@pytest.mark.parametrize("tnear, tfar", [(0.0, np.inf), (0.5, 1.5), (1.0, 1.0)])
def test_test_occlusions_matches_the_reference(scene, rays, tnear, tfar):
    got = scene.test_occlusions(rays, tnear=tnear, tfar=tfar)
    t, _, _, hit, clear = hits(rays, TRIS, tnear)
    scale = np.linalg.norm(rays[:, 3:].astype(np.float64), axis=1)[:, None]
    clear &= ~(hit & (np.abs(t - tfar) * scale <= MARGIN)).any(axis=1)
    ref = (hit & (t <= tfar)).any(axis=1)
    assert np.array_equal(got[clear], ref[clear])
    if tfar == np.inf:
        assert np.array_equal(got, np.isfinite(scene.cast_rays(rays)["t_hit"]))


def test_count_and_list_intersections_match_the_reference(scene, rays):
    count = scene.count_intersections(rays)
    t, u, v, hit, clear = hits(rays, TRIS)
    assert np.array_equal(count[clear], hit.sum(axis=1)[clear])
    assert count.max() >= 2
    lst = scene.list_intersections(rays)
    assert set(lst) == {"ray_splits", "ray_ids", "t_hit", "geometry_ids", "primitive_ids",
                        "primitive_uvs"}
    for k in ("ray_splits", "ray_ids", "geometry_ids", "primitive_ids"):
        assert lst[k].dtype == np.uint32, k
    assert lst["t_hit"].dtype == lst["primitive_uvs"].dtype == np.float32
    splits = lst["ray_splits"]
    assert splits.shape == (len(rays) + 1,) and splits[0] == 0
    assert np.array_equal(np.diff(splits), count)
    assert np.array_equal(lst["ray_ids"], np.repeat(np.arange(len(rays)), count))
    for i in np.flatnonzero(clear & (count > 0))[:300]:
        s = slice(splits[i], splits[i + 1])
        ts = lst["t_hit"][s]
        assert np.all(np.diff(ts) >= 0)
        want = sorted(zip(t[i, hit[i]], GEOMETRY[hit[i]], PRIMITIVE[hit[i]]))
        assert list(zip(lst["geometry_ids"][s], lst["primitive_ids"][s])) == [(g, p) for _, g, p in want]
        np.testing.assert_allclose(ts, [x for x, _, _ in want], rtol=1e-5, atol=1e-6)
        rows = [np.flatnonzero((GEOMETRY == g) & (PRIMITIVE == p))[0] for _, g, p in want]
        np.testing.assert_allclose(lst["primitive_uvs"][s], np.stack([u[i, rows], v[i, rows]], 1), atol=1e-4)


def test_counts_from_outside_a_closed_mesh_are_even(rays):
    s = penumbra.RaycastingScene()
    s.add_triangles(*icosphere(2))
    outside = np.linalg.norm(rays[:, :3], axis=1) > 1.01
    assert np.all(s.count_intersections(rays[outside]) % 2 == 0)


def test_closest_points_and_distance_match_the_reference(scene):
    pts = np.random.default_rng(2).uniform(-2, 2.5, (400, 3)).astype(np.float32)
    ans = scene.compute_closest_points(pts)
    assert ans["points"].shape == (400, 3) and ans["geometry_ids"].dtype == np.uint32
    ref = closest_points(pts, TRIS)
    dist = scene.compute_distance(pts)
    assert dist.dtype == np.float32 and dist.shape == (400,)
    np.testing.assert_allclose(dist, ref, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(ans["points"] - pts, axis=1), ref, rtol=1e-5, atol=1e-6)
    rows = np.array([np.flatnonzero((GEOMETRY == g) & (PRIMITIVE == p))[0]
                     for g, p in zip(ans["geometry_ids"], ans["primitive_ids"])])
    uv = ans["primitive_uvs"].astype(np.float64)
    on = (1 - uv.sum(1))[:, None] * TRIS[rows, 0] + uv[:, :1] * TRIS[rows, 1] + uv[:, 1:] * TRIS[rows, 2]
    np.testing.assert_allclose(on, ans["points"], atol=1e-5)
    n = np.cross(TRIS[rows, 1] - TRIS[rows, 0], TRIS[rows, 2] - TRIS[rows, 0])
    np.testing.assert_allclose(ans["primitive_normals"], n / np.linalg.norm(n, axis=1, keepdims=True), atol=1e-5)


def test_an_empty_scene_misses_everything(rays):
    s = penumbra.RaycastingScene()
    ans = s.cast_rays(rays[:5])
    assert np.all(np.isinf(ans["t_hit"])) and np.all(ans["geometry_ids"] == INVALID)
    assert not s.test_occlusions(rays[:5]).any()
    near = s.compute_closest_points(np.zeros((2, 3)))
    assert np.all(np.isnan(near["points"])) and np.all(near["primitive_ids"] == INVALID)
    assert np.all(np.isinf(s.compute_distance(np.zeros((2, 3)))))


def test_occupancy_and_signed_distance_of_a_unit_cube_are_closed_form():
    s = penumbra.RaycastingScene()
    s.add_triangles(*cube())
    p = np.random.default_rng(3).uniform(-0.5, 1.5, (2000, 3)).astype(np.float32)
    q = np.abs(p.astype(np.float64) - 0.5) - 0.5
    sdf = np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)
    inside = q.max(axis=1) < 0
    occ = s.compute_occupancy(p)
    assert occ.dtype == np.float32 and occ.shape == (2000,)
    assert np.array_equal(occ, inside.astype(np.float32))
    assert np.array_equal(s.compute_occupancy(p, nsamples=3), occ)
    sd = s.compute_signed_distance(p.reshape(40, 50, 3))
    assert sd.dtype == np.float32 and sd.shape == (40, 50)
    np.testing.assert_allclose(sd.ravel(), sdf, atol=1e-6)
    with pytest.raises(ValueError, match="nsamples"):
        s.compute_occupancy(p, nsamples=2)


def test_rays_aimed_at_shared_edges_and_vertices_hit(rays):
    v, t = icosphere(2)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    edges = np.unique(np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    targets = np.concatenate([v, (v[edges[:, 0]] + v[edges[:, 1]]) / 2,
                              (v[edges[:, 0]] * 0.25 + v[edges[:, 1]] * 0.75)]).astype(np.float32)
    # From outside toward each target, crossing the surface there (not grazing a silhouette,
    # where a float32 target just outside the surface is rightly missed), and radially.
    rng = np.random.default_rng(4)
    w = targets / np.linalg.norm(targets, axis=1, keepdims=True)
    origins = (3 * w + rng.uniform(-0.6, 0.6, w.shape)).astype(np.float32)
    d = targets - origins
    assert np.all(np.einsum("ij,ij->i", d / np.linalg.norm(d, axis=1, keepdims=True), w) < -0.5)
    r = np.concatenate([np.hstack([origins, d]),
                        np.hstack([targets * 3, -2 * targets])]).astype(np.float32)
    ans = s.cast_rays(r)
    assert np.all(np.isfinite(ans["t_hit"])), f"{np.isinf(ans['t_hit']).sum()} rays slipped through"
    assert np.all(ans["t_hit"] <= 1 + 1e-5)
    assert s.test_occlusions(r).all()
    counts = s.count_intersections(r)
    assert np.all(counts % 2 == 0) and np.all(counts >= 1)
    # From the center every ray leaves exactly once.
    out = np.hstack([np.zeros_like(targets), targets]).astype(np.float32)
    assert np.all(s.count_intersections(out) == 1)
    assert np.all(s.compute_occupancy(np.zeros((1, 3))) == 1)
