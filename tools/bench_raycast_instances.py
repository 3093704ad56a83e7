#!/usr/bin/env python3
"""Ray casting with many placements of one mesh (not a test): memory and time of a
penumbra.RaycastingScene that places the mesh N times with add_instance, or that adds N
transformed copies with add_triangles (what add_instance did before it placed meshes).

    python tools/bench_raycast_instances.py MESH.obj placed 1000
    python tools/bench_raycast_instances.py MESH.obj copied 100

The placements stand on a cubic grid (one mesh size apart), each turned about y by a random
angle; 200,000 rays leave the grid's centre in random directions. Prints the time to add the
geometries and build (the first query builds), the time of one cast_rays of the 200,000 rays
on 2 threads, the number of hits and the process's peak resident memory (run each case in a
process of its own: the peak only grows).
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

import penumbra


def read_obj(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an OBJ file (polygons fanned)."""
    v, f = [], []
    for line in open(path, encoding="utf-8"):
        w = line.split()
        if w and w[0] == "v":
            v.append([float(x) for x in w[1:4]])
        elif w and w[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in w[1:]]
            f.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return np.array(v, np.float32), np.array(f, np.uint32)


def placements(n: int, size: float, rng: np.random.Generator) -> list[np.ndarray]:
    """`n` row-major 4×4 maps on a cubic grid of pitch `size`, each turned about y."""
    side = int(np.ceil(n ** (1 / 3)))
    out = []
    for i in range(n):
        m = np.eye(4)
        a = rng.uniform(0, 2 * np.pi)
        m[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
        m[:3, 3] = np.array([i % side, (i // side) % side, i // side // side]) * size
        out.append(m)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mesh")
    parser.add_argument("mode", choices=["placed", "copied"])
    parser.add_argument("n", type=int)
    args = parser.parse_args()
    v, t = read_obj(args.mesh)
    size = float(np.abs(v).max()) * 2.5
    rng = np.random.default_rng(1)
    maps = placements(args.n, size, rng)
    side = int(np.ceil(args.n ** (1 / 3)))
    d = rng.normal(size=(200_000, 3)).astype(np.float32)
    centre = np.full((len(d), 3), side / 2 * size, np.float32)
    rays = np.concatenate([centre, d], axis=1)
    start = time.perf_counter()
    s = penumbra.RaycastingScene()
    if args.mode == "placed":
        g = s.add_triangles(v, t)
        for m in maps:
            s.add_instance(g, m)
    else:
        for m in maps:
            s.add_triangles((v.astype(np.float64) @ m[:3, :3].T + m[:3, 3]).astype(np.float32), t)
    s.cast_rays(rays[:1])
    build = time.perf_counter() - start
    start = time.perf_counter()
    hits = np.isfinite(s.cast_rays(rays, nthreads=2)["t_hit"].numpy()).sum()
    cast = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"{args.mode} {args.n} x {len(t)} triangles: add + build {build:.2f} s, "
        f"cast {len(rays)} rays {cast:.3f} s ({len(rays) / cast / 1e6:.2f} Mrays/s), "
        f"{hits} hits, peak RSS {peak:.0f} MB"
    )


if __name__ == "__main__":
    main()
