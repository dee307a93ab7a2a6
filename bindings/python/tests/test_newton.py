"""minkq.newton.TriMeshCollisionDetector against Newton's own detector (newton 1.8) and a
double-precision oracle, on Newton's cloth scenes (data/meshes.tar.xz) and on a fine twisted sheet
whose short edges make Newton lose about half of its edge-edge contacts.

"Where Newton is right" means: every pair on which the two detectors differ is either a true
contact (oracle) that Newton misses, or a pair within 1e-5 r of the radius, where a float
distance and minkq's leaf-exact bound (within r + 2**-19 S) may decide either way."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

wp = pytest.importorskip("warp")
pytest.importorskip("newton")

wp.config.quiet = True

import minkq  # noqa: E402
import minkq.newton as mn  # noqa: E402
import newton_scenes as ns  # noqa: E402
from newton._src.geometry import tri_mesh_collision as _newton_tmc  # noqa: E402
from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector as NewtonDetector  # noqa: E402

# Buffers large enough for every row of the comparison scenes (overflow has its own test).
ROOMY = dict(vertex_collision_buffer_pre_alloc=256, edge_collision_buffer_pre_alloc=512)


@dataclass
class Rows:
    """One detection's results, read back from Newton's layout."""

    vt: np.ndarray  # (vertex << 32 | triangle), as stored
    ee: np.ndarray  # (edge << 32 | other edge), as stored: both directions
    vt_count: np.ndarray
    ee_count: np.ndarray
    vt_stored: np.ndarray
    ee_stored: np.ndarray
    vt_min: np.ndarray
    ee_min: np.ndarray
    tri_min: np.ndarray
    flags: np.ndarray

    @property
    def ee_pairs(self) -> np.ndarray:
        return ns.unordered(self.ee)


def read(detector) -> Rows:
    vt, vt_count, vt_stored = ns.rows(
        detector.vertex_colliding_triangles,
        detector.vertex_colliding_triangles_offsets,
        detector.vertex_colliding_triangles_count,
        detector.vertex_colliding_triangles_buffer_sizes,
    )
    ee, ee_count, ee_stored = ns.rows(
        detector.edge_colliding_edges,
        detector.edge_colliding_edges_offsets,
        detector.edge_colliding_edges_count,
        detector.edge_colliding_edges_buffer_sizes,
    )
    return Rows(
        vt, ee, vt_count, ee_count, vt_stored, ee_stored,
        detector.vertex_colliding_triangles_min_dist.numpy(),
        detector.edge_colliding_edges_min_dist.numpy(),
        detector.triangle_colliding_vertices_min_dist.numpy(),
        detector.resize_flags.numpy().copy(),
    )


def detect(cls, model, r, refit=True, **kwargs) -> Rows:
    detector = cls(model, init_collision_info=True, **kwargs)
    if refit:
        detector.refit(model.particle_q)
    detector.vertex_triangle_collision_detection(r)
    detector.edge_edge_collision_detection(r)
    return read(detector)


def subset(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.isin(a, b).all())


def tolerance(xyz: np.ndarray, r: float) -> float:
    """Float distances from float coordinates: a few ulps of the coordinates, and of r."""
    return 4e-7 * float(np.abs(xyz).max()) + 1e-5 * r


def truths(model, r):
    xyz = model.particle_q.numpy()
    world = model.particle_world.numpy()
    edges = model.edge_indices.numpy()[:, 2:4].copy()
    return ns.vt_truth(xyz, model.tri_indices.numpy(), r, world), ns.ee_truth(xyz, edges, r, world)


def check_against_oracle(rows: Rows, vt_truth: ns.Truth, ee_truth: ns.Truth, model, r: float) -> None:
    """Every true contact, nothing beyond the boundary band, rows symmetric for EE, counts and
    minimum distances right."""
    for name, found, truth in (("VT", rows.vt, vt_truth), ("EE", rows.ee_pairs, ee_truth)):
        missing = np.setdiff1d(truth.within(r), found)
        assert len(missing) == 0, f"{name}: {len(missing)} true contacts missing, e.g. {missing[:3] >> 32}, {missing[:3] & 0xFFFFFFFF}"
        extra = np.setdiff1d(found, truth.within(r))
        assert subset(extra, truth.band(r)), f"{name}: pairs beyond r"
    # Each EE contact in both edges' rows; counts are the rows' lengths (no overflow here).
    e, f = rows.ee_pairs >> 32, rows.ee_pairs & 0xFFFFFFFF
    assert np.array_equal(np.sort(rows.ee), np.sort(np.concatenate([e << 32 | f, f << 32 | e])))
    assert np.array_equal(rows.vt_count, np.bincount(rows.vt >> 32, minlength=model.particle_count))
    assert np.array_equal(rows.ee_count, np.bincount(rows.ee >> 32, minlength=model.edge_count))
    assert not rows.flags.any()
    xyz = model.particle_q.numpy()
    tol = tolerance(xyz, r)
    vt_min = ns.min_dist(vt_truth.within(r), vt_truth.dist[vt_truth.dist <= r], model.particle_count, r)
    ee_min = ns.min_dist(ee_truth.within(r), ee_truth.dist[ee_truth.dist <= r], model.edge_count, r, both=True)
    assert np.abs(rows.vt_min - vt_min).max(initial=0) <= tol
    assert np.abs(rows.ee_min - ee_min).max(initial=0) <= tol
    assert np.all(rows.tri_min == np.float32(r))


def check_against_newton(ours: Rows, theirs: Rows, vt_truth: ns.Truth, ee_truth: ns.Truth, model, r: float) -> dict:
    """The sets equal Newton's except for true contacts Newton misses and boundary pairs; the
    minimum distances equal Newton's on every row Newton gets complete. Returns the counts."""
    report = {}
    tol = tolerance(model.particle_q.numpy(), r)
    for name, a, n, truth in (("vt", ours.vt, theirs.vt, vt_truth), ("ee", ours.ee_pairs, theirs.ee_pairs, ee_truth)):
        band = truth.band(r)
        only_newton = np.setdiff1d(n, a)
        assert subset(only_newton, band), f"{name}: Newton reports pairs minkq does not, away from the boundary"
        newton_misses = np.setdiff1d(np.setdiff1d(truth.within(r), n), band)
        only_ours = np.setdiff1d(np.setdiff1d(a, n), band)
        assert np.array_equal(only_ours, newton_misses), f"{name}: differences other than Newton's misses"
        report[name] = (len(truth.within(r)), len(n), len(a))
        # Rows Newton gets complete hold the same minimum distance.
        rows_of = (lambda k: k >> 32) if name == "vt" else (lambda k: np.concatenate([k >> 32, k & 0xFFFFFFFF]))
        count = model.particle_count if name == "vt" else model.edge_count
        complete = np.ones(count, bool)
        complete[rows_of(np.setdiff1d(truth.within(r), n))] = False
        ours_min, theirs_min = (ours.vt_min, theirs.vt_min) if name == "vt" else (ours.ee_min, theirs.ee_min)
        assert np.abs(ours_min - theirs_min)[complete].max(initial=0) <= tol, name
    return report


@pytest.fixture(scope="module")
def built():
    """name -> (scene, model, VT truth, EE truth), built once."""
    cache = {}

    def get(name):
        if name not in cache:
            scene = ns.scenes()[name]()
            model = ns.cloth_model(scene.meshes, worlds=scene.worlds)
            cache[name] = (scene, model) + truths(model, scene.radius)
        return cache[name]

    return get


@pytest.mark.parametrize("name", list(ns.scenes()))
def test_newton_scene_pairs_equal_newtons_where_newton_is_right(built, name, capsys):
    scene, model, vt_truth, ee_truth = built(name)
    r = scene.radius
    ours = detect(mn.TriMeshCollisionDetector, model, r, **ROOMY)
    theirs = detect(NewtonDetector, model, r, **ROOMY)
    check_against_oracle(ours, vt_truth, ee_truth, model, r)
    report = check_against_newton(ours, theirs, vt_truth, ee_truth, model, r)
    if scene.worlds is not None:
        # The worlds overlap in space: without Newton's world rule there would be more pairs.
        everywhere = ns.vt_truth(model.particle_q.numpy(), model.tri_indices.numpy(), r)
        assert len(everywhere.within(r)) > len(vt_truth.within(r))
    with capsys.disabled():
        print(
            f"\n  {scene.name}: r {r:.4g}; VT oracle/Newton/minkq {report['vt'][0]}/{report['vt'][1]}/{report['vt'][2]}; "
            f"EE {report['ee'][0]}/{report['ee'][1]}/{report['ee'][2]}",
            end="",
        )


def test_fine_sheet_finds_every_contact_newtons_epsilon_loses(capsys):
    """A 500 x 500 grid on the unit square twisted three turns (edges across the sheet
    ~2e-3 long, under the 3.2e-3 that Newton's edge_edge_parallel_epsilon = 1e-5 turns into
    points), r = 0.25 x the mean edge: minkq's rows hold every contact of the oracle."""
    from minkq.demo import derive_edges, mean_edge_length

    xyz, tris = ns.fine_sheet(500)
    r = float(np.float32(0.25 * mean_edge_length(xyz, derive_edges(tris))))
    model = ns.cloth_model([(xyz, tris)])
    vt_truth, ee_truth = truths(model, r)
    ours = detect(mn.TriMeshCollisionDetector, model, r)
    theirs = detect(NewtonDetector, model, r)
    check_against_oracle(ours, vt_truth, ee_truth, model, r)
    report = check_against_newton(ours, theirs, vt_truth, ee_truth, model, r)
    true_ee, newton_ee, minkq_ee = report["ee"]
    with capsys.disabled():
        print(
            f"\n  fine sheet 500x500, 3 turns, r {r:.4g}: EE contacts oracle {true_ee}, Newton {newton_ee} "
            f"({100 * (1 - newton_ee / true_ee):.1f}% lost, resize flags {theirs.flags.tolist()}), minkq {minkq_ee}; "
            f"VT oracle/Newton/minkq {report['vt'][0]}/{report['vt'][1]}/{report['vt'][2]}",
            end="",
        )
    assert minkq_ee == true_ee and not theirs.flags.any()
    assert newton_ee < 0.75 * true_ee, "the scene no longer shows Newton's loss"


def test_refit_after_moving_vertices_equals_a_fresh_detector(built):
    scene, model, _, _ = built("cloth_hanging")
    r = scene.radius
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, **ROOMY)
    rest = model.particle_q.numpy()
    for step, squash in enumerate((0.97, 0.94, 0.9)):
        moved = rest.copy()
        moved[:, 0] *= squash  # the roll tightens: contacts come and go
        moved[:, 2] *= squash
        moved[:, 1] += 0.01 * step
        positions = wp.array(moved, dtype=wp.vec3, device=model.device)
        detector.refit(positions)
        detector.vertex_triangle_collision_detection(r)
        detector.edge_edge_collision_detection(r)
        refitted = read(detector)
        model.particle_q.assign(positions)
        try:
            fresh = detect(mn.TriMeshCollisionDetector, model, r, refit=False, **ROOMY)
            vt_truth, ee_truth = truths(model, r)
            check_against_oracle(refitted, vt_truth, ee_truth, model, r)
        finally:
            model.particle_q.assign(rest)
        assert np.array_equal(refitted.vt, fresh.vt) and np.array_equal(refitted.ee, fresh.ee)
    # rebuild from new positions equals the refit.
    detector.rebuild(positions)
    detector.vertex_triangle_collision_detection(r)
    detector.edge_edge_collision_detection(r)
    rebuilt = read(detector)
    assert np.array_equal(rebuilt.vt, refitted.vt) and np.array_equal(rebuilt.ee, refitted.ee)


def test_overflowing_rows_keep_counts_and_set_the_resize_flags(built):
    """Rows too small: counts still count every pair, each row keeps its lowest-numbered
    pairs, the unused slots stay -1 and resize_flags [0] (vertices) and [2] (edges) are set,
    as Newton does; Newton's counts are the same."""
    scene, model, _, _ = built("cloth_hanging")
    r = scene.radius
    small = dict(vertex_collision_buffer_pre_alloc=3, edge_collision_buffer_pre_alloc=5)
    full = detect(mn.TriMeshCollisionDetector, model, r, **ROOMY)
    cut = detect(mn.TriMeshCollisionDetector, model, r, **small)
    newton_cut = detect(NewtonDetector, model, r, **small)
    assert cut.flags.tolist() == [1, 0, 1, 0] == newton_cut.flags.tolist()
    assert np.array_equal(cut.vt_count, full.vt_count) and np.array_equal(cut.ee_count, full.ee_count)
    assert np.array_equal(cut.vt_count, newton_cut.vt_count) and np.array_equal(cut.ee_count, newton_cut.ee_count)
    assert np.array_equal(cut.vt_stored, np.minimum(full.vt_count, 3))
    assert np.array_equal(cut.ee_stored, np.minimum(full.ee_count, 5))
    assert (full.vt_count > 3).any() and (full.ee_count > 5).any()
    for stored, everything, keep in ((cut.vt, full.vt, 3), (cut.ee, full.ee, 5)):
        # The first `keep` of every sorted row.
        rows_all = everything >> 32
        rank = np.arange(len(everything)) - np.searchsorted(rows_all, rows_all)
        assert np.array_equal(stored, everything[rank < keep])
    # The minimum distances count every pair, stored or not.
    assert np.array_equal(cut.vt_min, full.vt_min) and np.array_equal(cut.ee_min, full.ee_min)
    # Flags stay set until the caller clears them (as in Newton), and then stay clear.
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, **small)
    detector.vertex_triangle_collision_detection(r)
    assert detector.resize_flags.numpy().tolist() == [1, 0, 0, 0]
    detector.vertex_triangle_collision_detection(0.0)
    assert detector.resize_flags.numpy().tolist() == [1, 0, 0, 0]
    detector.resize_flags.zero_()
    detector.vertex_triangle_collision_detection(0.0)
    assert not detector.resize_flags.numpy().any()


def test_triangle_rows_when_recording_triangle_contacting_vertices(built):
    scene, model, _, _ = built("cloth_poker_cards")
    r = scene.radius
    results = {}
    for cls in (mn.TriMeshCollisionDetector, NewtonDetector):
        detector = cls(model, init_collision_info=True, record_triangle_contacting_vertices=True, **ROOMY)
        detector.vertex_triangle_collision_detection(r)
        detector.edge_edge_collision_detection(r)
        tv, tv_count, _ = ns.rows(
            detector.triangle_colliding_vertices,
            detector.triangle_colliding_vertices_offsets,
            detector.triangle_colliding_vertices_count,
            detector.triangle_colliding_vertices_buffer_sizes,
            interleaved=False,
        )
        results[cls] = (read(detector), tv, tv_count, detector.triangle_colliding_vertices_min_dist.numpy())
    ours, tv, tv_count, tri_min = results[mn.TriMeshCollisionDetector]
    # The triangle rows are the vertex rows transposed, each sorted.
    v, t = ours.vt >> 32, ours.vt & 0xFFFFFFFF
    assert np.array_equal(tv, np.sort(t << 32 | v))
    assert np.array_equal(tv_count, np.bincount(t, minlength=model.tri_count))
    theirs = results[NewtonDetector]
    assert np.array_equal(np.sort(theirs[1]), tv) and np.array_equal(theirs[2], tv_count)
    assert np.abs(theirs[3] - tri_min).max() <= tolerance(model.particle_q.numpy(), r)
    assert (tri_min < r).any()


def test_filters_and_rest_shape_exclusion_as_newton(built):
    """The topological filter (2-ring), an external map and min_query_radius with reference
    positions drop the same pairs as in Newton."""
    scene, model, vt_truth, ee_truth = built("cloth_rollers")
    r = scene.radius
    kwargs = dict(ROOMY, topological_contact_filter_threshold=2, external_vertex_triangle_filtering_map={0: {5, 7}})
    results = {}
    for cls in (mn.TriMeshCollisionDetector, NewtonDetector):
        detector = cls(model, init_collision_info=True, **kwargs)
        detector.vertex_triangle_collision_detection(r, min_query_radius=0.3, min_distance_filtering_ref_pos=model.particle_q)
        detector.edge_edge_collision_detection(r, min_query_radius=0.3, min_distance_filtering_ref_pos=model.particle_q)
        results[cls] = (read(detector), detector)
    ours, detector = results[mn.TriMeshCollisionDetector]
    theirs, _ = results[NewtonDetector]
    # Expected: the oracle's pairs in [0.3, r], minus the filter lists' pairs.
    vt_list = detector.vertex_triangle_filtering_list.numpy()
    vt_offsets = detector.vertex_triangle_filtering_list_offsets.numpy()
    listed_vt = np.repeat(np.arange(model.particle_count), np.diff(vt_offsets)).astype(np.int64) << 32 | vt_list
    kept = vt_truth.keys[(vt_truth.dist <= r) & (vt_truth.dist >= 0.3)]
    expected_vt = np.setdiff1d(kept, listed_vt)
    band = np.concatenate([vt_truth.band(r), vt_truth.band(0.3)])
    assert np.array_equal(np.setdiff1d(ours.vt, band), np.setdiff1d(expected_vt, band))
    assert np.array_equal(np.setdiff1d(ours.vt, band), np.setdiff1d(theirs.vt, band))
    ee_list = detector.edge_filtering_list.numpy()
    ee_offsets = detector.edge_filtering_list_offsets.numpy()
    listed_ee = np.repeat(np.arange(model.edge_count), np.diff(ee_offsets)).astype(np.int64) << 32 | ee_list
    assert not np.isin(ours.ee, listed_ee).any()
    assert len(np.setdiff1d(theirs.ee, ours.ee)) == 0 or subset(
        ns.unordered(np.setdiff1d(theirs.ee, ours.ee)), np.concatenate([ee_truth.band(r), ee_truth.band(0.3)])
    )
    assert len(ours.vt) < len(vt_truth.within(r)) and len(ours.ee) > 0


def test_result_struct_and_attributes_are_newtons(built):
    scene, model, _, _ = built("cloth_bending")
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True)
    assert isinstance(detector, NewtonDetector)
    assert detector.collision_info._cls is _newton_tmc.TriMeshCollisionInfo  # Newton's wp.struct
    assert detector.get_collision_data() is detector.collision_info
    assert detector.edge_edge_parallel_epsilon == 1e-5 and detector.minkq_device.backend == "cpu"
    assert "bvh_tris" not in detector.__dict__  # Newton's Warp BVHs: not built until read
    with pytest.raises(AttributeError, match="has no attribute 'bvh_nothing'"):
        detector.bvh_nothing
    with pytest.raises(ValueError, match="no result buffers"):
        mn.TriMeshCollisionDetector(model).vertex_triangle_collision_detection(0.1)
    with pytest.raises(ValueError, match="either collision_info or init_collision_info"):
        mn.TriMeshCollisionDetector(model, collision_info=detector.collision_info, init_collision_info=True)
    # Results bound later, as CollisionPipeline does.
    late = mn.TriMeshCollisionDetector(model)
    late._bind_external_buffers(detector.collision_info)
    late.vertex_triangle_collision_detection(scene.radius)
    # Inside a Warp graph capture on the CPU the call is recorded, not run (test_newton_capture.py).
    with wp.ScopedCapture(device=model.device) as capture:
        detector.edge_edge_collision_detection(scene.radius)
    assert detector.replayed_calls == 0
    wp.capture_launch(capture.graph)
    assert detector.replayed_calls == 1 and detector.replay_failures == 0
    # Triangle-triangle intersections: Newton's kernel over a Warp BVH built for the call.
    detector.triangle_triangle_intersection_detection()
    assert not detector.triangle_intersecting_triangles_count.numpy().any()


def test_warp_bvhs_are_built_when_read_and_follow_refit_and_rebuild(built):
    """bvh_tris / bvh_edges, their bounds, groups and group roots equal Newton's detector's at
    first access, after a refit to moved vertices and after a rebuild; queried with Warp they
    find the same triangles."""
    scene, model, _, _ = built("cloth_bending")
    ours = mn.TriMeshCollisionDetector(model, init_collision_info=True)
    theirs = NewtonDetector(model, init_collision_info=True)
    names = ("lower_bounds_tris", "upper_bounds_tris", "tri_groups", "bvh_tris_group_roots",
             "lower_bounds_edges", "upper_bounds_edges", "edge_groups", "bvh_edges_group_roots")

    def same():
        for name in names:
            assert np.array_equal(getattr(ours, name).numpy(), getattr(theirs, name).numpy()), name
        assert isinstance(ours.bvh_tris, wp.Bvh) and isinstance(ours.bvh_edges, wp.Bvh)

    same()
    moved = wp.array(model.particle_q.numpy() * np.float32(1.25) + np.float32(0.1), dtype=wp.vec3, device=model.device)
    ours.refit(moved)
    theirs.refit(moved)
    same()
    ours.rebuild(model.particle_q)
    theirs.rebuild(model.particle_q)
    same()

    @wp.kernel
    def count_hits(bvh: wp.uint64, lower: wp.vec3, upper: wp.vec3, hits: wp.array(dtype=wp.int32)):
        query = wp.bvh_query_aabb(bvh, lower, upper)
        index = int(0)
        while wp.bvh_query_next(query, index):
            wp.atomic_add(hits, 0, 1)

    lo, hi = model.particle_q.numpy().min(axis=0), model.particle_q.numpy().max(axis=0)
    box = (wp.vec3(*lo), wp.vec3(*(lo + 0.5 * (hi - lo))))
    counts = []
    for detector in (ours, theirs):
        hits = wp.zeros(1, dtype=wp.int32, device=model.device)
        wp.launch(count_hits, dim=1, inputs=[detector.bvh_tris.id, box[0], box[1], hits], device=model.device)
        counts.append(int(hits.numpy()[0]))
    assert counts[0] == counts[1] > 0


def test_install_swaps_the_detector_into_newton():
    import newton._src.sim.collide as collide
    import newton._src.solvers.vbd.solver_vbd as solver_vbd

    before = solver_vbd.TriMeshCollisionDetector
    mn.install()
    try:
        assert solver_vbd.TriMeshCollisionDetector is mn.TriMeshCollisionDetector
        assert collide.TriMeshCollisionDetector is mn.TriMeshCollisionDetector
    finally:
        mn.uninstall()
    assert solver_vbd.TriMeshCollisionDetector is before is NewtonDetector


def test_model_on_a_gpu_needs_a_cuda_minkq():
    if minkq.cuda_device_count() > 0:
        pytest.skip("a CUDA device is present: covered by the gpu tests")
    assert mn._minkq_device_for(wp.get_device("cpu")).backend == "cpu"


@pytest.mark.gpu
def test_cuda_model_detects_on_the_gpu_in_place():
    """On a CUDA model the positions are read on the GPU (DLPack, no host copy) and the rows
    equal those of the CPU model."""
    if minkq.cuda_device_count() == 0 or not wp.is_cuda_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")
    scene = ns.scenes()["cloth_poker_cards"]()
    cpu = detect(mn.TriMeshCollisionDetector, ns.cloth_model(scene.meshes), scene.radius, **ROOMY)
    model = ns.cloth_model(scene.meshes, device="cuda:0")
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, **ROOMY)
    assert detector.minkq_device.backend == "cuda"
    stream = wp.Stream("cuda:0")
    with wp.ScopedStream(stream):  # positions produced on another stream than the default
        moved = wp.clone(model.particle_q)
        detector.refit(moved)
        detector.vertex_triangle_collision_detection(scene.radius)
        detector.edge_edge_collision_detection(scene.radius)
    gpu = read(detector)
    assert np.array_equal(gpu.vt, cpu.vt) and np.array_equal(gpu.ee, cpu.ee)
    assert np.abs(gpu.vt_min - cpu.vt_min).max() <= 1e-6


def test_solver_vbd_steps_with_minkqs_detector_as_with_newtons():
    """install() makes SolverVBD build minkq's detector; a few self-contact steps of a rolled
    cloth end where Newton's own detector leads (this cloth's edges are long: Newton loses no
    pair here), up to the order in which contacts are summed."""
    xyz, tris = ns.grid(20, 20, 0.05, 0.05)
    xyz = ns.roll(xyz, 1.5, 0.012)  # layers within the query radius 0.015

    def simulate():
        builder = __import__("newton").ModelBuilder(gravity=(0.0, 0.0, -9.8))
        builder.add_cloth_mesh(
            pos=wp.vec3(0.0, 0.0, 1.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
            vertices=xyz, indices=tris.reshape(-1), density=0.2, tri_ke=1e3, tri_ka=1e3, tri_kd=2e-4,
            edge_ke=1e-3, edge_kd=1e-2,
        )
        builder.color()
        model = builder.finalize(device="cpu")
        solver = __import__("newton").solvers.SolverVBD(
            model, iterations=5, particle_enable_self_contact=True, particle_self_contact_margin=0.01,
            particle_self_contact_gap=0.005,
        )
        state, next_state, control = model.state(), model.state(), model.control()
        for _ in range(5):
            state.clear_forces()
            solver.step(state, next_state, control, None, 1.0 / 600)
            state, next_state = next_state, state
        detector = solver.trimesh_collision_detector
        contacts = int(detector.edge_colliding_edges_count.numpy().sum() + detector.vertex_colliding_triangles_count.numpy().sum())
        return type(detector), contacts, state.particle_q.numpy()

    newton_type, newton_contacts, newton_q = simulate()
    mn.install()
    try:
        minkq_type, minkq_contacts, minkq_q = simulate()
    finally:
        mn.uninstall()
    assert newton_type is NewtonDetector and minkq_type is mn.TriMeshCollisionDetector
    assert minkq_contacts == newton_contacts > 0
    assert np.isfinite(minkq_q).all()
    assert np.allclose(minkq_q, newton_q, atol=1e-5)
