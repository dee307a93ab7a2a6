"""minkq.newton's Warp functions and kernels: float distances without an absolute epsilon,
the filter-list and world tests, and the kernels that turn minkq's pairs into Newton's rows
(see the package's documentation)."""

from __future__ import annotations

import warp as wp


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
