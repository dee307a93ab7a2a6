"""A brute-force numpy oracle in double precision, independent of minkq: every (vertex,
triangle), (edge, edge), (vertex, vertex) and (vertex, edge) distance by formulas written here,
and small test meshes."""

from __future__ import annotations

from typing import Tuple

import numpy as np


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...k,...k->...", a, b)


def point_segment_sq(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distance from points p to segments ab (broadcast over leading axes)."""
    d = b - a
    dd = _dot(d, d)
    t = np.where(dd > 0, _dot(p - a, d) / np.where(dd > 0, dd, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    w = p - (a + d * t[..., None])
    return _dot(w, w)


def point_triangle_sq(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The minimum over the three edges, and the plane distance where the projection lies
    strictly inside (degenerate triangles have only their edges)."""
    best = np.minimum(np.minimum(point_segment_sq(p, a, b), point_segment_sq(p, b, c)), point_segment_sq(p, c, a))
    n = np.cross(b - a, c - a)
    nn = _dot(n, n)
    inside = (
        (nn > 0)
        & (_dot(np.cross(b - a, p - a), n) > 0)
        & (_dot(np.cross(c - b, p - b), n) > 0)
        & (_dot(np.cross(a - c, p - c), n) > 0)
    )
    h = _dot(p - a, n)
    plane = np.where(inside, h * h / np.where(nn > 0, nn, 1.0), np.inf)
    return np.minimum(best, plane)


def segment_segment_sq(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """The minimum over the four endpoint-segment distances, and the interior minimum where
    both parameters lie strictly inside."""
    best = np.minimum(
        np.minimum(point_segment_sq(p0, q0, q1), point_segment_sq(p1, q0, q1)),
        np.minimum(point_segment_sq(q0, p0, p1), point_segment_sq(q1, p0, p1)),
    )
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, b, c, f = _dot(d1, d1), _dot(d2, d2), _dot(d1, d2), _dot(d1, r), _dot(d2, r)
    denom = a * e - b * b
    ok = denom > 0
    safe = np.where(ok, denom, 1.0)
    s = (b * f - c * e) / safe
    t = (a * f - b * c) / safe
    inside = ok & (s > 0) & (s < 1) & (t > 0) & (t < 1)
    w = (p0 + d1 * s[..., None]) - (q0 + d2 * t[..., None])
    return np.minimum(best, np.where(inside, _dot(w, w), np.inf))


def vt_distances(xyz: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Every (vertex, triangle) distance, (n, m), in double."""
    x = xyz.astype(np.float64)
    a, b, c = (x[tris[:, k]][None, :, :] for k in range(3))
    return np.sqrt(point_triangle_sq(x[:, None, :], a, b, c))


def ee_distances(xyz: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Every (edge, edge) distance, (e, e), in double."""
    x = xyz.astype(np.float64)
    p0, p1 = x[edges[:, 0]][:, None, :], x[edges[:, 1]][:, None, :]
    return np.sqrt(segment_segment_sq(p0, p1, p0.transpose(1, 0, 2), p1.transpose(1, 0, 2)))


def derive_edges(tris: np.ndarray) -> np.ndarray:
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    e = np.sort(e, axis=1).astype(np.int64)
    keys = np.unique(e[:, 0] << 32 | e[:, 1])
    return np.stack([keys >> 32, keys & 0xFFFFFFFF], axis=1).astype(np.int32)


def vt_contacts(xyz: np.ndarray, tris: np.ndarray, r: float, drop_incident: bool = True) -> set:
    """Every (vertex, triangle) within r."""
    p = xyz.astype(np.float64)[:, None, :]
    a, b, c = (xyz.astype(np.float64)[tris[:, k]][None, :, :] for k in range(3))
    close = point_triangle_sq(p, a, b, c) <= r * r
    if drop_incident:
        v = np.arange(len(xyz))[:, None]
        close &= (tris[None, :, 0] != v) & (tris[None, :, 1] != v) & (tris[None, :, 2] != v)
    return set(zip(*map(np.ndarray.tolist, np.nonzero(close))))


def ee_contacts(xyz: np.ndarray, edges: np.ndarray, r: float, drop_incident: bool = True) -> set:
    """Every (e, f), e < f, within r."""
    x = xyz.astype(np.float64)
    p0, p1 = x[edges[:, 0]][:, None, :], x[edges[:, 1]][:, None, :]
    q0, q1 = x[edges[:, 0]][None, :, :], x[edges[:, 1]][None, :, :]
    close = segment_segment_sq(p0, p1, q0, q1) <= r * r
    close &= np.triu(np.ones((len(edges), len(edges)), dtype=bool), k=1)
    if drop_incident:
        a, b = edges[:, None, :], edges[None, :, :]
        shared = (a[..., 0] == b[..., 0]) | (a[..., 0] == b[..., 1]) | (a[..., 1] == b[..., 0]) | (a[..., 1] == b[..., 1])
        close &= ~shared
    return set(zip(*map(np.ndarray.tolist, np.nonzero(close))))


def vv_contacts(xyz: np.ndarray, r: float) -> set:
    """Every (v, w), v < w, within r."""
    x = xyz.astype(np.float64)
    d = x[:, None, :] - x[None, :, :]
    close = _dot(d, d) <= r * r
    close &= np.triu(np.ones((len(x), len(x)), dtype=bool), k=1)
    return set(zip(*map(np.ndarray.tolist, np.nonzero(close))))


def ev_contacts(xyz: np.ndarray, edges: np.ndarray, r: float, drop_incident: bool = True) -> set:
    """Every (vertex, edge) within r, without a vertex's own edges when ``drop_incident``."""
    x = xyz.astype(np.float64)
    close = point_segment_sq(x[:, None, :], x[edges[:, 0]][None, :, :], x[edges[:, 1]][None, :, :]) <= r * r
    if drop_incident:
        v = np.arange(len(x))[:, None]
        close &= (edges[None, :, 0] != v) & (edges[None, :, 1] != v)
    return set(zip(*map(np.ndarray.tolist, np.nonzero(close))))


def rods_and_particles(seed: int, rods: int, per_rod: int, loose: int, scale: float = 1.0, offset: float = 0.0):
    """``rods`` random-walk polylines of ``per_rod`` vertices (consecutive vertices joined by an
    edge) and ``loose`` particles in [offset, offset + scale]^3, in float64; and the edges."""
    rng = np.random.default_rng(seed)
    starts = rng.random((rods, 1, 3))
    walks = starts + np.cumsum(0.08 * (rng.random((rods, per_rod, 3)) - 0.5), axis=1)
    xyz = np.concatenate([walks.reshape(-1, 3), rng.random((loose, 3))]) * scale + offset
    first = (np.arange(rods)[:, None] * per_rod + np.arange(per_rod - 1)[None, :]).ravel()
    return xyz, np.stack([first, first + 1], axis=1).astype(np.int32)


def rolled_sheet(n: int, seed: int) -> Tuple[np.ndarray, np.ndarray]:
    """An n x n sheet rolled ~1.4 turns with jitter: its layers, ~0.035 apart, come close to
    each other in many places."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    u, v = u.ravel(), v.ravel()
    angle, radius = 9.0 * u, 0.2 + 0.05 * u
    xyz = np.stack([radius * np.cos(angle), v, radius * np.sin(angle)], axis=1)
    xyz += 0.02 * (rng.random(xyz.shape) - 0.5)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel()
    tris = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 1], 1), np.stack([v00, v00 + n + 1, v00 + n], 1)])
    return xyz.astype(np.float32), tris.astype(np.int32)


def degenerate_soup(count: int, seed: int) -> Tuple[np.ndarray, np.ndarray]:
    """Independent small triangles, a third of them degenerate: a repeated vertex (a point or
    a segment, with a zero-length edge) or three collinear vertices."""
    rng = np.random.default_rng(seed)
    centres = rng.random((count, 1, 3))
    xyz = centres + 0.15 * (rng.random((count, 3, 3)) - 0.5)
    xyz[0::6, 1] = xyz[0::6, 0]  # a segment: vertex 1 on vertex 0
    xyz[1::6, 2] = 0.5 * (xyz[1::6, 0] + xyz[1::6, 1])  # collinear
    xyz[2::6, 1:] = xyz[2::6, :1]  # a point
    tris = np.arange(3 * count, dtype=np.int32).reshape(count, 3)
    tris[3::6, 2] = tris[3::6, 0]  # a repeated index: a zero-length edge
    return xyz.reshape(-1, 3).astype(np.float32), tris


def as_set(pairs: np.ndarray) -> set:
    return set(map(tuple, pairs.tolist()))
