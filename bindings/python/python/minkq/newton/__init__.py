"""minkq.newton: a drop-in for Newton's ``TriMeshCollisionDetector`` (newton 1.8).

Newton's VBD cloth solver gets its self-contact pairs from
``newton._src.geometry.tri_mesh_collision.TriMeshCollisionDetector``: Warp BVHs queried with
r-padded boxes, then Warp's ``closest_point_edge_edge`` with an absolute
``edge_edge_parallel_epsilon`` (1e-5 by default), compared with *squared edge lengths*: every
edge shorter than about 3.2e-3 scene units is treated as a point, and on fine meshes most
edge-edge contacts are lost silently. This class has the same constructor, methods and result
arrays, fills them with the same layout, on the model's device, from minkq's queries (every
pair within the radius, no absolute epsilon)::

    # from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector
    from minkq.newton import TriMeshCollisionDetector

    detector = TriMeshCollisionDetector(model, init_collision_info=True)
    detector.refit(state.particle_q)
    detector.vertex_triangle_collision_detection(radius)
    detector.edge_edge_collision_detection(radius)
    detector.vertex_colliding_triangles, detector.edge_colliding_edges_count, ...

For Newton's own users of the class (``SolverVBD``, ``CollisionPipeline``, and the name
``newton._src.solvers.vbd.tri_mesh_collision.TriMeshCollisionDetector`` its tests import),
:func:`install` swaps it in, and makes ``SolverVBD`` give a force to every edge-edge contact it
reports (below); ``python -m minkq.newton.examples <example> [options]`` runs any of Newton's
examples with it installed (:mod:`minkq.newton.examples`). The class subclasses Newton's, so the result struct
(``collision_info``: a Newton ``TriMeshCollisionInfo``), its accessors, the filter-list
building, ``resize_flags`` and ``isinstance`` checks are Newton's own.

What is the same as Newton (newton/_src/geometry/kernels.py):

- Rows. Vertex v's row holds ``(v, t)`` int32 pairs interleaved in
  ``vertex_colliding_triangles[2 * (offsets[v] + i) + {0, 1}]``; edge e's row ``(e, f)`` in
  ``edge_colliding_edges``; with ``record_triangle_contacting_vertices``, triangle t's row the
  plain vertex indices ``triangle_colliding_vertices[offsets[t] + i]``. A row's capacity is
  ``offsets[i + 1] - offsets[i]`` (triangles: ``buffer_sizes[t]``), unused slots are -1, and
  ``*_count`` is the number of pairs found, which may exceed the capacity: the pairs past it
  are dropped and ``resize_flags[0]`` (vertices), ``[1]`` (triangles) or ``[2]`` (edges) is
  set to 1. As in Newton the flags are never cleared by a detection, except that with
  ``record_triangle_contacting_vertices`` the vertex-triangle pass clears all four first.
- Which pairs. Incident pairs are dropped (a vertex and a triangle it belongs to; two edges
  sharing a vertex); each edge-edge contact is reported in both edges' rows; a vertex and a
  triangle (two edges) of different worlds are paired only if one of them is global (world
  -1); the topological and external filter lists (``topological_contact_filter_threshold``,
  ``external_*_filtering_map``, explicit ``*_filtering_list``) drop a pair from the row whose
  list names it; ``min_query_radius`` with ``min_distance_filtering_ref_pos`` drops pairs
  closer than it at the reference positions.
- Minimum distances. ``vertex_colliding_triangles_min_dist[v]`` (and the edge and triangle
  ones) is the smallest distance of a pair in the element's row, counted before truncation,
  and ``max_query_radius`` when there is none (triangles: ``max_query_radius`` unless
  recording).

Deliberate differences (documented choices):

- Pairs Newton misses. A pair is reported when its distance is within the radius by minkq's
  leaf-exact test, which reports every pair within r of a double-precision oracle, plus at
  most pairs within r + 2**-19 S (S the size of the two elements and their distance); Newton
  keeps float distances ``< r``, so the sets can differ at the boundary, and Newton loses the
  edge-edge contacts of short edges. ``edge_edge_parallel_epsilon`` is kept as an attribute
  but not used: distances here are computed without an absolute epsilon (float, relative
  tolerances only), also for the ``min_query_radius`` rest-shape filter.
- Row order. A row lists its pairs in ascending order of the other element (Newton: BVH
  traversal order); when a row overflows it keeps the lowest-numbered ones. Deterministic on
  every device.
- Positions. Pairs come from the positions of the last ``refit`` / ``rebuild`` (as Newton's
  BVHs do); distances and min distances from ``vertex_positions`` at detection time (as
  Newton's kernels do).
- Newton's Warp BVHs (``bvh_tris``, ``bvh_edges``, their group roots and bounds), which other
  Newton code (its collision tests, ``soft_contacts_mesh``) queries directly, are built as
  Newton builds them the first time one is read, and from then on refit and rebuilt with the
  detector; a detector whose BVHs nobody reads never builds them. minkq's pairs never come
  from them. ``collision_detection_block_size`` is unused.
- Graph capture. On the CPU, ``refit``, ``rebuild``, both detections (and the first read of
  Newton's Warp BVHs) work inside ``wp.ScopedCapture``, and every ``wp.capture_launch`` redoes
  minkq's work on the data of that moment. Warp 1.19 records a CPU graph (APIC) as a stream of
  kernel launches, memsets and copies that ``capture_launch`` replays in C++; while recording,
  ``wp.launch`` and ``fill_`` / ``zero_`` only record (they run at replay), ``device.is_capturing``
  is true, and a Python call made meanwhile (minkq's query, the host read of the pair count)
  would run once, at record time, and never again. So inside a CPU capture each of these
  methods records one launch of a one-thread kernel whose ``wp.func_native`` snippet calls a
  host function pointer (a ctypes callback kept by this module); the replay calls back into
  Python and runs the method's normal eager body then (no capture is active at replay: its
  launches, sorts and scans execute at once, between the graph's other operations, in recorded
  order). The body runs with the arguments of the recorded call and the ``vertex_positions``
  array of that moment, as a graph bakes its pointers: write new positions into the recorded
  arrays (Newton's states are), do not rebind them. A recorded call lives as long as its graph
  (``replayed_calls`` counts the replayed calls run). Newton's Warp BVHs, if first read inside a
  capture, are built then with the capture paused (Warp's ``capture_pause``), from the current
  positions; the recorded refits and rebuilds keep them current.

  Errors. An exception cannot cross Warp's kernel back into ``wp.capture_launch``. A body that
  fails at replay prints a message (the first failure with its traceback) to stderr, counts in
  ``replay_failures``, leaves that call's results invalid, and is kept: the detector's next call
  raises :class:`ReplayError` (its ``__cause__`` the original exception), as does
  :meth:`TriMeshCollisionDetector.check_replays`; :func:`capture_launch` (use it instead of
  ``wp.capture_launch``) raises it as soon as the replay returns. Later replays run the bodies
  again. Replaying such a graph inside another CPU capture is refused the same way.

  CUDA. Inside a CUDA capture the same bodies run at once, recording only device work on
  Warp's capture stream: minkq's stream-ordered calls (``Scene.refit_async``,
  ``rebuild_async``, ``query_async``, their scratch reserved when the scene is made) and Warp's
  kernels, sorts and scans, over every slot of each pass's pair buffer (slots past the pairs a
  replay finds carry none), so no count is read on the host. Each pass's buffer holds at least
  as many pairs as Newton's rows of that kind (a detection outside a capture grows it to what
  it found); a replay finding more loses the pairs past it and sets Newton's resize flag, as a
  full row does. The arrays a graph recorded are kept as long as the detector. Newton's Warp
  BVHs must be read once before a CUDA capture that uses them. Not run on a GPU yet (the tests
  marked gpu).
- Solver evaluation (``install()``). Newton's VBD force kernels recompute each edge-edge
  contact with Warp's ``closest_point_edge_edge(..., particle_edge_parallel_epsilon)`` and apply
  a force only if that distance is below the contact radius. The epsilon (1e-5 by default) is
  compared with *squared* edge lengths: an edge under 3.2e-3 is taken for a point (both edges:
  the distance of their first vertices), so on fine meshes most contacts this detector reports
  get no force. :func:`install` makes ``SolverVBD`` use epsilon 0 there (``install(None)`` keeps
  Newton's): Warp's function is safe at 0 (it divides by a squared length only when it is
  > 0, by ``a e - b^2`` only when that is > 0, takes s = 0 for exactly parallel edges and clamps
  every parameter to [0, 1], so finite input gives finite points on the edges; only zero-length
  edges are points), and 0 is scale-free, where a value relative to the mesh's edge lengths at
  construction would still drop the contacts of edges that shrink under compression. Newton's
  value stays readable as ``solver.newton_edge_edge_parallel_epsilon``.
- Device. The model's device: minkq's CPU backend for ``"cpu"``, its CUDA backend for
  ``"cuda:N"`` (positions read in place on the GPU, no host round trip; a libminkq built
  without CUDA raises :class:`~minkq.UnsupportedError`).
"""

from __future__ import annotations

import contextlib
import ctypes
import sys
import traceback
import weakref
from typing import Any, Callable, Optional, Tuple

import numpy as np
import warp as wp
from newton._src.geometry import tri_mesh_collision as _newton_tmc
from newton._src.geometry.bvh import compute_bvh_group_roots
from newton._src.geometry.kernels import (
    compute_edge_aabbs,
    compute_edge_groups,
    compute_tri_aabbs,
    compute_tri_groups,
    init_triangle_collision_data_kernel,
)

from .. import _api
from .._errors import CapacityError, UnsupportedError

__all__ = ["ReplayError", "TriMeshCollisionDetector", "capture_launch", "install", "uninstall"]

VERTEX_OVERFLOW, TRIANGLE_OVERFLOW, EDGE_OVERFLOW = 0, 1, 2  # resize_flags (Newton's indices)


# ---- Distances: float, no absolute epsilon ---------------------------------------------------


@wp.func
def _point_segment_sq(p: wp.vec3, a: wp.vec3, b: wp.vec3):
    d = b - a
    dd = wp.dot(d, d)
    t = float(0.0)
    if dd > 0.0:
        t = wp.clamp(wp.dot(p - a, d) / dd, 0.0, 1.0)
    w = p - (a + t * d)
    return wp.dot(w, w)


@wp.func
def _vertex_triangle_distance(p: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3):
    """Distance from p to triangle abc: the nearest edge, or the plane where p projects
    strictly inside. Degenerate triangles have only their edges; the normal is scaled to its
    largest component first, so no product of tiny lengths underflows."""
    best = wp.min(wp.min(_point_segment_sq(p, a, b), _point_segment_sq(p, b, c)), _point_segment_sq(p, c, a))
    n = wp.cross(b - a, c - a)
    scale = wp.max(wp.max(wp.abs(n[0]), wp.abs(n[1])), wp.abs(n[2]))
    if scale > 0.0:
        n = n / scale
        if (
            wp.dot(wp.cross(b - a, p - a), n) > 0.0
            and wp.dot(wp.cross(c - b, p - b), n) > 0.0
            and wp.dot(wp.cross(a - c, p - c), n) > 0.0
        ):
            h = wp.dot(p - a, n)
            best = wp.min(best, h * h / wp.dot(n, n))
    return wp.sqrt(best)


@wp.func
def _edge_edge_distance(p0: wp.vec3, p1: wp.vec3, q0: wp.vec3, q1: wp.vec3):
    """Distance between segments p0p1 and q0q1: the four endpoint-segment distances, and the
    closest points of the two lines (clamped, then projected once more, as in Ericson's
    algorithm) where both segments have length. Any clamped parameters name actual points of
    the segments, so ill-conditioned near-parallel cases stay within the endpoint bound."""
    best = wp.min(
        wp.min(_point_segment_sq(p0, q0, q1), _point_segment_sq(p1, q0, q1)),
        wp.min(_point_segment_sq(q0, p0, p1), _point_segment_sq(q1, p0, p1)),
    )
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = wp.dot(d1, d1)
    e = wp.dot(d2, d2)
    if a > 0.0 and e > 0.0:
        b = wp.dot(d1, d2)
        c = wp.dot(d1, r)
        f = wp.dot(d2, r)
        denom = a * e - b * b
        s = float(0.0)
        if denom > 0.0:
            s = wp.clamp((b * f - c * e) / denom, 0.0, 1.0)
        t = wp.clamp((b * s + f) / e, 0.0, 1.0)
        s = wp.clamp((b * t - c) / a, 0.0, 1.0)
        w = (p0 + s * d1) - (q0 + t * d2)
        best = wp.min(best, wp.dot(w, w))
    return wp.sqrt(best)


@wp.func
def _listed(values: wp.array(dtype=wp.int32), offsets: wp.array(dtype=wp.int32), row: int, value: int):
    """Whether the sorted row ``row`` of a CSR filter list holds ``value``."""
    lo = offsets[row]
    end = offsets[row + 1]
    hi = end
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo < end and values[lo] == value


@wp.func
def _same_world(group_a: int, group_b: int, global_group: int):
    return group_a == group_b or group_a == global_group or group_b == global_group


@wp.func
def _row_key(source: int, other: int):
    return (wp.int64(source) << wp.int64(32)) | wp.int64(other)


# ---- Graph capture on the CPU: host calls recorded as kernel launches ----------------------
#
# Warp's CPU graphs (APIC) record kernel launches, memsets and copies and replay them in C++;
# a Python call made during the capture runs once, at record time, and never again. What a
# replay does repeat is a kernel, and a CPU kernel may call a host function pointer: each
# detector method called inside a CPU capture records one launch of _host_call_kernel
# (dim 1) whose token names the method's body with its arguments, and the replay calls back
# into Python to run that body eagerly (no capture is active then) on the current data.


class ReplayError(RuntimeError):
    """A detector method recorded into a Warp CPU graph failed while the graph was replayed
    (``wp.capture_launch``); raised by the detector's next call or :meth:`check_replays`, or by
    :func:`capture_launch`, with the original exception as ``__cause__``."""


_HostCall = ctypes.CFUNCTYPE(None, ctypes.c_uint64)
# token -> (detector weakref, method name, body, arguments, vertex_positions at record time); an
# entry lives as long as the graph that recorded it.
_recorded: dict = {}
_next_token = [1]


def _dispatch(token: int) -> None:
    # Called from a Warp CPU kernel during capture_launch. Nothing may escape into C: a failure
    # is kept on the detector (and printed) for the next call to raise.
    entry = _recorded.get(token)
    if entry is None:
        return
    ref, what, body, args, positions = entry
    detector = ref()
    if detector is None:
        return
    try:
        if wp.get_device("cpu").is_capturing:
            raise RuntimeError("a graph holding minkq's detection was replayed inside another CPU graph capture")
        detector.vertex_positions = positions  # as a graph bakes its pointers
        body(detector, *args)
        detector.replayed_calls += 1
    except BaseException as error:  # noqa: BLE001 - reported, never swallowed
        detector._replay_failed(what, error)


_dispatch_pointer_keepalive = _HostCall(_dispatch)
_DISPATCH = ctypes.cast(_dispatch_pointer_keepalive, ctypes.c_void_p).value


@wp.func_native(
    """
    #if !defined(__CUDA_ARCH__)  // host code only: the module is compiled for CUDA devices too
    typedef void (*minkq_host_call)(unsigned long long);
    ((minkq_host_call)fn)(token);
    #endif
    """
)
def _call_host(fn: wp.uint64, token: wp.uint64): ...


@wp.kernel
def _host_call_kernel(fn: wp.uint64, token: wp.uint64):
    _call_host(fn, token)


def _graph_being_captured() -> Any:
    # The Graph object a CPU capture is recording into (Warp keeps it on its runtime).
    runtime = getattr(getattr(wp, "_src", None), "context", None)
    runtime = getattr(runtime, "runtime", None)
    return getattr(runtime, "_apic_graph", None)


def capture_launch(graph: Any) -> None:
    """``wp.capture_launch(graph)``, then raises :class:`ReplayError` if a minkq detector
    method recorded into a CPU graph failed during a replay (``wp.capture_launch`` itself
    cannot: the failure happens inside a kernel). Use it in place of ``wp.capture_launch``
    where a failure must stop the loop at once."""
    wp.capture_launch(graph)
    for ref, _, _, _, _ in list(_recorded.values()):
        detector = ref()
        if detector is not None:
            detector.check_replays()


# ---- Pairs to rows ---------------------------------------------------------------------------


@wp.kernel
def _vertex_triangle_pairs_kernel(
    pairs: wp.array2d(dtype=wp.int32),
    found: wp.array(dtype=wp.int64),
    pos: wp.array(dtype=wp.vec3),
    tri_indices: wp.array2d(dtype=wp.int32),
    ref_pos: wp.array(dtype=wp.vec3),
    min_query_radius: float,
    vertex_group: wp.array(dtype=wp.int32),
    tri_group: wp.array(dtype=wp.int32),
    global_group: int,
    filter_list: wp.array(dtype=wp.int32),
    filter_offsets: wp.array(dtype=wp.int32),
    use_filter: int,
    record_triangles: int,
    num_vertices: int,
    num_triangles: int,
    # outputs
    vertex_keys: wp.array(dtype=wp.int64),
    vertex_count: wp.array(dtype=wp.int32),
    vertex_min_dist: wp.array(dtype=float),
    tri_keys: wp.array(dtype=wp.int64),
    tri_count: wp.array(dtype=wp.int32),
    tri_min_dist: wp.array(dtype=float),
):
    # Slot i holds a pair if i < found[0] (the pairs found; a captured query's slots past them
    # hold none).
    i = wp.tid()
    vertex_keys[i] = _row_key(num_vertices, 0)  # dropped: sorts after every row
    if record_triangles:
        tri_keys[i] = _row_key(num_triangles, 0)
    if wp.int64(i) >= found[0]:
        return
    v = pairs[i, 0]
    t = pairs[i, 1]
    if not _same_world(vertex_group[v], tri_group[t], global_group):
        return
    if use_filter:
        if _listed(filter_list, filter_offsets, v, t):
            return
    t0 = tri_indices[t, 0]
    t1 = tri_indices[t, 1]
    t2 = tri_indices[t, 2]
    if min_query_radius > 0.0:
        if _vertex_triangle_distance(ref_pos[v], ref_pos[t0], ref_pos[t1], ref_pos[t2]) < min_query_radius:
            return
    dist = _vertex_triangle_distance(pos[v], pos[t0], pos[t1], pos[t2])
    vertex_keys[i] = _row_key(v, t)
    wp.atomic_add(vertex_count, v, 1)
    wp.atomic_min(vertex_min_dist, v, dist)
    if record_triangles:
        tri_keys[i] = _row_key(t, v)
        wp.atomic_add(tri_count, t, 1)
        wp.atomic_min(tri_min_dist, t, dist)


@wp.kernel
def _edge_edge_pairs_kernel(
    pairs: wp.array2d(dtype=wp.int32),
    found: wp.array(dtype=wp.int64),
    num_pairs: int,
    pos: wp.array(dtype=wp.vec3),
    edge_indices: wp.array2d(dtype=wp.int32),
    ref_pos: wp.array(dtype=wp.vec3),
    min_query_radius: float,
    edge_group: wp.array(dtype=wp.int32),
    global_group: int,
    filter_list: wp.array(dtype=wp.int32),
    filter_offsets: wp.array(dtype=wp.int32),
    use_filter: int,
    num_edges: int,
    # outputs
    edge_keys: wp.array(dtype=wp.int64),
    edge_count: wp.array(dtype=wp.int32),
    edge_min_dist: wp.array(dtype=float),
):
    # Pair i (e, f), e < f, goes to f's row at slot i and to e's row at slot num_pairs + i;
    # slot i holds a pair if i < found[0].
    i = wp.tid()
    dropped = _row_key(num_edges, 0)
    edge_keys[i] = dropped
    edge_keys[num_pairs + i] = dropped
    if wp.int64(i) >= found[0]:
        return
    e = pairs[i, 0]
    f = pairs[i, 1]
    if not _same_world(edge_group[e], edge_group[f], global_group):
        return
    e0 = edge_indices[e, 2]
    e1 = edge_indices[e, 3]
    f0 = edge_indices[f, 2]
    f1 = edge_indices[f, 3]
    if min_query_radius > 0.0:
        if _edge_edge_distance(ref_pos[e0], ref_pos[e1], ref_pos[f0], ref_pos[f1]) < min_query_radius:
            return
    dist = _edge_edge_distance(pos[e0], pos[e1], pos[f0], pos[f1])
    keep_in_f = True
    keep_in_e = True
    if use_filter:
        keep_in_f = not _listed(filter_list, filter_offsets, f, e)
        keep_in_e = not _listed(filter_list, filter_offsets, e, f)
    if keep_in_f:
        edge_keys[i] = _row_key(f, e)
        wp.atomic_add(edge_count, f, 1)
        wp.atomic_min(edge_min_dist, f, dist)
    if keep_in_e:
        edge_keys[num_pairs + i] = _row_key(e, f)
        wp.atomic_add(edge_count, e, 1)
        wp.atomic_min(edge_min_dist, e, dist)


@wp.kernel
def _write_rows_kernel(
    sorted_keys: wp.array(dtype=wp.int64),
    row_start: wp.array(dtype=wp.int32),
    offsets: wp.array(dtype=wp.int32),
    buffer_sizes: wp.array(dtype=wp.int32),
    capacity_from_offsets: int,
    interleaved: int,
    num_rows: int,
    flag_index: int,
    # outputs
    rows: wp.array(dtype=wp.int32),
    resize_flags: wp.array(dtype=wp.int32),
):
    # The keys are sorted: row r's pairs are entries row_start[r] ... in ascending order.
    i = wp.tid()
    key = sorted_keys[i]
    source = int(key >> wp.int64(32))
    if source >= num_rows:
        return
    other = int(key & wp.int64(0xFFFFFFFF))
    rank = i - row_start[source]
    capacity = buffer_sizes[source]
    if capacity_from_offsets:
        capacity = offsets[source + 1] - offsets[source]
    if rank < capacity:
        slot = offsets[source] + rank
        if interleaved:
            rows[2 * slot] = source
            rows[2 * slot + 1] = other
        else:
            rows[slot] = other
    else:
        resize_flags[flag_index] = 1


@wp.kernel
def _flag_lost_pairs_kernel(found: wp.array(dtype=wp.int64), capacity: int, flag_index: int,
                            resize_flags: wp.array(dtype=wp.int32)):
    # A captured query found more pairs than its buffer holds: those past it are lost, as pairs
    # past a full row are, and Newton's resize flag says so.
    if found[0] > wp.int64(capacity):
        resize_flags[flag_index] = 1


@contextlib.contextmanager
def _capture_paused(device: Any):
    """Runs the block outside a Warp graph capture in progress on ``device`` (Warp's
    ``capture_pause`` / ``capture_resume``), or as it is when none is."""
    if not getattr(device, "is_capturing", False):
        yield
        return
    from warp._src.context import capture_pause, capture_resume

    graph = capture_pause(device=device)
    try:
        yield
    finally:
        capture_resume(graph, device=device)


class _Scratch:
    """Device arrays of one pass kept between calls, grown geometrically. While ``pinned`` is a
    list (inside a CUDA graph capture) every array handed out is also kept there: a graph bakes
    their addresses, so they must outlive any later growth. An array first needed inside a
    capture is allocated with the capture paused: a graph allocation would be freed with its
    graph, and is not memory minkq's device-pointer check accepts."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self.arrays: dict = {}
        self.pinned: Optional[list] = None

    def get(self, name: str, dtype: Any, size: int, shape_tail: tuple = ()) -> wp.array:
        array = self.arrays.get(name)
        if array is None or array.shape[0] < size:
            capacity = max(size, 2 * (array.shape[0] if array is not None else 0), 16)
            with _capture_paused(self.device):
                array = wp.empty(shape=(capacity,) + shape_tail, dtype=dtype, device=self.device)
            self.arrays[name] = array
        if self.pinned is not None:
            self.pinned.append(array)
        return array


def _minkq_device_for(device: Any) -> _api.Device:
    spec = f"cuda:{device.ordinal}" if device.is_cuda else "cpu"
    try:
        return _api.Device(spec)
    except UnsupportedError as e:
        raise UnsupportedError(
            f"the Newton model is on {device} but minkq cannot use {spec}: {e.message} (build libminkq with CUDA)"
        ) from None


_NewtonDetector = _newton_tmc.TriMeshCollisionDetector  # Newton's class, whatever install() swaps


class TriMeshCollisionDetector(_NewtonDetector):
    """Newton's ``TriMeshCollisionDetector`` (newton 1.8) with minkq's VT and EE queries: same
    constructor, methods, result arrays and layout (see the module's documentation for the
    few deliberate differences). Every vertex-triangle and edge-edge pair within the query
    radius is reported, however short the edges.

    The VT pass runs minkq's ``vt_mode`` node test and the EE pass ``ee_mode``, both with
    the leaf-exact primitive test; the node test changes the speed, not the pairs (box, the
    default, is the one meant for contacts: bench/README.md).
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
            collision_info = _newton_tmc.build_tri_mesh_collision_info(
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
        self._scene = _api.Scene(self.minkq_device, self.vertex_positions, triangles, edges, vt=vt, ee=ee, drop_incident=True)
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
            self._scene.query_async(pairs, found, kind, mode, radius, leaf_exact=True)
            flag = VERTEX_OVERFLOW if kind == "vt" else EDGE_OVERFLOW
            wp.launch(_flag_lost_pairs_kernel, dim=1, inputs=[found, pairs.shape[0], flag], outputs=[self.resize_flags],
                      device=self.device)
            return pairs, found, pairs.shape[0]
        pairs = self._scratch.get(name, wp.int32, 0, (2,))
        try:
            info = self._scene.query_into(pairs, kind, mode, radius, leaf_exact=True)
        except CapacityError as e:
            pairs = self._scratch.get(name, wp.int32, e.needed + e.needed // 4, (2,))
            info = self._scene.query_into(pairs, kind, mode, radius, leaf_exact=True)
        found.fill_(info.count)
        return pairs[: info.count], found, info.count

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


# ---- Swapping it into Newton -------------------------------------------------------------------

_PATCHED = (
    "newton._src.solvers.vbd.solver_vbd",
    "newton._src.sim.collide",
    "newton._src.solvers.vbd.tri_mesh_collision",  # the VBD package's name for the class (Newton's tests use it)
)
_originals: dict = {}
_SOLVER_EPSILON_ATTRIBUTE = "_self_contact_edge_edge_parallel_epsilon"  # SolverVBD's, read by its force kernels


def _solver_vbd_class() -> Any:
    from newton._src.solvers.vbd.solver_vbd import SolverVBD

    return SolverVBD


def _patch_solver_epsilon(epsilon: Optional[float]) -> None:
    """Wraps ``SolverVBD._init_particle_system`` (where Newton stores
    ``particle_edge_parallel_epsilon`` for its self-contact force kernels) so that solvers built
    from now on use ``epsilon`` there; Newton's value stays readable as
    ``solver.newton_edge_edge_parallel_epsilon``."""
    solver = _solver_vbd_class()
    original = _originals.setdefault("SolverVBD._init_particle_system", solver.__dict__["_init_particle_system"])
    if epsilon is None:
        solver._init_particle_system = original
        return
    value = float(epsilon)

    def _init_particle_system(self, *args, **kwargs):
        original(self, *args, **kwargs)
        if _SOLVER_EPSILON_ATTRIBUTE in self.__dict__:  # self-contact on
            self.newton_edge_edge_parallel_epsilon = self.__dict__[_SOLVER_EPSILON_ATTRIBUTE]
            setattr(self, _SOLVER_EPSILON_ATTRIBUTE, value)

    _init_particle_system.__wrapped__ = original
    _init_particle_system.__doc__ = original.__doc__
    solver._init_particle_system = _init_particle_system


def install(edge_edge_parallel_epsilon: Optional[float] = 0.0) -> None:
    """Makes Newton's ``SolverVBD`` and ``CollisionPipeline`` (soft self-contact) construct this
    detector instead of their own, and makes ``SolverVBD``'s self-contact force kernels evaluate
    every edge-edge contact the detector reports: solvers built from now on pass
    ``edge_edge_parallel_epsilon`` (default 0: see the module's documentation) to Warp's
    ``closest_point_edge_edge`` instead of their ``particle_edge_parallel_epsilon`` (None keeps
    Newton's). :func:`uninstall` undoes both. Call it before creating the solver or pipeline;
    calling it again replaces the epsilon."""
    import importlib

    for name in _PATCHED:
        module = importlib.import_module(name)
        _originals.setdefault(name, module.TriMeshCollisionDetector)
        module.TriMeshCollisionDetector = TriMeshCollisionDetector
    _patch_solver_epsilon(edge_edge_parallel_epsilon)


def uninstall() -> None:
    """Restores Newton's own detector and ``SolverVBD``'s epsilon handling where :func:`install`
    replaced them (solvers already built keep what they were built with)."""
    import importlib

    for name, original in list(_originals.items()):
        if name == "SolverVBD._init_particle_system":
            _solver_vbd_class()._init_particle_system = original
        else:
            importlib.import_module(name).TriMeshCollisionDetector = original
        del _originals[name]
