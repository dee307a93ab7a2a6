"""The rank program of test_mpi.py, under ``mpirun -n K python mpi_ranks.py SEED``.

A wavy grid sheet, split at random over the ranks (every triangle and every vertex on a
random rank, each rank holding the corners of its triangles as copies), queried through
minkq.mpi; rank 0 gathers the pairs and compares them, pair by pair, with the single-process
query of the wheel's minkq.Scene. Also after a refit, a collective error, and with a skin. Exits non-zero
on any difference.
"""

import sys
import warnings

import numpy as np
from mpi4py import MPI

import minkq
import minkq.mpi

comm = MPI.COMM_WORLD
rank, size = comm.Get_rank(), comm.Get_size()
seed = int(sys.argv[1])
failures = []


def sheet(n, phase):
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="xy")
    x, y = i.ravel() / (n - 1), j.ravel() / (n - 1)
    xyz = np.stack([x, y, 0.08 * np.sin(9 * x + phase) * np.cos(7 * y)], axis=1).astype(np.float32)
    a = (j[:-1, :-1] * n + i[:-1, :-1]).ravel()
    tris = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)]).astype(np.int32)
    return xyz, tris


n = 24
xyz, tris = sheet(n, 0.0)
rng = np.random.default_rng(seed)
tri_owner = rng.integers(0, size, len(tris))
vertex_owner = rng.integers(0, size, len(xyz))
mine_t = np.flatnonzero(tri_owner == rank)
held = np.zeros(len(xyz), bool)
held[tris[mine_t].ravel()] = True
held[vertex_owner == rank] = True
local_v = rng.permutation(np.flatnonzero(held))
index = np.full(len(xyz), -1)
index[local_v] = np.arange(len(local_v))
r = 0.6 / (n - 1)


def check(scene, whole_xyz, what):
    single = minkq.Scene(whole_xyz, tris, vt=True, ee=True, drop_incident=True)
    for kind, mode, leaf in [("vt", "box", False), ("vt", "sphere", False), ("vt", "box", True),
                             ("ee", "box", False), ("ee", "capsule_exact", False), ("ee", "box", True)]:
        mine = scene.query(kind, r, mode=mode, leaf_exact=leaf)
        counted = scene.count(kind, r, mode=mode, leaf_exact=leaf)
        if counted != len(mine):
            failures.append(f"{what} {kind} {mode}: count {counted} but {len(mine)} pairs on rank {rank}")
        gathered = comm.gather(mine, root=0)
        if rank != 0:
            continue
        union = np.concatenate(gathered)
        want = single.query(kind, r, mode=mode, leaf_exact=leaf, canonical=True).astype(np.int64)
        got = np.unique(union, axis=0)
        if len(got) != len(union):
            failures.append(f"{what} {kind} {mode}: {len(union) - len(got)} pairs on two ranks")
        if not np.array_equal(got, want):
            failures.append(f"{what} {kind} {mode}: {len(got)} pairs, single process {len(want)}")


with minkq.mpi.Scene(comm, xyz[local_v], index[tris[mine_t]], local_v, mine_t, vertex_owner[local_v] == rank,
                     np.ones(len(mine_t), bool)) as scene:
    check(scene, xyz, "created")
    if scene.rank_info()["global_edges"] != 3 * (n - 1) ** 2 + 2 * (n - 1):
        failures.append(f"global edges {scene.rank_info()['global_edges']}")
    moved, _ = sheet(n, 1.3)
    scene.refit(moved[local_v])
    check(scene, moved, "refit")
    bad = moved[local_v].copy()
    if rank == size - 1 and len(bad):
        bad[0, 2] = np.nan
    try:
        scene.refit(bad)
        failures.append("a NaN on the last rank was accepted")
    except minkq.NonFiniteError as e:
        if f"rank {size - 1}: vertex 0" not in str(e):
            failures.append(f"message {e}")
    check(scene, moved, "after a failed refit")
    # The conventions of minkq.Scene: mode="box" by default, out= (an int64 array or a growing
    # PairBuffer), the old positional mode with a DeprecationWarning.
    box = scene.query("ee", r, canonical=True)
    buffer = minkq.PairBuffer(np.zeros((1, 2), np.int64))
    if not np.array_equal(scene.query("ee", r, mode="box", canonical=True, out=buffer), box):
        failures.append("out=PairBuffer differs")
    out = np.full((len(box) + 2, 2), -1, np.int64)
    got = scene.query("ee", r, canonical=True, out=out)
    if not (np.shares_memory(got, out) and np.array_equal(got, box) and (out[len(box):] == -1).all()):
        failures.append("out= array differs")
    try:
        scene.query("ee", r, out=np.zeros((len(box) - 1, 2), np.int64)) if len(box) else None
        if len(box):
            failures.append("a short out= was accepted")
    except minkq.CapacityError as e:
        if e.needed != len(box):
            failures.append(f"needed {e.needed}, not {len(box)}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if scene.count("ee", "box", r) != len(box):
            failures.append("old positional mode differs")
    if not any(issubclass(w.category, DeprecationWarning) for w in caught):
        failures.append("no DeprecationWarning for a positional mode")
    # Double values are refused on every rank, not rounded to float32 (before any collective).
    try:
        scene.refit(moved[local_v].astype(np.float64))
        failures.append("float64 vertices were rounded")
    except TypeError as e:
        if "float32 only" not in str(e):
            failures.append(f"message {e}")
    # A skin keeps the ghost layer over a small move: the pairs are the same.
    scene.set_skin(2 * r)
    check(scene, moved, "skin chosen")
    nudged, _ = sheet(n, 1.301)
    scene.refit(nudged[local_v])
    before = scene.rank_info()["ghost_updates"]
    check(scene, nudged, "skin kept")
    if scene.rank_info()["ghost_updates"] == before:
        failures.append(f"rank {rank}: the skin did not keep the ghost layer")

# Indices are range checked, not wrapped around (before any collective call).
far = index[tris[mine_t]].astype(np.int64)
if comm.allreduce(len(far) > 0, op=MPI.LAND):  # every rank refuses it, or none calls
    far[0, 0] += 2**32
    try:
        minkq.mpi.Scene(comm, xyz[local_v], far, local_v, mine_t, vertex_owner[local_v] == rank, np.ones(len(mine_t), bool))
        failures.append("an index beyond int32 wrapped around")
    except minkq.IndexOutOfRangeError as e:
        if "triangles[0, 0]" not in str(e):
            failures.append(f"message {e}")

everyone = comm.allgather(failures)
if rank == 0:
    for rank_failures in everyone:
        for f in rank_failures:
            print("FAIL", f)
    print(f"mpi_ranks: {size} ranks, seed {seed}, {sum(map(len, everyone))} failures")
sys.exit(1 if any(everyone) else 0)
