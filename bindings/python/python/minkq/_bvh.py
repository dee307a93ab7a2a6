"""BVHs over user boxes: sphere, capsule and box queries."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional, Tuple, overload

import numpy as np

from . import _native
from ._args import MODES, _Args, _choice, _like, _radius
from ._conventions import Closable, deprecated, old_device_form, resolve_device
from ._results import QueryInfo, _SizedQueries

if TYPE_CHECKING:
    import numpy.typing as npt

    from ._args import Array, Mode, Pairs, Shape


class BVH(Closable, _SizedQueries):
    """A BVH over user boxes: (n, 2, 3) float32 (lo, hi), or (n, 6) as lo x, y, z, hi x, y, z,
    with lo <= hi. Answers sphere, capsule and box queries; pairs are (query, box). Arrays of
    other libraries are read in place as by :class:`Scene`; results take the library and device
    of the query array (or of ``like``). ``device`` as for :class:`Scene` (None: the boxes'
    device). ``close()`` or ``with`` releases the tree at once. The old spelling
    ``BVH(device, boxes)`` works for one more release with a DeprecationWarning.

    >>> import numpy as np, minkq
    >>> boxes = np.array([[[0, 0, 0], [1, 1, 1]], [[2, 2, 2], [3, 3, 3]]], np.float32)
    >>> bvh = minkq.BVH(boxes)
    >>> centres = np.array([[1.5, 1.5, 1.5], [0.5, 0.5, 0.5]], np.float32)
    >>> bvh.query("sphere", centres, 0.5, canonical=True).tolist()  # mode="box": the spheres' boxes
    [[0, 0], [0, 1], [1, 0]]
    >>> bvh.query("sphere", centres, 0.5, mode="sphere").tolist()  # the spheres themselves
    [[1, 0]]
    """

    def __init__(self, boxes: Any, *_deprecated: Any, device: Any = None) -> None:
        super().__init__()
        positional, device = old_device_form("BVH", (boxes,) + _deprecated, device)
        if len(positional) != 1:
            raise TypeError(f"BVH: expected (boxes, *, device=None), got {len(positional)} positional arguments")
        boxes = positional[0]
        self.device = device = resolve_device(device, (boxes,))
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
        >>> bvh = minkq.BVH(boxes)
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

    @overload
    def query(self, shape: "Shape", queries: "npt.ArrayLike", radius: float = ..., *, mode: "Mode" = ...,
              canonical: bool = ..., like: None = ..., out: "Optional[np.ndarray]" = ...) -> "Pairs": ...

    @overload
    def query(self, shape: "Shape", queries: "Array", radius: float = ..., *, mode: "Mode" = ...,
              canonical: bool = ..., like: Any = ..., out: Any = ...) -> Any: ...

    def query(
        self,
        shape: "Shape",
        queries: Any,
        radius: float = 0.0,
        *,
        mode: "Mode" = "box",
        canonical: bool = False,
        like: Any = None,
        out: Any = None,
    ) -> Any:
        """(query, box) pairs for every query shape overlapping a box, as a (k, 2) int32 array.

        ``shape="sphere"``: ``queries`` are centres (n, 3) float32; modes ``"box"`` (the
        default, as everywhere), ``"sphere"``. ``"capsule"``: segments (n, 2, 3) float32; modes
        ``"box"``, ``"capsule_ray"``, ``"capsule_exact"``. ``"box"``: boxes (n, 2, 3) or (n, 6);
        mode ``"box"``, radius 0. ``out=``: an array or :class:`PairBuffer` to reuse, as for
        :meth:`Scene.query`; the result is then a view of it. Typed by the queries' library:
        numpy in, ``NDArray[int32]`` out; arrays of other libraries give theirs (Any).
        """
        return self._query(shape, queries, radius, mode, canonical, False, like, out)[0]

    def query_digest(
        self, shape: "Shape", queries: Any, radius: float = 0.0, *, mode: "Mode" = "box", like: Any = None, out: Any = None
    ) -> Tuple[Any, int]:
        """Like :meth:`query`, canonical, with the xxHash64 of the pairs."""
        pairs, digest = self._query(shape, queries, radius, mode, True, True, like, out)
        assert digest is not None
        return pairs, digest

    def query_into(
        self,
        out: Any,
        shape: "Shape",
        queries: Any,
        radius: float = 0.0,
        *,
        mode: "Mode" = "box",
        canonical: bool = False,
        digest: bool = False,
    ) -> QueryInfo:
        """Deprecated (removed in the next release): ``query(shape, queries, radius, out=out)``
        returns ``out[:count]``. Runs queries into ``out`` ((capacity, 2) int32);
        :class:`CapacityError` when too small."""
        deprecated("BVH.query_into(out, shape, queries, ...)", "BVH.query(shape, queries, radius, out=out)")
        args = _Args(self.device)
        native_args = self._args(args, shape, queries, radius, mode)
        count, dig = self._native.query_into(args.out(out), *native_args, bool(canonical), bool(digest))
        return QueryInfo(count, dig)

    def count(self, shape: "Shape", queries: Any, radius: float = 0.0, *, mode: "Mode" = "box") -> int:
        """The exact number of pairs :meth:`query` would return, none written or kept.

        >>> import numpy as np, minkq
        >>> boxes = np.array([[[0, 0, 0], [1, 1, 1]], [[2, 2, 2], [3, 3, 3]]], np.float32)
        >>> bvh = minkq.BVH(boxes)
        >>> bvh.count("sphere", np.array([[0.5, 0.5, 0.5], [1.5, 1.5, 1.5]], np.float32), 0.9)
        3
        """
        return self._native.count(*self._args(_Args(self.device), shape, queries, radius, mode))

    def _args(self, args: _Args, shape: Any, queries: Any, radius: Any, mode: Any) -> Tuple[str, Any, str, float]:
        shape = _choice(shape, "shape", ("sphere", "capsule", "box"))
        mode = _choice(mode, "mode", MODES)
        if shape == "sphere":
            array = args.rows(queries, "centres", np.float32, (3,))
        elif shape == "capsule":
            array = args.rows(queries, "segments", np.float32, (2, 3))
        else:
            array = args.boxes(queries, "boxes")
        return shape, array, mode, _radius(radius)

    def _query(self, shape: Any, queries: Any, radius: Any, mode: Any, canonical: bool, digest: bool, like: Any,
               out: Any) -> Tuple[Any, Optional[int]]:
        args = _Args(self.device)
        native_args = self._args(args, shape, queries, radius, mode)
        target = _like(args.last) if like is None else args.like(like)
        count = native_args[1][2] if isinstance(native_args[1], tuple) else len(native_args[1])
        key = (native_args[0], native_args[2], count, bool(canonical), bool(digest))
        return self._run(key, lambda out: self._native.query_into(out, *native_args, bool(canonical), bool(digest)), target, out)

    def __repr__(self) -> str:
        if self.closed:
            return "minkq.BVH(closed)"
        return f"minkq.BVH({len(self)} boxes)"
