"""The package around the extension: typing files, docstring examples, zero-copy inputs, the
GIL released during build, refit, rebuild and queries, threads, and the demo's default scene."""

import doctest
import os
import threading
import time

import numpy as np
import pytest

import minkq
from minkq import _args, _bvh, _conventions, _device, _geometry, _scene, _scene_queries, _stream_ordered
from oracle import rolled_sheet


def test_package_ships_type_information():
    root = os.path.dirname(minkq.__file__)
    for name in ("py.typed", "_native.pyi", "__init__.py", "__main__.py", "_errors.py", "_api.py", "_args.py",
                 "_results.py", "_device.py", "_scene.py", "_stream_ordered.py", "_geometry.py", "_bvh.py", "_interop.py",
                 "newton/__init__.py", "newton/_compat.py", "newton/_kernels.py", "newton/_capture.py", "newton/_detector.py",
                 "newton/_install.py", "newton/_body_contacts.py", "newton/examples.py", "demo.py", "mpi.py"):
        assert os.path.exists(os.path.join(root, name)), name
    assert minkq.abi_version() == minkq.ABI_VERSION
    # The library the package loaded is the release the package says it is.
    assert minkq.version() == tuple(int(x) for x in minkq.__version__.split("."))
    assert set(minkq.__all__) <= set(dir(minkq))


def test_public_items_have_docstrings():
    for name in minkq.__all__:
        item = getattr(minkq, name)
        if callable(item):
            assert item.__doc__, name
    # The classes and the package's own bases they take methods from (Scene's stream-ordered
    # calls and its geometries' calls).
    classes = (minkq.Device, minkq.Scene, minkq.Geometry, minkq.BVH)
    own = [c for cls in classes for c in cls.__mro__ if c.__module__.startswith("minkq.")]
    assert _stream_ordered._StreamOrdered in own and _geometry._Geometries in own
    for cls in own:
        for attr, member in vars(cls).items():
            if not attr.startswith("_") and (callable(member) or isinstance(member, property)):
                assert member.__doc__, f"{cls.__name__}.{attr}"


def test_docstring_examples_run():
    for module in (_device, _scene, _scene_queries, _conventions, _stream_ordered, _geometry, _bvh):
        failures, tried = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert tried >= 1 and failures == 0, module.__name__


def test_c_contiguous_inputs_are_not_copied():
    xyz, tris = rolled_sheet(5, 0)
    assert _args._rows(xyz, "vertices", np.float32, (3,)) is xyz
    assert _args._rows(tris, "triangles", np.int32, (3,)) is tris
    boxes = np.zeros((4, 6), np.float32)
    assert np.shares_memory(_args._boxes(boxes, "boxes"), boxes)
    strided = np.zeros((5, 6), np.float32)[:, ::2]
    assert not np.shares_memory(_args._rows(strided, "vertices", np.float32, (3,)), strided)


def test_repr_and_properties(device):
    xyz, tris = rolled_sheet(4, 0)
    scene = minkq.Scene(xyz, tris, device=device)
    assert (scene.vertex_count, scene.triangle_count, scene.edge_count) == (16, 18, 33)
    assert repr(scene) == "minkq.Scene(16 vertices, 18 triangles, 33 edges)"
    assert repr(device).startswith("minkq.Device('cpu (")
    assert device.backend == "cpu" and scene.device is device


def _longest_pause_while(work) -> tuple:
    """Runs `work` in a thread while this thread counts; returns (work's seconds, the longest
    gap between two of this thread's steps). A call that kept the GIL would stall this thread
    for its whole duration."""
    done = threading.Event()
    spent = []

    def worker():
        start = time.perf_counter()
        work()
        spent.append(time.perf_counter() - start)
        done.set()

    thread = threading.Thread(target=worker)
    last = time.perf_counter()
    longest = 0.0
    thread.start()
    while not done.is_set():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
    thread.join()
    return spent[0], longest


@pytest.fixture(scope="module")
def gil_sheet(device):
    """sheet(n): (vertices, triangles, moved vertices, radius, scene) of an n x n twisted sheet,
    made once for the GIL tests of this module."""
    from minkq import demo

    sheets = {}

    def sheet(n):
        if n not in sheets:
            xyz, tris = demo.twisted_sheet(n, 3.0)
            r = 0.25 * demo.mean_edge_length(xyz, demo.derive_edges(tris))
            sheets[n] = (xyz, tris, xyz * np.float32(1.001), r, minkq.Scene(xyz, tris, device=device))
        return sheets[n]

    return sheet


# One test per call, so that a call too fast to time here skips alone, not the calls after it.
@pytest.mark.parametrize("name", ["build", "refit", "rebuild", "query"])
def test_gil_is_released_during_build_refit_rebuild_and_query(device, gil_sheet, name):
    sheet = gil_sheet
    calls = {
        "build": lambda n: lambda: minkq.Scene(sheet(n)[0], sheet(n)[1], device=device),
        "refit": lambda n: lambda: sheet(n)[4].refit(sheet(n)[2]),
        "rebuild": lambda n: lambda: sheet(n)[4].rebuild(sheet(n)[2]),
        "query": lambda n: lambda: sheet(n)[4].query("ee", sheet(n)[3], mode="capsule_exact",
                                                     leaf_exact=True),
    }
    make_call = calls[name]
    # One call must last long enough that scheduling noise on a busy machine (the counting
    # thread shares the cores with the library's threads) is small beside it: the scene
    # grows until it does, so fast machines are tested as strictly as slow ones.
    for n in (160, 320, 640, 1280):
        call = make_call(n)
        call()  # warm: the sheet and its scene exist before timing
        start = time.perf_counter()
        call()
        if time.perf_counter() - start >= 0.1:
            break
    else:
        pytest.skip(f"{name}: one call on a 1280 x 1280 sheet takes under 0.1 s here")
    spent, longest = _longest_pause_while(call)
    # A call that kept the GIL would stall this thread for its whole duration.
    assert longest < 0.5 * spent, f"{name}: this thread stalled {longest:.3f} s of {spent:.3f} s"


def test_threads_share_a_scene_and_a_device(device):
    xyz, tris = rolled_sheet(14, 3)
    scene = minkq.Scene(xyz, tris, device=device)
    expected = scene.query_digest("ee", 0.03, mode="capsule_exact")[1]
    results, errors = [], []

    def work(seed):
        try:
            own = minkq.Scene(*rolled_sheet(10, seed), device=device)  # builds on the shared device
            for _ in range(5):
                results.append(scene.query_digest("ee", 0.03, mode="capsule_exact")[1])
                own.query("vt", 0.03, mode="sphere")
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(s,)) for s in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert results == [expected] * 20


def test_default_demo_scene_true_contacts_equal_minkq_demo_reference(device):
    """examples/python/demo.py rebuilds `minkq demo`'s scene bit for bit: its leaf_exact counts
    are the reference oracle's 62694 VT and 192090 EE contacts."""
    from minkq import demo

    xyz, tris = demo.twisted_sheet(demo.DEFAULT_SIZE, 3.0)
    edges = demo.derive_edges(tris)
    assert (len(xyz), len(tris), len(edges)) == (150544, 299538, 450081)
    h = demo.mean_edge_length(xyz, edges)
    r = float(np.float32(demo.DEFAULT_FACTOR * h))
    assert (f"{r:.6g}", f"{h:.6g}") == ("0.00235628", "0.00942512")  # as `minkq demo` prints them
    scene = minkq.Scene(xyz, tris, device=device)
    assert np.array_equal(scene.edges(), edges)
    vt = len(scene.query("vt", r, mode="sphere", leaf_exact=True))
    ee = len(scene.query("ee", r, mode="capsule_exact", leaf_exact=True))
    assert {"vt": vt, "ee": ee} == demo.REFERENCE_CONTACTS


def test_demo_prints_the_table(capsys):
    from minkq import demo

    assert demo.main(["--backend", "cpu", "--size", "40", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "kind mode                         candidates         true  fp ratio  false neg   query ms  speedup" in out
    assert out.count("\nVT ") == 3 and out.count("\nEE ") == 4
    assert "no false negatives" in out
