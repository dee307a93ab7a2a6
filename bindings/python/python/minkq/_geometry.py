"""Scenes of many geometries (``minkq_scene_create_geometries``): :class:`Geometry`, the
description of one mesh, rod set or particle set of a scene, and :class:`_Geometries`, the calls
of :class:`minkq.Scene` that serve such a scene: its geometries' ranges in the global
numbering, the ids of pairs mapped back to (geometry, local id), and the refits and rebuilds of
one geometry."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Dict, Iterable, List, Optional, Tuple, Union

import numpy as np

from ._args import FLOAT32, FLOAT64, KINDS, _Args, _array, _choice, _rows
from ._interop import has_protocol

if TYPE_CHECKING:
    import numpy.typing as npt

    from ._args import Kind
    from ._device import Device

ELEMENTS = ("vertex", "triangle", "edge")
"""The elements :meth:`Scene.geometry_range` and :meth:`Scene.geometry_of` number
(``minkq_element``)."""
_PAIR_ELEMENTS = {
    "vt": ("vertex", "triangle"),
    "ee": ("edge", "edge"),
    "vv": ("vertex", "vertex"),
    "ev": ("vertex", "edge"),
}
"""The elements of each kind's pairs, in their order."""
_NO_TRIANGLES = np.zeros((0, 3), np.int32)
_INT32_MAX, _UINT32_MAX = 2**31 - 1, 2**32 - 1


def _integer(value: Any, name: str, low: int, high: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an int, got {type(value).__name__}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name}: expected {what}, got {int(value)}")
    return int(value)


def _kinds(kinds: Union[str, Iterable[str]]) -> Tuple[str, ...]:
    """``kinds`` as a tuple of distinct names from KINDS, in their order; one name alone is
    accepted as a str."""
    names = (kinds,) if isinstance(kinds, str) else tuple(kinds)
    for k in names:
        if k not in KINDS:
            raise ValueError(f"kinds: expected names among {', '.join(repr(c) for c in KINDS)}, got {k!r}")
    if not names:
        raise ValueError("kinds: expected at least one of 'vt', 'ee', 'vv', 'ev'")
    return tuple(k for k in KINDS if k in names)


class Geometry:
    """One geometry of a scene of several (:meth:`Scene.from_geometries`): a triangle mesh, an
    edge set (rods, yarn: ``triangles=None`` and ``edges``) or a vertex set (particles: vertices
    only), with its own pair kinds, thickness, world and collision filter, moving or static.

    ``vertices``, ``triangles`` and ``edges`` follow the rules of :class:`Scene` (float32 or
    float64 (n, 3) vertices, each geometry of its own precision; (m, 3) and (e, 2) int32
    indices into this geometry's own vertices, int64 and other integer host arrays converted
    with a range check; ``edges=None`` derives them from the triangles for ``"ee"`` and
    ``"ev"``). The arrays are read when the scene is made, which copies them: keeping or
    changing them afterwards changes nothing.

    ``kinds``: the pairs it takes part in, among ``"vt"``, ``"ee"``, ``"vv"``, ``"ev"`` (a
    tuple, or one name). ``self_pairs``: report pairs of its own elements (``drop_incident``
    drops the incident ones, as :class:`Scene` does); a static collider usually has none.
    ``static``: built once, never moved: :meth:`Scene.refit` and :meth:`Scene.rebuild` skip it
    (their vertices are those of the moving geometries, concatenated) and
    :meth:`Scene.refit_geometry` refuses it.

    Cross pairs between two geometries a and b are reported when both take part in the kind,
    they share a ``world`` (equal ids, or either is -1: part of every world) and each one's
    ``group`` has a bit in the other's ``mask`` (``(a.group & b.mask) and (b.group &
    a.mask)``, as PhysX and Embree filter). VT and EV run both ways (a's vertices against b's
    triangles or edges and b's against a's); EE and VV pairs are unordered.

    ``thickness``: None, one value for every vertex, or an (n,) array of one per vertex (float32;
    float64 and integer host values are rounded up to float32, never down, so that no pair is
    lost): finite and >= 0. An element's thickness is the largest of its vertices', and a pair
    of elements a, b is within reach when its distance is at most r + t(a) + t(b), in every mode
    and with ``leaf_exact``.

    >>> import numpy as np, minkq
    >>> floor = minkq.Geometry(np.array([[-1, -1, 0], [2, -1, 0], [-1, 2, 0]], np.float32), [[0, 1, 2]],
    ...                        kinds="vt", self_pairs=False, static=True)
    >>> cloth = minkq.Geometry(np.array([[0, 0, .05], [1, 0, .05], [0, 1, .05]], np.float32), [[0, 1, 2]],
    ...                        kinds="vt", thickness=0.02)
    >>> scene = minkq.Scene.from_geometries([floor, cloth])
    >>> scene.query("vt", 0.035, leaf_exact=True, canonical=True).tolist()  # 0.05 <= 0.035 + 0.02 + 0
    [[3, 0], [4, 0], [5, 0]]
    >>> scene.geometry_of("vertex", [3, 4, 5])
    (array([1, 1, 1], dtype=int32), array([0, 1, 2], dtype=int32))
    """

    def __init__(
        self,
        vertices: Any,
        triangles: Any = None,
        edges: Any = None,
        *,
        kinds: Union["Kind", Iterable["Kind"]] = ("vt", "ee"),
        self_pairs: bool = True,
        drop_incident: bool = True,
        static: bool = False,
        world: int = 0,
        group: int = 1,
        mask: int = _UINT32_MAX,
        thickness: Any = None,
    ) -> None:
        self.vertices = vertices
        self.triangles = triangles
        self.edges = edges
        self.kinds = _kinds(kinds)
        self.self_pairs = bool(self_pairs)
        self.drop_incident = bool(drop_incident)
        self.static = bool(static)
        self.world = _integer(world, "world", -1, _INT32_MAX, "a world id >= 0, or -1 for every world")
        self.group = _integer(group, "group", 0, _UINT32_MAX, "a uint32 bit set")
        self.mask = _integer(mask, "mask", 0, _UINT32_MAX, "a uint32 bit set")
        self.thickness = thickness

    def __repr__(self) -> str:
        flags = [f"kinds={self.kinds!r}", f"world={self.world}", f"group={self.group:#x}", f"mask={self.mask:#x}"]
        if not self.self_pairs:
            flags.append("self_pairs=False")
        if self.static:
            flags.append("static=True")
        if self.thickness is not None:
            flags.append("thickness=...")
        return f"minkq.Geometry({', '.join(flags)})"


@dataclass(frozen=True)
class _NativeGeometry:
    """A :class:`Geometry` checked for minkq._native (read by attribute: src/geometries.rs)."""

    vertices: Any
    triangles: Any
    edges: Any
    thickness: Any
    float64: bool
    vt: bool
    ee: bool
    vv: bool
    ev: bool
    self_pairs: bool
    drop_incident: bool
    static: bool
    world: int
    group: int
    mask: int


def _thickness(args: _Args, value: Any, name: str, vertices: Any) -> Any:
    """A geometry's thickness for minkq._native: None, float32 rows (n,) used in place, or a
    copy of host values rounded up to float32 (a number: one for every vertex)."""
    if value is None or has_protocol(value):
        return None if value is None else args.rows(value, name, np.float32, ())
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        count = len(vertices) if isinstance(vertices, np.ndarray) else vertices[2]
        value = np.full(count, value, np.float64)
    array = _array(value, name, FLOAT32, ())
    if array.dtype.kind in "iuf" and array.dtype != FLOAT32:
        wide = array.astype(np.float64)
        array = wide.astype(np.float32)
        below = array.astype(np.float64) < wide
        array[below] = np.nextafter(array[below], np.float32(np.inf))
    return _rows(array, name, np.float32, ())


def _native_geometries(device: "Device", geometries: Any) -> Tuple[_Args, List[_NativeGeometry], List[np.dtype], Any]:
    """The geometries checked and converted for minkq._native, the arguments that keep their
    arrays alive, each geometry's precision, and the last array of another library among their
    vertices (results are made like it), or None."""
    if isinstance(geometries, Geometry) or not isinstance(geometries, (list, tuple)):
        raise TypeError(f"geometries: expected a list of minkq.Geometry, got {type(geometries).__name__}")
    args = _Args(device)
    natives, dtypes, like = [], [], None
    for g, geometry in enumerate(geometries):
        name = f"geometries[{g}]"
        if not isinstance(geometry, Geometry):
            raise TypeError(f"{name}: expected a minkq.Geometry, got {type(geometry).__name__}")
        viewed = len(args.views)
        vertices, dtype = args.vertices(geometry.vertices, f"{name}.vertices", None)
        if len(args.views) > viewed:
            like = args.last
        triangles = geometry.triangles
        triangles = args.rows(_NO_TRIANGLES if triangles is None else triangles, f"{name}.triangles", np.int32, (3,))
        edges = None if geometry.edges is None else args.rows(geometry.edges, f"{name}.edges", np.int32, (2,))
        thickness = _thickness(args, geometry.thickness, f"{name}.thickness", vertices)
        vt, ee, vv, ev = (k in geometry.kinds for k in KINDS)
        natives.append(
            _NativeGeometry(
                vertices,
                triangles,
                edges,
                thickness,
                dtype == FLOAT64,
                vt,
                ee,
                vv,
                ev,
                geometry.self_pairs,
                geometry.drop_incident,
                geometry.static,
                geometry.world,
                geometry.group,
                geometry.mask,
            )
        )
        dtypes.append(dtype)
    return args, natives, dtypes, like


def _moving_dtype(geometries: List[Geometry], dtypes: List[np.dtype]) -> np.dtype:
    """The precision of the scene-wide refits' vertices: float64 when every moving geometry is
    float64 (as the library sets MINKQ_SCENE_FLOAT64), else float32 (the library refuses a
    scene-wide refit of moving geometries of mixed precision)."""
    moving = [d for geometry, d in zip(geometries, dtypes) if not geometry.static]
    return FLOAT64 if moving and all(d == FLOAT64 for d in moving) else FLOAT32


class _Geometries:
    """The calls of :class:`minkq.Scene` for its geometries (documented there)."""

    _native: Any
    _geometry_dtypes: List[np.dtype]
    """Each geometry's precision (one for a one-mesh scene: the scene's)."""
    _ranges: Optional[np.ndarray]
    """(geometry_count, 3, 2) int64: first id and count of each element, read once."""

    if TYPE_CHECKING:

        def _move(
            self,
            call: Callable[..., None],
            positions: Dict[str, Any],
            stream: Any = ...,
            dtype: Optional[np.dtype] = ...,
        ) -> None: ...

    @property
    def geometry_count(self) -> int:
        """The number of geometries (1 for a scene made by the :class:`Scene` constructor)."""
        return self._native.geometry_count

    def geometry_range(self, g: int, element: str) -> Tuple[int, int]:
        """Geometry ``g``'s first global id and its count of ``element`` (``"vertex"``,
        ``"triangle"`` or ``"edge"``; edges: the derived ones when it derived them). Pairs use
        one global numbering, the geometries' elements concatenated in their order: geometry
        g's ids are ``first`` to ``first + count - 1``. Raises :class:`InvalidArgumentError`
        for ``g`` out of range."""
        element = _element(element)
        return self._native.geometry_range(self._geometry_index(g), element)

    def geometry_of(self, element: str, ids: Any) -> Tuple["npt.NDArray[np.int32]", "npt.NDArray[np.int32]"]:
        """The geometry of each global ``element`` id (``"vertex"``, ``"triangle"`` or
        ``"edge"``) and its id within that geometry, as two int32 numpy arrays of ``ids``'s
        shape: for a column of pairs, e.g. ``scene.geometry_of("triangle", vt[:, 1])``.
        ``ids``: a host array or sequence of integers (copy device arrays to the host first);
        an id outside the scene's range raises :class:`IndexError`.

        >>> import numpy as np, minkq
        >>> tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
        >>> a, b = minkq.Geometry(tri, [[0, 1, 2]]), minkq.Geometry(tri + [0, 0, .1], [[0, 1, 2]])
        >>> scene = minkq.Scene.from_geometries([a, b])
        >>> vt = scene.query("vt", 0.2, leaf_exact=True, canonical=True)
        >>> vt.tolist()
        [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]
        >>> [g.tolist() for g in scene.geometry_of("vertex", vt[:, 0])]
        [[0, 0, 0, 1, 1, 1], [0, 1, 2, 0, 1, 2]]
        """
        e = ELEMENTS.index(_element(element))
        try:
            values = np.asarray(ids)
        except (TypeError, ValueError, RuntimeError) as err:
            raise TypeError(f"ids: expected a host array of integers, got {type(ids).__name__}: {err}") from None
        if values.size and values.dtype.kind not in "iu":
            raise TypeError(f"ids: expected integers, got {values.dtype}")
        values = values.astype(np.int64)
        ranges = self._geometry_ranges()
        first, count = ranges[:, e, 0], ranges[:, e, 1]
        total = int(first[-1] + count[-1])
        bad = (values < 0) | (values >= total)
        if bad.any():
            raise IndexError(f"ids: {element} id {int(values[bad].flat[0])} is outside the scene's 0 to {total - 1}")
        # Geometries without such elements share their first id with the next: the last
        # geometry whose first id is <= the id holds it.
        g = np.searchsorted(first, values, side="right") - 1
        return g.astype(np.int32), (values - first[g]).astype(np.int32)

    def geometry_of_pairs(self, kind: "Kind", pairs: Any) -> Tuple["npt.NDArray[np.int32]", "npt.NDArray[np.int32]"]:
        """:meth:`geometry_of` for both columns of a (k, 2) array of ``kind``'s pairs ((vertex,
        triangle) for ``"vt"``, (edge, edge) for ``"ee"``, (vertex, vertex) for ``"vv"``,
        (vertex, edge) for ``"ev"``): each pair's two geometries and its two local ids, as two
        (k, 2) int32 numpy arrays. ``pairs``: a host array (numpy, or anything numpy reads, such
        as a Warp CPU array or a PyTorch CPU tensor).

        >>> import numpy as np, minkq
        >>> tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
        >>> body = minkq.Geometry(tri, [[0, 1, 2]], self_pairs=False, static=True)
        >>> scene = minkq.Scene.from_geometries([body, minkq.Geometry(tri + [0, 0, .1], [[0, 1, 2]])])
        >>> geometries, local = scene.geometry_of_pairs("vt", scene.query("vt", 0.2, canonical=True))
        >>> geometries[:4].tolist(), local[:4].tolist()
        ([[0, 1], [0, 1], [0, 1], [1, 0]], [[0, 0], [1, 0], [2, 0], [0, 0]])
        """
        elements = _PAIR_ELEMENTS[_choice(kind, "kind", KINDS)]
        try:
            values = np.asarray(pairs)
        except (TypeError, ValueError, RuntimeError) as err:
            raise TypeError(f"pairs: expected a host array of pairs, got {type(pairs).__name__}: {err}") from None
        if values.ndim != 2 or values.shape[1] != 2:
            raise ValueError(f"pairs: expected shape (k, 2), got {values.shape}")
        columns = [self.geometry_of(element, values[:, k]) for k, element in enumerate(elements)]
        return np.stack([g for g, _ in columns], 1), np.stack([local for _, local in columns], 1)

    def refit_geometry(self, g: int, vertices: Any) -> None:
        """Moves geometry ``g``'s vertices ((n, 3) of its own precision, its vertex count) and
        refits its trees; the other geometries are not touched. A step that moves one cloth
        against a static body refits only the cloth. Errors as :meth:`refit`, the library's
        messages naming the geometry; :class:`InvalidArgumentError` for a static geometry or
        ``g`` out of range."""
        self._move_geometry(g, self._native.refit_geometry, {"vertices": vertices})

    def rebuild_geometry(self, g: int, vertices: Any) -> None:
        """Moves geometry ``g``'s vertices like :meth:`refit_geometry` and builds its trees
        afresh (see :meth:`rebuild`)."""
        self._move_geometry(g, self._native.rebuild_geometry, {"vertices": vertices})

    def refit_geometry_swept(self, g: int, x0: Any, x1: Any) -> None:
        """Swept positions x0 -> x1 of geometry ``g`` alone, its trees refitted to the swept
        boxes (see :meth:`refit_swept`). They last until its next plain refit or rebuild; while
        any geometry is swept the scene's queries are swept (:attr:`is_swept`)."""
        self._move_geometry(g, self._native.refit_geometry_swept, {"x0": x0, "x1": x1})

    def rebuild_geometry_swept(self, g: int, x0: Any, x1: Any) -> None:
        """Swept positions of geometry ``g`` like :meth:`refit_geometry_swept`, its trees built
        afresh for the swept boxes."""
        self._move_geometry(g, self._native.rebuild_geometry_swept, {"x0": x0, "x1": x1})

    def _move_geometry(self, g: int, call: Callable[..., None], positions: Dict[str, Any]) -> None:
        g = self._geometry_index(g)
        self._move(functools.partial(call, g), positions, dtype=self._geometry_dtypes[g])

    def _geometry_index(self, g: Any) -> int:
        """``g`` as a geometry index, checked by the library (InvalidArgumentError, its message,
        out of range)."""
        if isinstance(g, bool) or not isinstance(g, (int, np.integer)):
            raise TypeError(f"g: expected an int, got {type(g).__name__}")
        if not 0 <= g <= _UINT32_MAX:
            raise ValueError(f"g: expected a geometry index >= 0, got {int(g)}")
        self._native.geometry_range(int(g), "vertex")
        return int(g)

    def _geometry_ranges(self) -> np.ndarray:
        if self._ranges is None:
            count = self.geometry_count
            self._ranges = np.array(
                [[self._native.geometry_range(g, e) for e in ELEMENTS] for g in range(count)], np.int64
            ).reshape(count, 3, 2)
        return self._ranges


def _element(element: Any) -> str:
    if element not in ELEMENTS:
        raise ValueError(f"element: expected one of {', '.join(repr(e) for e in ELEMENTS)}, got {element!r}")
    return str(element)
