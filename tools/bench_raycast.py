#!/usr/bin/env python3
"""Ray-casting benchmark (not a test): penumbra.RaycastingScene, and Open3D's when `open3d` is
importable, on the same meshes and rays, alternately in the same run.

    python tools/bench_raycast.py                                  # the Stanford bunny
    python tools/bench_raycast.py MESH.obj [MESH.obj ...] --threads 2 --scale 0.25

For each mesh (an OBJ file; polygons are fanned into triangles): (a) 1024² coherent pinhole
rays from a camera that frames the mesh, as `create_rays_pinhole` makes them (an image, shape
(1024, 1024, 6), which both libraries take as it is), (b) 1 M incoherent rays between random
points around and inside its bounding box, (c) 1 M occlusion segments between random points of
its box. Times cast_rays on (a) and (b), count_intersections on (b) and test_occlusions on (c),
each --repeat times, the two libraries alternately, and prints Mrays/s of the best runs, the
penumbra / Open3D ratio of the best runs, the median of the ratios of each run to the other
library's run beside it (steadier on a busy machine), and the fraction of rays with identical
results (primitive ids, counts, occlusion flags). --scale shrinks the batches (1024² · scale and
1 M · scale rays) on a busy machine. Progress on stderr, table on stdout.
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


def workloads(v: np.ndarray, scale: float, rng: np.random.Generator):
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
    return {"coherent": coherent, "incoherent": incoherent, "segments": segments}


def calls(scene, threads: int, numpy_of):
    """The timed calls, each returning the array compared between libraries."""
    return {
        ("cast_rays", "coherent"): lambda r: numpy_of(scene.cast_rays(r, nthreads=threads)["primitive_ids"]),
        ("cast_rays", "incoherent"): lambda r: numpy_of(scene.cast_rays(r, nthreads=threads)["primitive_ids"]),
        ("count_intersections", "incoherent"): lambda r: numpy_of(scene.count_intersections(r, nthreads=threads)),
        ("test_occlusions", "segments"): lambda r: numpy_of(
            scene.test_occlusions(r, tnear=0.0, tfar=1.0, nthreads=threads)),
    }


def timed(fn, rays):
    start = time.perf_counter()
    out = fn(rays)
    return time.perf_counter() - start, out


def bench_mesh(path: Path, args, o3d) -> list:
    print(f"{path.name}: reading", file=sys.stderr)
    v, t = read_obj(path)
    rng = np.random.default_rng(1)
    rays = workloads(v, args.scale, rng)
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
    for key, fn in mine.items():
        call, load = key
        r = rays[load]
        print(f"{path.name}: {call} {load} ({r.size // 6} rays)", file=sys.stderr)
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
            same = float(np.mean(a == b))
        rows.append((path.name, call, load, r.size // 6, t_ours, t_o3d, pairs, same))
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="*", type=Path, default=[BUNNY], help="OBJ files (default: the bunny)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scale", type=float, default=1.0, help="batch size factor (1: 1024² and 1 M rays)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-open3d", action="store_true", help="time penumbra alone")
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
    print("| mesh | call | rays | n | penumbra Mrays/s | Open3D Mrays/s | ratio | median ratio | identical |")
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
