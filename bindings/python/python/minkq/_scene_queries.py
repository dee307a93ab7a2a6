"""A mesh scene's blocking queries: pairs (into new arrays or ``out=``), their digest, count and
work. :class:`minkq.Scene` takes them from :class:`_SceneQueries`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional, Tuple, overload

from ._args import KINDS, MODES, _Args, _choice, _radius
from ._conventions import deprecated, old_mode_form
from ._results import QueryInfo, WorkStats, _SizedQueries

if TYPE_CHECKING:
    import numpy as np

    from ._args import Kind, Mode, Pairs
    from ._interop import Like

    OutPair = Tuple[Any, Any]


class _SceneQueries(_SizedQueries):
    """The blocking queries of :class:`minkq.Scene` (documented there)."""

    _native: Any
    _like: Optional["Like"]

    @overload
    def query(self, kind: "Kind", radius: float, *, mode: "Mode" = ..., leaf_exact: bool = ..., canonical: bool = ...,
              like: "np.ndarray", out: None = ...) -> "Pairs": ...

    @overload
    def query(self, kind: "Kind", radius: float, *, mode: "Mode" = ..., leaf_exact: bool = ..., canonical: bool = ...,
              like: Any = ..., out: "np.ndarray") -> "Pairs": ...

    @overload
    def query(self, kind: "Kind", radius: Any, *_deprecated: Any, mode: "Mode" = ..., leaf_exact: bool = ...,
              canonical: bool = ..., like: Any = ..., out: Any = ...) -> Any: ...

    def query(
        self,
        kind: "Kind",
        radius: Any,
        *_deprecated: Any,
        mode: "Mode" = "box",
        leaf_exact: bool = False,
        canonical: bool = False,
        like: Any = None,
        out: Any = None,
    ) -> Any:
        """Pairs within ``radius`` as a (k, 2) int32 array: (vertex, triangle) for ``kind="vt"``,
        (e, f) with e < f for ``"ee"``, (v, w) with v < w for ``"vv"``, (vertex, edge) for
        ``"ev"`` (each needs the scene's flag of the same name).

        ``mode`` is the node test, from fast to tight: ``"box"`` (the default, and the fastest
        on the benchmark scenes), ``"sphere"`` (point queries: VT, VV, EV), ``"capsule_ray"``,
        ``"capsule_exact"``; every mode reports every pair within r. ``leaf_exact=True`` tests
        the primitives at the leaves, so that the pairs are the true contacts (plus, at most,
        pairs within r + 2**-19 S). ``canonical=True`` sorts the pairs.

        The result is a new numpy array, or an array of the library and device of the vertices
        last given (a Warp array on ``cuda:0`` gives a Warp array on ``cuda:0``, written there
        in place), or of ``like`` when given. ``out=`` reuses memory instead: a writable
        C-contiguous (capacity, 2) int32 array (numpy, or another library's on the scene's
        device; :class:`CapacityError`, with the exact count as ``needed``, when it is too
        small, nothing written past it), or a :class:`PairBuffer`, which grows as needed; the
        result is then ``out[:count]``, a view of it. Typed: a numpy ``like`` or ``out`` gives
        an ``NDArray[int32]``; otherwise the library of the scene's arrays decides (Any).

        The old spelling ``query(kind, mode, radius)`` (a positional mode) works for one more
        release with a DeprecationWarning.
        """
        mode, radius = old_mode_form("query", radius, _deprecated, mode)
        return self._query(kind, mode, radius, leaf_exact, canonical, False, like, out)[0]

    def query_digest(
        self, kind: "Kind", radius: Any, *_deprecated: Any, mode: "Mode" = "box", leaf_exact: bool = False, like: Any = None,
        out: Any = None,
    ) -> Tuple[Any, int]:
        """Like :meth:`query`, canonical, with the xxHash64 (seed 0) of the little-endian pairs:
        equal across backends, runs and language bindings."""
        mode, radius = old_mode_form("query_digest", radius, _deprecated, mode)
        pairs, digest = self._query(kind, mode, radius, leaf_exact, True, True, like, out)
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
        """Deprecated (removed in the next release): ``query(kind, radius, mode=mode, out=out)``
        returns ``out[:count]``. Runs a query into ``out`` as :meth:`query` with ``out=`` does
        and returns the count (and the digest with ``digest=True``)."""
        deprecated("Scene.query_into(out, kind, mode, radius)", "Scene.query(kind, radius, mode=mode, out=out)")
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
        out: Optional["OutPair"] = None,
    ) -> Tuple[Any, Any]:
        """The VT and the EE pairs within ``radius`` from one pass (one parallel loop on the CPU,
        one kernel launch and one count readback on CUDA): exactly what ``query("vt", radius,
        mode=vt_mode, ...)`` and ``query("ee", radius, mode=ee_mode, ...)`` return (VV and EV
        queries run through :meth:`query`). ``leaf_exact=True`` gives the contacts (meant for
        the default box modes: docs/design-notes.md). Results as :meth:`query`; ``out=(vt_out,
        ee_out)`` reuses two arrays or :class:`PairBuffer` (as ``out=`` of :meth:`query`).

        >>> import numpy as np, minkq
        >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0.1], [1, 0, 0.1], [0, 1, 0.1]], np.float32)
        >>> scene = minkq.Scene(xyz, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> vt, ee = scene.query_vt_ee(0.2, leaf_exact=True, canonical=True)
        >>> vt.tolist()
        [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]
        >>> len(ee)
        9
        >>> buffers = (minkq.PairBuffer(), minkq.PairBuffer())
        >>> vt, ee = scene.query_vt_ee(0.2, leaf_exact=True, out=buffers)  # grown once, then reused
        >>> len(vt), len(ee)
        (6, 9)
        """
        vt_mode = _choice(vt_mode, "vt_mode", MODES)
        ee_mode = _choice(ee_mode, "ee_mode", MODES)
        r = _radius(radius)
        outs = _out_pair(out)
        flags = (bool(leaf_exact), bool(canonical), False)
        target = self._like if like is None else _Args(self.device).like(like)
        key = (vt_mode, ee_mode) + flags
        (vt, _), (ee, _) = self._run_outputs(
            [("vt",) + key, ("ee",) + key],
            lambda vt_out, ee_out: self._native.query_vt_ee_into(vt_out, ee_out, vt_mode, ee_mode, r, *flags),
            target,
            lambda e: 0 if e.message.startswith("VT:") else 1,  # the first short buffer, VT before EE
            outs,
        )
        return vt, ee

    def count(self, kind: "Kind", radius: Any, *_deprecated: Any, mode: "Mode" = "box", leaf_exact: bool = False) -> int:
        """The exact number of pairs :meth:`query` would return, none written or kept: to size
        a buffer for ``out=`` first, or when the count is all that is needed.

        >>> import numpy as np, minkq
        >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.1]], np.float32)
        >>> scene = minkq.Scene(xyz, np.array([[0, 1, 2]], np.int32))
        >>> scene.count("vt", 0.2, mode="sphere") == len(scene.query("vt", 0.2, mode="sphere")) == 1
        True
        """
        mode, radius = old_mode_form("count", radius, _deprecated, mode)
        checked = (_choice(kind, "kind", KINDS), _choice(mode, "mode", MODES), _radius(radius))
        return int(self._native.count(*checked, bool(leaf_exact)))

    def work(self, kind: "Kind", radius: Any, *_deprecated: Any, mode: "Mode" = "box", leaf_exact: bool = False) -> WorkStats:
        """Runs the query once with the library's work counters on and returns them (the pairs
        are not kept). The counts depend only on the tree and the queries: the same on every
        backend.

        >>> import numpy as np, minkq
        >>> xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.1]], np.float32)
        >>> scene = minkq.Scene(xyz, np.array([[0, 1, 2]], np.int32))
        >>> w = scene.work("vt", 0.2, mode="sphere")
        >>> (w.candidates, w.primitive_tests >= w.candidates)
        (1, True)
        """
        mode, radius = old_mode_form("work", radius, _deprecated, mode)
        checked = (_choice(kind, "kind", KINDS), _choice(mode, "mode", MODES), _radius(radius))
        return WorkStats(*self._native.work(*checked, bool(leaf_exact)))

    def _query(self, kind: Any, mode: Any, radius: Any, leaf_exact: bool, canonical: bool, digest: bool, like: Any,
               out: Any) -> Tuple[Any, Optional[int]]:
        kind = _choice(kind, "kind", KINDS)
        mode = _choice(mode, "mode", MODES)
        r = _radius(radius)
        flags = (bool(leaf_exact), bool(canonical), bool(digest))
        target = self._like if like is None else _Args(self.device).like(like)
        run = lambda array: self._native.query_into(array, kind, mode, r, *flags)  # noqa: E731
        return self._run((kind, mode) + flags, run, target, out)


def _out_pair(out: Any) -> Optional[list]:
    """``out=`` of :meth:`_SceneQueries.query_vt_ee`: None or two outputs (arrays or
    :class:`PairBuffer`), VT's first."""
    if out is None:
        return None
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise TypeError(f"out: expected (vt_out, ee_out), two arrays or minkq.PairBuffer, got {type(out).__name__}")
    return list(out)

