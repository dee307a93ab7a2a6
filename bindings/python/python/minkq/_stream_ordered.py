"""A scene's stream-ordered calls, for a simulation step captured into a CUDA graph: the
reservation, the refits, rebuilds and swept steps, and the queries enqueued on a stream, and
the pending error (``minkq_scene_*_async``). :class:`minkq.Scene` takes them from
:class:`_StreamOrdered`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict

import numpy as np

from ._args import KINDS, MODES, _Args, _choice, _radius
from ._conventions import old_mode_form
from ._interop import stream_handle

if TYPE_CHECKING:
    from ._args import Kind, Mode
    from ._device import Device


class _StreamOrdered:
    """The stream-ordered calls of :class:`minkq.Scene` (documented there)."""

    device: "Device"
    _native: Any
    _stream: int
    """The stream of the last stream-ordered call, for :meth:`async_status`."""

    if TYPE_CHECKING:

        def _move(self, call: Callable[..., None], positions: Dict[str, Any], stream: Any = ...) -> None: ...

    def reserve(
        self, refit: bool = True, rebuild: bool = False, canonical_capacity: int = 0, *, swept: bool = False
    ) -> None:
        """Reserves, on the scene's device, the scratch the stream-ordered calls use, so that
        they never allocate: ``refit`` for :meth:`refit_async`, ``rebuild`` for
        :meth:`rebuild_async` (and refits), ``swept`` with either for the swept ones
        (:meth:`refit_swept_async` needs ``refit`` and ``swept``, :meth:`rebuild_swept_async`
        ``rebuild`` and ``swept``: two more copies of the vertices), and ``canonical_capacity``
        pairs for the sort of ``canonical=True`` :meth:`query_async` calls (whose capacity may
        not exceed it; other queries need no reservation). Reservations only grow and last as
        long as the scene. A blocking call (it may allocate and synchronise): call it before
        capturing a graph.

        >>> import numpy as np, minkq
        >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
        >>> scene = minkq.Scene(v, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> scene.reserve(refit=True, canonical_capacity=64)
        >>> pairs, count = np.zeros((64, 2), np.int32), np.zeros(1, np.uint64)
        >>> v[3:, 2] = 0.15
        >>> scene.refit_async(v)
        >>> scene.query_async(pairs, count, "vt", 0.2, mode="sphere", canonical=True)
        >>> scene.async_status()  # waits for the stream; raises if a refit met a NaN
        >>> int(count[0]), pairs[: count[0]].tolist()
        (6, [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]])
        """
        if isinstance(canonical_capacity, bool) or not isinstance(canonical_capacity, (int, np.integer)):
            raise TypeError(f"canonical_capacity: expected an int, got {type(canonical_capacity).__name__}")
        if canonical_capacity < 0:
            raise ValueError(f"canonical_capacity: expected a count >= 0, got {canonical_capacity}")
        self._native.reserve(bool(refit), bool(rebuild), bool(swept), int(canonical_capacity))

    def refit_async(self, vertices: Any, stream: Any = None) -> None:
        """:meth:`refit`, enqueued on ``stream`` without waiting, allocating or synchronising
        (``minkq_scene_refit_async``), so that it can be captured into a CUDA graph (e.g. in
        ``wp.ScopedCapture``). On a CUDA device ``vertices`` are device memory (a Warp, PyTorch
        or CuPy array on the scene's GPU), read when the stream runs the work: keep them alive
        (for a captured graph, as long as it is replayed). On the CPU they are host memory
        (numpy, or a Warp CPU array) and the refit has run when this returns. Nothing is
        converted: the vertices have the scene's :attr:`dtype` (a float64 scene takes float64
        only).

        ``stream``: None for the current stream of the array's library (Warp:
        ``wp.get_stream(device)``, the capture stream inside ``wp.ScopedCapture``; PyTorch:
        ``torch.cuda.current_stream(device)``; CuPy: ``cupy.cuda.get_current_stream()``), or an
        int (a ``cudaStream_t``) or a stream with ``.cuda_stream`` / ``.ptr``; ignored on the
        CPU. Needs :meth:`reserve` (``refit=True``): :class:`InvalidArgumentError` without it.
        A NaN or infinity (or, in a float64 scene, a double beyond the float range) is no
        error here: the scene keeps its positions and
        :meth:`async_status` raises :class:`NonFiniteError`, naming the call and the vertex."""
        self._move(self._native.refit_async, {"vertices": vertices}, stream)

    def rebuild_async(self, vertices: Any, stream: Any = None) -> None:
        """:meth:`rebuild`, enqueued on ``stream`` as :meth:`refit_async` is
        (``minkq_scene_rebuild_async``). Needs :meth:`reserve` with ``rebuild=True``."""
        self._move(self._native.rebuild_async, {"vertices": vertices}, stream)

    def refit_swept_async(self, x0: Any, x1: Any, stream: Any = None) -> None:
        """:meth:`refit_swept`, enqueued on ``stream`` as :meth:`refit_async` is
        (``minkq_scene_refit_swept_async``): ``x0`` and ``x1`` are device memory on a CUDA
        device (kept alive until the stream has run the work), host memory on the CPU, both of
        the scene's :attr:`dtype` (a float64 scene takes float64 only). ``stream=None`` is the
        current stream of the library of the first array that has one; each array's own stream
        is ordered before the call as for :meth:`refit_async`. Needs :meth:`reserve` with
        ``refit=True, swept=True``: :class:`InvalidArgumentError` without it. Both arrays are
        checked together on the device: with a NaN or infinity in either, the scene stays at
        rest at the start positions it kept (of its last accepted step, or its static
        positions; not this call's ``x0``) as both ends, so that its queries give the static
        pairs there while :attr:`is_swept` is True, and :meth:`async_status` raises
        :class:`NonFiniteError` naming the call and the vertex.

        >>> import numpy as np, minkq
        >>> x0 = np.array([[0, -1, -1], [0, 2, -1], [0, -1, 2], [-1, .1, .1]], np.float32)
        >>> x1 = x0.copy()
        >>> x1[3, 0] = 1.0  # the flying vertex of refit_swept
        >>> scene = minkq.Scene(x0, np.array([[0, 1, 2]], np.int32))
        >>> scene.reserve(refit=True, swept=True)
        >>> scene.refit_swept_async(x0, x1)
        >>> scene.async_status()
        >>> scene.query("vt", 0.01, mode="capsule_exact").tolist()
        [[3, 0]]
        >>> x1[3, 1] = np.nan
        >>> scene.refit_swept_async(x0, x1)  # accepted: the scene is at rest at x0
        >>> scene.query("vt", 0.01, mode="capsule_exact").tolist(), scene.is_swept
        ([], True)
        >>> try:
        ...     scene.async_status()
        ... except minkq.NonFiniteError as e:
        ...     print(str(e).split(";")[0])
        minkq_scene_refit_swept_async: vertex 3 has a non-finite coordinate (in x0 or x1)
        """
        self._move(self._native.refit_swept_async, {"x0": x0, "x1": x1}, stream)

    def rebuild_swept_async(self, x0: Any, x1: Any, stream: Any = None) -> None:
        """:meth:`rebuild_swept`, enqueued on ``stream`` as :meth:`refit_swept_async` is
        (``minkq_scene_rebuild_swept_async``; with a NaN or infinity, the trees are built for
        the positions at rest). Needs :meth:`reserve` with ``rebuild=True, swept=True``."""
        self._move(self._native.rebuild_swept_async, {"x0": x0, "x1": x1}, stream)

    def query_async(
        self,
        out_pairs: Any,
        out_count: Any,
        kind: "Kind",
        radius: Any,
        *_deprecated: Any,
        mode: "Mode" = "box",
        leaf_exact: bool = False,
        canonical: bool = False,
        stream: Any = None,
    ) -> None:
        """:meth:`query` with ``out=``, enqueued on ``stream`` (``minkq_scene_query_async``): writes the
        exact number of pairs to ``out_count[0]`` (a (1,) uint64 or int64 array), also when it
        exceeds the capacity of ``out_pairs`` ((capacity, 2) int32, C-contiguous), and
        min(count, capacity) of the pairs, never past it (which ones, when they do not all fit,
        is unspecified, as is their order). Never :class:`CapacityError`: read the count, and grow the array
        between steps when it says so. On a CUDA device both arrays are device memory on the
        scene's GPU, written when the stream runs the work (the count is never copied to the
        host); on the CPU they are host memory, written when this returns. ``stream`` as in
        :meth:`refit_async` (None: the current stream of ``out_pairs``'s library).
        ``canonical=True`` sorts the pairs when they fit and needs the capacity reserved
        (:meth:`reserve`). The old spelling with a positional mode, ``query_async(out_pairs,
        out_count, kind, mode, radius)``, works for one more release with a DeprecationWarning."""
        mode, radius = old_mode_form("query_async", radius, _deprecated, mode)
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
        :class:`NonFiniteError` when a :meth:`refit_async`, :meth:`rebuild_async` or swept
        one since the last call met a NaN or infinity (the first such call, named in the message
        with the vertex; the scene kept its positions, at rest for a swept one). Afterwards the
        counts and pairs of the queries enqueued on the stream are ready. A blocking call: not
        for inside a graph capture."""
        handle = self._stream if stream is None else stream_handle(stream, self.device)
        self._native.async_status(handle)
