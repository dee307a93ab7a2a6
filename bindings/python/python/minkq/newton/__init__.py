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

Cloth against body meshes. :class:`ClothBodyContacts` finds the contacts between a model's
cloth and the mesh shapes of its bodies (vertex-triangle both ways and edge-edge, every pair
within ``radius`` plus the particle radius and the shape margin) from one minkq scene of many
geometries, beside Newton's soft contacts (one closest point per particle and shape)::

    contacts = ClothBodyContacts(model)            # the cloth, and every mesh shape colliding with particles
    contacts.update(state)                         # particle_q, and body_q for the shapes on bodies
    pairs = contacts.detect(soft_contact_gap)      # pairs.vertex_triangle, .triangle_vertex, .edge_edge
"""


# The package's parts, by concern: _body_contacts (cloth against the model's body meshes), _compat (the only module that imports Newton's and Warp's
# private modules), _kernels (Warp functions and kernels), _capture (Warp graph capture: host
# calls replayed by CPU graphs, paused captures, pass buffers), _detector (the detector class)
# and _install (install / uninstall). The names used from outside them (the
# tests, minkq.newton.examples) are re-exported here.

import warp as wp  # noqa: F401 - minkq.newton.wp (the tests patch Warp through it)

from ._body_contacts import ClothBodyContacts, ClothBodyPairs
from ._capture import ReplayError, capture_launch
from ._capture import _capture_paused, _graph_being_captured, _recorded, _Scratch  # noqa: F401 - used by the tests
from ._detector import TriMeshCollisionDetector
from ._detector import EDGE_OVERFLOW, TRIANGLE_OVERFLOW, VERTEX_OVERFLOW, _minkq_device_for  # noqa: F401 - used by the tests
from ._install import install, uninstall

__all__ = [
    "ClothBodyContacts",
    "ClothBodyPairs",
    "ReplayError",
    "TriMeshCollisionDetector",
    "capture_launch",
    "install",
    "uninstall",
]
