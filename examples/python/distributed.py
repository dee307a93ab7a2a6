#!/usr/bin/env python3
"""The distributed queries from Python (minkq.mpi over mpi4py): a twisted sheet split into slabs
of triangles over the ranks, each rank passing its part; rank 0 gathers the pairs and checks
them against the same queries on the whole sheet in one process.

    mpirun -n 3 python3 examples/python/distributed.py [--size N] [--device cpu|cuda]

minkq.mpi loads libminkq_mpi.so (built with minkq's MPI component): the installed one, or
MINKQ_MPI_LIB_DIR. Exits 1 if the union of the ranks' pairs differs from one process's.
"""

import argparse
import sys

import numpy as np
from mpi4py import MPI

import minkq
import minkq.mpi
from minkq.demo import derive_edges, mean_edge_length, twisted_sheet


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=80)
    parser.add_argument("--device", default="cpu", help='"cuda": the GPU of this rank on its node')
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    device = minkq.mpi.local_device(comm) if args.device == "cuda" else args.device

    # The whole sheet (every rank builds it here; a simulator holds only its part).
    xyz, tris = twisted_sheet(args.size)
    r = 0.25 * mean_edge_length(xyz, derive_edges(tris))

    # Slabs: triangles by centroid x; each vertex owned by the rank of its first triangle.
    order = np.argsort(xyz[tris].mean(axis=1)[:, 0], kind="stable")
    tri_rank = np.empty(len(tris), np.int64)
    tri_rank[order] = np.arange(len(tris)) * size // len(tris)
    first = np.full(len(xyz), len(tris))  # each vertex's lowest-index triangle
    np.minimum.at(first, tris.ravel(), np.repeat(np.arange(len(tris)), 3))
    vertex_rank = tri_rank[first]
    mine = np.flatnonzero(tri_rank == rank)
    local = np.unique(np.concatenate([tris[mine].ravel(), np.flatnonzero(vertex_rank == rank)]))
    index = np.full(len(xyz), -1)
    index[local] = np.arange(len(local))

    with minkq.mpi.Scene(comm, xyz[local], index[tris[mine]], local, mine, vertex_rank[local] == rank,
                         np.ones(len(mine), bool), device=device) as scene:
        pairs = {kind: scene.query(kind, r, leaf_exact=True) for kind in ("vt", "ee")}
        info = scene.rank_info()
    everyone = comm.gather((pairs, info), root=0)
    if rank != 0:
        return 0
    whole = minkq.Scene(xyz, tris, vt=True, ee=True, drop_incident=True)
    ok = True
    for kind in ("vt", "ee"):
        union = np.concatenate([p[kind] for p, _ in everyone])
        single = whole.query(kind, r, leaf_exact=True, canonical=True)
        same = len(np.unique(union, axis=0)) == len(union) and np.array_equal(np.unique(union, axis=0), single)
        ok &= same
        print(f"{kind}: {len(union)} contacts over {size} ranks, {len(single)} in one process: "
              f"{'equal' if same else 'DIFFERENT'}")
    for k, (_, i) in enumerate(everyone):
        print(f"rank {k}: owns {i['owned_triangles']} triangles and {i['owned_edges']} edges; "
              f"ghosts {i['ghost_vertices']} vertices, {i['ghost_edges']} edges")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
