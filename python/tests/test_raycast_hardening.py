"""penumbra.RaycastingScene under abuse: the four ray queries agree on a lone triangle's
edges and vertices; far coordinates are answered exactly or refused; results too large for
memory raise MemoryError instead of killing the process; Ctrl-C is answered within about
0.1 s in a dense region and during the BVH build; bad integers, singular cameras and sets are
refused with one clear line; geometry added while another thread queries is safe."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import penumbra
from raycast_ref import cube
from test_threads import interrupt_after

TRIANGLE = (
    np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32),
    np.array([[0, 1, 2]], np.uint32),
)


def lone_triangle() -> penumbra.RaycastingScene:
    s = penumbra.RaycastingScene()
    s.add_triangles(*TRIANGLE)
    return s


@pytest.mark.parametrize(
    "point", [(0, 0), (1, 0), (0, 1), (0.5, 0), (0, 0.5), (0.5, 0.5), (0.25, 0.25)],
    ids=["corner 0", "corner 1", "corner 2", "edge 01", "edge 02", "edge 12", "inside"],
)
@pytest.mark.parametrize("direction", [(0, 0, -1), (0.25, -0.5, -1), (-0.125, 0.25, 2)])
def test_the_four_queries_agree_on_a_lone_triangles_edges_and_vertices(point, direction):
    s = lone_triangle()
    d = np.array(direction, np.float32)
    ray = np.concatenate([np.array([*point, 0], np.float32) - d, d])[None]
    assert np.isfinite(s.cast_rays(ray)["t_hit"][0])
    assert s.test_occlusions(ray)[0]
    assert s.count_intersections(ray).tolist() == [1]  # Open3D counts 1
    assert s.list_intersections(ray)["ray_splits"].tolist() == [0, 1]


@pytest.mark.parametrize("scale", [1e8, 1e10, 1e11, 1e12])
def test_far_scenes_are_answered_as_near_ones(scale):
    s = penumbra.RaycastingScene()
    s.add_triangles(TRIANGLE[0] * np.float32(scale), TRIANGLE[1])
    points = np.array([[0.25, 0.25, 0.5], [0.3, -1, 0]]) * scale
    closest = s.compute_closest_points(points)["points"]
    np.testing.assert_allclose(closest, np.array([[0.25, 0.25, 0], [0.3, 0, 0]]) * scale,
                               rtol=1e-5, atol=1e-5 * scale)
    origin = np.array([0.2, 0.2, 0.9]) * scale
    targets = np.array([[x, y, 0] for x in (0.1, 0.3, 0.5) for y in (0.1, 0.4)]) * scale
    d = targets - origin
    for direction in (d, d / np.linalg.norm(d, axis=1)[:, None] * 1e-3):
        rays = np.hstack([np.broadcast_to(origin, d.shape), direction])
        assert np.isfinite(s.cast_rays(rays)["t_hit"]).all()
        assert s.count_intersections(rays).tolist() == [1] * len(rays)


def test_coordinates_beyond_1e12_are_refused_naming_the_argument():
    s = lone_triangle()
    with pytest.raises(ValueError, match=r"add_triangles: vertex_positions: vertex 1 .*1e12"):
        s.add_triangles(TRIANGLE[0] * np.float32([[1, 1, 1], [3e12, 1, 1], [1, 1, 1]]),
                        TRIANGLE[1])
    rays = np.tile(np.float32([0.2, 0.2, 1, 0, 0, -1]), (5, 1))
    rays[3, 0] = -2e12
    for query in ("cast_rays", "test_occlusions", "count_intersections", "list_intersections"):
        with pytest.raises(ValueError, match=rf"{query}: rays: ray 3 .*1e12"):
            getattr(s, query)(rays)
    with pytest.raises(ValueError, match=r"compute_occupancy: query_points: query point 1"):
        s.compute_occupancy([[0, 0, 0], [0, 0, 5e12]])
    # Closest points work for any finite query point.
    assert s.compute_distance([[0, 0, 1e30]])[0] == pytest.approx(1e30)


def run_limited(code: str, extra_bytes: int) -> subprocess.CompletedProcess:
    """Runs `code` in a Python whose address space may grow by `extra_bytes` beyond what it
    takes once penumbra is imported."""
    prelude = textwrap.dedent(f"""
        import resource, numpy as np, penumbra
        from raycast_ref import cube
        size = int(open('/proc/self/status').read().split('VmSize:')[1].split()[0]) * 1024
        resource.setrlimit(resource.RLIMIT_AS, (size + {extra_bytes}, resource.RLIM_INFINITY))
        try:
    """)
    body = textwrap.indent(textwrap.dedent(code), "    ")
    epilogue = "\nexcept MemoryError as e:\n    print('MemoryError:', e)\n"
    env = dict(os.environ, PYTHONPATH=os.path.dirname(__file__))
    return subprocess.run([sys.executable, "-c", prelude + body + epilogue],
                          capture_output=True, text=True, env=env, timeout=300)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS and /proc")
@pytest.mark.parametrize("code, call", [
    ("s = penumbra.RaycastingScene(); s.add_triangles(*cube())\n"
     "rays = np.zeros((24_000_000, 6), np.float32); rays[:, 5] = 1\n"
     "s.cast_rays(rays, nthreads=2)", "cast_rays"),
    ("penumbra.RaycastingScene.create_rays_pinhole(60.0, [0, 0, 0], [0, 0, 5], [0, 1, 0],"
     " 20000, 20000)", "create_rays_pinhole"),
    ("v = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], np.float32)\n"
     "s = penumbra.RaycastingScene()\n"
     "s.add_triangles(np.vstack([v + [0, 0, k * 1e-3] for k in range(1000)]),\n"
     "                np.arange(3000, dtype=np.uint32).reshape(-1, 3))\n"
     "rays = np.zeros((300_000, 6), np.float32); rays[:, 2] = -1; rays[:, 5] = 1\n"
     "s.list_intersections(rays, nthreads=2)", "list_intersections"),
], ids=["cast_rays", "create_rays_pinhole", "list_intersections"])
def test_results_too_large_for_memory_raise_memory_error(code, call):
    out = run_limited(code, 900 << 20)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.startswith(f"MemoryError: {call}:"), (out.stdout, out.stderr[-2000:])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS and /proc")
def test_an_occupancy_vote_streams_its_rays():
    # 100 000 points × 255 rays were 612 MB of rays made up front; now a round at a time.
    out = run_limited(
        "s = penumbra.RaycastingScene(); s.add_triangles(*cube())\n"
        "p = np.random.default_rng(1).uniform(-0.5, 1.5, (100_000, 3))\n"
        "occ = s.compute_occupancy(p, nthreads=2, nsamples=255)\n"
        "inside = np.all((p > 0) & (p < 1), axis=1)\n"
        "print('ok', bool(np.array_equal(occ == 1, inside)))",
        400 << 20,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "ok True", out.stdout


def dense(n: int) -> penumbra.RaycastingScene:
    """`n` stacked squares: every ray up through them crosses `n` triangles."""
    z = np.arange(n, dtype=np.float32) * 1e-5
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    v = (v[None] + np.stack([np.zeros(n), np.zeros(n), z], 1)[:, None]).astype(np.float32)
    t = np.arange(n)[:, None, None] * 4 + np.array([[0, 1, 2], [0, 2, 3]])
    s = penumbra.RaycastingScene()
    s.add_triangles(v.reshape(-1, 3), t.reshape(-1, 3).astype(np.uint32))
    return s


def up(n: int) -> np.ndarray:
    xy = np.random.default_rng(3).uniform(-0.9, 0.9, (n, 2))
    return np.hstack([xy, -np.ones((n, 1)), np.zeros((n, 2)), np.ones((n, 1))]).astype(
        np.float32)


def interrupted(query, delay: float) -> float:
    """Seconds from a SIGINT sent `delay` s into `query()` to its KeyboardInterrupt."""
    sent = interrupt_after(delay, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        query()
    raised = time.perf_counter()
    assert "at" in sent and sent["at"] > start
    return raised - sent["at"]


@pytest.mark.usefixtures("sigint_raises")
def test_ctrl_c_in_a_dense_region_is_answered_fast():
    # 50 000 crossings per ray: a chunk of 1024 rays is seconds of counting.
    s = dense(50_000)
    s.count_intersections(up(1))  # the BVH is built
    rays = up(4096)
    latency = interrupted(lambda: s.count_intersections(rays, nthreads=2), 0.3)
    print(f"KeyboardInterrupt {1000 * latency:.0f} ms after the signal")
    assert latency < 0.15, latency


@pytest.mark.usefixtures("sigint_raises")
def test_ctrl_c_during_the_bvh_build_is_answered_fast():
    rng = np.random.default_rng(5)
    n = 1 << 20
    s = penumbra.RaycastingScene()
    s.add_triangles(rng.uniform(0, 1, (3 * n, 3)).astype(np.float32),
                    np.arange(3 * n, dtype=np.uint32).reshape(-1, 3))
    latency = interrupted(lambda: s.cast_rays(up(1), nthreads=2), 0.05)
    print(f"KeyboardInterrupt {1000 * latency:.0f} ms after the signal, during the build")
    assert latency < 0.15, latency
    # The scene still answers, with the build done meanwhile.
    assert np.isfinite(s.cast_rays([[0.5, 0.5, -1, 0, 0, 1]])["t_hit"][0])


@pytest.mark.parametrize("call, kwargs, name", [
    ("cast_rays", {"nthreads": -1}, "nthreads"),
    ("cast_rays", {"nthreads": 2**70}, "nthreads"),
    ("count_intersections", {"nthreads": 2**64}, "nthreads"),
    ("compute_occupancy", {"nsamples": -1}, "nsamples"),
    ("compute_occupancy", {"nsamples": 2**40 + 1}, "nsamples"),
    ("compute_occupancy", {"nsamples": 4}, "nsamples"),
    ("compute_signed_distance", {"nsamples": -3}, "nsamples"),
    ("compute_distance", {"nthreads": -(2**70)}, "nthreads"),
])
def test_bad_integers_name_their_argument(call, kwargs, name):
    s = lone_triangle()
    arg = [[0, 0, 0, 0, 0, 1]] if call in ("cast_rays", "count_intersections") else [[0, 0, 0]]
    with pytest.raises(ValueError, match=rf"^{call}: {name} must be"):
        getattr(s, call)(arg, **kwargs)


@pytest.mark.parametrize("size, name", [
    ((-1, 4), "width_px"), ((4, -1), "height_px"), ((2**40, 4), "width_px"),
    ((4, 2**64), "height_px"),
])
def test_bad_image_sizes_name_their_argument(size, name):
    k = [[2, 0, 1], [0, 2, 1], [0, 0, 1]]
    with pytest.raises(ValueError, match=rf"create_rays_pinhole: {name} must be"):
        penumbra.RaycastingScene.create_rays_pinhole(k, np.eye(4), *size)
    with pytest.raises(ValueError, match=rf"create_rays_pinhole: {name} must be"):
        penumbra.RaycastingScene.create_rays_pinhole(60, [0, 0, 0], [0, 0, 1], [0, 1, 0], *size)
    with pytest.raises(ValueError, match=r"^nthreads|RaycastingScene: nthreads must be"):
        penumbra.RaycastingScene(nthreads=-5)
    with pytest.raises(TypeError, match="create_rays_pinhole: width_px must be an integer"):
        penumbra.RaycastingScene.create_rays_pinhole(k, np.eye(4), 4.5, 4)


@pytest.mark.parametrize("extrinsic", [
    np.zeros((4, 4)),
    np.diag([1.0, 1.0, 0.0, 1.0]),
    np.array([[1, 0, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]),
], ids=["zero", "flat", "repeated row"])
def test_a_singular_extrinsic_matrix_is_refused(extrinsic):
    k = [[2, 0, 1], [0, 2, 1], [0, 0, 1]]
    with pytest.raises(ValueError, match="create_rays_pinhole: .*extrinsic.*singular"):
        penumbra.RaycastingScene.create_rays_pinhole(k, extrinsic, 4, 4)


@pytest.mark.parametrize("where", ["center", "eye", "up", "vertex_positions", "rays",
                                   "query_points", "nested"])
def test_a_set_is_not_taken_as_a_vector(where):
    s = lone_triangle()
    fov = dict(fov_deg=60, center=[0, 0, 0], eye=[0, 0, 5], up=[0, 1, 0], width_px=2,
               height_px=2)
    with pytest.raises(TypeError, match=r"must be an array .*not a (set|frozenset)"):
        if where in ("center", "eye", "up"):
            penumbra.RaycastingScene.create_rays_pinhole(**{**fov, where: {0.0, 1.0, 5.0}})
        elif where == "vertex_positions":
            s.add_triangles([{0, 1, 2}, [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
        elif where == "rays":
            s.cast_rays([{0.0, 1.0, 2.0, 3.0, 4.0, 5.0}])
        elif where == "query_points":
            s.compute_distance(frozenset({(0, 0, 0)}))
        else:
            s.count_intersections([[[0, 0, 1, 0, 0, -1]], [{1, 2, 3, 4, 5, 6}]])


def test_geometry_added_during_a_query_waits_for_it():
    s = dense(20_000)
    s.count_intersections(up(1))
    rays = up(3000)
    counts = []
    worker = threading.Thread(target=lambda: counts.append(s.count_intersections(rays)))
    worker.start()
    time.sleep(0.05)
    assert worker.is_alive()  # the query runs with the GIL released
    v, t = cube((5, 5, 5), (6, 6, 6))
    assert s.add_triangles(v, t) == 1  # no "Already borrowed": it waited
    worker.join()
    assert counts and np.all(counts[0] == 20_000)
    assert s.count_intersections([[5.5, 5.5, 0, 0, 0, 1]]).tolist() == [2]
