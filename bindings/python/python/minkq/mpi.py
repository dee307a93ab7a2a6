"""Distributed VT and EE queries of a mesh split over MPI ranks (``minkq_mpi.h``), over mpi4py.

Each rank passes its part of the mesh: its local vertices and triangles, a global id for each
(int64) and which of them it owns; every call is collective over the communicator. A query
returns this rank's share of the pairs as a (k, 2) int64 array of global ids, such that the
union over the ranks is exactly the pair set of the same query on the whole mesh in one
process (EE pairs in the global edge numbering, which for vertex ids 0..n-1 is the
single-process scene's) and each pair is on exactly one rank::

    from mpi4py import MPI
    import minkq.mpi
    scene = minkq.mpi.Scene(MPI.COMM_WORLD, vertices, triangles, vertex_ids, triangle_ids,
                            vertex_owned, triangle_owned)
    pairs = scene.query("ee", radius, leaf_exact=True)   # this rank's pairs

An error on any rank raises the same exception, with the same message naming the rank and
the element, on every rank.

This module loads ``libminkq_mpi.so`` (built with minkq's MPI component and linked against
the system's MPI, so it is not in the wheel): from ``MINKQ_MPI_LIB`` (the file) or
``MINKQ_MPI_LIB_DIR`` (its folder) when set, else from the library search path (after
``cmake --install`` or the Debian package). It uses the libminkq that library links, not the
wheel's, so its scenes take ``device=`` as a spec ("cpu", "cuda:N"), a ``torch.device`` or a Warp
device (a :class:`minkq.Device` gives its spec) and make their own device from it.

The conventions and dtype policy are :class:`minkq.Scene`'s: ``mode="box"`` by default,
``out=`` (an (capacity, 2) int64 array, :class:`CapacityError` when short, or a
:class:`minkq.PairBuffer`, grown as needed), ``close()`` and ``with``; float64 vertices are
refused rather than rounded (a distributed scene is float32 only), int64 and other integer
indices converted with a range check, floats never rounded to indices. The old spelling
``query(kind, mode, radius)`` works for one more release with a DeprecationWarning.
"""

from __future__ import annotations

import ctypes
import os
from typing import Any, Dict, Optional, Tuple

import numpy as np

from ._args import _rows
from ._conventions import PairBuffer, array_device, device_spec, old_mode_form
from ._errors import CapacityError, _from_status
from ._interop import has_protocol, host_copy

__all__ = ["Scene", "library_path", "local_device"]

# The C declarations of minkq_mpi.h and minkq.h this module mirrors in ctypes. Each is named
# after its C counterpart in _C_CONSTANTS, _C_STRUCTS and _C_FUNCTIONS below, which
# tests/test_mpi_header.py compiles a probe against the real headers with (struct sizes, field
# names, offsets and kinds, constant values, function signatures): change them together.
_ABI_VERSION, _MPI_ABI_VERSION = 2, 1  # the SONAMEs libminkq.so.2, libminkq_mpi.so.1
_KINDS = {"vt": 0, "ee": 1}
_MODES = {"box": 0, "sphere": 1, "capsule_ray": 2, "capsule_exact": 3}
_SCENE_VT, _SCENE_EE, _SCENE_DROP_INCIDENT = 1, 2, 4
_LEAF_EXACT, _CANONICAL, _STATS, _COUNT = 1, 2, 8, 16
_MEMORY_HOST, _SUCCESS = 0, 0


class _Buffer(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("byte_stride", ctypes.c_size_t), ("count", ctypes.c_size_t),
                ("memory", ctypes.c_int)]


class _Desc(ctypes.Structure):
    _fields_ = [("flags", ctypes.c_uint32)] + [
        (name, _Buffer)
        for name in ("vertices", "triangles", "vertex_ids", "triangle_ids", "vertex_owned", "triangle_owned")
    ]


class _QueryDesc(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_int), ("mode", ctypes.c_int), ("flags", ctypes.c_uint32), ("radius", ctypes.c_float)]


class _Stats(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint64) for name in ("nodes_visited", "node_tests", "primitive_tests", "candidates")]


class _RankInfo(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint64) for name in (
        "owned_vertices", "owned_triangles", "owned_edges", "copied_vertices", "ghost_vertices", "ghost_edges",
        "neighbours", "global_edges", "local_builds", "local_refits", "ghost_exchanges", "ghost_updates",
        "bytes_sent", "last_bytes_sent")] + [
        (name, ctypes.c_double) for name in ("last_reach_ms", "last_ghost_ms", "last_trees_ms", "last_query_ms")]


_C_STRUCTS: Dict[str, Any] = {
    "minkq_buffer": _Buffer,
    "minkq_mpi_scene_desc": _Desc,
    "minkq_query_desc": _QueryDesc,
    "minkq_query_stats": _Stats,
    "minkq_mpi_rank_info": _RankInfo,
}
_C_CONSTANTS: Dict[str, int] = {
    "MINKQ_ABI_VERSION": _ABI_VERSION,
    "MINKQ_MPI_ABI_VERSION": _MPI_ABI_VERSION,
    "MINKQ_QUERY_VT": _KINDS["vt"],
    "MINKQ_QUERY_EE": _KINDS["ee"],
    "MINKQ_MODE_BOX": _MODES["box"],
    "MINKQ_MODE_SPHERE": _MODES["sphere"],
    "MINKQ_MODE_CAPSULE_RAY": _MODES["capsule_ray"],
    "MINKQ_MODE_CAPSULE_EXACT": _MODES["capsule_exact"],
    "MINKQ_SCENE_VT": _SCENE_VT,
    "MINKQ_SCENE_EE": _SCENE_EE,
    "MINKQ_SCENE_DROP_INCIDENT": _SCENE_DROP_INCIDENT,
    "MINKQ_QUERY_LEAF_EXACT": _LEAF_EXACT,
    "MINKQ_QUERY_CANONICAL": _CANONICAL,
    "MINKQ_QUERY_STATS": _STATS,
    "MINKQ_QUERY_COUNT": _COUNT,
    "MINKQ_MEMORY_HOST": _MEMORY_HOST,
    "MINKQ_SUCCESS": _SUCCESS,
}

# The functions this module calls, as the headers declare them: (result, parameters) in C,
# from which _ctype makes their ctypes signatures.
_C_FUNCTIONS: Dict[str, Tuple[str, Tuple[str, ...]]] = {  # libminkq_mpi (minkq_mpi.h)
    "minkq_mpi_last_error_message": ("const char*", ()),
    "minkq_mpi_scene_create": (
        "minkq_status", ("MPI_Comm", "minkq_device*", "const minkq_mpi_scene_desc*", "minkq_mpi_scene**")),
    "minkq_mpi_scene_release": ("void", ("minkq_mpi_scene*",)),
    "minkq_mpi_scene_refit": ("minkq_status", ("minkq_mpi_scene*", "minkq_buffer")),
    "minkq_mpi_scene_rebuild": ("minkq_status", ("minkq_mpi_scene*", "minkq_buffer")),
    "minkq_mpi_scene_set_skin": ("minkq_status", ("minkq_mpi_scene*", "double")),
    "minkq_mpi_scene_query": (
        "minkq_status", ("minkq_mpi_scene*", "const minkq_query_desc*", "minkq_mpi_result*")),
    "minkq_mpi_scene_rank_info": ("minkq_status", ("const minkq_mpi_scene*", "minkq_mpi_rank_info*")),
    "minkq_mpi_result_create": ("minkq_status", ("minkq_mpi_result**",)),
    "minkq_mpi_result_release": ("void", ("minkq_mpi_result*",)),
    "minkq_mpi_result_count": ("uint64_t", ("const minkq_mpi_result*",)),
    "minkq_mpi_result_pairs": ("const int64_t*", ("const minkq_mpi_result*",)),
    "minkq_mpi_result_stats": ("minkq_query_stats", ("const minkq_mpi_result*",)),
}
_C_CORE_FUNCTIONS: Dict[str, Tuple[str, Tuple[str, ...]]] = {  # libminkq (minkq.h)
    "minkq_last_error_message": ("const char*", ()),
    "minkq_device_create": ("minkq_status", ("const char*", "minkq_device**")),
    "minkq_device_release": ("void", ("minkq_device*",)),
    "minkq_cuda_device_count": ("int", ()),
}
# The C types of those signatures that are not structs, pointers to them or handles. MPI_Comm:
# a pointer, as in Open MPI (what the bindings are built and tested with; the test checks it).
_C_SCALARS: Dict[str, Any] = {
    "void": None,
    "int": ctypes.c_int,
    "double": ctypes.c_double,
    "uint64_t": ctypes.c_uint64,
    "minkq_status": ctypes.c_int,
    "const char*": ctypes.c_char_p,
    "const int64_t*": ctypes.POINTER(ctypes.c_int64),
    "MPI_Comm": ctypes.c_void_p,
}


def _ctype(c_type: str) -> Any:
    """The ctypes type of a C type of _C_FUNCTIONS: a scalar of _C_SCALARS, a struct of
    _C_STRUCTS or a pointer to one, a pointer to a handle (``T**``), or a handle (an opaque
    ``T*``: c_void_p)."""
    if c_type in _C_SCALARS:
        return _C_SCALARS[c_type]
    bare = c_type.replace("const ", "")
    if bare in _C_STRUCTS:
        return _C_STRUCTS[bare]
    if bare.endswith("**"):
        return ctypes.POINTER(ctypes.c_void_p)
    if bare.endswith("*") and bare[:-1] in _C_STRUCTS:
        return ctypes.POINTER(_C_STRUCTS[bare[:-1]])
    if bare.endswith("*") and bare.startswith("minkq_"):
        return ctypes.c_void_p
    raise ValueError(f"minkq.mpi: no ctypes type for the C type {c_type!r}")


_lib: Optional[ctypes.CDLL] = None
_core: Optional[ctypes.CDLL] = None
_path: Optional[str] = None


def library_path() -> str:
    """The libminkq_mpi this module loads (see the module's documentation)."""
    if os.environ.get("MINKQ_MPI_LIB"):
        return os.environ["MINKQ_MPI_LIB"]
    if os.environ.get("MINKQ_MPI_LIB_DIR"):
        return os.path.join(os.environ["MINKQ_MPI_LIB_DIR"], "libminkq_mpi.so")
    return f"libminkq_mpi.so.{_MPI_ABI_VERSION}"


def _load() -> ctypes.CDLL:
    global _lib, _core, _path
    if _lib is not None:
        return _lib
    _path = library_path()
    try:
        lib = ctypes.CDLL(_path)
    except OSError as e:
        raise ImportError(
            f"minkq.mpi: cannot load {_path} ({e}); build minkq with its MPI component and set "
            "MINKQ_MPI_LIB_DIR to the folder of libminkq_mpi.so, or install it") from e
    # The libminkq that libminkq_mpi links: its SONAME (libminkq.so.<MINKQ_ABI_VERSION>) resolves
    # to the copy already loaded with it.
    core = ctypes.CDLL(f"libminkq.so.{_ABI_VERSION}")
    for library, functions in ((lib, _C_FUNCTIONS), (core, _C_CORE_FUNCTIONS)):
        for name, (result, parameters) in functions.items():
            function = getattr(library, name)
            function.restype = _ctype(result)
            function.argtypes = [_ctype(p) for p in parameters]
    _lib, _core = lib, core
    return lib


def local_device(comm: Any) -> str:
    """One GPU per rank: "cuda:N" for this rank's index among the ranks of its node (modulo the
    GPUs minkq sees there), or "cpu" where it sees none. Collective."""
    from mpi4py import MPI

    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    try:
        local = node.Get_rank()
    finally:
        node.Free()
    _load()
    assert _core is not None
    gpus = _core.minkq_cuda_device_count()
    return f"cuda:{local % gpus}" if gpus > 0 else "cpu"


def _check(status: int, message: bytes) -> None:
    if status != _SUCCESS:
        raise _from_status(status, message.decode("utf-8", "replace"))


def _comm_handle(comm: Any) -> Any:
    """The C MPI_Comm of an mpi4py communicator, as ctypes passes it."""
    from mpi4py import MPI

    handle = MPI._handleof(comm)
    return ctypes.c_void_p(handle) if MPI._sizeof(MPI.Comm) == ctypes.sizeof(ctypes.c_void_p) else ctypes.c_int(handle)


def _vertices(value: Any, name: str) -> np.ndarray:
    """Vertex rows as (n, 3) float32; TypeError for double (or wider) values, which would be
    rounded: a distributed scene is float32 only (minkq_mpi_scene_create refuses
    MINKQ_SCENE_FLOAT64), and minkq.Scene refuses the same rounding for a float32 scene."""
    array = host_copy(value) if has_protocol(value) else np.asarray(value)
    if array.dtype.kind == "f" and array.dtype.itemsize > 4:
        raise TypeError(
            f"{name}: got {array.dtype} values for a minkq.mpi scene, which is float32 only: rounding them "
            "could lose a pair within r in double; pass float32 values"
        )
    return _rows(array, name, np.float32, (3,))


def _indices(value: Any, name: str, dtype: Any, trailing: tuple) -> np.ndarray:
    """Index rows (or ids) as C-contiguous ``dtype``, converted as :class:`minkq.Scene` converts
    them: integers range checked, floats refused."""
    return _rows(host_copy(value) if has_protocol(value) else value, name, dtype, trailing)


def _host(array: np.ndarray, count: int) -> _Buffer:
    return _Buffer(array.ctypes.data if array.size else None, 0, count, _MEMORY_HOST)


class Scene:
    """A mesh split over the ranks of ``comm`` (an mpi4py communicator): this rank's part.

    ``vertices`` (n, 3) float32 (double values raise TypeError rather than be rounded);
    ``triangles`` (m, 3) local vertex indices; ``vertex_ids`` (n,) and ``triangle_ids`` (m,)
    global ids (int64 >= 0, distinct on a rank); ``vertex_owned`` (n,) and ``triangle_owned``
    (m,) booleans: whether this rank owns each. ``vt`` and ``ee`` pick the queries the scene answers; ``drop_incident`` drops pairs that
    share a vertex. ``device``: this rank's device ("cpu", "cuda:N", a ``torch.device``, a Warp
    device or a :class:`minkq.Device`; None: the vertices' device, the CPU for host arrays;
    :func:`local_device` picks one GPU per rank). Collective.
    """

    def __init__(self, comm: Any, vertices: Any, triangles: Any, vertex_ids: Any, triangle_ids: Any,
                 vertex_owned: Any, triangle_owned: Any, *, vt: bool = True, ee: bool = True,
                 drop_incident: bool = True, device: Any = None) -> None:
        spec = (array_device(vertices) or "cpu") if device is None else device_spec(device)
        v = _vertices(vertices, "vertices")  # before anything is allocated
        lib = _load()
        self._scene = ctypes.c_void_p()
        self._result = ctypes.c_void_p()
        self._device = ctypes.c_void_p()
        self._comm = comm
        # Arrays this rank checks (shape, the vertices' dtype: every rank must pass the same
        # kinds, as for any collective call); the library checks the rest, collectively.
        arrays: Dict[str, np.ndarray] = {
            "vertices": v, "triangles": _indices(triangles, "triangles", np.int32, (3,)),
            "vertex_ids": _indices(vertex_ids, "vertex_ids", np.int64, ()),
            "triangle_ids": _indices(triangle_ids, "triangle_ids", np.int64, ()),
            "vertex_owned": np.ascontiguousarray(vertex_owned, dtype=np.uint8).reshape(-1),
            "triangle_owned": np.ascontiguousarray(triangle_owned, dtype=np.uint8).reshape(-1),
        }
        assert _core is not None
        _check(_core.minkq_device_create(spec.encode(), ctypes.byref(self._device)), _core.minkq_last_error_message())
        desc = _Desc(flags=(_SCENE_VT if vt else 0) | (_SCENE_EE if ee else 0)
                     | (_SCENE_DROP_INCIDENT if drop_incident else 0))
        for name, array in arrays.items():
            setattr(desc, name, _host(array, len(array)))
        self._vertex_count = len(v)
        _check(lib.minkq_mpi_scene_create(_comm_handle(comm), self._device, ctypes.byref(desc),
                                          ctypes.byref(self._scene)), lib.minkq_mpi_last_error_message())
        _check(lib.minkq_mpi_result_create(ctypes.byref(self._result)), lib.minkq_mpi_last_error_message())

    def close(self) -> None:
        """Releases the scene (collective: every rank closes it); also when it is collected."""
        if _lib is None:
            return
        if getattr(self, "_result", None):
            _lib.minkq_mpi_result_release(self._result)
            self._result = ctypes.c_void_p()
        if getattr(self, "_scene", None):
            _lib.minkq_mpi_scene_release(self._scene)
            self._scene = ctypes.c_void_p()
        if getattr(self, "_device", None) and _core is not None:
            _core.minkq_device_release(self._device)
            self._device = ctypes.c_void_p()

    def __del__(self) -> None:
        self.close()

    def __enter__(self) -> "Scene":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _move(self, vertices: Any, rebuild: bool) -> None:
        v = _vertices(vertices, "vertices")
        call = _lib.minkq_mpi_scene_rebuild if rebuild else _lib.minkq_mpi_scene_refit
        _check(call(self._scene, _host(v, len(v))), _lib.minkq_mpi_last_error_message())

    def refit(self, vertices: Any) -> None:
        """Moves this rank's vertices (the next query refits the local trees). Collective."""
        self._move(vertices, False)

    def rebuild(self, vertices: Any) -> None:
        """Moves this rank's vertices; the next query builds the local trees afresh. Collective."""
        self._move(vertices, True)

    def set_skin(self, skin: float) -> None:
        """Chooses the ghost layer ``skin`` wider and keeps it until a vertex has moved more than
        ``skin / 2``: queries in between send only the ghosts' positions (0: choose it at every
        query). The pairs do not depend on it. Collective (the same skin on every rank)."""
        _check(_lib.minkq_mpi_scene_set_skin(self._scene, float(skin)), _lib.minkq_mpi_last_error_message())

    def _run(self, kind: str, mode: str, radius: float, flags: int) -> None:
        if kind not in _KINDS:
            raise ValueError(f"kind must be one of {tuple(_KINDS)}, not {kind!r}")
        if mode not in _MODES:
            raise ValueError(f"mode must be one of {tuple(_MODES)}, not {mode!r}")
        q = _QueryDesc(_KINDS[kind], _MODES[mode], flags, float(radius))
        _check(_lib.minkq_mpi_scene_query(self._scene, ctypes.byref(q), self._result),
               _lib.minkq_mpi_last_error_message())

    def query(self, kind: str, radius: Any, *_deprecated: Any, mode: str = "box", leaf_exact: bool = False,
              canonical: bool = False, out: Any = None) -> np.ndarray:
        """This rank's pairs, a (k, 2) int64 array of global ids: (vertex, triangle) for "vt",
        (e, f) with e < f for "ee". Modes and ``leaf_exact`` as :meth:`minkq.Scene.query`;
        ``canonical`` sorts this rank's pairs. ``out``: a writable C-contiguous (capacity, 2)
        int64 numpy array (:class:`CapacityError` when short; every rank has its pairs then) or
        a :class:`minkq.PairBuffer` (grown as needed); the result is then ``out[:k]``.
        Collective (the same arguments on every rank)."""
        mode, radius = old_mode_form("query", radius, _deprecated, mode)
        self._run(kind, mode, radius, (_LEAF_EXACT if leaf_exact else 0) | (_CANONICAL if canonical else 0))
        n = int(_lib.minkq_mpi_result_count(self._result))
        target = _target(out, n)
        if n:
            target[:n] = np.ctypeslib.as_array(_lib.minkq_mpi_result_pairs(self._result), shape=(n, 2))
        return target if out is None else target[:n]

    def count(self, kind: str, radius: Any, *_deprecated: Any, mode: str = "box", leaf_exact: bool = False) -> int:
        """The number of this rank's pairs, without keeping them. Collective."""
        mode, radius = old_mode_form("count", radius, _deprecated, mode)
        self._run(kind, mode, radius, _COUNT | (_LEAF_EXACT if leaf_exact else 0))
        return int(_lib.minkq_mpi_result_count(self._result))

    def rank_info(self) -> Dict[str, int]:
        """This rank's figures: owned vertices, triangles and edges, copies, the ghosts of the
        last VT and EE queries, neighbours, the global edge count, local builds and refits, how
        often the ghost layer was chosen afresh or, with a skin, kept and moved, the bytes sent,
        and the last query's bytes and time per phase (ms: floats)."""
        info = _RankInfo()
        _check(_lib.minkq_mpi_scene_rank_info(self._scene, ctypes.byref(info)), _lib.minkq_mpi_last_error_message())
        return {name: getattr(info, name) for name, _ in _RankInfo._fields_}


def _target(out: Any, count: int) -> np.ndarray:
    """The int64 array ``count`` pairs go to: a new one, the caller's (checked), or a
    PairBuffer's (grown with an eighth more room when short)."""
    if out is None:
        return np.empty((count, 2), np.int64)
    if isinstance(out, PairBuffer):
        if out.array is None or len(out.array) < count:
            out.array = np.empty((count + count // 8 + 64, 2), np.int64)
        out = out.array
    if not isinstance(out, np.ndarray) or out.dtype != np.int64 or out.ndim != 2 or out.shape[1] != 2:
        raise TypeError(f"out: expected a (capacity, 2) int64 numpy array or a minkq.PairBuffer, got {type(out).__name__}"
                        f"{'' if not isinstance(out, np.ndarray) else f' of {out.dtype} {out.shape}'}")
    if not (out.flags.c_contiguous and out.flags.writeable):
        raise ValueError("out: expected a writable C-contiguous array")
    if len(out) < count:
        raise CapacityError(f"out: {count} pairs do not fit in {len(out)} rows", needed=count)
    return out
