"""What queries return (:class:`WorkStats`, :class:`QueryInfo`) and the result arrays they
return it in: sized from the last exact count of the same query, regrown on CapacityError, of
numpy or of the caller's library and device."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Tuple

from ._args import _Args
from ._conventions import PairBuffer
from ._errors import CapacityError
from ._interop import Like, allocate_pairs, head

if TYPE_CHECKING:
    from ._device import Device


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

    def _run(self, key: Tuple[Any, ...], run: Callable[[Any], Tuple[int, Optional[int]]], like: Optional[Like] = None, out: Any = None) -> Tuple[Any, Optional[int]]:
        ((pairs, digest),) = self._run_outputs([key], lambda out: (run(out),), like, lambda e: 0, [out])
        return pairs, digest

    def _run_outputs(
        self,
        keys: List[Tuple[Any, ...]],
        run: Callable[..., Tuple[Tuple[int, Optional[int]], ...]],
        like: Optional[Like],
        short: Callable[[CapacityError], int],
        outs: Optional[List[Any]] = None,
    ) -> List[Tuple[Any, Optional[int]]]:
        """Runs ``run(*outs)``, one array per key: the caller's ``outs`` (``out=``: an array, used
        as it is, or a :class:`PairBuffer`, grown as needed; None: an array of ``like``'s kind,
        sized by the last count under its key). On CapacityError the array ``short(e)`` names
        regrows to ``e.needed`` (with headroom for a PairBuffer; the caller's own array raises it)
        and the call runs again (at most once per array). Returns (pairs, digest) per key: views
        of the caller's arrays, copies of ours when much larger than their pairs."""
        like_key = (None if like is None else (like.kind, like.cuda),)
        keys = [k + like_key for k in keys]
        given = [None] * len(keys) if outs is None else outs
        capacity = [_with_headroom(self._last_count[k]) if k in self._last_count else 0 for k in keys]
        arrays = [_initial(out, like, c) for out, c in zip(given, capacity)]
        for attempt in range(len(keys) + 1):
            args = _Args(self.device)
            try:
                results = run(*[args.out(out, _out_name(given, i)) for i, out in enumerate(arrays)])
                break
            except CapacityError as e:
                i = short(e)
                if attempt == len(keys) or (given[i] is not None and not isinstance(given[i], PairBuffer)):
                    raise
                arrays[i] = _grown(given[i], like, e.needed, self.device)
        pairs = []
        for key, out, array, (count, digest) in zip(keys, given, arrays, results):
            self._last_count[key] = count
            # Do not keep a much larger array of ours alive behind a small result.
            pairs.append((head(array, count, out is None and 2 * count < len(array)), digest))
        return pairs


def _out_name(given: List[Any], i: int) -> str:
    return "out" if len(given) == 1 else f"out[{i}]"


def _initial(out: Any, like: Optional[Like], capacity: int) -> Any:
    """The array a query writes into first: the caller's (``out``, or its PairBuffer's), else a
    new one of ``like``'s kind."""
    if isinstance(out, PairBuffer):
        if out.array is None:
            out.array = allocate_pairs(like, capacity)
        return out.array
    return allocate_pairs(like, capacity) if out is None else out


def _grown(out: Any, like: Optional[Like], needed: int, device: "Device") -> Any:
    """A new array for ``needed`` pairs: exactly, for ours; with headroom, in the kind of its
    current array, for a PairBuffer (which keeps it)."""
    if not isinstance(out, PairBuffer):
        return allocate_pairs(like, needed)
    out.array = allocate_pairs(_Args(device).like(out.array, "out"), _with_headroom(needed))
    return out.array
