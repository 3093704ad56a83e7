"""Open3D's ray-casting tutorials as scripts (open3d_scripts/), run as they are with
penumbra and checked against brute-force references; and, when Open3D is installed, run again
with the import line changed to Open3D's, checking that both give the same answers. The
scripts are Open3D's code (``.numpy()``, ``.isfinite()``, boolean indexing of the rays):
what a newcomer moving from Open3D runs first."""

from __future__ import annotations

import ast
import importlib.util
import sys
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np
import pytest

import penumbra
from raycast_ref import closest_points, hits, soup

SCRIPTS = Path(__file__).resolve().parent / "open3d_scripts"
PENUMBRA = "from penumbra import RaycastingScene"
OPEN3D = "from open3d.t.geometry import RaycastingScene"
NAMES = ["cast_rays", "virtual_point_cloud", "distance_queries", "closest_points"]

# The meshes the scripts build (their own module, imported as they import it).
sys.path.insert(0, str(SCRIPTS))
import meshes  # noqa: E402

BOX, TORUS, SPHERE = (
    meshes.create_box(),
    meshes.create_torus(translate=[0, 0, 2]),
    meshes.create_sphere(radius=0.5, translate=[1, 2, 3]),
)
RUNS: Dict[Tuple[str, str], dict] = {}


def run(name: str, library: str = "penumbra") -> dict:
    """The globals of script ``name`` after running it, with penumbra's import line or
    Open3D's (once per script and library)."""
    if (name, library) not in RUNS:
        path = SCRIPTS / f"{name}.py"
        text = path.read_text()
        if library == "open3d":
            text = text.replace(PENUMBRA, OPEN3D)
        namespace = {"__name__": "__main__", "__file__": str(path)}
        exec(compile(text, str(path), "exec"), namespace)
        RUNS[name, library] = namespace
    return RUNS[name, library]


def open3d_run(name: str) -> dict:
    if importlib.util.find_spec("open3d") is None:
        pytest.skip("open3d is not installed: the same script was not run with Open3D "
                    "(`pip install open3d` to compare)")
    return run(name, "open3d")


def reference_cast(rays: np.ndarray, meshes_: List[Tuple[np.ndarray, np.ndarray]]):
    """Brute-force closest hits of (R, 6) rays: t (inf on a miss), geometry id (INVALID_ID),
    unit normal, and which rays no triangle edge makes ambiguous."""
    tris = soup(meshes_)
    geometry = np.repeat(np.arange(len(meshes_)), [len(t) for _, t in meshes_])
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    t_out, g_out, n_out, clear_out = [], [], [], []
    for batch in np.array_split(rays, max(1, len(rays) // 200)):
        with np.errstate(invalid="ignore"):
            t, _, _, hit, clear = hits(batch, tris)
        t = np.where(hit, t, np.inf)
        first = t.argmin(axis=1)
        best = t[np.arange(len(batch)), first]
        t_out.append(best)
        g_out.append(np.where(np.isfinite(best), geometry[first], penumbra.INVALID_ID))
        n_out.append(np.where(np.isfinite(best)[:, None], normal[first], 0))
        clear_out.append(clear)
    return tuple(np.concatenate(a) for a in (t_out, g_out, n_out, clear_out))


def test_each_script_differs_from_open3ds_only_by_its_import_line():
    for name in NAMES:
        tree = ast.parse((SCRIPTS / f"{name}.py").read_text())
        imports = [
            ast.unparse(node)
            for node in ast.walk(tree)
            if isinstance(node, (ast.Import, ast.ImportFrom))
            and "penumbra" in ast.unparse(node)
        ]
        assert imports == [PENUMBRA], name


def test_cast_rays_images_hit_distance_normals_and_ids():
    ns = run("cast_rays")
    for key in ("t_hit", "geometry_ids", "depth", "normals", "ids"):
        assert type(ns[key]) is np.ndarray, key  # .numpy() gave plain arrays
    # The first ray meets the torus's tube (around z = 2) before the box (whose top it meets
    # on a diagonal); the second misses.
    t, g, _, _ = reference_cast(np.array([[0.5, 0.5, 10, 0, 0, -1], [-1, -1, -1, 0, 0, -1]],
                                         np.float32), [BOX, TORUS, SPHERE])
    assert g.tolist() == [1, penumbra.INVALID_ID]
    np.testing.assert_allclose(ns["t_hit"], t, rtol=1e-6)
    assert ns["geometry_ids"].tolist() == g.tolist()
    # The image: every 16th pixel against brute force (the rays near an edge excepted).
    depth, normals, ids = ns["depth"], ns["normals"], ns["ids"]
    assert depth.shape == ids.shape == (480, 640) and normals.shape == (480, 640, 3)
    rays = np.asarray(ns["rays"])[::16, ::16].reshape(-1, 6)
    t, g, n, clear = reference_cast(rays, [BOX, TORUS, SPHERE])
    assert clear.mean() > 0.97 and 0.1 < np.isfinite(t).mean() < 0.9
    sample = (slice(None, None, 16), slice(None, None, 16))
    np.testing.assert_allclose(depth[sample].ravel()[clear], t[clear], rtol=1e-5)
    assert np.array_equal(ids[sample].ravel()[clear], g[clear])
    np.testing.assert_allclose(normals[sample].reshape(-1, 3)[clear], np.abs(n[clear]), atol=1e-5)
    assert set(np.unique(ids)) == {0, 1, 2, penumbra.INVALID_ID}


def test_a_virtual_point_cloud_from_the_finite_hits():
    ns = run("virtual_point_cloud")
    hit, points, rays = ns["hit"], ns["points"], ns["rays_hit"]
    assert hit.dtype == bool and hit.shape == (480, 640)
    assert points.shape == (hit.sum(), 3) and points.dtype == np.float32
    # The hits are the rays the image hits (the cast_rays script's scene and camera).
    assert np.array_equal(hit, np.isfinite(run("cast_rays")["depth"]))
    # Every point is on the surface, along its own ray.
    tris = soup([BOX, TORUS, SPHERE])
    sample = points[:: max(1, len(points) // 1500)].astype(np.float64)
    assert closest_points(sample, tris).max() < 1e-4
    along = np.cross(points - rays[:, :3], rays[:, 3:])
    assert np.abs(along).max() < 1e-3


def inside_torus(p: np.ndarray, big: float = 1.0, small: float = 0.4) -> np.ndarray:
    """Signed distance to the exact torus (negative inside) that the mesh approximates."""
    ring = np.hypot(p[..., 0], p[..., 1]) - big
    return np.hypot(ring, p[..., 2]) - small


def test_distances_signs_and_occupancy_on_a_grid():
    ns = run("distance_queries")
    torus = meshes.create_torus(torus_radius=1.0, tube_radius=0.4)
    tris = soup([torus])
    far = np.array([[10, 10, 10]], np.float64)
    d_far = closest_points(far, tris)[0]
    np.testing.assert_allclose(ns["one"], [d_far, d_far, 0.0], rtol=1e-5)
    # Random points: |signed distance| is the distance, negative exactly inside.
    q, signed = ns["query_points"], ns["signed_random"]
    np.testing.assert_allclose(np.abs(signed), closest_points(q, tris), rtol=1e-4, atol=1e-5)
    exact = inside_torus(q.astype(np.float64))
    sure = np.abs(exact) > 0.03  # the mesh is within 0.01 of the exact torus
    assert np.array_equal((signed < 0)[sure], (exact < 0)[sure])
    # The grid: occupancy is the sign; distances on the slice the tutorial plots.
    grid, sd, ud, occ = ns["grid"], ns["signed_grid"], ns["unsigned_grid"], ns["occupancy_grid"]
    assert grid.shape == (32, 32, 32, 3) and sd.shape == ud.shape == occ.shape == (32, 32, 32)
    assert set(np.unique(occ)) == {0.0, 1.0}
    assert np.array_equal(occ == 1.0, sd < 0) and np.array_equal(np.abs(sd), ud)
    exact = inside_torus(grid.astype(np.float64))
    sure = np.abs(exact) > 0.03
    assert np.array_equal((occ == 1.0)[sure], (exact < 0)[sure]) and (occ == 1.0).sum() > 1000
    plane = grid[:, :, 15].reshape(-1, 3)
    np.testing.assert_allclose(ud[:, :, 15].ravel(), closest_points(plane, tris), rtol=1e-4,
                               atol=1e-5)


def test_closest_points_lie_on_the_nearest_mesh():
    ns = run("closest_points")
    box = meshes.create_box(translate=[-1.2, -1.2, 0])
    sphere = meshes.create_sphere(radius=0.5, translate=[0.7, 0.8, 0])
    q, points, ids = ns["query_points"], ns["points"], ns["geometry_ids"]
    per_mesh = np.stack([closest_points(q, soup([m])) for m in (box, sphere)], axis=1)
    np.testing.assert_allclose(ns["distance"], per_mesh.min(axis=1), rtol=1e-5, atol=1e-6)
    tie = np.abs(per_mesh[:, 0] - per_mesh[:, 1]) < 1e-5
    assert np.array_equal(ids[~tie], per_mesh.argmin(axis=1)[~tie])
    # Each point is on the very triangle reported.
    for i in range(0, len(q), 7):
        v, t = (box, sphere)[ids[i]]
        triangle = v.astype(np.float64)[t[ns["primitive_ids"][i]]][None]
        assert closest_points(points[i : i + 1], triangle)[0] < 1e-5, i


def agree(a: np.ndarray, b: np.ndarray, share: float = 0.999, **tolerance) -> None:
    """``a`` and ``b`` agree (allclose) on at least ``share`` of their entries: rays through
    an edge may find either triangle, or slip through in Open3D."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    assert a.shape == b.shape
    close = np.isclose(a, b, **tolerance) | (np.isinf(a) & (a == b))
    assert close.mean() >= share, close.mean()


@pytest.mark.parametrize("name", NAMES)
def test_open3d_gives_the_same_answers(name):
    theirs = open3d_run(name)
    ours = run(name)
    keys = {
        "cast_rays": ["t_hit", "geometry_ids", "depth", "normals", "ids"],
        "virtual_point_cloud": ["hit"],
        "distance_queries": ["one", "signed_random", "signed_grid", "unsigned_grid",
                             "occupancy_grid"],
        "closest_points": ["distance", "geometry_ids"],
    }[name]
    for key in keys:
        mine, other = np.asarray(ours[key]), np.asarray(theirs[key])
        assert mine.shape == other.shape, key
        agree(mine, other, rtol=1e-4, atol=1e-5)
    if name == "virtual_point_cloud":
        assert abs(len(ours["points"]) - len(theirs["points"])) <= 0.001 * len(ours["points"])
