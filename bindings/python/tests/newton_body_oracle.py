"""A double-precision brute-force oracle for minkq.newton.ClothBodyContacts: every cloth-body
pair (cloth vertex - body triangle, body vertex - cloth triangle, cloth edge - body edge) with
its distance and its reach ``radius + t(a) + t(b)`` (an element's thickness the largest of its
vertices'), by oracle.py's formulas, independent of minkq. Used by test_newton_body.py and by
bench/peers/newton_body.py."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple

import numpy as np

from oracle import derive_edges, point_triangle_sq, segment_segment_sq

KINDS = ("vertex_triangle", "triangle_vertex", "edge_edge")
"""ClothBodyPairs' fields, in order: rows (cloth element, shape, shape element)."""


@dataclass
class Side:
    """One side of the contacts, in world space: vertices (double), triangles, edges and each
    vertex's thickness."""

    xyz: np.ndarray
    tris: np.ndarray
    edges: np.ndarray
    thickness: np.ndarray

    def element_thickness(self, element: str) -> np.ndarray:
        if element == "vertex":
            return self.thickness
        return self.thickness[self.tris if element == "triangle" else self.edges].max(axis=1)


@dataclass
class Truth:
    """One kind's pairs within ``slack`` times their reach: rows (cloth element, shape, shape
    element), their distance and their reach."""

    rows: np.ndarray
    dist: np.ndarray
    reach: np.ndarray

    def within(self) -> np.ndarray:
        """The rows within their reach: the contacts."""
        return self.rows[self.dist <= self.reach]


def side(xyz: np.ndarray, tris: np.ndarray, edges: Optional[np.ndarray] = None, thickness=0.0) -> Side:
    tris = np.asarray(tris, np.int64).reshape(-1, 3)
    edges = derive_edges(tris).astype(np.int64) if edges is None else np.asarray(edges, np.int64)
    t = np.broadcast_to(np.asarray(thickness, np.float64), (len(xyz),))
    return Side(np.asarray(xyz, np.float64), tris, edges, t)


def _pairs_sq(kind: str, a: Side, b: Side, rows: slice) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Squared distances of a's elements ``rows`` (cloth) against all of b's (body), (k, m), and
    both elements' thickness."""
    if kind == "vertex_triangle":
        p = a.xyz[rows][:, None, :]
        tri = [b.xyz[b.tris[:, k]][None, :, :] for k in range(3)]
        return point_triangle_sq(p, *tri), a.element_thickness("vertex")[rows], b.element_thickness("triangle")
    if kind == "triangle_vertex":
        tri = [a.xyz[a.tris[rows, k]][:, None, :] for k in range(3)]
        return point_triangle_sq(b.xyz[None, :, :], *tri), a.element_thickness("triangle")[rows], b.element_thickness("vertex")
    p0, p1 = (a.xyz[a.edges[rows, k]][:, None, :] for k in range(2))
    q0, q1 = (b.xyz[b.edges[:, k]][None, :, :] for k in range(2))
    return segment_segment_sq(p0, p1, q0, q1), a.element_thickness("edge")[rows], b.element_thickness("edge")


def truth(cloth: Side, bodies: List[Tuple[int, Side]], radius: float, slack: float = 1e-5,
          chunk: int = 1 << 21) -> Dict[str, Truth]:
    """Each kind's pairs of the cloth against every (shape, body) within ``(1 + slack)`` times
    their reach, sorted by rows."""
    out = {}
    for kind in KINDS:
        count = {"vertex_triangle": len(cloth.xyz), "triangle_vertex": len(cloth.tris), "edge_edge": len(cloth.edges)}[kind]
        found: List[Tuple[np.ndarray, ...]] = []
        for shape, body in bodies:
            other = {"vertex_triangle": len(body.tris), "triangle_vertex": len(body.xyz), "edge_edge": len(body.edges)}[kind]
            step = max(1, chunk // max(other, 1))
            for start in range(0, count, step):
                sq, ta, tb = _pairs_sq(kind, cloth, body, slice(start, min(start + step, count)))
                reach = radius + ta[:, None] + tb[None, :]
                d = np.sqrt(sq)
                i, j = np.nonzero(d <= reach * (1 + slack))
                found.append((i + start, np.full_like(i, shape), j, d[i, j], reach[i, j]))
        if found:
            i, s, j, d, r = (np.concatenate(c) for c in zip(*found))
        else:
            i = s = j = np.zeros(0, np.int64)
            d = r = np.zeros(0)
        rows = np.stack([i, s, j], 1).astype(np.int32)
        order = np.lexsort(rows.T[::-1])
        out[kind] = Truth(rows[order], d[order], r[order])
    return out


def as_keys(rows: np.ndarray) -> set:
    return set(map(tuple, np.asarray(rows).tolist()))
