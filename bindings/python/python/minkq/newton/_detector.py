"""minkq.newton's ``TriMeshCollisionDetector``: Newton's detector with minkq's queries (see the
package's documentation)."""

from __future__ import annotations

import sys
import traceback
import weakref
from typing import Any, Callable, Optional, Tuple

import numpy as np
import warp as wp

from .. import _api
from .._errors import CapacityError, UnsupportedError
from . import _compat
from ._capture import (
    _DISPATCH,
    ReplayError,
    _capture_paused,
    _graph_being_captured,
    _host_call_kernel,
    _next_token,
    _recorded,
    _Scratch,
)
from ._compat import (
    compute_bvh_group_roots,
    compute_edge_aabbs,
    compute_edge_groups,
    compute_tri_aabbs,
    compute_tri_groups,
    init_triangle_collision_data_kernel,
)
from ._kernels import (
    _edge_edge_pairs_kernel,
    _flag_lost_pairs_kernel,
    _vertex_triangle_pairs_kernel,
    _write_rows_kernel,
)

VERTEX_OVERFLOW, TRIANGLE_OVERFLOW, EDGE_OVERFLOW = 0, 1, 2  # resize_flags (Newton's indices)


def _minkq_device_for(device: Any) -> _api.Device:
    spec = f"cuda:{device.ordinal}" if device.is_cuda else "cpu"
    try:
        return _api.Device(spec)
    except UnsupportedError as e:
        raise UnsupportedError(
            f"the Newton model is on {device} but minkq cannot use {spec}: {e.message} (build libminkq with CUDA)"
        ) from None


_NewtonDetector = _compat.newton_tri_mesh_collision.TriMeshCollisionDetector  # Newton's class, whatever install() swaps


class TriMeshCollisionDetector(_NewtonDetector):
    """Newton's ``TriMeshCollisionDetector`` (newton 1.8) with minkq's VT and EE queries: same
    constructor, methods, result arrays and layout (see the module's documentation for the
    few deliberate differences). Every vertex-triangle and edge-edge pair within the query
    radius is reported, however short the edges.

    The VT pass runs minkq's ``vt_mode`` node test and the EE pass ``ee_mode``, both with
    the leaf-exact primitive test; the node test changes the speed, not the pairs (box, the
    default, is the one meant for contacts: docs/design-notes.md).
    """

    vt_mode = "box"
    ee_mode = "box"

    def __init__(
        self,
        model: Any,
        record_triangle_contacting_vertices=False,
        vertex_positions=None,
        vertex_collision_buffer_pre_alloc=16,
        vertex_collision_buffer_max_alloc=256,
        vertex_triangle_filtering_list=None,
        vertex_triangle_filtering_list_offsets=None,
        triangle_collision_buffer_pre_alloc=16,
        triangle_collision_buffer_max_alloc=256,
        edge_collision_buffer_pre_alloc=32,
        edge_collision_buffer_max_alloc=256,
        edge_filtering_list=None,
        edge_filtering_list_offsets=None,
        topological_contact_filter_threshold: int = 0,
        external_vertex_triangle_filtering_map: Optional[dict] = None,
        external_edge_edge_filtering_map: Optional[dict] = None,
        triangle_triangle_collision_buffer_pre_alloc=8,
        triangle_triangle_collision_buffer_max_alloc=256,
        edge_edge_parallel_epsilon=1e-5,
        collision_detection_block_size: Optional[int] = None,
        collision_info: Optional[Any] = None,
        init_collision_info: bool = False,
    ):
        # Newton's constructor, step by step, without its Warp BVHs.
        self._replay_error: Optional[tuple] = None
        self.replayed_calls = 0  # calls recorded into Warp CPU graphs, run by their replays
        self.replay_failures = 0  # replayed calls that failed (see ReplayError)
        self.model = model
        self.record_triangle_contacting_vertices = record_triangle_contacting_vertices
        self.vertex_positions = model.particle_q if vertex_positions is None else vertex_positions
        self.device = model.device
        self.vertex_collision_buffer_pre_alloc = vertex_collision_buffer_pre_alloc
        self.vertex_collision_buffer_max_alloc = vertex_collision_buffer_max_alloc
        self.triangle_collision_buffer_pre_alloc = triangle_collision_buffer_pre_alloc
        self.triangle_collision_buffer_max_alloc = triangle_collision_buffer_max_alloc
        self.edge_collision_buffer_pre_alloc = edge_collision_buffer_pre_alloc
        self.edge_collision_buffer_max_alloc = edge_collision_buffer_max_alloc
        self.triangle_triangle_collision_buffer_pre_alloc = triangle_triangle_collision_buffer_pre_alloc
        self.triangle_triangle_collision_buffer_max_alloc = triangle_triangle_collision_buffer_max_alloc
        self.vertex_triangle_filtering_list = vertex_triangle_filtering_list
        self.vertex_triangle_filtering_list_offsets = vertex_triangle_filtering_list_offsets
        self.edge_filtering_list = edge_filtering_list
        self.edge_filtering_list_offsets = edge_filtering_list_offsets
        self.edge_edge_parallel_epsilon = edge_edge_parallel_epsilon  # kept for readers; unused
        if model.soft_mesh_adjacency is None:
            raise ValueError("model.soft_mesh_adjacency is missing; finalize the model with ModelBuilder.")
        self.mesh_adjacency = model.soft_mesh_adjacency.init_vertex_adjacency(model.particle_count)
        self.collision_detection_block_size = collision_detection_block_size

        need_vertex_triangle = vertex_triangle_filtering_list is None and (
            topological_contact_filter_threshold >= 2 or external_vertex_triangle_filtering_map is not None
        )
        need_edge_edge = edge_filtering_list is None and (
            topological_contact_filter_threshold >= 2 or external_edge_edge_filtering_map is not None
        )
        if (need_vertex_triangle or need_edge_edge) and model.tri_count > 0:
            adjacency = None
            if topological_contact_filter_threshold >= 2 and model.edge_indices is not None:
                adjacency = self._extract_filter_adjacency()
            if need_vertex_triangle:
                self._build_vertex_triangle_filter(
                    topological_contact_filter_threshold, external_vertex_triangle_filtering_map, adjacency
                )
            if need_edge_edge:
                self._build_edge_edge_filter(
                    topological_contact_filter_threshold, external_edge_edge_filtering_map, adjacency
                )

        if collision_info is not None and init_collision_info:
            raise ValueError("pass either collision_info or init_collision_info=True, not both")
        if init_collision_info:
            collision_info = _compat.newton_tri_mesh_collision.build_tri_mesh_collision_info(
                model.particle_count,
                model.tri_count,
                model.edge_count,
                vertex_collision_buffer_pre_alloc=vertex_collision_buffer_pre_alloc,
                triangle_collision_buffer_pre_alloc=triangle_collision_buffer_pre_alloc,
                edge_collision_buffer_pre_alloc=edge_collision_buffer_pre_alloc,
                record_triangle_contacting_vertices=record_triangle_contacting_vertices,
                device=self.device,
            )
        if collision_info is not None:
            self._validate_collision_info(collision_info)
        self.collision_info = collision_info

        self.resize_flags = wp.zeros(shape=(4,), dtype=wp.int32, device=self.device)
        self.triangle_intersecting_triangles = None
        self.triangle_intersecting_triangles_count = None
        self.triangle_intersecting_triangles_offsets = None

        # minkq's side: the scene (both trees), world groups, scratch.
        self.minkq_device = _minkq_device_for(self.device)
        tri_indices = model.tri_indices.numpy() if model.tri_count else np.zeros((0, 3), np.int32)
        edge_indices = model.edge_indices.numpy() if model.edge_count else np.zeros((0, 4), np.int32)
        world = model.particle_world.numpy() if model.particle_world is not None else np.full(model.particle_count, -1)
        self._global_group = int(model.world_count)
        vertex_group = np.where(world < 0, self._global_group, world).astype(np.int32)
        self._vertex_group = wp.array(vertex_group, dtype=wp.int32, device=self.device)
        self._tri_group = wp.array(vertex_group[tri_indices[:, 0]], dtype=wp.int32, device=self.device)
        self._edge_group = wp.array(vertex_group[edge_indices[:, 2]], dtype=wp.int32, device=self.device)
        self._scratch = _Scratch(self.device)
        self._found = {kind: wp.zeros(1, dtype=wp.int64, device=self.device) for kind in ("vt", "ee")}
        self._in_cuda_capture = False
        self._graph_arrays: list = []  # arrays CUDA graphs recorded (see _Scratch)
        self._row_slots: dict = {}
        self._empty_int = wp.zeros(1, dtype=wp.int32, device=self.device)
        self._scene: Optional[_api.Scene] = None
        self._build_scene()

    # ---- Now, or at every replay of a CPU graph --------------------------------------------

    def _call(self, what: str, body: Callable, *args: Any) -> None:
        """Runs ``body(self, *args)`` now or, inside a Warp graph capture on the CPU, records it
        to run at every replay with these arguments and the ``vertex_positions`` of now."""
        self.check_replays()
        device = self.device
        if not getattr(device, "is_capturing", False):
            body(self, *args)
            return
        if device.is_cuda:  # the body again, with minkq's stream-ordered calls on Warp's capture stream
            self._scratch.pinned = self._graph_arrays
            self._in_cuda_capture = True
            try:
                body(self, *args)
            finally:
                self._in_cuda_capture = False
                self._scratch.pinned = None
            return
        token = _next_token[0]
        _next_token[0] += 1
        _recorded[token] = (weakref.ref(self), what, body, args, self.vertex_positions)
        graph = _graph_being_captured()
        if graph is not None:
            weakref.finalize(graph, _recorded.pop, token, None)  # the entry lives as long as the graph
        wp.launch(_host_call_kernel, dim=1, inputs=[wp.uint64(_DISPATCH), wp.uint64(token)], device=device)

    def _replay_failed(self, what: str, error: BaseException) -> None:
        self.replay_failures += 1
        first = self._replay_error is None
        if first:
            self._replay_error = (what, error)
        print(
            f"minkq.newton: TriMeshCollisionDetector.{what} failed during a Warp graph replay ({type(error).__name__}: "
            f"{error}); its results in this replay are not valid. The detector's next call, check_replays() or "
            "minkq.newton.capture_launch() raises it.",
            file=sys.stderr,
        )
        if first:
            traceback.print_exception(type(error), error, error.__traceback__, file=sys.stderr)

    def check_replays(self) -> None:
        """Raises :class:`ReplayError` (once) if a call recorded into a Warp CPU graph failed
        during a replay since the last check; the first such failure is its ``__cause__``."""
        pending = self._replay_error
        if pending is None:
            return
        self._replay_error = None
        what, error = pending
        raise ReplayError(
            f"minkq.newton.TriMeshCollisionDetector.{what} failed during a Warp graph replay "
            f"({self.replay_failures} failed replayed call(s) so far): {type(error).__name__}: {error}"
        ) from error

    # ---- Trees ---------------------------------------------------------------------------

    def _build_scene(self) -> None:
        model = self.model
        vt, ee = model.tri_count > 0, model.edge_count > 0
        if not (vt or ee) or model.particle_count == 0:
            self._scene = None
            return
        # Newton's (E, 4) edge table holds each edge's vertices in its last two columns: read
        # them in place (16-byte records). Triangles and edges are copied into the scene once.
        edges = model.edge_indices[:, 2:4] if ee else np.zeros((0, 2), np.int32)
        triangles = model.tri_indices if vt else np.zeros((0, 3), np.int32)
        self._scene = _api.Scene(self.vertex_positions, triangles, edges, device=self.minkq_device, vt=vt, ee=ee,
                                 drop_incident=True)
        if self.device.is_cuda:  # the scratch of the stream-ordered refits and rebuilds of CUDA captures
            self._scene.reserve(refit=True, rebuild=True)

    def rebuild(self, new_pos=None):
        """Rebuilds both trees from ``new_pos`` (or the current ``vertex_positions``) in place:
        the scene keeps its topology and buffers (``Scene.rebuild``)."""
        if new_pos is not None:
            self.vertex_positions = new_pos
        self._call("rebuild", TriMeshCollisionDetector._rebuild_now)

    def _rebuild_now(self) -> None:
        if self._scene is not None and self._in_cuda_capture:
            self._scene.rebuild_async(self.vertex_positions)
        elif self._scene is not None:
            self._scene.rebuild(self.vertex_positions)
        else:
            self._build_scene()
        if self._warp_bvhs_built():
            _NewtonDetector.rebuild(self)

    def refit(self, new_pos=None):
        """Refits both trees to ``new_pos`` (or the current ``vertex_positions``), read in place
        on the model's device: the per-step call."""
        if new_pos is not None:
            self.vertex_positions = new_pos
        self._call("refit", TriMeshCollisionDetector._refit_now)

    def _refit_now(self) -> None:
        if self._scene is not None and self._in_cuda_capture:
            self._scene.refit_async(self.vertex_positions)
        elif self._scene is not None:
            self._scene.refit(self.vertex_positions)
        if self._warp_bvhs_built():  # Newton's own per-tree refits (its refit() calls the overrides below)
            _NewtonDetector.refit_triangles(self)
            _NewtonDetector.refit_edges(self)

    def refit_triangles(self):
        """Refits the trees to ``vertex_positions`` (minkq refits both trees together)."""
        self.refit()

    def refit_edges(self):
        """Refits the trees to ``vertex_positions`` (minkq refits both trees together)."""
        self.refit()

    # ---- Queries -----------------------------------------------------------------------------

    def _pairs(self, kind: str, mode: str, radius: float) -> Tuple[wp.array, wp.array, int]:
        """minkq's leaf-exact pairs, written in place into a device array of the model's device:
        (pairs, found, slots): slot i < slots holds a pair if i < found[0] (a one-element device
        array). Now: exactly the pairs found, found[0] == slots. Inside a CUDA capture: a
        stream-ordered query into the pass's buffer as it is (Newton's row capacity at least),
        found[0] the exact count; pairs past the buffer set Newton's resize flag."""
        name = kind + "_pairs"
        found = self._found[kind]
        if self._in_cuda_capture:
            pairs = self._scratch.get(name, wp.int32, self._capture_capacity(kind), (2,))
            self._scene.query_async(pairs, found, kind, radius, mode=mode, leaf_exact=True)
            flag = VERTEX_OVERFLOW if kind == "vt" else EDGE_OVERFLOW
            wp.launch(_flag_lost_pairs_kernel, dim=1, inputs=[found, pairs.shape[0], flag], outputs=[self.resize_flags],
                      device=self.device)
            return pairs, found, pairs.shape[0]
        pairs = self._scratch.get(name, wp.int32, 0, (2,))
        try:
            count = len(self._scene.query(kind, radius, mode=mode, leaf_exact=True, out=pairs))
        except CapacityError as e:
            pairs = self._scratch.get(name, wp.int32, e.needed + e.needed // 4, (2,))
            count = len(self._scene.query(kind, radius, mode=mode, leaf_exact=True, out=pairs))
        found.fill_(count)
        return pairs[:count], found, count

    def _capture_capacity(self, kind: str) -> int:
        """Pairs a captured query's buffer holds at least: as many as Newton's rows of that kind
        hold (a pair fills one vertex row slot, or two edge row slots)."""
        info = self.collision_info
        offsets = info.vertex_colliding_triangles_offsets if kind == "vt" else info.edge_colliding_edges_offsets
        key = (kind, offsets.ptr)
        if key not in self._row_slots:  # read once, outside the capture: Newton's offsets are fixed
            with _capture_paused(self.device):
                self._row_slots[key] = int(offsets[-1:].numpy()[0])
        return self._row_slots[key]

    def _filter(self, values: Any, offsets: Any):
        if values is None or offsets is None:
            return self._empty_int, self._empty_int, 0
        return values, offsets, 1

    def _reference(self, min_query_radius: float, ref_pos: Any):
        # As Newton: without reference positions, the current ones.
        ref_pos = self.vertex_positions if ref_pos is None else ref_pos
        return ref_pos, max(float(min_query_radius), 0.0)

    def _fill_rows(self, keys: wp.array, count: int, num_rows: int, counts: wp.array, offsets: wp.array,
                   buffer_sizes: wp.array, capacity_from_offsets: bool, interleaved: bool, rows: wp.array,
                   flag_index: int) -> None:
        """Sorts the (row, other) keys and writes each row's first pairs into Newton's buffer."""
        if count == 0:
            return
        values = self._scratch.get("sort_values", wp.int32, 2 * count)
        wp.utils.radix_sort_pairs(keys, values, count, 0, 32 + max(int(num_rows).bit_length(), 1))
        row_start = self._scratch.get("row_start", wp.int32, num_rows)
        wp.utils.array_scan(counts, row_start[:num_rows], inclusive=False)
        wp.launch(
            _write_rows_kernel,
            dim=count,
            inputs=[keys, row_start, offsets, buffer_sizes, int(capacity_from_offsets), int(interleaved), num_rows, flag_index],
            outputs=[rows, self.resize_flags],
            device=self.device,
        )

    def vertex_triangle_collision_detection(self, max_query_radius, min_query_radius=0.0, min_distance_filtering_ref_pos=None):
        """Fills each vertex's row with the triangles within ``max_query_radius`` (and, when
        recording, each triangle's row with the vertices); see the module documentation."""
        self._require_collision_info()
        self._call(
            "vertex_triangle_collision_detection", TriMeshCollisionDetector._vertex_triangle_now, max_query_radius,
            min_query_radius, min_distance_filtering_ref_pos,
        )

    def _vertex_triangle_now(self, max_query_radius, min_query_radius, min_distance_filtering_ref_pos) -> None:
        model = self.model
        r = float(max_query_radius)
        self.vertex_colliding_triangles.fill_(-1)
        if self.record_triangle_contacting_vertices:
            wp.launch(
                kernel=init_triangle_collision_data_kernel,
                inputs=[r],
                outputs=[self.triangle_colliding_vertices_count, self.triangle_colliding_vertices_min_dist, self.resize_flags],
                dim=model.tri_count,
                device=self.device,
            )
        else:
            self.triangle_colliding_vertices_min_dist.fill_(r)
        self.vertex_colliding_triangles_count.zero_()
        self.vertex_colliding_triangles_min_dist.fill_(r)
        if self._scene is None or model.tri_count == 0:
            return
        pairs, found, k = self._pairs("vt", self.vt_mode, r)
        if k == 0:
            return
        record = bool(self.record_triangle_contacting_vertices)
        vertex_keys = self._scratch.get("vertex_keys", wp.int64, 2 * k)
        tri_keys = self._scratch.get("tri_keys", wp.int64, 2 * k) if record else vertex_keys
        tri_count = self.triangle_colliding_vertices_count if record else self.vertex_colliding_triangles_count
        ref_pos, min_r = self._reference(min_query_radius, min_distance_filtering_ref_pos)
        filter_list, filter_offsets, use_filter = self._filter(
            self.vertex_triangle_filtering_list, self.vertex_triangle_filtering_list_offsets
        )
        wp.launch(
            _vertex_triangle_pairs_kernel,
            dim=k,
            inputs=[
                pairs, found, self.vertex_positions, model.tri_indices, ref_pos, min_r, self._vertex_group, self._tri_group,
                self._global_group, filter_list, filter_offsets, use_filter, int(record), model.particle_count,
                model.tri_count,
            ],
            outputs=[
                vertex_keys, self.vertex_colliding_triangles_count, self.vertex_colliding_triangles_min_dist,
                tri_keys, tri_count, self.triangle_colliding_vertices_min_dist,
            ],
            device=self.device,
        )
        info = self.collision_info
        self._fill_rows(
            vertex_keys, k, model.particle_count, self.vertex_colliding_triangles_count,
            info.vertex_colliding_triangles_offsets, info.vertex_colliding_triangles_buffer_sizes, True, True,
            info.vertex_colliding_triangles, VERTEX_OVERFLOW,
        )
        if record:
            self._fill_rows(
                tri_keys, k, model.tri_count, info.triangle_colliding_vertices_count,
                info.triangle_colliding_vertices_offsets, info.triangle_colliding_vertices_buffer_sizes, False, False,
                info.triangle_colliding_vertices, TRIANGLE_OVERFLOW,
            )

    def edge_edge_collision_detection(self, max_query_radius, min_query_radius=0.0, min_distance_filtering_ref_pos=None):
        """Fills each edge's row with the edges within ``max_query_radius`` (each contact in
        both edges' rows); see the module documentation."""
        self._require_collision_info()
        self._call(
            "edge_edge_collision_detection", TriMeshCollisionDetector._edge_edge_now, max_query_radius,
            min_query_radius, min_distance_filtering_ref_pos,
        )

    def _edge_edge_now(self, max_query_radius, min_query_radius, min_distance_filtering_ref_pos) -> None:
        model = self.model
        r = float(max_query_radius)
        self.edge_colliding_edges.fill_(-1)
        self.edge_colliding_edges_count.zero_()
        self.edge_colliding_edges_min_dist.fill_(r)
        if self._scene is None or model.edge_count == 0:
            return
        pairs, found, k = self._pairs("ee", self.ee_mode, r)
        if k == 0:
            return
        edge_keys = self._scratch.get("edge_keys", wp.int64, 4 * k)
        ref_pos, min_r = self._reference(min_query_radius, min_distance_filtering_ref_pos)
        filter_list, filter_offsets, use_filter = self._filter(self.edge_filtering_list, self.edge_filtering_list_offsets)
        wp.launch(
            _edge_edge_pairs_kernel,
            dim=k,
            inputs=[
                pairs, found, k, self.vertex_positions, model.edge_indices, ref_pos, min_r, self._edge_group, self._global_group,
                filter_list, filter_offsets, use_filter, model.edge_count,
            ],
            outputs=[edge_keys, self.edge_colliding_edges_count, self.edge_colliding_edges_min_dist],
            device=self.device,
        )
        info = self.collision_info
        self._fill_rows(
            edge_keys, 2 * k, model.edge_count, self.edge_colliding_edges_count, info.edge_colliding_edges_offsets,
            info.edge_colliding_edges_buffer_sizes, True, True, info.edge_colliding_edges, EDGE_OVERFLOW,
        )

    def triangle_triangle_intersection_detection(self):
        """Newton's triangle-triangle intersection test, over Newton's Warp BVH of the triangles
        when it has been built (see the module's documentation), else over one built for the
        call from ``vertex_positions`` (minkq has no triangle-triangle query)."""
        if self._warp_bvhs_built():  # Newton's BVH, as of the last refit or rebuild
            return super().triangle_triangle_intersection_detection()
        model = self.model
        lower = wp.empty(model.tri_count, dtype=wp.vec3, device=self.device)
        upper = wp.empty(model.tri_count, dtype=wp.vec3, device=self.device)
        wp.launch(compute_tri_aabbs, dim=model.tri_count, inputs=[self.vertex_positions, model.tri_indices, lower, upper], device=self.device)
        self.__dict__["bvh_tris"] = wp.Bvh(lower, upper)
        try:
            super().triangle_triangle_intersection_detection()
        finally:
            del self.__dict__["bvh_tris"]

    # Newton's Warp BVHs and what it keeps for them, built on first access.
    _WARP_BVH_ATTRIBUTES = frozenset(
        ("bvh_tris", "bvh_edges", "bvh_tris_group_roots", "bvh_edges_group_roots", "lower_bounds_tris",
         "upper_bounds_tris", "lower_bounds_edges", "upper_bounds_edges", "tri_groups", "edge_groups")
    )

    def _warp_bvhs_built(self) -> bool:
        return "bvh_tris" in self.__dict__ and "bvh_edges" in self.__dict__

    def _build_warp_bvhs(self) -> None:
        """Newton's BVHs of the triangles and edges, grouped by world, over ``vertex_positions``
        (those of the last refit or rebuild), with Newton's kernels: the attributes its
        constructor makes."""
        device = self.device
        if getattr(device, "is_capturing", False):
            if device.is_cuda:
                raise RuntimeError(
                    f"minkq.newton.TriMeshCollisionDetector: Newton's Warp BVHs (bvh_tris, bvh_edges) were first read "
                    f"inside a Warp graph capture on {device}, which minkq does not support on CUDA yet; read them once "
                    "before the capture."
                )
            # CPU: build them now, outside the recording (the graph only keeps their ids); the
            # recorded refits and rebuilds keep them current at every replay.
            with _capture_paused(device):
                self._build_warp_bvhs_now()
            return
        self._build_warp_bvhs_now()

    def _build_warp_bvhs_now(self) -> None:
        model, device = self.model, self.device
        built = {}
        # Per kind, as Newton keeps them: the groups' attribute name, whether an empty set still
        # gets a BVH (Warp cannot build an empty grouped BVH on every device: Newton keeps None
        # for no edges) and the group roots' fill value.
        for kind, groups_name, count, indices, aabbs, groups, empty_bvh, root_fill in (
            ("tris", "tri_groups", model.tri_count, model.tri_indices, compute_tri_aabbs, compute_tri_groups, True, 0),
            ("edges", "edge_groups", model.edge_count, model.edge_indices, compute_edge_aabbs, compute_edge_groups,
             False, -1),
        ):
            lower = wp.empty(count, dtype=wp.vec3, device=device)
            upper = wp.empty(count, dtype=wp.vec3, device=device)
            group = wp.empty(count, dtype=wp.int32, device=device)
            wp.launch(aabbs, dim=count, inputs=[self.vertex_positions, indices, lower, upper], device=device)
            wp.launch(groups, dim=count, inputs=[indices, model.particle_world, model.world_count, group], device=device)
            bvh = wp.Bvh(lower, upper, groups=group) if count or empty_bvh else None
            roots = wp.full(model.world_count + 1, root_fill, dtype=wp.int32, device=device)
            if bvh is not None:
                wp.launch(compute_bvh_group_roots, dim=model.world_count + 1, inputs=[bvh.id, roots], device=device)
            built.update({f"lower_bounds_{kind}": lower, f"upper_bounds_{kind}": upper, groups_name: group,
                          f"bvh_{kind}": bvh, f"bvh_{kind}_group_roots": roots})
        self.__dict__.update(built)

    def __getattr__(self, name: str) -> Any:
        # Only reached for attributes that do not exist (yet).
        if name in TriMeshCollisionDetector._WARP_BVH_ATTRIBUTES and not self._warp_bvhs_built():
            self._build_warp_bvhs()
            return self.__dict__[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
