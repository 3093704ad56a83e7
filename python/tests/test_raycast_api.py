"""penumbra.RaycastingScene's interface: input conversion and errors, Open3D's argument forms
(tensors with .numpy(), a mesh object, both create_rays_pinhole forms with Open3D's ray
layout), results as penumbra.Tensor, Scene.raycasting_scene(), the GIL and Ctrl-C."""

from __future__ import annotations

import os
import signal
import threading
import time
import _thread

import numpy as np
import pytest

import penumbra
from penumbra import _raycast
from raycast_ref import cube, icosphere, random_rays
from test_threads import interrupt_after


@pytest.fixture(scope="module")
def sphere() -> penumbra.RaycastingScene:
    s = penumbra.RaycastingScene()
    s.add_triangles(*icosphere(2))
    return s


def same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k]), k


def test_float64_integer_and_non_contiguous_input_is_converted_not_misread(sphere):
    r32 = random_rays(np.random.default_rng(5), 200)
    want = sphere.cast_rays(r32)
    same(sphere.cast_rays(r32.astype(np.float64)), want)
    same(sphere.cast_rays(r32.tolist()), want)
    wide = np.zeros((200, 12), np.float32)
    wide[:, ::2] = r32  # every other column: a strided view
    same(sphere.cast_rays(wide[:, ::2]), want)
    same(sphere.cast_rays(np.asfortranarray(r32)), want)
    np.testing.assert_array_equal(sphere.cast_rays(r32[::-1])["t_hit"], want["t_hit"][::-1])
    ints = np.array([[0, 0, 5, 0, 0, -1]])
    assert sphere.cast_rays(ints)["t_hit"][0] == pytest.approx(4.0)
    p64 = np.random.default_rng(6).uniform(-2, 2, (50, 3))
    np.testing.assert_array_equal(sphere.compute_distance(p64),
                                  sphere.compute_distance(p64.astype(np.float32)))


def test_open3d_style_tensors_and_mesh_objects_are_accepted():
    class Tensor:  # what open3d.core.Tensor offers: .numpy()
        def __init__(self, a):
            self.a = np.asarray(a)

        def numpy(self):
            return self.a

    class Mesh:  # open3d.t.geometry.TriangleMesh: vertex.positions, triangle.indices
        def __init__(self, v, t):
            self.vertex = type("V", (), {"positions": Tensor(v)})()
            self.triangle = type("T", (), {"indices": Tensor(t)})()

    s = penumbra.RaycastingScene()
    v, t = cube()
    assert s.add_triangles(Tensor(v), Tensor(t)) == 0
    assert s.add_triangles(Mesh(v + 2, t)) == 1
    ans = s.cast_rays(Tensor(np.array([[0.5, 0.5, 9, 0, 0, -1], [2.5, 2.5, 9, 0, 0, -1]], np.float32)))
    assert ans["t_hit"].tolist() == [8.0, 6.0] and ans["geometry_ids"].tolist() == [0, 1]
    with pytest.raises(TypeError, match="TriangleMesh"):
        s.add_triangles(v)


def test_real_open3d_tensors_and_meshes_are_accepted():
    o3d = pytest.importorskip("open3d", reason="open3d is not installed (pip install open3d)")
    v, t = cube()
    mesh = o3d.t.geometry.TriangleMesh()
    mesh.vertex.positions = o3d.core.Tensor(v)
    mesh.triangle.indices = o3d.core.Tensor(t.astype(np.int64))
    s = penumbra.RaycastingScene()
    assert s.add_triangles(mesh) == 0
    assert s.add_triangles(o3d.core.Tensor(v + 2), o3d.core.Tensor(t)) == 1
    rays = o3d.core.Tensor([[0.5, 0.5, 9, 0, 0, -1], [2.5, 2.5, 9, 0, 0, -1]], o3d.core.float64)
    ans = s.cast_rays(rays)
    assert ans["t_hit"].numpy().tolist() == [8.0, 6.0]
    assert s.compute_distance(o3d.core.Tensor([[0.5, 0.5, 3.0]])).tolist() == [2.0]


def test_every_result_is_a_tensor_an_ndarray_with_open3ds_methods(sphere):
    rays = np.array([[0, 0, 5, 0, 0, -1], [3, 3, 5, 0, 0, -1], [0, 0, 0, 0, 0, 0]], np.float32)
    points = np.array([[0, 0, 3], [0.1, 0.2, 0.3]], np.float32)
    pinhole = penumbra.RaycastingScene.create_rays_pinhole(
        fov_deg=60, center=[0, 0, 0], eye=[0, 0, 4], up=[0, 1, 0], width_px=8, height_px=6)
    results = {
        "create_rays_pinhole": pinhole,
        "test_occlusions": sphere.test_occlusions(rays),
        "count_intersections": sphere.count_intersections(rays),
        "compute_distance": sphere.compute_distance(points),
        "compute_signed_distance": sphere.compute_signed_distance(points),
        "compute_occupancy": sphere.compute_occupancy(points),
    }
    for query, answer in [("cast_rays", sphere.cast_rays(rays)),
                          ("list_intersections", sphere.list_intersections(rays)),
                          ("compute_closest_points", sphere.compute_closest_points(points))]:
        results.update({f"{query}[{k!r}]": v for k, v in answer.items()})
    for what, t in results.items():
        assert type(t) is penumbra.Tensor and isinstance(t, np.ndarray), what
        plain = t.numpy()
        assert type(plain) is np.ndarray and np.shares_memory(plain, t), what
        assert t.cpu() is t and np.array_equal(plain, t), what
    t_hit = results["cast_rays['t_hit']"]
    assert t_hit.isfinite().tolist() == [True, False, False]
    assert t_hit.isinf().tolist() == [False, True, True] and not t_hit.isnan().any()
    assert type(t_hit.isfinite()) is penumbra.Tensor
    # A whole-array reduction gives a number, as for an array; an element, a numpy scalar.
    assert type(t_hit[t_hit.isfinite()].sum()) is np.float32 and float(t_hit.min()) == 4.0
    assert type(t_hit[0]) is np.float32
    # Open3D's virtual point cloud: boolean indexing of the rays by the finite hits.
    ans = sphere.cast_rays(pinhole)
    hit = ans["t_hit"].isfinite()
    cloud = pinhole[hit][:, :3] + pinhole[hit][:, 3:] * ans["t_hit"][hit].reshape((-1, 1))
    assert cloud.shape == (int(hit.sum()), 3) and hit.sum() > 10
    np.testing.assert_allclose(np.linalg.norm(cloud.numpy(), axis=1), 1.0, atol=0.02)
    # A Tensor goes back in as rays, and into numpy and penumbra like any array.
    same(sphere.cast_rays(pinhole), ans)
    assert np.asarray(t_hit).dtype == np.float32 and type(np.asarray(t_hit)) is np.ndarray


def test_large_inputs_are_converted_piece_by_piece_to_the_same_rays(sphere, monkeypatch):
    # Conversions go in pieces (so that Ctrl-C is seen between them); tiny pieces here, over
    # leading shapes of one, two and three axes, strided and broadcast.
    rays = random_rays(np.random.default_rng(11), 360)
    want = sphere.cast_rays(rays)
    monkeypatch.setattr(_raycast, "_PIECE", 7)
    r64 = rays.astype(np.float64)
    same(sphere.cast_rays(r64), want)
    same({k: v.reshape(want[k].shape) for k, v in sphere.cast_rays(r64.reshape(12, 30, 6)).items()},
         want)
    same({k: v[0].reshape(want[k].shape) for k, v in
          sphere.cast_rays(r64.reshape(1, 2, 180, 6)).items()}, want)
    wide = np.zeros((360, 12))
    wide[:, ::2] = rays
    same(sphere.cast_rays(wide[:, ::2]), want)
    one = np.broadcast_to(rays[:1], (5, 6))
    np.testing.assert_array_equal(sphere.cast_rays(one)["t_hit"], [want["t_hit"][0]] * 5)


def test_bad_input_raises_clear_errors(sphere):
    s = penumbra.RaycastingScene()
    v, t = cube()
    with pytest.raises(ValueError, match="vertex 8"):
        s.add_triangles(v, np.array([[0, 1, 8]], np.uint32))
    with pytest.raises(ValueError, match=r"\[0, 8\)"):
        s.add_triangles(v, np.array([[0, 1, -1]]))
    with pytest.raises(TypeError, match="integers"):
        s.add_triangles(v, t.astype(np.float32))
    with pytest.raises(ValueError, match=r"\(M, 3\)"):
        s.add_triangles(v, t.reshape(-1))
    with pytest.raises(ValueError, match=r"\(\.\.\., 3\)"):
        s.add_triangles(v[:, :2], t)
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        s.add_triangles(bad, t)
    # Nothing was added by the failed calls: the next mesh is geometry 0.
    assert s.add_triangles(v, t) == 0
    with pytest.raises(ValueError, match=r"rays must have shape \(\.\.\., 6\), not \(4, 3\)"):
        sphere.cast_rays(np.zeros((4, 3), np.float32))
    with pytest.raises(ValueError, match=r"\(\.\.\., 6\)"):
        sphere.count_intersections(np.float32(1.0))
    with pytest.raises(TypeError, match="real numbers"):
        sphere.test_occlusions(np.zeros((2, 6), np.complex64))
    with pytest.raises(ValueError, match="query_points"):
        sphere.compute_distance(np.zeros((2, 6)))
    with pytest.raises(ValueError, match="nthreads"):
        sphere.cast_rays(np.zeros((1, 6)), nthreads=-1)
    with pytest.raises(ValueError, match="nthreads"):
        sphere.cast_rays(np.zeros((1, 6)), nthreads=penumbra.MAX_THREADS + 1)


def test_rays_with_nan_or_a_zero_direction_miss(sphere):
    r = np.array([[0, 0, 5, 0, 0, 0], [np.nan, 0, 5, 0, 0, -1], [0, 0, 5, 0, 0, np.inf]], np.float32)
    assert np.all(np.isinf(sphere.cast_rays(r)["t_hit"]))
    assert not sphere.test_occlusions(r).any()
    assert not sphere.count_intersections(r).any()


def test_threads_do_not_change_results(sphere):
    r = random_rays(np.random.default_rng(7), 5000)
    same(sphere.cast_rays(r, nthreads=1), sphere.cast_rays(r, nthreads=3))
    same(sphere.list_intersections(r, nthreads=1), sphere.list_intersections(r, nthreads=2))


def rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def test_create_rays_pinhole_follows_open3ds_formula():
    rng = np.random.default_rng(8)
    k = np.array([[300.0, 0, 41.5], [0, 280.0, 30.2], [0, 0, 1]])
    rot, t = rotation(rng), rng.normal(size=3)
    e = np.eye(4)
    e[:3, :3], e[:3, 3] = rot, t
    rays = penumbra.RaycastingScene.create_rays_pinhole(k, e, 80, 60)
    assert rays.shape == (60, 80, 6) and rays.dtype == np.float32
    y, x = np.mgrid[0:60, 0:80]
    pix = np.stack([x + 0.5, y + 0.5, np.ones_like(x, float)], -1)
    want_d = pix @ np.linalg.inv(k).T @ rot  # R^T K^-1 p, row-wise
    np.testing.assert_allclose(rays[..., :3], np.broadcast_to(-rot.T @ t, (60, 80, 3)), atol=1e-5)
    np.testing.assert_allclose(rays[..., 3:], want_d, rtol=1e-5, atol=1e-6)
    same_kw = penumbra.RaycastingScene.create_rays_pinhole(
        intrinsic_matrix=k.tolist(), extrinsic_matrix=e, width_px=80, height_px=60)
    np.testing.assert_array_equal(same_kw, rays)


def test_an_image_of_rays_gives_the_flat_batchs_answers(sphere):
    # (height, width, 6) rays are traced as an image (square packets); every answer must be
    # the flat batch's, bit for bit, whatever the image's shape.
    for w, h in [(64, 48), (37, 23), (3, 5), (1, 7)]:
        rays = penumbra.RaycastingScene.create_rays_pinhole(
            fov_deg=40, center=[0, 0, 0], eye=[0.4, 0.3, 2.5], up=[0, 1, 0], width_px=w, height_px=h)
        image = sphere.cast_rays(rays)
        flat = sphere.cast_rays(rays.reshape(-1, 6))
        assert image["t_hit"].shape == (h, w)
        assert np.isfinite(image["t_hit"]).sum() > w * h // 4 or w * h < 40
        same(image, {k: v.reshape(image[k].shape) for k, v in flat.items()})
        # Leading shapes of more than two axes.
        deep = sphere.cast_rays(rays.reshape(1, h, w, 6))
        same({k: v[0] for k, v in deep.items()}, image)


def test_create_rays_pinhole_fov_form_is_open3ds_look_at():
    eye, center, up = np.array([-1.0, -1, -1]), np.array([0.5, 0.5, 0.5]), np.array([0.0, 0, 1])
    rays = penumbra.RaycastingScene.create_rays_pinhole(
        fov_deg=60, center=center, eye=eye, up=up, width_px=32, height_px=24)
    # Open3D: f = w / 2 / tan(fov / 2), principal point at the center; camera rows
    # x = up × forward, y = forward × x, z = forward.
    f = 16 / np.tan(np.radians(30))
    fwd = (center - eye) / np.linalg.norm(center - eye)
    xa = np.cross(up, fwd)
    xa /= np.linalg.norm(xa)
    rot = np.stack([xa, np.cross(fwd, xa), fwd])
    e = np.eye(4)
    e[:3, :3], e[:3, 3] = rot, -rot @ eye
    k = np.array([[f, 0, 16], [0, f, 12], [0, 0, 1]])
    np.testing.assert_allclose(rays, penumbra.RaycastingScene.create_rays_pinhole(k, e, 32, 24),
                               rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(rays[..., :3], np.broadcast_to(eye, (24, 32, 3)), atol=1e-6)
    # The row index grows toward `up`; the middle ray looks at `center`.
    assert rays[-1, 16, 5] > rays[0, 16, 5]
    mid = rays[11:13, 15:17, 3:].mean(axis=(0, 1))
    np.testing.assert_allclose(mid / np.linalg.norm(mid), fwd, atol=1e-6)
    # Positional form, as Open3D's docs call it.
    pos = penumbra.RaycastingScene.create_rays_pinhole(60, center, eye, up, 32, 24)
    np.testing.assert_array_equal(pos, rays)
    with pytest.raises(ValueError, match="fov_deg"):
        penumbra.RaycastingScene.create_rays_pinhole(0, center, eye, up, 32, 24)
    with pytest.raises(ValueError, match="up"):
        penumbra.RaycastingScene.create_rays_pinhole(60, center, eye, fwd, 32, 24)
    with pytest.raises(TypeError, match="missing"):
        penumbra.RaycastingScene.create_rays_pinhole(fov_deg=60, center=center)
    with pytest.raises(ValueError, match="intrinsic_matrix"):
        penumbra.RaycastingScene.create_rays_pinhole(np.eye(4), np.eye(4), 32, 24)


def test_a_loaded_scene_casts_rays_against_its_objects():
    scene = penumbra.loads('''
[film]
width = 4
height = 4
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 40
[[objects]]
type = "quad"
corner = [-1, -1, 0]
u = [2, 0, 0]
v = [0, 2, 0]
[[objects]]
type = "cube"
center = [3, 0, 0]
size = 1
''')
    rc = scene.raycasting_scene()
    assert isinstance(rc, penumbra.RaycastingScene)
    r = np.array([[0.2, 0.3, 5, 0, 0, -1], [3, 0, 5, 0, 0, -1], [9, 9, 5, 0, 0, -1]], np.float32)
    ans = rc.cast_rays(r)
    assert ans["geometry_ids"].tolist() == [0, 1, penumbra.INVALID_ID]
    np.testing.assert_allclose(ans["t_hit"][:2], [5.0, 4.5], rtol=1e-6)
    assert rc.count_intersections(r).tolist() == [1, 2, 0]
    assert rc.compute_occupancy([[3, 0, 0], [0, 0, 0.1]]).tolist() == [1.0, 0.0]


def layers(n: int = 2000) -> penumbra.RaycastingScene:
    """`n` stacked squares: every ray up through them crosses n triangles."""
    z = np.arange(n) * 1e-3
    v = np.array([[[-1, -1, h], [1, -1, h], [1, 1, h], [-1, 1, h]] for h in z], np.float32)
    t = np.arange(n)[:, None, None] * 4 + np.array([[0, 1, 2], [0, 2, 3]])
    s = penumbra.RaycastingScene()
    s.add_triangles(v.reshape(-1, 3), t.reshape(-1, 3).astype(np.uint32))
    return s


def up_rays(n: int) -> np.ndarray:
    xy = np.random.default_rng(9).uniform(-0.9, 0.9, (n, 2))
    return np.hstack([xy, -np.ones((n, 1)), np.zeros((n, 2)), np.ones((n, 1))]).astype(np.float32)


@pytest.mark.usefixtures("sigint_raises")
@pytest.mark.parametrize(
    "how",
    [_thread.interrupt_main, lambda: os.kill(os.getpid(), signal.SIGINT)],
    ids=["interrupt_main", "SIGINT"],
)
def test_ctrl_c_stops_a_huge_batch_fast(how):
    s = layers()
    rays = up_rays(1_000_000)  # 2 billion crossings: many seconds on any machine
    sent = interrupt_after(0.3, how)
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        s.count_intersections(rays, nthreads=2)
    raised = time.perf_counter()
    assert raised - start > 0.25  # it was interrupted, not refused
    latency = raised - sent["at"]
    print(f"KeyboardInterrupt {1000 * latency:.0f} ms after the signal")
    assert latency < 0.25, latency
    assert s.count_intersections(rays[:3]).tolist() == [2000] * 3


@pytest.mark.usefixtures("sigint_raises")
@pytest.mark.parametrize("kind", ["float32", "float64 broadcast"])
def test_ctrl_c_in_the_first_moments_of_a_huge_cast_rays_is_answered_fast(sphere, kind):
    # 20 million rays: 640 MB of results to allocate and fill before the first ray is traced,
    # or, for float64 rays, 480 MB of float32 rays to convert first. Either must stop on
    # Ctrl-C as promptly as the tracing does.
    n = 20_000_000
    one = [0.1, 0.2, 5.0, 0.0, 0.0, -1.0]
    if kind == "float32":
        rays = np.empty((n, 6), np.float32)
        rays[:] = one
    else:
        rays = np.broadcast_to(np.array(one), (n, 6))
    sent = interrupt_after(0.02, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        sphere.cast_rays(rays, nthreads=2)
    raised = time.perf_counter()
    assert sent["at"] > start  # the signal came during the call
    latency = raised - sent["at"]
    print(f"KeyboardInterrupt {1000 * latency:.0f} ms after the signal, "
          f"{1000 * (sent['at'] - start):.0f} ms into the call")
    assert latency < 0.15, latency


def test_the_gil_is_released_during_a_query():
    s = layers()
    rays = up_rays(30_000)
    ticks = []
    worker = threading.Thread(target=lambda: ticks.append(s.count_intersections(rays, nthreads=1)))
    start = time.perf_counter()
    worker.start()
    spins = 0
    while worker.is_alive():
        spins += 1
        time.sleep(0.001)
    assert time.perf_counter() - start > 0.05
    assert spins > 20  # this thread kept running Python meanwhile
    assert np.all(ticks[0] == 2000)


def test_tnear_and_tfar_bound_cast_rays_and_count_intersections(sphere):
    # penumbra's extension (Open3D#5870): the closest hit within [tnear, tfar] is the first
    # listed crossing there, and the count is the listed crossings there.
    rays = random_rays(np.random.default_rng(7), 500)
    listed = sphere.list_intersections(rays)
    splits, t = listed["ray_splits"].numpy(), listed["t_hit"].numpy()
    for tnear, tfar in [(0.0, np.inf), (0.5, 2.0), (1.0, 1.0), (3.0, 1.0)]:
        hit = sphere.cast_rays(rays, tnear=tnear, tfar=tfar)["t_hit"].numpy()
        count = sphere.count_intersections(rays, tfar=tfar, tnear=tnear).numpy()
        for i in range(len(rays)):
            ts = t[splits[i] : splits[i + 1]]
            ts = ts[(ts >= tnear) & (ts <= tfar)]
            assert count[i] == len(ts)
            assert hit[i] == (ts[0] if len(ts) else np.inf)
    # The defaults are Open3D's queries, bit for bit.
    plain = sphere.cast_rays(rays)
    same = sphere.cast_rays(rays, tnear=0.0, tfar=np.inf)
    assert all(np.array_equal(plain[k].numpy(), same[k].numpy()) for k in plain)
    with pytest.raises((TypeError, ValueError), match="tnear"):
        sphere.cast_rays(rays, tnear="near")
