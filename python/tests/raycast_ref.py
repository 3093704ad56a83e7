"""Brute-force references for the ray-casting tests: meshes built in numpy, and every query
computed in float64 over all triangles (Möller–Trumbore, vectorized), with a margin that
marks the rays too close to an edge for float32 and float64 to agree."""

from __future__ import annotations

from typing import Dict, Tuple

import numpy as np

# A barycentric or t this close to a boundary is "on the edge": f32 and f64 may disagree.
MARGIN = 1e-5


def icosphere(subdivisions: int = 2) -> Tuple[np.ndarray, np.ndarray]:
    """A closed unit sphere: (N, 3) float32 vertices, (M, 3) uint32 outward-wound triangles."""
    g = (1 + 5**0.5) / 2
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g),
         (0, -1, -g), (0, 1, -g), (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        cache: Dict[Tuple[int, int], int] = {}

        def mid(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        f = [t for a, b, c in f for t in
             ((a, mid(a, b), mid(c, a)), (b, mid(b, c), mid(a, b)),
              (c, mid(c, a), mid(b, c)), (mid(a, b), mid(b, c), mid(c, a)))]
    return np.array(verts, np.float32), np.array(f, np.uint32)


def cube(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0)) -> Tuple[np.ndarray, np.ndarray]:
    """A closed axis-aligned box as 12 outward-wound triangles."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[(hi if (i >> k) & 1 else lo)[k] for k in range(3)] for i in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return corners.astype(np.float32), np.array(tris, np.uint32)


def soup(meshes) -> np.ndarray:
    """(T, 3, 3) float64 corners of every triangle of [(vertices, triangles), ...] in order."""
    return np.concatenate([v.astype(np.float64)[t] for v, t in meshes])


def intersect(rays: np.ndarray, tris: np.ndarray):
    """Möller–Trumbore in float64 for every ray (R, 6) against every triangle (T, 3, 3):
    t, u, v (R, T), and the margin (R, T): the smallest of u, v, 1 - u - v, positive
    inside. Parallel pairs get margin -inf."""
    o = rays[:, None, :3].astype(np.float64)
    d = rays[:, None, 3:].astype(np.float64)
    a, e1, e2 = tris[None, :, 0], tris[None, :, 1] - tris[None, :, 0], tris[None, :, 2] - tris[None, :, 0]
    p = np.cross(d, e2)
    det = np.einsum("rtk,rtk->rt", e1 * np.ones_like(d), p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o - a
        u = np.einsum("rtk,rtk->rt", s, p) * inv
        q = np.cross(s, e1 * np.ones_like(d))
        v = np.einsum("rtk,rtk->rt", d * np.ones_like(q), q) * inv
        t = np.einsum("rtk,rtk->rt", e2 * np.ones_like(q), q) * inv
    margin = np.minimum(np.minimum(u, v), 1 - u - v)
    margin[~np.isfinite(margin) | (det == 0)] = -np.inf
    return t, u, v, margin


def hits(rays: np.ndarray, tris: np.ndarray, tnear: float = 0.0):
    """Reference hits: (t, u, v, hit (R, T) bool, clear (R,) bool), where `clear` marks the
    rays no triangle hits ambiguously (on an edge within MARGIN, or at t within MARGIN of
    `tnear`)."""
    t, u, v, m = intersect(rays, tris)
    scale = np.linalg.norm(rays[:, 3:].astype(np.float64), axis=1)[:, None]
    hit = (m > 0) & (t >= tnear)
    unsure = (np.abs(m) <= MARGIN) & (t >= tnear - MARGIN) | (m > 0) & (np.abs(t - tnear) * scale <= MARGIN)
    return t, u, v, hit, ~unsure.any(axis=1)


def closest_points(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Distance (P,) of each point to the nearest triangle, in float64: the projection on
    the plane when it falls inside, else the nearest point of the three edges."""
    p = points.astype(np.float64)[:, None]
    a, b, c = (tris[None, :, i] for i in range(3))
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    h = np.einsum("ptk,ptk->pt", p - a, n * np.ones_like(p - a))
    proj = p - h[..., None] * n
    inside = np.ones(h.shape, bool)
    for x, y in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ptk,ptk->pt", np.cross(y - x, proj - x), n * np.ones_like(p - a)) >= 0
    best = np.where(inside, np.abs(h), np.inf)
    for x, y in ((a, b), (b, c), (c, a)):
        e = y - x
        s = np.clip(np.einsum("ptk,ptk->pt", p - x, e * np.ones_like(p - x)) / np.einsum("ptk,ptk->pt", e, e), 0, 1)
        best = np.minimum(best, np.linalg.norm(p - (x + s[..., None] * e), axis=-1))
    return best.min(axis=1)


def random_rays(rng: np.random.Generator, n: int, radius: float = 3.0) -> np.ndarray:
    """Rays from random points in a cube of half-size `radius` toward random points near the
    origin, with directions of random length (t is in units of it)."""
    o = rng.uniform(-radius, radius, (n, 3))
    target = rng.uniform(-1.2, 1.2, (n, 3))
    d = (target - o) * rng.uniform(0.3, 2.0, (n, 1))
    return np.hstack([o, d]).astype(np.float32)
