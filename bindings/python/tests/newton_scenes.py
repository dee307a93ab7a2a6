"""Newton cloth scenes for the minkq.newton tests, a double-precision oracle that scales to a
million elements, and readers of Newton's result rows.

The oracle is independent of minkq: candidate pairs come from Warp's BVH (boxes padded by
more than r, so no pair within r is missed), the decision from the double-precision distance
formulas of oracle.py."""

from __future__ import annotations

import functools
import math
import os
import tarfile
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Tuple

import numpy as np
import warp as wp

import newton
from oracle import point_triangle_sq, segment_segment_sq

# The repository's meshes (data/README.md): read from the archive in place, member by member.
MESHES = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "data", "meshes.tar.xz"))


# ---- Meshes ----------------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def mesh_text(name: str, archive: str = MESHES) -> str:
    """The text of ``name`` (such as "newton/bear.obj") in the repository's mesh archive. A
    missing archive or member raises FileNotFoundError naming it."""
    if not os.path.isfile(archive):
        raise FileNotFoundError(f"{archive} not found: the repository's test meshes (data/README.md)")
    with tarfile.open(archive) as tar:
        try:
            member = tar.extractfile(name)
        except KeyError:
            member = None
        if member is None:
            raise FileNotFoundError(f"{name} is not in {archive} (data/README.md lists its files)")
        return member.read().decode()


def load_obj(name: str) -> Tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles (fans of polygons) of a Wavefront OBJ file of the mesh archive."""
    xyz, tris = [], []
    for line in mesh_text(name).splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            xyz.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            ids = [int(p.split("/")[0]) for p in parts[1:]]
            ids = [i - 1 if i > 0 else len(xyz) + i for i in ids]
            tris += [[ids[0], ids[k], ids[k + 1]] for k in range(1, len(ids) - 1)]
    return np.array(xyz, np.float32), np.array(tris, np.int32)


def grid(nx: int, ny: int, cell_x: float, cell_y: float) -> Tuple[np.ndarray, np.ndarray]:
    """(nx + 1) x (ny + 1) vertices on the plane z = 0, two triangles per cell."""
    i, j = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1))
    xyz = np.stack([i.ravel() * cell_x, j.ravel() * cell_y, np.zeros(i.size)], axis=1)
    ci, cj = np.meshgrid(np.arange(nx), np.arange(ny))
    v00 = (cj * (nx + 1) + ci).ravel()
    v10, v01 = v00 + 1, v00 + nx + 1
    tris = np.concatenate([np.stack([v00, v10, v01 + 1], 1), np.stack([v00, v01 + 1, v01], 1)])
    return xyz.astype(np.float32), tris.astype(np.int32)


def twist(xyz: np.ndarray, turns: float, axis: int = 0) -> np.ndarray:
    """Twists a mesh about the coordinate axis ``axis`` through its centre: ``turns`` full turns
    from one end to the other (as Newton's cloth_twist example winds its sheet)."""
    x = xyz.astype(np.float64)
    lo, hi = x[:, axis].min(), x[:, axis].max()
    centre = 0.5 * (x.min(axis=0) + x.max(axis=0))
    angle = turns * 2 * math.pi * (x[:, axis] - lo) / (hi - lo)
    a, b = [k for k in range(3) if k != axis]
    ya, yb = x[:, a] - centre[a], x[:, b] - centre[b]
    out = x.copy()
    out[:, a] = centre[a] + ya * np.cos(angle) - yb * np.sin(angle)
    out[:, b] = centre[b] + ya * np.sin(angle) + yb * np.cos(angle)
    return out.astype(np.float32)


def roll(xyz: np.ndarray, turns: float, pitch: float, axis: int = 0) -> np.ndarray:
    """Rolls a flat sheet (z = 0) up along ``axis`` into a spiral of ``turns`` turns whose
    layers lie ``pitch`` apart: the layers come within a cloth radius of each other."""
    x = xyz.astype(np.float64)
    u = x[:, axis] - x[:, axis].min()
    length = u.max()
    # Arc length of an Archimedean spiral rho = c * phi, c = pitch / (2 pi), from phi0.
    c = pitch / (2 * math.pi)
    phi0 = 2 * math.pi
    phi_end = phi0 + 2 * math.pi * turns
    s_of = lambda phi: 0.5 * c * (phi * np.sqrt(1 + phi * phi) + np.arcsinh(phi))  # noqa: E731
    table_phi = np.linspace(phi0, phi_end, 20001)
    table_s = s_of(table_phi) - s_of(phi0)
    phi = np.interp(u / length * table_s[-1], table_s, table_phi)
    rho = c * phi
    out = x.copy()
    other = [k for k in range(3) if k != axis][0]
    out[:, axis] = rho * np.cos(phi)
    out[:, 2] = rho * np.sin(phi)
    out[:, other] = x[:, other]
    return out.astype(np.float32)


def mean_edge(xyz: np.ndarray, tris: np.ndarray) -> float:
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    d = xyz[e[:, 0]].astype(np.float64) - xyz[e[:, 1]].astype(np.float64)
    return float(np.sqrt((d * d).sum(1)).mean())


# ---- Newton models -----------------------------------------------------------------------------


def cloth_model(meshes, device: str = "cpu", worlds: Optional[list] = None) -> "newton.Model":
    """A finalised Newton model of cloth meshes [(xyz, tris), ...]; ``worlds[i]`` (consecutive
    equal numbers share a world; -1: global) places mesh i."""
    builder = newton.ModelBuilder()
    current = -1
    for k, (xyz, tris) in enumerate(meshes):
        world = -1 if worlds is None else worlds[k]
        if world != current:
            if current >= 0:
                builder.end_world()
            if world >= 0:
                builder.begin_world()
            current = world
        builder.add_cloth_mesh(
            pos=wp.vec3(0.0, 0.0, 0.0),
            rot=wp.quat_identity(),
            scale=1.0,
            vel=wp.vec3(0.0, 0.0, 0.0),
            vertices=xyz,
            indices=tris.reshape(-1),
            density=1.0,
        )
    if current >= 0:
        builder.end_world()
    return builder.finalize(device=device)


@dataclass
class Scene:
    name: str
    meshes: list
    radius: float
    worlds: Optional[list] = None


def poker_cards(count: int = 52, seed: int = 42) -> list:
    """Newton's cloth_poker_cards: 52 cards of 4 x 6 cells stacked 1 mm apart, slightly shifted
    and turned at random (the example's set-up, without the cube and the sphere)."""
    rng = np.random.default_rng(seed)
    width, height = 0.0635, 0.0889
    cards = []
    for i in range(count):
        xyz, tris = grid(4, 6, width / 4, height / 6)
        dx, dy = rng.uniform(-0.005, 0.005, 2)
        angle = rng.uniform(-0.1, 0.1)
        c, s = math.cos(angle), math.sin(angle)
        x = xyz[:, 0] - width / 2 + dx
        y = xyz[:, 1] - height / 2 + dy
        xyz = np.stack([c * x - s * y, s * x + c * y, np.full_like(x, 0.25 + 0.001 * i)], axis=1)
        cards.append((xyz.astype(np.float32), tris))
    return cards


def scenes() -> Dict[str, Callable[[], Scene]]:
    """The Newton cloth scenes (meshes of data/meshes.tar.xz, radii of the Newton examples),
    posed so that they come close to themselves: name -> builder."""

    def obj(name: str) -> Tuple[np.ndarray, np.ndarray]:
        return load_obj("newton/" + name)

    def cloth_twist() -> Scene:
        # The example's sheet (x 0.01, in the xz plane) wrung: rolled up with its layers closer
        # than the radius, then twisted a quarter turn.
        xyz, tris = obj("square_cloth.obj")
        flat = (xyz * np.float32(0.01))[:, [0, 2, 1]]
        return Scene("cloth_twist (wrung)", [(twist(roll(flat, 2.0, 0.003), 0.25, axis=1), tris)], 0.0035)

    def cloth_franka() -> Scene:
        return Scene("cloth_franka (unisex_shirt)", [obj("unisex_shirt.obj")], 0.2)

    def cloth_bending() -> Scene:
        return Scene("cloth_bending (curvedSurface)", [obj("curvedSurface.obj")], 0.35)

    def bunny() -> Scene:
        xyz, tris = obj("bunny.obj")
        return Scene("bunny", [(xyz, tris)], 0.5 * mean_edge(xyz, tris))

    def bear() -> Scene:
        xyz, tris = obj("bear.obj")
        return Scene("bear", [(xyz, tris)], 1.0 * mean_edge(xyz, tris))

    def cloth_hanging() -> Scene:
        xyz, tris = grid(64, 32, 0.1, 0.1)
        return Scene("cloth_hanging (rolled)", [(roll(xyz, 2.5, 0.025), tris)], 0.03)

    def cloth_poker_cards() -> Scene:
        return Scene("cloth_poker_cards", poker_cards(), 0.0015)

    def cloth_rollers() -> Scene:
        xyz, tris = grid(320, 15, 0.25, 0.25)
        return Scene("cloth_rollers (spiral)", [(roll(xyz, 12.7, 0.4), tris)], 0.6)

    def worlds() -> Scene:
        # Two card stacks in two worlds, in the same place, and a global sheet through them:
        # pairs across the worlds must not be reported, pairs with the global sheet must.
        cards = poker_cards(6, seed=1) + poker_cards(6, seed=2)
        sheet, tris = grid(8, 8, 0.1 / 8, 0.1 / 8)
        sheet = sheet + np.array([-0.05, -0.05, 0.25375], np.float32)  # off the cards' 1 mm grid
        return Scene("worlds", cards + [(sheet, tris)], 0.0015, worlds=[0] * 6 + [1] * 6 + [-1])

    return {
        "cloth_twist": cloth_twist,
        "cloth_franka": cloth_franka,
        "cloth_bending": cloth_bending,
        "bunny": bunny,
        "bear": bear,
        "cloth_hanging": cloth_hanging,
        "cloth_poker_cards": cloth_poker_cards,
        "cloth_rollers": cloth_rollers,
        "worlds": worlds,
    }


def fine_sheet(n: int = 500, turns: float = 3.0) -> Tuple[np.ndarray, np.ndarray]:
    """An n x n grid on the unit square twisted ``turns`` turns about the x axis (demo.py's
    twisted_sheet): edges across the sheet are 1 / (n - 1) long, far below 3.2e-3 for n = 500."""
    from minkq.demo import twisted_sheet

    return twisted_sheet(n, turns)


# ---- Newton's result rows ----------------------------------------------------------------------


def rows(buffer, offsets, counts, sizes, interleaved: bool = True) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stored (row, other) pairs of Newton-layout result arrays as int64 keys
    row << 32 | other, the counts, and the number stored per row; checks the layout: the row
    index in every interleaved slot, -1 in every unused slot."""
    buffer, offsets, counts, sizes = (np.asarray(a.numpy() if hasattr(a, "numpy") else a) for a in (buffer, offsets, counts, sizes))
    capacity = np.diff(offsets) if interleaved else sizes
    stored = np.minimum(counts, capacity)
    row = np.repeat(np.arange(len(counts)), stored)
    slot = np.repeat(offsets[:-1], stored) + (np.arange(stored.sum()) - np.repeat(np.cumsum(stored) - stored, stored))
    if interleaved:
        assert np.array_equal(buffer[2 * slot], row), "a stored pair does not name its row"
        other = buffer[2 * slot + 1]
        used = np.zeros(len(buffer) // 2, bool)
        used[slot] = True
        assert (buffer.reshape(-1, 2)[~used] == -1).all(), "an unused slot is not -1"
    else:
        other = buffer[slot]
    return row.astype(np.int64) << 32 | other.astype(np.int64), counts, stored


def unordered(keys: np.ndarray) -> np.ndarray:
    """Directed edge-edge keys as sorted unique unordered pairs e << 32 | f, e < f."""
    a, b = keys >> 32, keys & 0xFFFFFFFF
    return np.unique(np.minimum(a, b) << 32 | np.maximum(a, b))


# ---- The oracle ----------------------------------------------------------------------------------


@wp.kernel
def _count_overlaps(bvh: wp.uint64, lower: wp.array(dtype=wp.vec3), upper: wp.array(dtype=wp.vec3), counts: wp.array(dtype=wp.int32)):
    i = wp.tid()
    query = wp.bvh_query_aabb(bvh, lower[i], upper[i])
    j = int(0)
    n = int(0)
    while wp.bvh_query_next(query, j):
        n += 1
    counts[i] = n


@wp.kernel
def _write_overlaps(bvh: wp.uint64, lower: wp.array(dtype=wp.vec3), upper: wp.array(dtype=wp.vec3), offsets: wp.array(dtype=wp.int32), out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    query = wp.bvh_query_aabb(bvh, lower[i], upper[i])
    j = int(0)
    n = offsets[i]
    while wp.bvh_query_next(query, j):
        out[n] = j
        n += 1


def _box_candidates(query_lo: np.ndarray, query_hi: np.ndarray, prim_lo: np.ndarray, prim_hi: np.ndarray, pad: float) -> Tuple[np.ndarray, np.ndarray]:
    """(query, primitive) pairs whose boxes come within ``pad`` per axis: a Warp BVH over the
    primitive boxes, queried with the query boxes padded by ``pad``."""
    bvh = wp.Bvh(wp.array(prim_lo, dtype=wp.vec3, device="cpu"), wp.array(prim_hi, dtype=wp.vec3, device="cpu"))
    lo = wp.array(query_lo - pad, dtype=wp.vec3, device="cpu")
    hi = wp.array(query_hi + pad, dtype=wp.vec3, device="cpu")
    counts = wp.zeros(len(query_lo), dtype=wp.int32, device="cpu")
    wp.launch(_count_overlaps, dim=len(query_lo), inputs=[bvh.id, lo, hi, counts], device="cpu")
    c = counts.numpy()
    offsets = np.concatenate([[0], np.cumsum(c)[:-1]]).astype(np.int32)
    out = wp.empty(max(int(c.sum()), 1), dtype=wp.int32, device="cpu")
    wp.launch(_write_overlaps, dim=len(query_lo), inputs=[bvh.id, lo, hi, wp.array(offsets, dtype=wp.int32, device="cpu"), out], device="cpu")
    return np.repeat(np.arange(len(query_lo)), c), out.numpy()[: int(c.sum())].astype(np.int64)


def _pad(xyz: np.ndarray, r: float) -> float:
    # More than r: the float boxes and their padding are rounded, so leave a relative margin.
    return 1.001 * r + 1e-6 * float(np.abs(xyz).max())


@dataclass
class Truth:
    """Oracle pairs as int64 keys a << 32 | b (VT: vertex, triangle; EE: e < f) with their
    double-precision distances."""

    keys: np.ndarray
    dist: np.ndarray

    def within(self, r: float) -> np.ndarray:
        return self.keys[self.dist <= r]

    def band(self, r: float, rel: float = 1e-5) -> np.ndarray:
        """Pairs whose distance lies within ``rel`` r of r: where float and double answers may
        differ."""
        return self.keys[np.abs(self.dist - r) <= rel * r]


def _same_world(world: Optional[np.ndarray], a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Newton's rule: elements of different worlds pair only if one is global (world < 0)."""
    if world is None:
        return np.ones(len(a), bool)
    wa, wb = world[a], world[b]
    return (wa < 0) | (wb < 0) | (wa == wb)


def vt_truth(xyz: np.ndarray, tris: np.ndarray, r: float, world: Optional[np.ndarray] = None, chunk: int = 1 << 20) -> Truth:
    """Every (vertex, triangle) within 1.001 r, vertex not in the triangle, of the same world
    (``world``: per vertex; a triangle's is its first vertex's), with double distances."""
    x = xyz.astype(np.float64)
    corners = x[tris]
    v, t = _box_candidates(xyz, xyz, corners.min(1).astype(np.float32), corners.max(1).astype(np.float32), _pad(xyz, r))
    keep = (tris[t, 0] != v) & (tris[t, 1] != v) & (tris[t, 2] != v) & _same_world(world, v, tris[t, 0])
    v, t = v[keep], t[keep]
    dist = np.empty(len(v))
    for s in range(0, len(v), chunk):
        vv, tt = v[s : s + chunk], t[s : s + chunk]
        dist[s : s + chunk] = np.sqrt(point_triangle_sq(x[vv], x[tris[tt, 0]], x[tris[tt, 1]], x[tris[tt, 2]]))
    return _truth(v, t, dist, 1.001 * r)


def ee_truth(xyz: np.ndarray, edges: np.ndarray, r: float, world: Optional[np.ndarray] = None, chunk: int = 1 << 20) -> Truth:
    """Every (e, f), e < f, not sharing a vertex, of the same world (an edge's is its first
    vertex's), within 1.001 r, with double distances."""
    x = xyz.astype(np.float64)
    ends = x[edges]
    lo, hi = ends.min(1).astype(np.float32), ends.max(1).astype(np.float32)
    e, f = _box_candidates(lo, hi, lo, hi, _pad(xyz, r))
    keep = (e < f) & (edges[e, 0] != edges[f, 0]) & (edges[e, 0] != edges[f, 1]) & (edges[e, 1] != edges[f, 0]) & (edges[e, 1] != edges[f, 1])
    keep &= _same_world(world, edges[e, 0], edges[f, 0])
    e, f = e[keep], f[keep]
    dist = np.empty(len(e))
    for s in range(0, len(e), chunk):
        ee, ff = e[s : s + chunk], f[s : s + chunk]
        dist[s : s + chunk] = np.sqrt(segment_segment_sq(x[edges[ee, 0]], x[edges[ee, 1]], x[edges[ff, 0]], x[edges[ff, 1]]))
    return _truth(e, f, dist, 1.001 * r)


def _truth(a: np.ndarray, b: np.ndarray, dist: np.ndarray, limit: float) -> Truth:
    keep = dist <= limit
    keys = a[keep].astype(np.int64) << 32 | b[keep].astype(np.int64)
    order = np.argsort(keys)
    return Truth(keys[order], dist[keep][order])


def min_dist(truth_keys: np.ndarray, dist: np.ndarray, count: int, r: float, both: bool = False) -> np.ndarray:
    """Per element: the smallest distance of its pairs (``both``: EE, each pair counts for
    both edges), r where there is none."""
    out = np.full(count, r)
    np.minimum.at(out, truth_keys >> 32, dist)
    if both:
        np.minimum.at(out, truth_keys & 0xFFFFFFFF, dist)
    return out
