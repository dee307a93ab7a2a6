"""minkq.newton's :class:`ClothBodyContacts`: contacts between a Newton model's cloth and the
mesh shapes of its bodies, from one minkq scene of many geometries (see the class)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, List, Optional, Sequence, Tuple

import newton
import numpy as np

from .. import _api
from .._geometry import Geometry

_MESH_TYPES = (int(newton.GeoType.MESH), int(newton.GeoType.CONVEX_MESH))
# Collision filter bits: the cloth meets every body geometry, body geometries never meet each other.
_CLOTH_GROUP, _BODY_GROUP = 1, 2
_CLOTH = 0  # the cloth's geometry index in the scene; body mesh shape k is geometry k + 1


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotates rows v by the unit quaternion q = (x, y, z, w) (Warp's order)."""
    u, w = q[:3], q[3]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _compose(a: np.ndarray, b: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """The transform a * b (Warp's (p, q) layout, 7 floats each) as (p, q), in double."""
    pa, qa, pb, qb = a[:3], a[3:], b[:3], b[3:]
    x1, y1, z1, w1 = qa
    x2, y2, z2, w2 = qb
    q = np.array([
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
    ])
    return pa + _rotate(qa, pb[None, :])[0], q


def shape_world_vertices(local: np.ndarray, scale: np.ndarray, shape_xform: np.ndarray,
                         body_xform: Optional[np.ndarray]) -> np.ndarray:
    """A mesh shape's vertices in world space, in double: ``body_xform * shape_xform *
    (scale * local)`` as Newton places them (``body_xform`` None for a static shape)."""
    p, q = (shape_xform[:3], shape_xform[3:]) if body_xform is None else _compose(body_xform, shape_xform)
    return _rotate(q, np.asarray(local, np.float64) * scale) + p


@dataclass
class ClothBodyPairs:
    """One detection's contacts, each a (k, 3) int32 host array sorted by rows, local ids:

    - ``vertex_triangle``: (particle, shape, triangle of the shape's mesh): a cloth vertex
      near a body triangle (the kind Newton's soft contacts find, one per particle and shape
      there, every triangle within reach here);
    - ``triangle_vertex``: (cloth triangle, shape, vertex of the shape's mesh): a body vertex
      near a cloth triangle (a body corner poking into the cloth between its particles);
    - ``edge_edge``: (cloth edge, shape, edge of the shape's mesh): cloth edge ``e`` is Newton's
      ``model.edge_indices[e]`` (vertices in its columns 2 and 3), the shape's edges those of
      :meth:`ClothBodyContacts.shape_edges`.

    With ``self_contacts``, ``self_vertex_triangle`` (particle, cloth triangle) and
    ``self_edge_edge`` (edge, edge), incident pairs dropped; else None."""

    vertex_triangle: np.ndarray
    triangle_vertex: np.ndarray
    edge_edge: np.ndarray
    self_vertex_triangle: Optional[np.ndarray] = None
    self_edge_edge: Optional[np.ndarray] = None


class ClothBodyContacts:
    """Contacts between the cloth of a Newton model (its particles, triangles and edges) and the
    mesh shapes of its bodies: vertex-triangle both ways (cloth vertices against body triangles,
    body vertices against cloth triangles) and edge-edge, every pair within reach, from one
    minkq scene of many geometries (:meth:`minkq.Scene.from_geometries`).

    The scene holds the cloth as one moving geometry (self pairs only with ``self_contacts``)
    and each selected mesh shape as a geometry of its own with cross pairs only (body shapes
    never pair with each other): static when the shape is on no body (``shape_body`` -1, its
    vertices placed once by ``shape_transform`` and ``shape_scale``), else moved by
    :meth:`update` from the body's pose in ``state.body_q``.

    Reach. A pair is reported when its distance is within ``radius + t(a) + t(b)`` (minkq's
    leaf-exact test: every such pair of a double-precision oracle, plus at most pairs within a
    relative 2**-19 of the bound), with thickness t, when ``thickness`` is true (the default),
    Newton's ``particle_radius`` of the cloth's vertices (an element: its largest) and the
    shape's ``shape_margin``: with ``radius`` Newton's ``soft_contact_gap`` this is the band in
    which Newton's soft contact pass (``create_soft_contacts``) reports a particle. With
    ``thickness=False`` the band is ``radius`` alone.

    Differences from Newton's soft contacts, by design: Newton asks, per particle and shape,
    for the closest point of the mesh (vertex-triangle only, one contact), and uses a signed
    distance, so it also reports particles deep inside a body; here every pair of features
    within the band is reported, by unsigned distance (a particle deeper inside than the band
    has none). All particles take part, active or not (Newton skips inactive ones: filter the
    rows with ``model.particle_flags`` if needed). Pairs follow Newton's worlds (a cloth
    element's world is that of its first vertex; different worlds pair only if one is -1).

    Positions are read on the host (``.numpy()`` of Warp's arrays) and the queries run on
    minkq's CPU backend, whatever the model's device.

    ``shapes``: the mesh shapes to include (indices into the model's shapes), by default every
    ``MESH`` or ``CONVEX_MESH`` shape whose ``shape_flags`` has ``COLLIDE_PARTICLES``.
    ``state``: positions to build from (default ``model.state()``'s, the initial ones).

    Raises ValueError for a model without cloth triangles, without such mesh shapes, or a
    ``shapes`` entry that is out of range, listed twice or not a mesh (naming it), a state
    without ``body_q`` when a shape is on a body; minkq's errors for
    non-finite positions (naming the geometry: 0 the cloth, k + 1 the k-th shape).

    >>> contacts = ClothBodyContacts(model)                  # doctest: +SKIP
    >>> contacts.update(state)                               # doctest: +SKIP
    >>> pairs = contacts.detect(soft_contact_gap)            # doctest: +SKIP
    >>> pairs.vertex_triangle[:, 0], pairs.edge_edge.shape   # doctest: +SKIP
    """

    mode = "box"  # minkq's node test: changes the speed, not the pairs

    def __init__(self, model: Any, *, shapes: Optional[Sequence[int]] = None, self_contacts: bool = False,
                 thickness: bool = True, state: Any = None) -> None:
        self.model = model
        if model.particle_count == 0 or model.tri_count == 0:
            raise ValueError(
                f"model: expected cloth (particles and triangles), got {model.particle_count} particles and "
                f"{model.tri_count} triangles"
            )
        self.shapes = self._select_shapes(model, shapes)
        self.self_contacts = bool(self_contacts)
        self.thickness = bool(thickness)
        self._shape_body = model.shape_body.numpy()[self.shapes].astype(np.int64)
        self._shape_scale = model.shape_scale.numpy()[self.shapes].astype(np.float64)
        self._shape_xform = model.shape_transform.numpy()[self.shapes].astype(np.float64)
        self._local = [np.asarray(model.shape_source[s].vertices, np.float64) for s in self.shapes]
        self._tris = [np.asarray(model.shape_source[s].indices, np.int32).reshape(-1, 3) for s in self.shapes]
        self.tri_indices = model.tri_indices.numpy().astype(np.int32)
        self.edge_indices = (model.edge_indices.numpy()[:, 2:4].astype(np.int32) if model.edge_count
                             else np.zeros((0, 2), np.int32))
        particle_world = (model.particle_world.numpy() if model.particle_world is not None
                          else np.full(model.particle_count, -1))
        self._worlds = {
            "vertex": particle_world,
            "triangle": particle_world[self.tri_indices[:, 0]],
            "edge": particle_world[self.edge_indices[:, 0]],
        }
        self._shape_world = (model.shape_world.numpy()[self.shapes] if model.shape_world is not None
                             else np.full(len(self.shapes), -1))
        state = model.state() if state is None else state
        self.scene = _api.Scene.from_geometries(self._geometries(state), device="cpu")

    # ---- Building ------------------------------------------------------------------------

    @staticmethod
    def _select_shapes(model: Any, shapes: Optional[Sequence[int]]) -> List[int]:
        types = model.shape_type.numpy() if model.shape_count else np.zeros(0, np.int32)
        if shapes is None:
            flags = model.shape_flags.numpy() if model.shape_count else np.zeros(0, np.int32)
            collide = int(newton.ShapeFlags.COLLIDE_PARTICLES)
            chosen = [s for s in range(len(types)) if int(types[s]) in _MESH_TYPES and flags[s] & collide]
            if not chosen:
                raise ValueError(
                    f"model: none of its {len(types)} shapes is a mesh (MESH or CONVEX_MESH) that collides with "
                    "particles (shape_flags COLLIDE_PARTICLES)"
                )
            return chosen
        chosen = []
        for i, s in enumerate(shapes):
            if isinstance(s, bool) or not isinstance(s, (int, np.integer)):
                raise TypeError(f"shapes[{i}]: expected a shape index (int), got {type(s).__name__}")
            if not 0 <= s < len(types):
                raise ValueError(f"shapes[{i}]: shape {int(s)} is out of range (the model has {len(types)} shapes)")
            if int(types[s]) not in _MESH_TYPES or model.shape_source[s] is None:
                raise ValueError(
                    f"shapes[{i}]: shape {int(s)} is a {newton.GeoType(int(types[s])).name}, not a mesh (MESH or "
                    "CONVEX_MESH)"
                )
            if int(s) in chosen:
                raise ValueError(f"shapes[{i}]: shape {int(s)} is listed twice")
            chosen.append(int(s))
        if not chosen:
            raise ValueError("shapes: expected at least one mesh shape")
        return chosen

    def _geometries(self, state: Any) -> List[Geometry]:
        model = self.model
        cloth = Geometry(
            self._particles(state), self.tri_indices, self.edge_indices, kinds=("vt", "ee"),
            self_pairs=self.self_contacts, world=-1, group=_CLOTH_GROUP,
            thickness=model.particle_radius.numpy() if self.thickness else None,
        )
        margins = (model.shape_margin.numpy() if getattr(model, "shape_margin", None) is not None
                   else np.zeros(model.shape_count))
        bodies = [
            Geometry(
                self._shape_vertices(k, state), self._tris[k], kinds=("vt", "ee"), self_pairs=False,
                static=self._shape_body[k] < 0, world=-1, group=_BODY_GROUP, mask=_CLOTH_GROUP,
                thickness=float(margins[s]) if self.thickness else None,
            )
            for k, s in enumerate(self.shapes)
        ]
        return [cloth, *bodies]

    def _particles(self, state: Any) -> np.ndarray:
        return np.ascontiguousarray(state.particle_q.numpy(), np.float32)

    def _shape_vertices(self, k: int, state: Any) -> np.ndarray:
        """Shape k's vertices in world space (float32), at ``state``'s body pose."""
        body = int(self._shape_body[k])
        if body >= 0 and getattr(state, "body_q", None) is None:
            raise ValueError(f"state: has no body_q, but shape {self.shapes[k]} is on body {body}")
        pose = None if body < 0 else state.body_q.numpy()[body].astype(np.float64)
        xyz = shape_world_vertices(self._local[k], self._shape_scale[k], self._shape_xform[k], pose)
        return xyz.astype(np.float32)

    def shape_world_vertices(self, shape: int, state: Any) -> np.ndarray:
        """Mesh shape ``shape``'s vertices in world space at ``state``'s body poses, (n, 3)
        float32: the positions the scene holds after ``update(state)``."""
        return self._shape_vertices(self._shape_index(shape), state)

    def shape_edges(self, shape: int) -> np.ndarray:
        """Mesh shape ``shape``'s edges, (e, 2) int32 indices into its vertices: the edges that
        ``edge_edge``'s third column numbers (derived from its triangles)."""
        g = self._shape_index(shape) + 1
        first, count = self.scene.geometry_range(g, "edge")
        vertex_first, _ = self.scene.geometry_range(g, "vertex")
        return (self.scene.edges()[first:first + count] - vertex_first).astype(np.int32)

    def _shape_index(self, shape: int) -> int:
        if shape not in self.shapes:
            raise ValueError(f"shape: shape {shape!r} is not one of this detector's mesh shapes {self.shapes}")
        return self.shapes.index(shape)

    # ---- Per step --------------------------------------------------------------------------

    def update(self, state: Any) -> None:
        """Moves the cloth to ``state.particle_q`` and each moving shape to its body's pose in
        ``state.body_q``, refitting their trees (static shapes are not touched)."""
        self._move(state, self.scene.refit_geometry)

    def rebuild(self, state: Any) -> None:
        """As :meth:`update`, building the trees afresh (after large motion)."""
        self._move(state, self.scene.rebuild_geometry)

    def _move(self, state: Any, call: Any) -> None:
        call(_CLOTH, self._particles(state))
        for k in range(len(self.shapes)):
            if self._shape_body[k] >= 0:
                call(k + 1, self._shape_vertices(k, state))

    def detect(self, radius: float) -> ClothBodyPairs:
        """The contacts at the positions of the last :meth:`update` (see the class for the
        reach). ``radius``: a finite number >= 0 (ValueError otherwise)."""
        if isinstance(radius, bool) or not isinstance(radius, (int, float, np.integer, np.floating)):
            raise TypeError(f"radius: expected a number, got {type(radius).__name__}")
        if not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"radius: expected a finite number >= 0, got {radius}")
        r = float(radius)
        vt = self.scene.query("vt", r, mode=self.mode, leaf_exact=True, canonical=True)
        ee = self.scene.query("ee", r, mode=self.mode, leaf_exact=True, canonical=True)
        vt_g, vt_local = self.scene.geometry_of_pairs("vt", vt)
        ee_g, ee_local = self.scene.geometry_of_pairs("ee", ee)
        cloth_v, cloth_t = vt_g[:, 0] == _CLOTH, vt_g[:, 1] == _CLOTH
        # EE pairs are (lower, higher) global id: the cloth, geometry 0, comes first.
        cloth_e0, cloth_e1 = ee_g[:, 0] == _CLOTH, ee_g[:, 1] == _CLOTH
        pairs = ClothBodyPairs(
            vertex_triangle=self._cross(vt_local[:, 0], vt_g[:, 1], vt_local[:, 1], "vertex", cloth_v & ~cloth_t),
            triangle_vertex=self._cross(vt_local[:, 1], vt_g[:, 0], vt_local[:, 0], "triangle", cloth_t & ~cloth_v),
            edge_edge=self._cross(ee_local[:, 0], ee_g[:, 1], ee_local[:, 1], "edge", cloth_e0 & ~cloth_e1),
        )
        if self.self_contacts:
            pairs.self_vertex_triangle = self._self(vt_local, cloth_v & cloth_t, "vertex", "triangle")
            pairs.self_edge_edge = self._self(ee_local, cloth_e0 & cloth_e1, "edge", "edge")
        return pairs

    def _cross(self, cloth: np.ndarray, geometry: np.ndarray, other: np.ndarray, element: str,
               keep: np.ndarray) -> np.ndarray:
        """The (cloth element, shape, shape element) rows of the cross pairs ``keep`` marks whose
        worlds meet, sorted."""
        cloth, k, other = cloth[keep], geometry[keep] - 1, other[keep]
        a, b = self._worlds[element][cloth], self._shape_world[k]
        meet = (a < 0) | (b < 0) | (a == b)
        rows = np.stack([cloth[meet], np.asarray(self.shapes, np.int32)[k[meet]], other[meet]], 1).astype(np.int32)
        return rows[np.lexsort(rows.T[::-1])] if len(rows) else rows.reshape(0, 3)

    def _self(self, local: np.ndarray, keep: np.ndarray, first: str, second: str) -> np.ndarray:
        rows = local[keep].astype(np.int32)
        a, b = self._worlds[first][rows[:, 0]], self._worlds[second][rows[:, 1]]
        return rows[(a < 0) | (b < 0) | (a == b)].reshape(-1, 2)
