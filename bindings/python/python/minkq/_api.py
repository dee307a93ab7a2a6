"""The typed Python surface over minkq._native: argument checks with messages naming the
argument; numpy arrays, and arrays of other libraries read in place through DLPack or the CUDA
array interface (minkq._interop), in and out; output arrays sized from the exact counts."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Tuple

import numpy as np

from . import _native
from ._errors import CapacityError, IndexOutOfRangeError
from ._interop import Like, allocate_pairs, checked, checked_count, has_protocol, head, like, stream_handle, view

if TYPE_CHECKING:
    from typing import Literal

    import numpy.typing as npt

    Kind = Literal["vt", "ee"]
    Mode = Literal["box", "sphere", "capsule_ray", "capsule_exact"]
    Shape = Literal["sphere", "capsule", "box"]
    Pairs = npt.NDArray[np.int32]

KINDS = ("vt", "ee")
MODES = ("box", "sphere", "capsule_ray", "capsule_exact")
_DEFAULT_BVH_MODE = {"sphere": "sphere", "capsule": "capsule_exact", "box": "box"}


@dataclass(frozen=True)
class WorkStats:
    """The work of one query (:meth:`Scene.work`; the C API's ``minkq_query_stats``)."""

    nodes_visited: int
    """Internal node records read."""
    node_tests: int
    """Child boxes tested against a query shape."""
    primitive_tests: int
    """Primitives whose box passed, handed to the leaf filter."""
    candidates: int
    """Pairs emitted: the query's pair count."""


@dataclass(frozen=True)
class QueryInfo:
    """What :meth:`Scene.query_into` and :meth:`BVH.query_into` report."""

    count: int
    """The exact number of pairs written."""
    digest: Optional[int]
    """With ``digest=True``: xxHash64 (seed 0) of the canonical little-endian int32 pairs."""


def _rows(value: Any, name: str, dtype: Any, trailing: Tuple[int, ...]) -> np.ndarray:
    """``value`` as a C-contiguous array of shape (n, *trailing) and dtype ``dtype``.

    A C-contiguous numpy array of exactly ``dtype`` (float32 coordinates, int32 indices, native
    byte order) is used in place, without a copy. Other host arrays are converted once, into a
    copy that lives for the call:
    float64 vertices and int64 / uint32 indices, as trimesh and most mesh loaders give, strided
    or byte-swapped arrays, lists and tuples. Coordinates may come from any float or integer
    dtype; indices from integer dtypes only (no rounding of floats), and an index that does not
    fit in int32 raises :class:`~minkq.IndexOutOfRangeError` naming the element instead of
    wrapping around. Arrays of other libraries (DLPack, the CUDA array interface) are never
    converted: see :func:`minkq._interop.checked`.
    """
    dtype = np.dtype(dtype)
    if isinstance(value, np.ndarray):
        array = value
    else:
        try:
            array = np.asarray(value)
        except (TypeError, ValueError) as e:
            raise TypeError(f"{name}: expected an array of {dtype.name}, got {type(value).__name__}: {e}") from None
        if array.size == 0:
            array = array.astype(dtype)
        if array.size == 0 and array.ndim == 1:
            array = array.reshape((0,) + trailing)
    if array.dtype != dtype:
        array = _converted(array, name, dtype)
    if array.ndim != 1 + len(trailing) or array.shape[1:] != trailing:
        wanted = ", ".join(["n"] + [str(d) for d in trailing])
        raise ValueError(f"{name}: expected shape ({wanted}), got {array.shape}")
    if not (array.flags.c_contiguous and array.flags.aligned):
        array = np.require(array, requirements=("C", "A"))  # strided input: a contiguous copy
    return array


def _converted(array: np.ndarray, name: str, dtype: np.dtype) -> np.ndarray:
    """A copy of ``array`` in ``dtype`` (float32 from any real dtype, int32 from integers whose
    values fit), or TypeError / IndexOutOfRangeError naming the argument."""
    kind = array.dtype.kind
    if dtype.kind == "f" and kind in "fiu":
        return array.astype(dtype)
    if dtype.kind == "i" and kind in "iu":
        info = np.iinfo(dtype)
        if array.size:
            for bad in (array < info.min, array > info.max):
                if bad.any():
                    at = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), array.shape))
                    raise IndexOutOfRangeError(
                        f"{name}[{', '.join(map(str, at))}] = {array[at]} does not fit in int32: minkq indices "
                        f"are int32 (0 to {info.max})"
                    )
        return array.astype(dtype)
    hint = " (floats are not rounded to indices)" if kind == "f" else ""
    raise TypeError(f"{name}: expected {dtype.name} values, got {array.dtype}{hint}")


def _boxes(value: Any, name: str) -> np.ndarray:
    """Boxes as (n, 2, 3) float32 (lo, hi); (n, 6) is accepted as (lo x, y, z, hi x, y, z)."""
    if getattr(value, "ndim", None) == 2 or (isinstance(value, (list, tuple)) and value and len(value[0]) == 6):
        flat = _rows(value, name, np.float32, (6,))
        return flat.reshape(-1, 2, 3)
    return _rows(value, name, np.float32, (2, 3))


def _like(array: Any) -> Optional[Like]:
    """What results need of ``array`` (a view or None) to be made like it; the array itself is
    not kept alive."""
    return None if array is None else like(array)


class _Args:
    """Array arguments on their way to minkq._native: numpy arrays as they are (the buffer
    protocol), arrays of other libraries as raw descriptors of their memory (DLPack, the CUDA
    array interface), whose views this object keeps alive until the call has returned."""

    def __init__(self, device: "Device", stream: Optional[int] = None) -> None:
        self.device = device
        self.stream = stream
        """None for the blocking calls; the cudaStream_t of a stream-ordered call."""
        self.views: list = []

    def rows(self, value: Any, name: str, dtype: Any, trailing: Tuple[int, ...]) -> Any:
        if not has_protocol(value):
            return _rows(value, name, dtype, trailing)
        array = checked(view(value, name, self.device, self.stream), name, dtype, trailing)
        self.views.append(array)
        return array.descriptor()

    def boxes(self, value: Any, name: str) -> Any:
        if not has_protocol(value):
            return _boxes(value, name)
        array = view(value, name, self.device)
        array = checked(array, name, np.float32, (6,) if len(array.shape) == 2 else (2, 3))
        self.views.append(array)
        return array.descriptor()

    def out(self, value: Any, name: str = "out") -> Any:
        if isinstance(value, np.ndarray) or not has_protocol(value):
            return _out(value, name)
        array = view(value, name, self.device, self.stream)
        array = checked(array, name, np.int32, (2,), writable=True, packed=True)
        self.views.append(array)
        return array.descriptor()

    def count(self, value: Any, name: str) -> Any:
        """A stream-ordered query's count: a writable (1,) uint64 or int64 array, passed as
        uint64 (a view of the same memory for a numpy int64 array: nothing is copied)."""
        if isinstance(value, np.ndarray) or not has_protocol(value):
            return _count(value, name)
        array = checked_count(view(value, name, self.device, self.stream), name)
        self.views.append(array)
        return array.descriptor()

    def like(self, value: Any, name: str = "like") -> Optional[Like]:
        """The library and device results take (None: numpy)."""
        if value is None or isinstance(value, np.ndarray) or not has_protocol(value):
            return None
        return like(view(value, name, self.device))

    @property
    def last(self) -> Any:
        """The last array viewed (a minkq._interop.Foreign), or None."""
        return self.views[-1] if self.views else None


def _radius(radius: Any) -> float:
    if isinstance(radius, bool) or not isinstance(radius, (int, float, np.integer, np.floating)):
        raise TypeError(f"radius: expected a number, got {type(radius).__name__}")
    return float(radius)


def _choice(value: Any, name: str, choices: Tuple[str, ...]) -> str:
    if value not in choices:
        raise ValueError(f"{name}: expected one of {', '.join(repr(c) for c in choices)}, got {value!r}")
    return str(value)


def _out(out: Any, name: str = "out") -> np.ndarray:
    if not isinstance(out, np.ndarray):
        raise TypeError(
            f"{name}: expected a numpy array or an array with __dlpack__ or __cuda_array_interface__, got {type(out).__name__}"
        )
    if out.dtype != np.int32:
        raise TypeError(f"{name}: expected an int32 array, got {out.dtype}")
    if out.ndim != 2 or out.shape[1] != 2:
        raise ValueError(f"{name}: expected shape (capacity, 2), got {out.shape}")
    if not (out.flags.c_contiguous and out.flags.aligned):
        raise ValueError(f"{name}: expected a C-contiguous array")
    if not out.flags.writeable:
        raise ValueError(f"{name}: the array is read-only")
    return out


def _count(count: Any, name: str) -> np.ndarray:
    """A numpy (1,) uint64 / int64 count as a uint64 view of the same memory."""
    if not isinstance(count, np.ndarray):
        raise TypeError(
            f"{name}: expected a (1,) uint64 numpy array or an array with __dlpack__ or __cuda_array_interface__, got "
            f"{type(count).__name__}"
        )
    if count.dtype not in (np.dtype(np.uint64), np.dtype(np.int64)) or not count.dtype.isnative:
        raise TypeError(f"{name}: expected a uint64 or int64 array, got {count.dtype}")
    if count.shape != (1,):
        raise ValueError(f"{name}: expected shape (1,), got {count.shape}")
    if not count.flags.aligned:
        raise ValueError(f"{name}: the data address is not 8-byte aligned")
    if not count.flags.writeable:
        raise ValueError(f"{name}: the array is read-only")
    return count.view(np.uint64)


def _with_headroom(count: int) -> int:
    """Room for ``count`` pairs and an eighth more (at least 64)."""
    return count + count // 8 + 64


class _SizedQueries:
    """Runs queries into arrays sized by the last count of the same query and an eighth more
    (one run per call while a simulation's counts drift by less than that) and regrown to the
    exact count on CapacityError. The arrays are numpy arrays, or arrays of the library and
    device of ``like`` (a Warp array gives Warp results on its device)."""

    device: "Device"

    def __init__(self) -> None:
        self._last_count: Dict[Tuple[Any, ...], int] = {}

    def _run(self, key: Tuple[Any, ...], run: Callable[[Any], Tuple[int, Optional[int]]], like: Optional[Like] = None) -> Tuple[Any, Optional[int]]:
        ((pairs, digest),) = self._run_outputs([key], lambda out: (run(out),), like, lambda e: 0)
        return pairs, digest

    def _run_outputs(
        self,
        keys: List[Tuple[Any, ...]],
        run: Callable[..., Tuple[Tuple[int, Optional[int]], ...]],
        like: Optional[Like],
        short: Callable[[CapacityError], int],
    ) -> List[Tuple[Any, Optional[int]]]:
        """Runs ``run(*outs)``, one array per key, each sized by the last count under its key; on
        CapacityError the array ``short(e)`` names regrows to ``e.needed`` and the call runs again
        (at most once per array). Returns (pairs, digest) per key."""
        like_key = (None if like is None else (like.kind, like.cuda),)
        keys = [k + like_key for k in keys]
        capacity = [_with_headroom(self._last_count[k]) if k in self._last_count else 0 for k in keys]
        for attempt in range(len(keys) + 1):
            outs = [allocate_pairs(like, c) for c in capacity]
            args = _Args(self.device)
            try:
                results = run(*[args.out(out) for out in outs])
                break
            except CapacityError as e:
                if attempt == len(keys):
                    raise
                capacity[short(e)] = e.needed
        pairs = []
        for key, out, (count, digest) in zip(keys, outs, results):
            self._last_count[key] = count
            # Do not keep a much larger array alive behind a small result.
            pairs.append((head(out, count, 2 * count < len(out)), digest))
        return pairs


class Device:
    """A compute device: ``"cpu"``, ``"cuda"`` (GPU 0), ``"cuda:N"`` or ``"auto"`` (CUDA when a GPU
    is usable, else the CPU). Scenes and BVHs are built on a device and keep it alive.

    >>> import minkq
    >>> minkq.Device("cpu").backend
    'cpu'

    Raises :class:`InvalidArgumentError` for an unknown spec and :class:`UnsupportedError` for CUDA
    where there is none.
    """

    def __init__(self, spec: str = "auto") -> None:
        if not isinstance(spec, str):
            raise TypeError(f"spec: expected a str, got {type(spec).__name__}")
        self._native = _native.Device(spec)

    @property
    def name(self) -> str:
        """A description such as ``"cpu (8 threads)"`` or ``"cuda:0 (NVIDIA H100 80GB HBM3)"``."""
        return self._native.name

    @property
    def backend(self) -> str:
        """``"cpu"`` or ``"cuda"``."""
        return self._native.backend

    @property
    def ordinal(self) -> Optional[int]:
        """The CUDA device number (``cuda:N``) of a CUDA device; None for the CPU."""
        if self.backend != "cuda":
            return None
        return int(self.name.split()[0].split(":")[1])

    def __repr__(self) -> str:
        return f"minkq.Device({self.name!r})"


class Scene(_SizedQueries):
    """A triangle mesh on a device with the BVHs for VT and/or EE queries.

    ``vertices``: (n, 3) float32; ``triangles``: (m, 3) int32; ``edges``: (e, 2) int32, or None
    (or an empty array) to derive them from the triangles (every distinct undirected edge as
    (min, max), sorted).
    C-contiguous numpy arrays of exactly these dtypes are used without a copy; other host
    arrays (float64 vertices, int64 indices, ...) are converted once: a copy is made (an index
    that does not fit in int32 raises IndexOutOfRangeError naming it). Arrays of other
    libraries must have exactly these dtypes.
    ``vt`` / ``ee`` say which queries the scene answers; ``drop_incident`` drops (v, t) with v
    a vertex of t and pairs of edges sharing a vertex (the cloth self-collision set-up).

    Arrays of other libraries (Warp arrays, PyTorch and CuPy tensors: anything with
    ``__dlpack__`` or ``__cuda_array_interface__``) are read in place, in host memory or, on a
    CUDA device, in device memory on their GPU, with their stream respected (see
    minkq._interop). They must have these dtypes and shapes, each row contiguous (rows may lie
    at any stride, e.g. the last two columns of an (e, 4) edge table); they are never copied or
    converted, and a CUDA array on a CPU device or another GPU raises
    :class:`InvalidArgumentError`. Queries then return arrays of the vertices' library and
    device (or of ``like``): Warp, PyTorch and CuPy arrays, numpy for other host arrays; for
    device arrays of other libraries (e.g. Numba) pass your own array to :meth:`query_into`.

    The GIL is released while the scene is built, refitted, rebuilt and queried. One scene may
    be used from several threads: calls on it wait for each other (as do builds on one device).
    Do not change an input array from another thread while a call that reads it runs.

    >>> import numpy as np, minkq
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
    >>> t = np.array([[0, 1, 2], [3, 4, 5]], np.int32)
    >>> scene = minkq.Scene(minkq.Device("cpu"), v, t)
    >>> scene.query("vt", "sphere", 0.2, leaf_exact=True, canonical=True).tolist()
    [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]

    Raises :class:`NonFiniteError`, :class:`IndexOutOfRangeError`, :class:`SizeOverflowError` or
    :class:`InvalidArgumentError` (with the library's message) for bad input, and
    TypeError / ValueError naming the argument for a wrong dtype or shape.
    """

    def __init__(
        self,
        device: Device,
        vertices: Any,
        triangles: Any,
        edges: Any = None,
        *,
        vt: bool = True,
        ee: bool = True,
        drop_incident: bool = True,
    ) -> None:
        super().__init__()
        if not isinstance(device, Device):
            raise TypeError(f"device: expected a minkq.Device, got {type(device).__name__}")
        self.device = device
        args = _Args(device)
        vertices = args.rows(vertices, "vertices", np.float32, (3,))
        self._like = _like(args.last)
        triangles = args.rows(triangles, "triangles", np.int32, (3,))
        if edges is not None:
            edges = args.rows(edges, "edges", np.int32, (2,))
        self._native = _native.Scene(device._native, vertices, triangles, edges, bool(vt), bool(ee), bool(drop_incident))
        self._stream = 0  # the stream of the last stream-ordered call, for async_status

    @property
    def vertex_count(self) -> int:
        """The number of vertices."""
        return self._native.vertex_count

    @property
    def triangle_count(self) -> int:
        """The number of triangles."""
        return self._native.triangle_count

    @property
    def edge_count(self) -> int:
        """The number of edges (given, or derived for an EE scene)."""
        return self._native.edge_count

    def edges(self) -> "Pairs":
        """The scene's edges as an (edge_count, 2) int32 numpy array, numbered as EE pairs number
        them."""
        out = np.empty((self.edge_count, 2), dtype=np.int32)
        self._native.edges_into(out)
        return out

    def refit(self, vertices: Any) -> None:
        """Moves the vertices ((n, 3) float32, same n; numpy or read in place as in the
        constructor) and refits the trees in place: the per-step call of a simulation. On error
        the scene keeps its previous positions. A refit keeps the grouping of the last build:
        after large deformations the boxes overlap more and queries visit more nodes
        (:meth:`tree_growth` measures it, :meth:`rebuild` resets it); the pairs found never
        change."""
        args = _Args(self.device)
        native = args.rows(vertices, "vertices", np.float32, (3,))
        self._native.refit(native)
        self._like = _like(args.last)

    def rebuild(self, vertices: Any) -> None:
        """Moves the vertices like :meth:`refit` and builds the trees afresh for the new
        positions: the trees the constructor would build there, with the same triangles, edges
        and edge numbering. The pairs are those of a refit; only the speed of later queries
        differs. Worth it once large motions have raised :meth:`tree_growth` (above about 1.5),
        and every so many steps when the mesh changes shape a lot. Same errors as
        :meth:`refit`; on error the scene keeps its positions and trees.

        >>> import numpy as np, minkq
        >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
        >>> scene = minkq.Scene(minkq.Device("cpu"), v, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> v[3:, 2] = 1.0  # lift the upper triangle away
        >>> scene.rebuild(v)
        >>> scene.query("vt", "sphere", 0.2).tolist(), scene.tree_growth()
        ([], 1.0)
        """
        args = _Args(self.device)
        native = args.rows(vertices, "vertices", np.float32, (3,))
        self._native.rebuild(native)
        self._like = _like(args.last)

    def tree_growth(self) -> float:
        """How far the refits since the last build (the constructor or :meth:`rebuild`) have
        stretched the trees: their area cost (scale-free; it grows with the nodes a query
        visits) now over its value right after that build, the larger of the scene's two trees.
        1.0 after a build. It sees boxes that stretch, not a mesh folding or flattening into new
        neighbours (where a rebuild can still help). Rebuild when it passes about 1.5, and every
        so many steps when the mesh changes shape a lot (the C header; what rebuilds bought on
        the benchmark scenes is in ``bench/README.md``). A tree whose elements all lie on one
        line parallel to an axis (or at one point) has no area: 1.0 while it stays so, ``inf``
        once it has any.

        >>> import numpy as np, minkq
        >>> u, v = np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 9))
        >>> flat = np.stack([u.ravel(), v.ravel(), np.zeros(81)], 1).astype(np.float32)
        >>> i, j = np.meshgrid(np.arange(8), np.arange(8))
        >>> v00 = (j * 9 + i).ravel()
        >>> tris = np.concatenate([np.stack([v00, v00 + 1, v00 + 10], 1), np.stack([v00, v00 + 10, v00 + 9], 1)])
        >>> scene = minkq.Scene(minkq.Device("cpu"), flat, tris.astype(np.int32))
        >>> scene.tree_growth()
        1.0
        >>> a = 2 * np.pi * flat[:, 0]  # rolled up into a tube
        >>> tube = np.stack([np.cos(a), flat[:, 1], np.sin(a)], 1).astype(np.float32)
        >>> scene.refit(tube)
        >>> scene.tree_growth() > 1.5
        True
        >>> scene.rebuild(tube)
        >>> scene.tree_growth()
        1.0
        """
        return self._native.tree_growth()

    def query(
        self,
        kind: "Kind",
        mode: "Mode",
        radius: float,
        *,
        leaf_exact: bool = False,
        canonical: bool = False,
        like: Any = None,
    ) -> "Pairs":
        """Pairs within ``radius`` as a (k, 2) int32 array: (vertex, triangle) for ``kind="vt"``,
        (e, f) with e < f for ``"ee"``.

        ``mode`` is the node test, from fast to tight: ``"box"``, ``"sphere"`` (VT only),
        ``"capsule_ray"``, ``"capsule_exact"``. ``leaf_exact=True`` tests the primitives at the
        leaves, so that the pairs are the true contacts (plus, at most, pairs within
        r + 2**-19 S). ``canonical=True`` sorts the pairs.

        The result is a numpy array, or an array of the library and device of the vertices last
        given (a Warp array on ``cuda:0`` gives a Warp array on ``cuda:0``, written there in
        place), or of ``like`` when given.
        """
        return self._query(kind, mode, radius, leaf_exact, canonical, False, like)[0]

    def query_digest(
        self, kind: "Kind", mode: "Mode", radius: float, *, leaf_exact: bool = False, like: Any = None
    ) -> Tuple["Pairs", int]:
        """Like :meth:`query`, canonical, with the xxHash64 (seed 0) of the little-endian pairs:
        equal across backends, runs and language bindings."""
        pairs, digest = self._query(kind, mode, radius, leaf_exact, True, True, like)
        assert digest is not None
        return pairs, digest

    def query_into(
        self,
        out: Any,
        kind: "Kind",
        mode: "Mode",
        radius: float,
        *,
        leaf_exact: bool = False,
        canonical: bool = False,
        digest: bool = False,
    ) -> QueryInfo:
        """Runs a query into ``out``, a writable C-contiguous (capacity, 2) int32 array (numpy,
        or another library's host or, on a CUDA device, device array written in place); pairs
        go to ``out[:count]``. Raises :class:`CapacityError` (``needed``: the exact count) when
        ``out`` is too small, writing nothing past it."""
        args = _Args(self.device)
        checked_args = (args.out(out), _choice(kind, "kind", KINDS), _choice(mode, "mode", MODES), _radius(radius))
        count, dig = self._native.query_into(*checked_args, bool(leaf_exact), bool(canonical), bool(digest))
        return QueryInfo(count, dig)

    def query_vt_ee(
        self,
        radius: float,
        *,
        vt_mode: "Mode" = "box",
        ee_mode: "Mode" = "box",
        leaf_exact: bool = False,
        canonical: bool = False,
        like: Any = None,
    ) -> Tuple["Pairs", "Pairs"]:
        """The VT and the EE pairs within ``radius`` from one pass (one parallel loop on the CPU,
        one kernel launch and one count readback on CUDA): exactly what ``query("vt", vt_mode,
        ...)`` and ``query("ee", ee_mode, ...)`` return. ``leaf_exact=True`` gives the contacts
        (meant for the default box modes: bench/README.md). Results as :meth:`query`.

        >>> import numpy as np, minkq
        >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0.1], [1, 0, 0.1], [0, 1, 0.1]], np.float32)
        >>> scene = minkq.Scene(minkq.Device("cpu"), xyz, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> vt, ee = scene.query_vt_ee(0.2, leaf_exact=True, canonical=True)
        >>> vt.tolist()
        [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]
        >>> len(ee)
        9
        """
        vt_mode = _choice(vt_mode, "vt_mode", MODES)
        ee_mode = _choice(ee_mode, "ee_mode", MODES)
        r = _radius(radius)
        flags = (bool(leaf_exact), bool(canonical), False)
        target = self._like if like is None else _Args(self.device).like(like)
        key = (vt_mode, ee_mode) + flags
        (vt, _), (ee, _) = self._run_outputs(
            [("vt",) + key, ("ee",) + key],
            lambda vt_out, ee_out: self._native.query_vt_ee_into(vt_out, ee_out, vt_mode, ee_mode, r, *flags),
            target,
            lambda e: 0 if e.message.startswith("VT:") else 1,  # the first short buffer, VT before EE
        )
        return vt, ee

    # ---- Stream-ordered calls ----------------------------------------------------------------

    def reserve(self, refit: bool = True, rebuild: bool = False, canonical_capacity: int = 0) -> None:
        """Reserves, on the scene's device, the scratch the stream-ordered calls use, so that
        they never allocate: ``refit`` for :meth:`refit_async`, ``rebuild`` for
        :meth:`rebuild_async` (and refits), and ``canonical_capacity`` pairs for the sort of
        ``canonical=True`` :meth:`query_async` calls (whose capacity may not exceed it; other
        queries need no reservation). Reservations only grow and last as long as the scene. A
        blocking call (it may allocate and synchronise): call it before capturing a graph.

        >>> import numpy as np, minkq
        >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
        >>> scene = minkq.Scene(minkq.Device("cpu"), v, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> scene.reserve(refit=True, canonical_capacity=64)
        >>> pairs, count = np.zeros((64, 2), np.int32), np.zeros(1, np.uint64)
        >>> v[3:, 2] = 0.15
        >>> scene.refit_async(v)
        >>> scene.query_async(pairs, count, "vt", "sphere", 0.2, canonical=True)
        >>> scene.async_status()  # waits for the stream; raises if a refit met a NaN
        >>> int(count[0]), pairs[: count[0]].tolist()
        (6, [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]])
        """
        if isinstance(canonical_capacity, bool) or not isinstance(canonical_capacity, (int, np.integer)):
            raise TypeError(f"canonical_capacity: expected an int, got {type(canonical_capacity).__name__}")
        if canonical_capacity < 0:
            raise ValueError(f"canonical_capacity: expected a count >= 0, got {canonical_capacity}")
        self._native.reserve(bool(refit), bool(rebuild), int(canonical_capacity))

    def refit_async(self, vertices: Any, stream: Any = None) -> None:
        """:meth:`refit`, enqueued on ``stream`` without waiting, allocating or synchronising
        (``minkq_scene_refit_async``), so that it can be captured into a CUDA graph (e.g. in
        ``wp.ScopedCapture``). On a CUDA device ``vertices`` are device memory (a Warp, PyTorch
        or CuPy array on the scene's GPU), read when the stream runs the work: keep them alive
        (for a captured graph, as long as it is replayed). On the CPU they are host memory
        (numpy, or a Warp CPU array) and the refit has run when this returns.

        ``stream``: None for the current stream of the array's library (Warp:
        ``wp.get_stream(device)``, the capture stream inside ``wp.ScopedCapture``; PyTorch:
        ``torch.cuda.current_stream(device)``; CuPy: ``cupy.cuda.get_current_stream()``), or an
        int (a ``cudaStream_t``) or a stream with ``.cuda_stream`` / ``.ptr``; ignored on the
        CPU. Needs :meth:`reserve` (``refit=True``): :class:`InvalidArgumentError` without it.
        A NaN or infinity is no error here: the scene keeps its positions and
        :meth:`async_status` raises :class:`NonFiniteError`, naming the call and the vertex."""
        self._move_async(vertices, stream, self._native.refit_async)

    def rebuild_async(self, vertices: Any, stream: Any = None) -> None:
        """:meth:`rebuild`, enqueued on ``stream`` as :meth:`refit_async` is
        (``minkq_scene_rebuild_async``). Needs :meth:`reserve` with ``rebuild=True``."""
        self._move_async(vertices, stream, self._native.rebuild_async)

    def query_async(
        self,
        out_pairs: Any,
        out_count: Any,
        kind: "Kind",
        mode: "Mode",
        radius: float,
        *,
        leaf_exact: bool = False,
        canonical: bool = False,
        stream: Any = None,
    ) -> None:
        """:meth:`query_into`, enqueued on ``stream`` (``minkq_scene_query_async``): writes the
        exact number of pairs to ``out_count[0]`` (a (1,) uint64 or int64 array), also when it
        exceeds the capacity of ``out_pairs`` ((capacity, 2) int32, C-contiguous), and
        min(count, capacity) of the pairs, never past it (which ones, when they do not all fit,
        is unspecified, as is their order). Never :class:`CapacityError`: read the count, and grow the array
        between steps when it says so. On a CUDA device both arrays are device memory on the
        scene's GPU, written when the stream runs the work (the count is never copied to the
        host); on the CPU they are host memory, written when this returns. ``stream`` as in
        :meth:`refit_async` (None: the current stream of ``out_pairs``'s library).
        ``canonical=True`` sorts the pairs when they fit and needs the capacity reserved
        (:meth:`reserve`)."""
        kind = _choice(kind, "kind", KINDS)
        mode = _choice(mode, "mode", MODES)
        r = _radius(radius)
        handle = stream_handle(stream, self.device, (out_pairs, out_count))
        args = _Args(self.device, handle)
        native = (args.out(out_pairs, "out_pairs"), args.count(out_count, "out_count"))
        self._native.query_async(*native, kind, mode, r, bool(leaf_exact), bool(canonical), handle)
        self._stream = handle

    def query_vt_ee_async(
        self,
        vt_pairs: Any,
        vt_count: Any,
        ee_pairs: Any,
        ee_count: Any,
        radius: float,
        *,
        vt_mode: "Mode" = "box",
        ee_mode: "Mode" = "box",
        leaf_exact: bool = False,
        canonical: bool = False,
        stream: Any = None,
    ) -> None:
        """:meth:`query_vt_ee`, enqueued on ``stream`` (``minkq_scene_query_vt_ee_async``: one
        kernel launch on CUDA): each query's pairs and count as :meth:`query_async` writes them
        alone. ``vt_count`` and ``ee_count`` must be different arrays."""
        vt_mode = _choice(vt_mode, "vt_mode", MODES)
        ee_mode = _choice(ee_mode, "ee_mode", MODES)
        r = _radius(radius)
        handle = stream_handle(stream, self.device, (vt_pairs, vt_count, ee_pairs, ee_count))
        args = _Args(self.device, handle)
        native = (
            args.out(vt_pairs, "vt_pairs"),
            args.count(vt_count, "vt_count"),
            args.out(ee_pairs, "ee_pairs"),
            args.count(ee_count, "ee_count"),
        )
        self._native.query_vt_ee_async(*native, vt_mode, ee_mode, r, bool(leaf_exact), bool(canonical), handle)
        self._stream = handle

    def async_status(self, stream: Any = None) -> None:
        """Waits for the work enqueued on ``stream`` (CUDA; None: the stream of this scene's
        last stream-ordered call), then raises the scene's pending error and clears it:
        :class:`NonFiniteError` when a :meth:`refit_async` or :meth:`rebuild_async` since the
        last call met a NaN or infinity (the first such call, named in the message with the
        vertex; the scene kept its positions). Afterwards the counts and pairs of the queries
        enqueued on the stream are ready. A blocking call: not for inside a graph capture."""
        handle = self._stream if stream is None else stream_handle(stream, self.device)
        self._native.async_status(handle)

    def _move_async(self, vertices: Any, stream: Any, call: Callable[[Any, int], None]) -> None:
        handle = stream_handle(stream, self.device, (vertices,))
        args = _Args(self.device, handle)
        native = args.rows(vertices, "vertices", np.float32, (3,))
        call(native, handle)
        self._like = _like(args.last)
        self._stream = handle

    def work(self, kind: "Kind", mode: "Mode", radius: float, *, leaf_exact: bool = False) -> "WorkStats":
        """Runs the query once with the library's work counters on and returns them (the pairs
        are not kept). The counts depend only on the tree and the queries: the same on every
        backend.

        >>> import numpy as np, minkq
        >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.1]], np.float32)
        >>> scene = minkq.Scene(minkq.Device("cpu"), xyz, np.array([[0, 1, 2]], np.int32))
        >>> w = scene.work("vt", "sphere", 0.2)
        >>> (w.candidates, w.primitive_tests >= w.candidates)
        (1, True)
        """
        checked = (_choice(kind, "kind", KINDS), _choice(mode, "mode", MODES), _radius(radius))
        return WorkStats(*self._native.work(*checked, bool(leaf_exact)))

    def _query(self, kind: Any, mode: Any, radius: Any, leaf_exact: bool, canonical: bool, digest: bool, like: Any) -> Tuple[Any, Optional[int]]:
        kind = _choice(kind, "kind", KINDS)
        mode = _choice(mode, "mode", MODES)
        r = _radius(radius)
        flags = (bool(leaf_exact), bool(canonical), bool(digest))
        target = self._like if like is None else _Args(self.device).like(like)
        return self._run((kind, mode) + flags, lambda out: self._native.query_into(out, kind, mode, r, *flags), target)

    def __repr__(self) -> str:
        return f"minkq.Scene({self.vertex_count} vertices, {self.triangle_count} triangles, {self.edge_count} edges)"


class BVH(_SizedQueries):
    """A BVH over user boxes: (n, 2, 3) float32 (lo, hi), or (n, 6) as lo x, y, z, hi x, y, z,
    with lo <= hi. Answers sphere, capsule and box queries; pairs are (query, box). Arrays of
    other libraries are read in place as by :class:`Scene`; results take the library and device
    of the query array (or of ``like``).

    >>> import numpy as np, minkq
    >>> boxes = np.array([[[0, 0, 0], [1, 1, 1]], [[2, 2, 2], [3, 3, 3]]], np.float32)
    >>> bvh = minkq.BVH(minkq.Device("cpu"), boxes)
    >>> centres = np.array([[1.5, 1.5, 1.5], [0.5, 0.5, 0.5]], np.float32)
    >>> bvh.query("sphere", centres, 0.5).tolist()
    [[1, 0]]
    """

    def __init__(self, device: Device, boxes: Any) -> None:
        super().__init__()
        if not isinstance(device, Device):
            raise TypeError(f"device: expected a minkq.Device, got {type(device).__name__}")
        self.device = device
        args = _Args(device)
        self._native = _native.Bvh(device._native, args.boxes(boxes, "boxes"))

    def __len__(self) -> int:
        return self._native.box_count

    def refit(self, boxes: Any) -> None:
        """New boxes (same count); refits in place. The tree keeps the grouping of its last
        build (:meth:`tree_growth` measures how much that costs, :meth:`rebuild` resets it)."""
        args = _Args(self.device)
        self._native.refit(args.boxes(boxes, "boxes"))

    def rebuild(self, boxes: Any) -> None:
        """New boxes (same count); builds the tree afresh, as the constructor would. The pairs
        are those of a refit; only the speed of later queries differs. Same errors as
        :meth:`refit`; on error the BVH keeps its boxes and tree."""
        args = _Args(self.device)
        self._native.rebuild(args.boxes(boxes, "boxes"))

    def tree_growth(self) -> float:
        """The tree's area cost now over its value right after the last build, as
        :meth:`Scene.tree_growth`: 1.0 after a build.

        >>> import numpy as np, minkq
        >>> lo = np.repeat(np.arange(16, dtype=np.float32)[:, None], 3, axis=1)
        >>> boxes = np.stack([lo, lo + 1], axis=1)  # unit boxes along a diagonal
        >>> bvh = minkq.BVH(minkq.Device("cpu"), boxes)
        >>> mixed = boxes.copy()
        >>> mixed[1::2] = boxes[::-1][1::2]  # every other box moved to the mirror position
        >>> bvh.refit(mixed)
        >>> bvh.tree_growth() > 1.5
        True
        >>> bvh.rebuild(mixed)
        >>> bvh.tree_growth()
        1.0
        """
        return self._native.tree_growth()

    def query(
        self,
        shape: "Shape",
        queries: Any,
        radius: float = 0.0,
        *,
        mode: Optional["Mode"] = None,
        canonical: bool = False,
        like: Any = None,
    ) -> "Pairs":
        """(query, box) pairs for every query shape overlapping a box, as a (k, 2) int32 array.

        ``shape="sphere"``: ``queries`` are centres (n, 3) float32; modes ``"box"``, ``"sphere"``
        (default). ``"capsule"``: segments (n, 2, 3) float32; modes ``"box"``, ``"capsule_ray"``,
        ``"capsule_exact"`` (default). ``"box"``: boxes (n, 2, 3) or (n, 6); mode ``"box"``,
        radius 0.
        """
        return self._query(shape, queries, radius, mode, canonical, False, like)[0]

    def query_digest(
        self, shape: "Shape", queries: Any, radius: float = 0.0, *, mode: Optional["Mode"] = None, like: Any = None
    ) -> Tuple["Pairs", int]:
        """Like :meth:`query`, canonical, with the xxHash64 of the pairs."""
        pairs, digest = self._query(shape, queries, radius, mode, True, True, like)
        assert digest is not None
        return pairs, digest

    def query_into(
        self,
        out: Any,
        shape: "Shape",
        queries: Any,
        radius: float = 0.0,
        *,
        mode: Optional["Mode"] = None,
        canonical: bool = False,
        digest: bool = False,
    ) -> QueryInfo:
        """Runs queries into ``out`` ((capacity, 2) int32, numpy or read in place as by
        :meth:`Scene.query_into`); :class:`CapacityError` when too small."""
        args = _Args(self.device)
        native_args = self._args(args, shape, queries, radius, mode)
        count, dig = self._native.query_into(args.out(out), *native_args, bool(canonical), bool(digest))
        return QueryInfo(count, dig)

    def _args(self, args: _Args, shape: Any, queries: Any, radius: Any, mode: Any) -> Tuple[str, Any, str, float]:
        shape = _choice(shape, "shape", ("sphere", "capsule", "box"))
        mode = _DEFAULT_BVH_MODE[shape] if mode is None else _choice(mode, "mode", MODES)
        if shape == "sphere":
            array = args.rows(queries, "centres", np.float32, (3,))
        elif shape == "capsule":
            array = args.rows(queries, "segments", np.float32, (2, 3))
        else:
            array = args.boxes(queries, "boxes")
        return shape, array, mode, _radius(radius)

    def _query(self, shape: Any, queries: Any, radius: Any, mode: Any, canonical: bool, digest: bool, like: Any) -> Tuple[Any, Optional[int]]:
        args = _Args(self.device)
        native_args = self._args(args, shape, queries, radius, mode)
        target = _like(args.last) if like is None else args.like(like)
        count = native_args[1][2] if isinstance(native_args[1], tuple) else len(native_args[1])
        key = (native_args[0], native_args[2], count, bool(canonical), bool(digest))
        return self._run(key, lambda out: self._native.query_into(out, *native_args, bool(canonical), bool(digest)), target)

    def __repr__(self) -> str:
        return f"minkq.BVH({len(self)} boxes)"


def cuda_device_count() -> int:
    """The number of usable CUDA devices (0 where minkq was built without CUDA or has no GPU)."""
    return _native.cuda_device_count()


def version() -> Tuple[int, int, int]:
    """The library's run-time version (major, minor, patch)."""
    return _native.version()


def abi_version() -> int:
    """The library's run-time ABI version (``minkq.ABI_VERSION`` is the one the bindings were
    generated against)."""
    return _native.abi_version()
