"""The meshes of Open3D's ray-casting tutorials, built with numpy: what
``o3d.geometry.TriangleMesh.create_box``, ``create_torus`` and ``create_sphere`` make, with
their default arguments (and, like them, closed and wound outward), as ``(vertices (N, 3)
float32, triangles (M, 3) uint32)``. Both penumbra's and Open3D's ``add_triangles`` take such
a pair."""

from __future__ import annotations

from typing import Sequence, Tuple

import numpy as np

Mesh = Tuple[np.ndarray, np.ndarray]


def _mesh(vertices, triangles, translate: Sequence[float]) -> Mesh:
    v = np.asarray(vertices, np.float64) + np.asarray(translate, np.float64)
    return v.astype(np.float32), np.asarray(triangles, np.uint32)


def create_box(width=1.0, height=1.0, depth=1.0, translate=(0.0, 0.0, 0.0)) -> Mesh:
    """The box [0, width] x [0, height] x [0, depth]: 8 vertices, 12 triangles."""
    v = [[x * width, y * height, z * depth] for y in (0, 1) for z in (0, 1) for x in (0, 1)]
    t = [[4, 7, 5], [4, 6, 7], [0, 2, 4], [2, 6, 4], [0, 1, 2], [1, 3, 2],
         [1, 5, 7], [1, 7, 3], [2, 3, 7], [2, 7, 6], [0, 4, 1], [1, 4, 5]]
    return _mesh(v, t, translate)


def create_torus(torus_radius=1.0, tube_radius=0.5, radial_resolution=30,
                 tubular_resolution=20, translate=(0.0, 0.0, 0.0)) -> Mesh:
    """A torus around the z axis: 600 vertices and 1200 triangles by default."""
    u = 2 * np.pi * np.arange(radial_resolution) / radial_resolution
    w = 2 * np.pi * np.arange(tubular_resolution) / tubular_resolution
    uu, ww = np.meshgrid(u, w, indexing="ij")
    ring = torus_radius + tube_radius * np.cos(ww)
    v = np.stack([ring * np.cos(uu), ring * np.sin(uu), tube_radius * np.sin(ww)], -1)
    i, j = np.meshgrid(np.arange(radial_resolution), np.arange(tubular_resolution), indexing="ij")
    a = i * tubular_resolution + j
    b = (i + 1) % radial_resolution * tubular_resolution + j
    c = (i + 1) % radial_resolution * tubular_resolution + (j + 1) % tubular_resolution
    d = i * tubular_resolution + (j + 1) % tubular_resolution
    t = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)]).reshape(-1, 3)
    return _mesh(v.reshape(-1, 3), t, translate)


def create_sphere(radius=1.0, resolution=20, translate=(0.0, 0.0, 0.0)) -> Mesh:
    """A UV sphere: poles on the z axis, ``resolution - 1`` rings of ``2 * resolution``
    vertices (762 vertices and 1520 triangles by default)."""
    n = 2 * resolution
    theta = np.pi * np.arange(1, resolution) / resolution  # from the north pole
    phi = 2 * np.pi * np.arange(n) / n
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    rings = radius * np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1)
    v = np.concatenate([[[0, 0, radius]], rings.reshape(-1, 3), [[0, 0, -radius]]])
    south = len(v) - 1
    k = np.arange(n)
    t = [np.stack([np.zeros(n, int), 1 + k, 1 + (k + 1) % n], -1)]
    for r in range(resolution - 2):
        top, bottom = 1 + r * n, 1 + (r + 1) * n
        a, b = top + k, top + (k + 1) % n
        c, d = bottom + (k + 1) % n, bottom + k
        t += [np.stack([a, d, c], -1), np.stack([a, c, b], -1)]
    last = 1 + (resolution - 2) * n
    t.append(np.stack([np.full(n, south), last + (k + 1) % n, last + k], -1))
    return _mesh(v, np.concatenate(t), translate)
