"""minkq.newton inside Warp graph captures on the CPU, Newton's own cloth examples and collision
tests with install() applied, the example runner, and the scale-free edge-edge evaluation that
install() gives SolverVBD.

Tests marked slow (Newton examples that take minutes on two cores) run only with
MINKQ_SLOW_TESTS=1."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

wp = pytest.importorskip("warp")
newton = pytest.importorskip("newton")

wp.config.quiet = True

import minkq.newton as mn  # noqa: E402
import newton_scenes as ns  # noqa: E402
from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector as NewtonDetector  # noqa: E402
from test_newton import ROOMY, read  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
slow = pytest.mark.skipif(os.environ.get("MINKQ_SLOW_TESTS") != "1", reason="slow (minutes): set MINKQ_SLOW_TESTS=1")


def _same(a, b) -> None:
    assert np.array_equal(a.vt, b.vt) and np.array_equal(a.ee, b.ee)
    assert np.array_equal(a.vt_count, b.vt_count) and np.array_equal(a.ee_count, b.ee_count)
    assert np.array_equal(a.vt_min, b.vt_min) and np.array_equal(a.ee_min, b.ee_min)
    assert np.array_equal(a.tri_min, b.tri_min) and np.array_equal(a.flags, b.flags)


def _squashed(rest: np.ndarray, step: int) -> np.ndarray:
    moved = rest.copy()
    squash = (0.97, 0.94, 0.9, 0.88)[step]
    moved[:, 0] *= squash  # the roll tightens: contacts come and go
    moved[:, 2] *= squash
    moved[:, 1] += 0.01 * step
    return moved


def _eager(model, positions, r, rebuild=False, **kwargs):
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions, **kwargs)
    (detector.rebuild if rebuild else detector.refit)(positions)
    detector.vertex_triangle_collision_detection(r)
    detector.edge_edge_collision_detection(r)
    return read(detector)


# ---- CPU graph capture ---------------------------------------------------------------------------


def _needs_cuda(device: str) -> None:
    import minkq

    if device != "cpu" and (minkq.cuda_device_count() == 0 or not wp.is_cuda_available()):
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")


@pytest.mark.parametrize("device", ["cpu", pytest.param("cuda:0", marks=pytest.mark.gpu)])
@pytest.mark.parametrize("update", ["refit", "rebuild"])
def test_captured_detection_replays_on_moved_vertices_as_eager(update, device):
    """refit (or rebuild) + VT + EE recorded once; every replay on new positions (written into
    the array the graph was recorded with) gives the rows, counts, minimum distances and flags
    of an eager detector on the same positions. On the CPU the replays call the recorded
    bodies back; on CUDA the graph holds only device work (minkq's stream-ordered calls and
    Warp's kernels on the capture stream) and nothing runs on the host."""
    _needs_cuda(device)
    scene = ns.scenes()["cloth_hanging"]()
    model = ns.cloth_model(scene.meshes, device=device)
    r = scene.radius
    small = dict(vertex_collision_buffer_pre_alloc=8, edge_collision_buffer_pre_alloc=16)  # rows overflow too
    for kwargs in (ROOMY, small):
        positions = wp.clone(model.particle_q)
        detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions, **kwargs)
        with wp.ScopedCapture(device=model.device) as capture:
            getattr(detector, update)(positions)
            detector.vertex_triangle_collision_detection(r)
            detector.edge_edge_collision_detection(r)
        # Recorded, not run: nothing was written yet.
        assert not detector.vertex_colliding_triangles_count.numpy().any()
        assert detector.replayed_calls == 0
        rest = model.particle_q.numpy()
        seen = []
        for step in range(4):
            positions.assign(_squashed(rest, step))
            detector.resize_flags.zero_()
            (mn.capture_launch if device == "cpu" else wp.capture_launch)(capture.graph)
            replayed = read(detector)
            _same(replayed, _eager(model, positions, r, rebuild=update == "rebuild", **kwargs))
            seen.append(int(replayed.vt_count.sum() + replayed.ee_count.sum()))
        assert detector.replayed_calls == (12 if device == "cpu" else 0) and detector.replay_failures == 0
        assert len(set(seen)) == len(seen) and min(seen) > 0, seen  # the contacts changed at every step
        if kwargs is small:
            assert replayed.flags.any()


def test_capture_inside_a_newton_solver_step_graph():
    """SolverVBD with self-contact (install()) recorded into a CPU graph and replayed: the states
    equal those of the same steps run eagerly."""
    xyz, tris = ns.grid(16, 16, 0.05, 0.05)
    xyz = ns.roll(xyz, 1.5, 0.012)

    def make():
        builder = newton.ModelBuilder(gravity=(0.0, 0.0, -9.8))
        builder.add_cloth_mesh(
            pos=wp.vec3(0.0, 0.0, 1.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
            vertices=xyz, indices=tris.reshape(-1), density=0.2, tri_ke=1e3, tri_ka=1e3, tri_kd=2e-4,
        )
        builder.color()
        model = builder.finalize(device="cpu")
        solver = newton.solvers.SolverVBD(
            model, iterations=3, particle_enable_self_contact=True, particle_self_contact_margin=0.01,
            particle_self_contact_gap=0.005,
        )
        return model, solver, model.state(), model.state(), model.control()

    def two_steps(solver, s0, s1, control):
        for _ in range(2):
            s0.clear_forces()
            solver.step(s0, s1, control, None, 1.0 / 600)
            s0, s1 = s1, s0

    mn.install()
    try:
        model, solver, s0, s1, control = make()
        detector = solver.trimesh_collision_detector
        assert type(detector) is mn.TriMeshCollisionDetector
        with wp.ScopedCapture(device="cpu") as capture:
            two_steps(solver, s0, s1, control)
        for _ in range(3):
            mn.capture_launch(capture.graph)
        captured = s0.particle_q.numpy()
        contacts = int(detector.vertex_colliding_triangles_count.numpy().sum() + detector.edge_colliding_edges_count.numpy().sum())
        assert detector.replayed_calls > 0 and detector.replay_failures == 0
        _, solver, s0, s1, control = make()
        for _ in range(3):
            two_steps(solver, s0, s1, control)
        eager_detector = solver.trimesh_collision_detector
        eager_contacts = int(eager_detector.vertex_colliding_triangles_count.numpy().sum() + eager_detector.edge_colliding_edges_count.numpy().sum())
    finally:
        mn.uninstall()
    assert contacts == eager_contacts > 0
    assert np.isfinite(captured).all() and np.array_equal(captured, s0.particle_q.numpy())


def test_warp_bvhs_first_read_inside_a_capture_follow_the_replays():
    scene = ns.scenes()["cloth_bending"]()
    model = ns.cloth_model(scene.meshes)
    positions = wp.clone(model.particle_q)
    ours = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions)
    with wp.ScopedCapture(device="cpu") as capture:
        ours.refit(positions)
        bvh = ours.bvh_tris  # built now, outside the recording
    assert isinstance(bvh, wp.Bvh) and "bvh_tris" in ours.__dict__
    moved = model.particle_q.numpy() * np.float32(1.25) + np.float32(0.1)
    positions.assign(moved)
    wp.capture_launch(capture.graph)
    theirs = NewtonDetector(model, init_collision_info=True, vertex_positions=wp.array(moved, dtype=wp.vec3, device="cpu"))
    for name in ("lower_bounds_tris", "upper_bounds_tris", "lower_bounds_edges", "upper_bounds_edges"):
        assert np.array_equal(getattr(ours, name).numpy(), getattr(theirs, name).numpy()), name
    assert ours.bvh_tris is bvh


def test_a_failure_during_a_replay_is_printed_kept_and_raised(capfd):
    scene = ns.scenes()["cloth_bending"]()
    model = ns.cloth_model(scene.meshes)
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True)
    with wp.ScopedCapture(device="cpu") as capture:
        detector.refit()
        detector.edge_edge_collision_detection(scene.radius)

    def broken(*args, **kwargs):
        raise ValueError("injected failure")

    detector._scene.query = broken
    wp.capture_launch(capture.graph)  # Warp's own replay cannot raise it...
    err = capfd.readouterr().err
    assert "edge_edge_collision_detection failed during a Warp graph replay" in err and "injected failure" in err
    assert "Traceback" in err  # the first failure with its traceback
    assert detector.replay_failures == 1 and detector.replayed_calls == 1  # the refit ran
    with pytest.raises(mn.ReplayError, match="injected failure") as caught:  # ...the detector's next call does
        detector.refit()
    assert isinstance(caught.value.__cause__, ValueError)
    detector.check_replays()  # raised once
    with pytest.raises(mn.ReplayError, match="2 failed"):  # minkq.newton.capture_launch raises at once
        mn.capture_launch(capture.graph)
    del detector._scene.query
    mn.capture_launch(capture.graph)  # and works again
    assert detector.replay_failures == 2 and detector.replayed_calls == 4


@pytest.mark.parametrize("update", ["refit", "rebuild"])
def test_the_bodies_a_cuda_capture_records_give_the_eager_rows(update):
    """The bodies a CUDA capture records (minkq's stream-ordered refit or rebuild and queries,
    Warp's kernels over every slot of the passes' fixed pair buffers, the counts left in device
    arrays), run here on the CPU, where the stream-ordered calls run at once: the rows, counts,
    minimum distances and flags of the eager bodies; a pass's buffer smaller than its pairs
    sets Newton's resize flag."""
    scene = ns.scenes()["cloth_hanging"]()
    model = ns.cloth_model(scene.meshes)
    r = scene.radius
    rest = model.particle_q.numpy()
    for kwargs in (ROOMY, dict(vertex_collision_buffer_pre_alloc=8, edge_collision_buffer_pre_alloc=16)):
        positions = wp.clone(model.particle_q)
        detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions, **kwargs)
        detector._scene.reserve(refit=True, rebuild=True)  # done when the scene is made on CUDA only
        detector._in_cuda_capture = True
        compared = 0
        for step in range(3):
            positions.assign(_squashed(rest, step))
            detector.resize_flags.zero_()
            getattr(detector, update)(positions)
            detector.vertex_triangle_collision_detection(r)
            detector.edge_edge_collision_detection(r)
            slots = {kind: detector._scratch.arrays[kind + "_pairs"].shape[0] for kind in ("vt", "ee")}
            found = {kind: int(detector._found[kind].numpy()[0]) for kind in ("vt", "ee")}
            assert slots["vt"] >= detector._capture_capacity("vt") and slots["ee"] >= detector._capture_capacity("ee")
            lost = {kind: found[kind] > slots[kind] for kind in ("vt", "ee")}
            if not any(lost.values()):
                _same(read(detector), _eager(model, positions, r, rebuild=update == "rebuild", **kwargs))
                compared += 1
            flags = detector.resize_flags.numpy()  # pairs past a pass's buffer are lost: the flag says so
            assert not lost["vt"] or flags[mn.VERTEX_OVERFLOW] == 1
            assert not lost["ee"] or flags[mn.EDGE_OVERFLOW] == 1
        if kwargs is ROOMY:
            assert compared == 3
    # A buffer too small for the pairs: the flag.
    positions = wp.clone(model.particle_q)
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions,
                                           vertex_collision_buffer_pre_alloc=1, edge_collision_buffer_pre_alloc=1)
    detector._scene.reserve(refit=True)
    detector._in_cuda_capture = True
    detector.refit(positions)
    detector.edge_edge_collision_detection(4 * r)
    assert int(detector._found["ee"].numpy()[0]) > detector._scratch.arrays["ee_pairs"].shape[0]
    assert detector.resize_flags.numpy()[mn.EDGE_OVERFLOW] == 1


def test_pass_buffers_first_needed_inside_a_capture_are_allocated_with_it_paused(monkeypatch):
    """A pass's buffer first needed inside a CUDA capture (no eager detection ran first), or
    grown there, is allocated with the capture paused (issue 30): a graph allocation would
    belong to the graph and fail minkq's device-pointer check. Kept buffers need nothing."""
    import warp._src.context as context

    events = []

    class CapturingDevice:
        is_capturing = True

    monkeypatch.setattr(context, "capture_pause", lambda device=None: events.append("pause") or "graph")
    monkeypatch.setattr(context, "capture_resume", lambda graph, device=None: events.append(("resume", graph)))
    monkeypatch.setattr(mn.wp, "empty", lambda shape, dtype, device: events.append(("empty", shape)) or np.empty(shape))
    scratch = mn._Scratch(CapturingDevice())
    scratch.pinned = []
    first = scratch.get("vt_pairs", wp.int32, 100, (2,))
    assert events == ["pause", ("empty", (100, 2)), ("resume", "graph")]
    events.clear()
    assert scratch.get("vt_pairs", wp.int32, 60, (2,)) is first and events == []
    grown = scratch.get("vt_pairs", wp.int32, 150, (2,))
    assert events == ["pause", ("empty", (200, 2)), ("resume", "graph")]
    assert [id(a) for a in scratch.pinned] == [id(first), id(first), id(grown)]  # the graph's arrays outlive growth


@pytest.mark.gpu
def test_cuda_captured_query_buffer_too_small_sets_the_resize_flag():
    """A CUDA graph whose query buffer is smaller than a replay's pairs: Newton's resize flag,
    never a write past it."""
    _needs_cuda("cuda:0")
    scene = ns.scenes()["cloth_hanging"]()
    model = ns.cloth_model(scene.meshes, device="cuda:0")
    positions = wp.clone(model.particle_q)
    detector = mn.TriMeshCollisionDetector(model, init_collision_info=True, vertex_positions=positions,
                                           vertex_collision_buffer_pre_alloc=1, edge_collision_buffer_pre_alloc=1)
    with wp.ScopedCapture(device="cuda:0") as capture:
        detector.refit(positions)
        detector.edge_edge_collision_detection(4 * scene.radius)
    wp.capture_launch(capture.graph)
    assert int(detector._found["ee"].numpy()[0]) > detector._scratch.arrays["ee_pairs"].shape[0]
    assert detector.resize_flags.numpy()[mn.EDGE_OVERFLOW] == 1


# ---- Newton's examples, its collision tests, the runner ------------------------------------------


def _run(args, timeout=1200):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (HERE, env.get("PYTHONPATH")) if p)
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, timeout=timeout, check=False)


def _run_example(name, *options):
    """The example through the runner (install() + Newton's entry point), graph capture as the
    example does it, headless; returns the probe's summary of the detectors it built."""
    process = _run([os.path.join(HERE, "newton_example_probe.py"), name, "--viewer", "null", "--device", "cpu", "--quiet", *options])
    assert process.returncode == 0, process.stdout[-3000:] + process.stderr[-6000:]
    summary = json.loads(process.stdout.strip().splitlines()[-1])
    assert summary["status"] == 0 and summary["detectors"], summary
    for detector in summary["detectors"]:
        assert detector["replay_failures"] == 0, summary
    return summary


# (example, options, whether it records its step into a graph on the CPU)
EXAMPLES = [
    ("cloth_twist", ("--num-frames", "3"), True),
    ("cloth_hanging", ("--num-frames", "3", "--width", "32", "--height", "16"), True),
    ("cloth_bending", ("--num-frames", "3"), True),
    pytest.param("cloth_rollers", ("--num-frames", "2"), True, marks=slow),
    pytest.param("cloth_poker_cards", ("--num-frames", "2"), False, marks=slow),
    pytest.param("softbody_gift", ("--num-frames", "2"), True, marks=slow),
    pytest.param("softbody_dropping_to_cloth", ("--num-frames", "2"), True, marks=slow),
    pytest.param("vbd_dat_rigid_soft", ("--num-frames", "2"), False, marks=slow),
]


@pytest.mark.parametrize("name, options, captured", EXAMPLES)
def test_newton_example_runs_with_the_detector_installed(name, options, captured, capsys):
    summary = _run_example(name, *options)
    replayed = sum(d["replayed_calls"] for d in summary["detectors"])
    if captured:
        assert replayed > 0, summary  # minkq's work ran inside the example's graph replays
    with capsys.disabled():
        print(f"\n  {name} {' '.join(options)}: {summary['detectors']}", end="")


def test_runner_lists_newtons_examples():
    process = _run(["-m", "minkq.newton.examples", "--list"], timeout=300)
    assert process.returncode == 0, process.stderr
    marked = {line.split()[1] for line in process.stdout.splitlines() if line.strip().startswith("*")}
    assert {"cloth_twist", "cloth_hanging", "cloth_bending", "cloth_rollers", "cloth_poker_cards"} <= marked
    usage = _run(["-m", "minkq.newton.examples"], timeout=300)
    assert usage.returncode == 2 and "usage: python -m minkq.newton.examples" in usage.stdout


def test_runner_runs_an_example_headless():
    process = _run(["-m", "minkq.newton.examples", "cloth_bending", "--viewer", "null", "--num-frames", "2", "--device", "cpu", "--quiet"])
    assert process.returncode == 0, process.stderr[-6000:]


def test_newtons_cloth_collision_tests_pass_with_the_detector_installed(tmp_path, capsys):
    """Newton's own test_collision_cloth.py (its TestCollision cases), run by pytest with a
    plugin that calls install() before the module is imported."""
    (tmp_path / "minkq_install_plugin.py").write_text(
        "import minkq.newton\n"
        "minkq.newton.install()\n"
        "from newton._src.solvers.vbd import tri_mesh_collision\n"
        "assert tri_mesh_collision.TriMeshCollisionDetector is minkq.newton.TriMeshCollisionDetector\n"
    )
    tests = os.path.join(os.path.dirname(newton.__file__), "tests", "test_collision_cloth.py")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(tmp_path), os.environ.get("PYTHONPATH")) if p))
    process = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "minkq_install_plugin", "-rs",
         f"{tests}::TestCollision"],
        capture_output=True, text=True, env=env, timeout=1800, check=False, cwd=str(tmp_path),
    )
    tail = process.stdout.strip().splitlines()[-1] if process.stdout.strip() else ""
    assert process.returncode == 0, process.stdout[-6000:] + process.stderr[-3000:]
    assert "passed" in tail and "failed" not in tail and "error" not in tail, tail
    with capsys.disabled():
        print(f"\n  newton test_collision_cloth.py::TestCollision with install(): {tail}", end="")


# ---- Scale-free edge-edge evaluation in SolverVBD ----------------------------------------------


@wp.kernel
def _solver_ee_test(
    pos: wp.array(dtype=wp.vec3),
    edges: wp.array2d(dtype=wp.int32),
    pairs: wp.array2d(dtype=wp.int32),
    radius: float,
    epsilon: float,
    passes: wp.array(dtype=wp.int32),
):
    # What SolverVBD's evaluate_edge_edge_contact does before applying a force.
    i = wp.tid()
    e = pairs[i, 0]
    f = pairs[i, 1]
    st = wp.closest_point_edge_edge(pos[edges[e, 2]], pos[edges[e, 3]], pos[edges[f, 2]], pos[edges[f, 3]], epsilon)
    if st[2] < radius:
        passes[i] = 1


def _fine_rolled_cloth():
    xyz, tris = ns.grid(40, 30, 0.002, 0.002)  # edges 2 mm, diagonals 2.8 mm
    xyz = ns.roll(xyz, 5.6, 0.0006)  # 80 mm rolled into 5.6 turns 0.6 mm apart: edges keep their length
    return xyz, tris


def test_solver_vbd_evaluates_every_edge_edge_contact_minkq_reports(capsys):
    """On a fine mesh (edges 2-2.8 mm, squared lengths under Newton's 1e-5), every EE pair minkq
    reports within the radius passes the solver's test (closest_point_edge_edge with the
    epsilon the patched solver uses, distance < radius); with Newton's default epsilon many
    fail. uninstall() restores Newton's epsilon."""
    xyz, tris = _fine_rolled_cloth()
    margin, gap = 0.0008, 0.0004

    def solver_for():
        builder = newton.ModelBuilder(gravity=(0.0, 0.0, 0.0))
        builder.add_cloth_mesh(
            pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
            vertices=xyz, indices=tris.reshape(-1), density=0.2,
        )
        builder.color()
        model = builder.finalize(device="cpu")
        solver = newton.solvers.SolverVBD(
            model, iterations=1, particle_enable_self_contact=True, particle_self_contact_margin=margin,
            particle_self_contact_gap=gap, particle_edge_contact_buffer_size=256,
        )
        return model, solver

    mn.install()
    try:
        model, solver = solver_for()
    finally:
        mn.uninstall()
    _, newton_solver = solver_for()
    assert newton_solver._self_contact_edge_edge_parallel_epsilon == 1e-5
    assert type(newton_solver.trimesh_collision_detector) is NewtonDetector
    epsilon = solver._self_contact_edge_edge_parallel_epsilon
    assert epsilon == 0.0 and solver.newton_edge_edge_parallel_epsilon == 1e-5

    detector = solver.trimesh_collision_detector
    radius = margin  # the force kernels' collision radius (detection queries margin + gap)
    detector.refit(model.particle_q)
    detector.edge_edge_collision_detection(radius)
    ee, _, _ = ns.rows(
        detector.edge_colliding_edges, detector.edge_colliding_edges_offsets, detector.edge_colliding_edges_count,
        detector.edge_colliding_edges_buffer_sizes,
    )
    assert not detector.resize_flags.numpy().any()
    pairs = ns.unordered(ee)
    # Away from the radius (float distances may decide either way within 1e-5 r of it).
    edges = model.edge_indices.numpy()[:, 2:4].copy()
    truth = ns.ee_truth(model.particle_q.numpy(), edges, radius)
    pairs = np.setdiff1d(pairs, truth.band(radius))
    assert len(pairs) > 1000
    pair_array = wp.array(np.stack([pairs >> 32, pairs & 0xFFFFFFFF], 1).astype(np.int32), dtype=wp.int32, device="cpu")
    lengths = np.linalg.norm(np.diff(model.particle_q.numpy()[edges], axis=1)[:, 0], axis=1)
    assert lengths.max() < 3e-3 and (lengths**2).max() < 1e-5  # every edge is a "point" to Newton's epsilon

    def passing(eps):
        passes = wp.zeros(len(pairs), dtype=wp.int32, device="cpu")
        wp.launch(_solver_ee_test, dim=len(pairs), inputs=[model.particle_q, model.edge_indices, pair_array, radius, eps, passes], device="cpu")
        return passes.numpy().astype(bool)

    assert passing(epsilon).all()
    lost = 1.0 - passing(1e-5).mean()
    assert lost > 0.2, lost  # Newton's epsilon: contacts reported but given no force
    with capsys.disabled():
        print(
            f"\n  fine rolled cloth (edges {lengths.min() * 1e3:.2f}-{lengths.max() * 1e3:.2f} mm), radius {radius}: "
            f"{len(pairs)} EE pairs; solver test passes all with epsilon {epsilon}, loses {100 * lost:.1f}% with 1e-5",
            end="",
        )
