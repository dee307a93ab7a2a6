"""What queries return (:class:`WorkStats`, :class:`QueryInfo`) and the result arrays they
return it in: sized from the last exact count of the same query, regrown on CapacityError, of
numpy or of the caller's library and device."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Tuple

from ._args import _Args
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
