"""Brute-force distances in numpy, double precision, for the tutorials' checks: every vertex
against every triangle, so small meshes only. What minkq is checked against in its own tests
is the oracle (oracle/); this is the same idea in a few lines a reader can follow."""
import numpy as np


def _segment(p, a, b):
    """Distance from points p to segments ab (broadcast over leading axes)."""
    ab = b - a
    t = np.clip(np.einsum("...k,...k", p - a, ab) / np.maximum(np.einsum("...k,...k", ab, ab), 1e-300), 0, 1)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


def point_triangle(p, a, b, c):
    """Distance from points p to triangles abc: to the plane when p projects inside the
    triangle, else to the nearest of its three edges."""
    n = np.cross(b - a, c - a)
    nn = np.einsum("...k,...k", n, n)
    inside = np.ones(np.broadcast(p[..., 0], a[..., 0]).shape, bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("...k,...k", np.cross(v - u, p - u), n) >= 0
    plane = np.abs(np.einsum("...k,...k", p - a, n)) / np.sqrt(np.maximum(nn, 1e-300))
    edges = np.minimum(np.minimum(_segment(p, a, b), _segment(p, b, c)), _segment(p, c, a))
    return np.where(inside & (nn > 0), plane, edges)


def vt_within(xyz, tris, r, drop_incident=True):
    """Every (vertex, triangle) pair within r, sorted: the true VT contacts."""
    x = xyz.astype(np.float64)
    d = point_triangle(x[:, None, :], x[tris[:, 0]][None], x[tris[:, 1]][None], x[tris[:, 2]][None])
    if drop_incident:
        d[tris, np.arange(len(tris))[:, None]] = np.inf
    return np.argwhere(d <= r).astype(np.int32)
