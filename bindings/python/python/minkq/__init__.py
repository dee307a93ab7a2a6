"""minkq: which pairs of mesh elements may lie within distance r of each other?

Builds a BVH over triangles, edges or boxes and runs batched sphere, capsule and box queries
against it, on the CPU or with CUDA, with zero false negatives. Cloth and soft-body simulators
use it for their per-step vertex-triangle (VT) and edge-edge (EE) broad phase::

    import numpy as np, minkq
    scene = minkq.Scene(vertices, triangles)  # (n, 3) float32, (m, 3) int32; device from the arrays
    vt = scene.query("vt", r, leaf_exact=True)  # contacts: (k, 2) int32 (vertex, triangle)
    ee = scene.query("ee", r)                   # (k, 2) int32 (e, f), e < f; mode="box" by default
    scene.refit(new_vertices)                   # every step
    if scene.tree_growth() > 1.5:               # after large motions:
        scene.rebuild(new_vertices)             # fresh trees, same pairs

The conventions of numpy, Warp and PyTorch: the device is the arrays' (numpy: the CPU; a Warp
array or a torch tensor on ``cuda:1``: ``cuda:1``) or ``device=`` ("cpu", "cuda:0", a
``torch.device``, a Warp device or a :class:`Device`); the node test is ``mode=`` (``"box"``
by default); ``out=`` writes into an array or a growing :class:`PairBuffer` of yours;
``close()`` or ``with`` releases a scene or BVH at once. The spellings these replaced
(``Scene(device, vertices, triangles)``, ``query(kind, mode, radius)``, ``query_into(out,
...)``) work for one more release with a DeprecationWarning.

Particles, rods and yarn get vertex-vertex (VV) and edge-vertex (EV) queries, with no triangles:
``minkq.Scene(vertices, None, edges, vt=False, ee=False, vv=True, ev=True)``, then
``scene.query("vv", r)`` and ``scene.query("ev", r)``.

Cloth against a collider, per-vertex thickness, many worlds: a scene of several geometries,
``minkq.Scene.from_geometries([minkq.Geometry(body_v, body_t, static=True,
self_pairs=False), minkq.Geometry(cloth_v, cloth_t, thickness=t)])``, reports self and cross
pairs in one global numbering (``scene.geometry_of_pairs`` maps them back to geometries).

Arrays of other libraries (``__dlpack__``, ``__cuda_array_interface__``: Warp, PyTorch, CuPy)
are read in place, on the GPU for a CUDA device, and results come back in their kind.
:mod:`minkq.newton` (import it explicitly; it needs warp and newton) is a drop-in for Newton's
``TriMeshCollisionDetector``.

Errors raise subclasses of :class:`MinkqError` named after the C error codes.
"""

from . import _native
from ._api import BVH, ELEMENTS, KINDS, MODES, Device, Geometry, PairBuffer, QueryInfo, Scene, WorkStats, abi_version, cuda_device_count, version
from ._errors import *  # noqa: F401, F403 - the exceptions, _errors.__all__ (listed below)

ABI_VERSION: int = _native.ABI_VERSION
"""The ABI version the bindings were generated against (MINKQ_ABI_VERSION)."""

__version__ = "0.3.0"

__all__ = [
    "ABI_VERSION",
    "BVH",
    "KINDS",
    "MODES",
    "CapacityError",
    "Device",
    "DeviceError",
    "ELEMENTS",
    "Geometry",
    "IndexOutOfRangeError",
    "InternalError",
    "InvalidArgumentError",
    "MinkqError",
    "NonFiniteError",
    "OutOfMemoryError",
    "PairBuffer",
    "QueryInfo",
    "Scene",
    "SizeOverflowError",
    "UnsupportedError",
    "WorkStats",
    "abi_version",
    "cuda_device_count",
    "version",
]
