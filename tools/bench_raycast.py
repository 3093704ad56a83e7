#!/usr/bin/env python3
"""Ray-casting benchmark (not a test): penumbra.RaycastingScene, and Open3D's when `open3d` is
importable, on the same meshes and rays, alternately in the same run.

    python tools/bench_raycast.py                                  # the Stanford bunny
    python tools/bench_raycast.py MESH.obj [MESH.obj ...] --threads 2 --scale 0.25

For each mesh (an OBJ file; polygons are fanned into triangles) the workloads are:
(a) 1024² coherent pinhole rays from a camera that frames the mesh, as `create_rays_pinhole`
makes them (an image, shape (1024, 1024, 6), which both libraries take as it is); (b) 1 M
incoherent rays between random points around and inside its bounding box; (c) 1 M occlusion
segments between random points of its box; (d) 1 M query points in its box; (e) 128 k query
points in its box grown by 10 %; (f) rays from random points around the box aimed at the midpoint
of every edge and at every vertex (the watertightness workload). The calls: cast_rays on (a),
(b) and (f), count_intersections, list_intersections on (b), test_occlusions on (c),
compute_occupancy on (d), compute_signed_distance, compute_distance and compute_closest_points
on (e). Each runs --repeat times, the two libraries alternately; the table gives M items/s of
the best runs, the penumbra / Open3D speed ratio of the best runs, the median of the ratios of
each run to the other library's run beside it (steadier on a busy machine), and the fraction of
items with the same result (primitive ids, counts, flags, occupancy; distances and points
within 1e-4 of the box's size; for (f), whether the ray hits at all, as a ray at a shared edge
may report either triangle, with each library's misses on stderr). --only NAME[,NAME] keeps the calls named (e.g. list_intersections).
--scale shrinks every batch on a busy machine. Progress on stderr, table on stdout.
Open3D comes from `pip install open3d`; its 0.20 wheel needs libusb-1.0 (Debian:
`apt-get install libusb-1.0-0`), without which `import open3d` fails and only penumbra runs.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import penumbra

# The shared folder beside the repository holds the public meshes.
SHARED = Path(__file__).resolve().parents[2] / "shared"
BUNNY = SHARED / "assets" / "meshes" / "stanford_bunny.obj"


def read_obj(path: Path):
    """(N, 3) float32 vertices and (M, 3) uint32 triangles of an OBJ file."""
    verts, tris = [], []
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"v "):
                verts.append(line.split()[1:4])
            elif line.startswith(b"f "):
                idx = [int(w.split(b"/")[0]) for w in line.split()[1:]]
                n = len(verts)
                idx = [i - 1 if i > 0 else n + i for i in idx]
                tris.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
    return np.array(verts, np.float32), np.array(tris, np.uint32)


def workloads(v: np.ndarray, t: np.ndarray, scale: float, rng: np.random.Generator):
    lo, hi = v.min(axis=0).astype(np.float64), v.max(axis=0).astype(np.float64)
    center, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    side = max(16, int(1024 * scale**0.5))
    n = max(1000, int(1_000_000 * scale))
    coherent = penumbra.RaycastingScene.create_rays_pinhole(
        fov_deg=50, center=center, eye=center + size * np.array([0.3, 0.4, 1.1]),
        up=[0, 1, 0], width_px=side, height_px=side)  # (side, side, 6), as both libraries make it
    a = center + size * rng.uniform(-0.75, 0.75, (n, 3))
    b = rng.uniform(lo, hi, (n, 3))
    incoherent = np.hstack([a, b - a]).astype(np.float32)
    p, q = rng.uniform(lo, hi, (n, 3)), rng.uniform(lo, hi, (n, 3))
    segments = np.hstack([p, q - p]).astype(np.float32)  # t in [0, 1]
    points = rng.uniform(lo, hi, (n, 3)).astype(np.float32)
    m = max(1000, int(131_072 * scale))
    grown = (hi - lo) * 0.05
    near = rng.uniform(lo - grown, hi + grown, (m, 3)).astype(np.float32)
    return {"coherent": coherent, "incoherent": incoherent, "segments": segments,
            "points": points, "near": near, "edges": aimed(v, t, center, size, rng)}


def aimed(v: np.ndarray, t: np.ndarray, center, size: float, rng: np.random.Generator):
    """Rays from random points on a sphere around the mesh aimed at the midpoint of every edge
    (each once) and at every vertex, direction = target - origin (the target at t = 1)."""
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    e = np.unique(e, axis=0)
    v64 = v.astype(np.float64)
    targets = np.concatenate([(v64[e[:, 0]] + v64[e[:, 1]]) / 2, v64])
    d = rng.normal(size=targets.shape)
    origins = center + size * d / np.linalg.norm(d, axis=1, keepdims=True)
    return np.hstack([origins, targets - origins]).astype(np.float32)


def close(tol: float):
    """Elementwise agreement of two float arrays within tol (inf and nan agree with themselves)."""
    def same(a, b):
        a, b = np.asarray(a), np.asarray(b)
        eq = np.isclose(a, b, rtol=0, atol=tol) | (a == b) | (np.isnan(a) & np.isnan(b))
        return eq.reshape(len(a), -1).all(axis=1) if eq.ndim > 1 else eq
    return same


def calls(scene, threads: int, numpy_of):
    """The timed calls, each returning the array compared between libraries."""
    def ids(r):
        return numpy_of(scene.cast_rays(r, nthreads=threads)["primitive_ids"])
    return {
        ("cast_rays", "coherent"): ids,
        ("cast_rays", "incoherent"): ids,
        ("cast_rays", "edges"): ids,
        ("count_intersections", "incoherent"): lambda r: numpy_of(scene.count_intersections(r, nthreads=threads)),
        ("list_intersections", "incoherent"): lambda r: numpy_of(
            scene.list_intersections(r, nthreads=threads)["ray_splits"]),
        ("test_occlusions", "segments"): lambda r: numpy_of(
            scene.test_occlusions(r, tnear=0.0, tfar=1.0, nthreads=threads)),
        ("compute_occupancy", "points"): lambda p: numpy_of(scene.compute_occupancy(p, nthreads=threads)),
        ("compute_signed_distance", "near"): lambda p: numpy_of(
            scene.compute_signed_distance(p, nthreads=threads)),
        ("compute_distance", "near"): lambda p: numpy_of(scene.compute_distance(p, nthreads=threads)),
        ("compute_closest_points", "near"): lambda p: numpy_of(
            scene.compute_closest_points(p, nthreads=threads)["points"]),
    }


MISS = 0xFFFFFFFF  # INVALID_ID, both libraries' primitive id of a miss


def agreement(call: str, load: str, a, b, size: float) -> float:
    """The fraction of items with the same result (see the module docs)."""
    if load == "edges":  # a ray at a shared edge may report either triangle: hit or miss
        a, b = np.asarray(a), np.asarray(b)
        print(f"  edges: penumbra misses {int(np.sum(a == MISS))}, Open3D misses "
              f"{int(np.sum(b == MISS))} of {len(a)}", file=sys.stderr)
        return float(np.mean((a == MISS) == (b == MISS)))
    if call == "list_intersections":  # ray_splits: compare each ray's number of hits
        a, b = np.diff(a), np.diff(b)
    if call.startswith("compute_") and call != "compute_occupancy":
        return float(np.mean(close(1e-4 * size)(a, b)))
    return float(np.mean(a == b))


def timed(fn, rays):
    start = time.perf_counter()
    out = fn(rays)
    return time.perf_counter() - start, out


def bench_mesh(path: Path, args, o3d) -> list:
    print(f"{path.name}: reading", file=sys.stderr)
    v, t = read_obj(path)
    rng = np.random.default_rng(1)
    rays = workloads(v, t, args.scale, rng)
    ours = penumbra.RaycastingScene(nthreads=args.threads)
    ours.add_triangles(v, t)
    start = time.perf_counter()
    ours.count_intersections(rays["segments"][:1])  # builds the BVH
    print(f"{path.name}: {len(t)} triangles, penumbra BVH {time.perf_counter() - start:.2f} s", file=sys.stderr)
    mine = calls(ours, args.threads, np.asarray)
    theirs = None
    if o3d is not None:
        scene = o3d.t.geometry.RaycastingScene(nthreads=args.threads)
        scene.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(t))
        scene.count_intersections(o3d.core.Tensor(rays["segments"][:1]))
        theirs = calls(scene, args.threads, lambda x: x.numpy())
        tensors = {k: o3d.core.Tensor(r) for k, r in rays.items()}
    rows = []
    size = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
    for key, fn in mine.items():
        call, load = key
        if args.only and call not in args.only.split(","):
            continue
        r = rays[load]
        n = r.size // r.shape[-1]
        print(f"{path.name}: {call} {load} ({n} items)", file=sys.stderr)
        mine_s, theirs_s = [], []
        a = b = same = None
        for _ in range(args.repeat):  # alternate the two libraries
            dt, a = timed(fn, r)
            mine_s.append(dt)
            if theirs is not None:
                dt, b = timed(theirs[key], tensors[load])
                theirs_s.append(dt)
        t_ours, t_o3d, pairs = min(mine_s), None, None
        if theirs is not None:
            t_o3d = min(theirs_s)
            pairs = float(np.median(np.array(theirs_s) / np.array(mine_s)))
            same = agreement(call, load, a, b, size)
        rows.append((path.name, call, load, n, t_ours, t_o3d, pairs, same))
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="*", type=Path, default=[BUNNY], help="OBJ files (default: the bunny)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scale", type=float, default=1.0, help="batch size factor (1: 1024² and 1 M rays)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-open3d", action="store_true", help="time penumbra alone")
    ap.add_argument("--only", default="", help="comma-separated call names to time (default: all)")
    args = ap.parse_args()
    o3d = None
    if not args.no_open3d:
        try:
            import open3d as o3d  # noqa: F811
        except ImportError:
            print("open3d is not importable: timing penumbra alone", file=sys.stderr)
    rows = [row for m in args.meshes for row in bench_mesh(m, args, o3d)]
    load = os.getloadavg()
    print(f"threads {args.threads}, scale {args.scale}, best of {args.repeat}, "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
          + (f", Open3D {o3d.__version__}" if o3d else ""))
    print("| mesh | call | items | n | penumbra M/s | Open3D M/s | ratio | median ratio | identical |")
    print("|---|---|---|---|---|---|---|---|---|")
    for mesh, call, load_name, n, t_ours, t_o3d, pairs, same in rows:
        theirs = f"{n / t_o3d / 1e6:.2f}" if t_o3d else "-"
        ratio = f"{t_o3d / t_ours:.2f}" if t_o3d else "-"
        median = f"{pairs:.2f}" if pairs is not None else "-"
        ident = f"{same:.5f}" if same is not None else "-"
        print(f"| {mesh} | {call} | {load_name} | {n} | {n / t_ours / 1e6:.2f} | {theirs} | {ratio} "
              f"| {median} | {ident} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
