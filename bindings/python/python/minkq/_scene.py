"""Mesh scenes: VT and EE queries over a triangle mesh, VV and EV over vertices and edges,
blocking (the stream-ordered calls are in minkq._stream_ordered)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict, Optional, Sequence

import numpy as np

from . import _native
from ._args import FLOAT64, _Args, _like
from ._conventions import Closable, old_device_form, resolve_device
from ._geometry import Geometry, _Geometries, _moving_dtype, _native_geometries
from ._interop import stream_handle
from ._results import _SizedQueries
from ._scene_queries import _SceneQueries
from ._stream_ordered import _StreamOrdered

if TYPE_CHECKING:
    from ._args import Pairs
    from ._device import Device

_BLOCKING = object()
"""The ``stream`` of :meth:`Scene._move` for the blocking calls."""
_NO_TRIANGLES = np.zeros((0, 3), np.int32)
"""``triangles=None``: a scene of vertices and edges only."""


class Scene(Closable, _StreamOrdered, _SceneQueries, _Geometries):
    """A triangle mesh, or codimensional elements (particles, rods), on a device with the BVHs
    for its queries: VT and EE over triangles, VV and EV over vertices and edges.

    ``device``: where the scene runs. None (the default) takes it from the arrays: the CPU for
    numpy arrays, lists and host arrays of other libraries, the GPU of a CUDA array (a Warp
    array or torch tensor on ``cuda:1`` gives ``cuda:1``). Or name it: ``"cpu"``, ``"cuda"``,
    ``"cuda:N"``, ``"auto"``, a ``torch.device``, a Warp device or a :class:`Device`.
    ``close()`` (or ``with minkq.Scene(...) as scene:``) releases the scene and its device
    memory at once; later calls raise ValueError. The old spelling ``Scene(device, vertices,
    triangles, edges)`` works for one more release with a DeprecationWarning.

    ``vertices``: (n, 3) float32 or float64; ``triangles``: (m, 3) int32, or None (the same
    as an empty (0, 3) array: no triangles); ``edges``: (e, 2) int32, or None (or an empty
    array) to derive them from the triangles (every distinct undirected edge as (min, max),
    sorted).
    C-contiguous numpy arrays of exactly these dtypes are used without a copy; other host
    arrays (int64 indices, strided or byte-swapped arrays, lists, ...) are converted once: a
    copy is made (an index that does not fit in int32 raises IndexOutOfRangeError naming it).
    Indices of other libraries in another integer dtype (PyTorch's int64 faces) are converted
    the same way, through a host copy; their vertices must have exactly these dtypes.

    Precision (:attr:`dtype`): float64 vertices (numpy, Warp ``wp.vec3d`` / float64, PyTorch
    float64, ...; also lists of Python floats, which numpy reads as float64) make a float64
    scene (``MINKQ_SCENE_FLOAT64``): it reads them as doubles, rounds them to float for its
    trees and widens every query radius by twice the farthest the rounding moved a vertex, so
    that every pair within r in double is reported, in every mode (extras lie within that
    wider radius). float32 vertices make a float32 scene, as do float16 and integer ones
    (converted to float32). The precision is the scene's for good: :meth:`refit` and
    :meth:`rebuild` of a float64 scene take float64 (float32 and narrower host arrays are
    converted to float64 exactly; arrays of other libraries and the stream-ordered calls must
    be float64 already); a float32 scene refuses float64 values with TypeError rather than
    round them to float32 (create it from float64 vertices to have the guarantee in double).
    Floats wider than float64 (``np.longdouble``) raise TypeError: minkq rounds none itself.

    ``vt`` / ``ee`` / ``vv`` / ``ev`` say which queries the scene answers (at least one);
    ``drop_incident`` drops (v, t) with v a vertex of t, pairs of edges sharing a vertex (the
    cloth self-collision set-up) and (v, e) with v an end of e; VV pairs are never incident.

    Codimensional elements (``MINKQ_SCENE_VV`` / ``MINKQ_SCENE_EV``): ``vv=True`` builds a
    vertex tree for ``"vv"`` queries, pairs (v, w), v < w, of vertices within r (each pair
    once; neighbours along a rod too); ``ev=True`` the edge tree for ``"ev"`` queries, pairs
    (vertex, edge) of a vertex within r of an edge (without its own edges under
    ``drop_incident``). Rods and yarn are vertices and explicit edges with ``triangles=None``;
    loose particles need vertices only (``vv=True``, every other kind off). The flags may also
    join VT and EE on a triangle mesh (then EV uses the derived edges). Every mode (for these
    point queries ``"capsule_ray"`` is ``"box"`` and ``"capsule_exact"`` is ``"sphere"``),
    ``leaf_exact``, float64 vertices and swept steps work as for VT. A query of a kind the
    scene was created without raises :class:`InvalidArgumentError` ("VV query on a scene
    created without MINKQ_SCENE_VV").

    >>> import numpy as np, minkq
    >>> rod = np.array([[0, 0, 0], [.1, 0, 0], [.2, 0, 0], [.3, 0, 0], [.2, .05, 0]], np.float32)
    >>> edges = np.array([[0, 1], [1, 2], [2, 3]], np.int32)  # vertex 4: a particle
    >>> rods = minkq.Scene(rod, None, edges, vt=False, ee=False, vv=True, ev=True)
    >>> rods.query("vv", 0.06, mode="sphere", leaf_exact=True, canonical=True).tolist()
    [[2, 4]]
    >>> rods.query("ev", 0.06, leaf_exact=True, canonical=True).tolist()
    [[4, 1], [4, 2]]

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
    >>> scene = minkq.Scene(v, t)
    >>> scene.query("vt", 0.2, mode="sphere", leaf_exact=True, canonical=True).tolist()
    [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]
    >>> minkq.Scene(v.astype(np.float64), t).dtype
    dtype('float64')

    Raises :class:`NonFiniteError` (also for a double beyond the float range, about 3.4e38),
    :class:`IndexOutOfRangeError`, :class:`SizeOverflowError` or :class:`InvalidArgumentError`
    (with the library's message) for bad input, and TypeError / ValueError naming the argument
    for a wrong dtype or shape.

    Cloth against colliders, per-vertex thickness, batched worlds: :meth:`from_geometries`
    makes one scene of several :class:`Geometry` (then :meth:`geometry_range`,
    :meth:`geometry_of` and :meth:`refit_geometry`); the constructor's scene is its one
    geometry.
    """

    def __init__(
        self,
        vertices: Any,
        triangles: Any = None,
        edges: Any = None,
        *_deprecated: Any,
        device: Any = None,
        vt: bool = True,
        ee: bool = True,
        vv: bool = False,
        ev: bool = False,
        drop_incident: bool = True,
    ) -> None:
        super().__init__()
        (vertices, triangles, edges), device = _old_constructor((vertices, triangles, edges) + _deprecated, device)
        self.device = device = resolve_device(device, (vertices, triangles, edges))
        args = _Args(device)
        vertices, self._dtype = args.vertices(vertices, "vertices", None)
        self._like = _like(args.last)
        triangles = args.rows(_NO_TRIANGLES if triangles is None else triangles, "triangles", np.int32, (3,))
        if edges is not None:
            edges = args.rows(edges, "edges", np.int32, (2,))
        flags = (bool(vt), bool(ee), bool(vv), bool(ev), bool(drop_incident), self._dtype == FLOAT64)
        self._native = _native.Scene(device._native, vertices, triangles, edges, *flags)
        self._stream = 0  # the stream of the last stream-ordered call, for async_status
        self._geometry_dtypes = [self._dtype]
        self._ranges = None

    @classmethod
    def from_geometries(cls, geometries: Sequence[Geometry], *_deprecated: Any, device: Any = None) -> "Scene":
        """A scene of several geometries (:class:`Geometry`: meshes, rods, particles), each with
        its own trees, pair kinds, thickness, world and collision filter, moving or static
        (``minkq_scene_create_geometries``), on ``device`` (None: the device of the geometries'
        vertices, as for the constructor; the old spelling ``from_geometries(device,
        geometries)`` works for one more release with a DeprecationWarning). Its queries report each geometry's self pairs (where
        it has ``self_pairs``) and the cross pairs its geometries' worlds, groups and masks allow,
        in every mode, with ``leaf_exact``, float64 and swept positions as for a one-mesh scene.

        Pairs use one global numbering: the geometries' vertices, triangles and edges
        concatenated in the order given (edges numbered per geometry as a one-mesh scene numbers
        them), so that they read as the pairs of one concatenated mesh; :meth:`geometry_range`
        gives each geometry's ids, :meth:`geometry_of` and :meth:`geometry_of_pairs` map ids back
        to (geometry, local id).
        EE and VV pairs are (lower, higher) global id. :attr:`vertex_count`,
        :attr:`triangle_count`, :attr:`edge_count` and :meth:`edges` describe the whole scene in
        that numbering.

        Moving: :meth:`refit` and :meth:`rebuild` (and their swept forms) take the vertices of
        every geometry that is not static, concatenated in geometry order, all of one precision
        (:attr:`dtype`: float64 when every moving geometry is float64); :meth:`refit_geometry`
        and its kin move one geometry. The stream-ordered calls take such scenes too (their
        whole-scene moves take the moving geometries' vertices as :meth:`refit` does; a
        geometry whose part holds a NaN keeps its positions and :meth:`async_status` names it).

        Errors: those of the constructor, messages naming the geometry (``"geometry 1: triangle 3
        references vertex 9 but the geometry has 8 vertices"``), TypeError / ValueError naming
        the argument (``geometries[1].vertices``); :class:`InvalidArgumentError` for an empty
        list or a thickness count other than the vertex count, :class:`NonFiniteError` or
        :class:`InvalidArgumentError` for a non-finite or negative thickness.

        >>> import numpy as np, minkq
        >>> tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
        >>> body = minkq.Geometry(tri, [[0, 1, 2]], self_pairs=False, static=True)
        >>> cloth = minkq.Geometry(tri + [0, 0, .1], [[0, 1, 2]])
        >>> scene = minkq.Scene.from_geometries([body, cloth])
        >>> scene.geometry_count, scene.geometry_range(1, "vertex"), scene.vertex_count
        (2, (3, 3), 6)
        >>> scene.query("vt", 0.2, leaf_exact=True, canonical=True).tolist()
        [[0, 1], [1, 1], [2, 1], [3, 0], [4, 0], [5, 0]]
        >>> scene.refit_geometry(1, tri + [0, 0, 1])  # the cloth moves away; the body stays
        >>> scene.query("vt", 0.2).tolist()
        []
        """
        positional, device = old_device_form("Scene.from_geometries", (geometries,) + _deprecated, device)
        if len(positional) != 1:
            raise TypeError(f"Scene.from_geometries: expected (geometries, *, device=None), got {1 + len(_deprecated)} positional arguments")
        geometries = positional[0]
        vertices = [getattr(g, "vertices", None) for g in geometries] if isinstance(geometries, (list, tuple)) else []
        device = resolve_device(device, vertices)
        args, natives, dtypes, like = _native_geometries(device, geometries)
        scene = cls.__new__(cls)
        _SizedQueries.__init__(scene)
        scene.device = device
        scene._native = _native.Scene.from_geometries(device._native, natives)
        scene._dtype = _moving_dtype(list(geometries), dtypes)
        scene._like = _like(like)
        scene._stream = 0
        scene._geometry_dtypes = dtypes
        scene._ranges = None
        return scene

    @property
    def dtype(self) -> np.dtype:
        """The precision of the scene's vertices: ``float32``, or ``float64`` for a scene
        created from float64 vertices (every pair within r in double is reported), whose
        refits and rebuilds take float64. For a scene of geometries (:meth:`from_geometries`):
        the precision :meth:`refit` and :meth:`rebuild` take, ``float64`` when every moving
        geometry is float64 (each geometry keeps its own for :meth:`refit_geometry`)."""
        return self._dtype

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
        """The number of edges (given, or derived for an EE or EV scene)."""
        return self._native.edge_count

    def edges(self) -> "Pairs":
        """The scene's edges as an (edge_count, 2) int32 numpy array, numbered as EE and EV pairs
        number them."""
        out = np.empty((self.edge_count, 2), dtype=np.int32)
        self._native.edges_into(out)
        return out

    def refit(self, vertices: Any) -> None:
        """Moves the vertices ((n, 3) of the scene's :attr:`dtype`, same n; numpy or read in
        place as in the constructor) and refits the trees in place: the per-step call of a simulation. On error
        the scene keeps its previous positions. A refit keeps the grouping of the last build:
        after large deformations the boxes overlap more and queries visit more nodes
        (:meth:`tree_growth` measures it, :meth:`rebuild` resets it); the pairs found never
        change."""
        self._move(self._native.refit, {"vertices": vertices})

    def rebuild(self, vertices: Any) -> None:
        """Moves the vertices like :meth:`refit` and builds the trees afresh for the new
        positions: the trees the constructor would build there, with the same triangles, edges
        and edge numbering. The pairs are those of a refit; only the speed of later queries
        differs. Worth it once large motions have raised :meth:`tree_growth` (above about 1.5),
        and every so many steps when the mesh changes shape a lot. Same errors as
        :meth:`refit`; on error the scene keeps its positions and trees.

        >>> import numpy as np, minkq
        >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
        >>> scene = minkq.Scene(v, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
        >>> v[3:, 2] = 1.0  # lift the upper triangle away
        >>> scene.rebuild(v)
        >>> scene.query("vt", 0.2, mode="sphere").tolist(), scene.tree_growth()
        ([], 1.0)
        """
        self._move(self._native.rebuild, {"vertices": vertices})

    # ---- Swept positions (continuous collision detection) -----------------------------------

    def refit_swept(self, x0: Any, x1: Any) -> None:
        """Swept positions, for continuous collision detection (CCD): every vertex moves
        linearly from ``x0`` to ``x1`` over the step (x(t) = x0 + t (x1 - x0), t in [0, 1]; each
        (n, 3) as for :meth:`refit`). The scene keeps both, boxes each element over both and
        refits its trees to those boxes (keeping the grouping of the last build, as
        :meth:`refit` does). Its queries are then swept (:attr:`is_swept`) until the next
        :meth:`refit` or :meth:`rebuild`: they report every pair whose elements come within r at
        some time of the step, the candidates a CCD narrow phase then decides.

        The modes test the elements' swept boxes. VT takes the vertex as its path, the segment
        x0 -> x1: ``"box"`` (its box grown by r), ``"capsule_ray"`` and ``"capsule_exact"`` (the
        capsule of radius r around it), and ``"sphere"``, the same as ``"capsule_exact"`` (the
        sphere swept along the path). VV and EV test paths as VT does (VV each vertex's path
        against the other's box), in every mode. EE runs ``"box"`` only (each edge's swept box
        grown by r): its other modes, and ``leaf_exact=True`` in every query (it needs the time
        of closest approach, which the narrow phase finds), raise :class:`UnsupportedError`.
        ``drop_incident`` and the once-per-pair EE and VV rule apply as for static queries. At
        ``x0 == x1`` the pairs are the static ones (VT, VV and EV ``"capsule_exact"`` and
        ``"sphere"``: the static ``"sphere"`` pairs). A float64 scene reports every pair within
        r in double at some time of the step. Results are like the vertices last given (``x1``,
        else ``x0``, when of another library).

        Errors: those of :meth:`refit` for either array (a wrong dtype or shape names ``x0`` or
        ``x1``); on error the scene keeps its positions, trees and swept state.

        A vertex flying from x = -1 to x = +1 through a still triangle in the plane x = 0: no
        static query at either end finds it, the swept ones do.

        >>> import numpy as np, minkq
        >>> x0 = np.array([[0, -1, -1], [0, 2, -1], [0, -1, 2], [-1, .1, .1]], np.float32)
        >>> x1 = x0.copy()
        >>> x1[3, 0] = 1.0  # vertex 3 crosses triangle 0
        >>> scene = minkq.Scene(x0, np.array([[0, 1, 2]], np.int32))
        >>> modes = ("box", "sphere", "capsule_ray", "capsule_exact")
        >>> for x in (x0, x1):  # at rest at either end, 1 from the triangle
        ...     scene.refit(x)
        ...     print([scene.query("vt", 0.01, mode=mode).tolist() for mode in modes])
        [[], [], [], []]
        [[], [], [], []]
        >>> scene.refit_swept(x0, x1)
        >>> scene.is_swept, [scene.query("vt", 0.01, mode=mode).tolist() for mode in modes]
        (True, [[[3, 0]], [[3, 0]], [[3, 0]], [[3, 0]]])
        >>> try:
        ...     scene.query("ee", 0.01, mode="capsule_exact")
        ... except minkq.UnsupportedError as e:
        ...     print(e)
        query: swept EE queries run box mode only (a moving edge sweeps no segment)
        >>> scene.refit(x1)  # a plain refit: static again
        >>> scene.is_swept
        False
        """
        self._move(self._native.refit_swept, {"x0": x0, "x1": x1})

    def rebuild_swept(self, x0: Any, x1: Any) -> None:
        """Swept positions like :meth:`refit_swept`, with the trees built afresh for the
        elements' swept boxes, as :meth:`rebuild` builds them for static positions. The pairs
        are those of :meth:`refit_swept`; only the speed of later queries differs (worth it when
        a step's motion is large next to the elements). Same errors; on error the scene keeps
        its positions, trees and swept state."""
        self._move(self._native.rebuild_swept, {"x0": x0, "x1": x1})

    @property
    def is_swept(self) -> bool:
        """Whether the scene's positions are swept ones (:meth:`refit_swept`,
        :meth:`rebuild_swept` and their stream-ordered variants, from the call on), so that its
        queries are swept: False after creation and after every plain refit or rebuild, blocking
        or stream-ordered."""
        return self._native.is_swept()

    def tree_growth(self) -> float:
        """How far the refits since the last build (the constructor or :meth:`rebuild`) have
        stretched the trees: their area cost (scale-free; it grows with the nodes a query
        visits) now over its value right after that build, the larger of the scene's two trees.
        1.0 after a build. It sees boxes that stretch, not a mesh folding or flattening into new
        neighbours (where a rebuild can still help). Rebuild when it passes about 1.5, and every
        so many steps when the mesh changes shape a lot (the C header; what rebuilds bought on
        the benchmark scenes is in ``docs/design-notes.md``). A tree whose elements all lie on one
        line parallel to an axis (or at one point) has no area: 1.0 while it stays so, ``inf``
        once it has any.

        >>> import numpy as np, minkq
        >>> u, v = np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 9))
        >>> flat = np.stack([u.ravel(), v.ravel(), np.zeros(81)], 1).astype(np.float32)
        >>> i, j = np.meshgrid(np.arange(8), np.arange(8))
        >>> v00 = (j * 9 + i).ravel()
        >>> tris = np.concatenate([np.stack([v00, v00 + 1, v00 + 10], 1), np.stack([v00, v00 + 10, v00 + 9], 1)])
        >>> scene = minkq.Scene(flat, tris.astype(np.int32))
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

    def _move(
        self,
        call: Callable[..., None],
        positions: Dict[str, Any],
        stream: Any = _BLOCKING,
        dtype: Optional[np.dtype] = None,
    ) -> None:
        """Passes vertex positions (by argument name: ``vertices``, or ``x0`` and ``x1``) of the
        scene's precision (or ``dtype``: one geometry's) to ``call``: for a blocking call (no
        ``stream``) with host arrays converted to it; for a stream-ordered one read in place,
        with the handle of ``stream`` (None: the current stream of the positions' library) after
        them. Results are then made like the last array of another library among them."""
        blocking = stream is _BLOCKING
        handle = None if blocking else stream_handle(stream, self.device, tuple(positions.values()))
        args = _Args(self.device, handle)
        dtype = self._dtype if dtype is None else dtype
        native = [args.vertices(value, name, dtype, convert=blocking)[0] for name, value in positions.items()]
        if blocking:
            call(*native)
        else:
            call(*native, handle)
            self._stream = handle
        self._like = _like(args.last)

    def __repr__(self) -> str:
        if self.closed:
            return "minkq.Scene(closed)"
        precision = ", float64" if self._dtype == FLOAT64 else ""
        if self.geometry_count > 1:
            precision += f", {self.geometry_count} geometries"
        return f"minkq.Scene({self.vertex_count} vertices, {self.triangle_count} triangles, {self.edge_count} edges{precision})"


def _old_constructor(positional: tuple, device: Any) -> tuple:
    """``((vertices, triangles, edges), device)`` of the constructor's positional arguments, also
    in the old spelling ``Scene(device, vertices, triangles, edges=None)`` (with a
    DeprecationWarning)."""
    positional, device = old_device_form("Scene", positional, device, depth=2)
    if len(positional) > 3 and any(p is not None for p in positional[3:]):
        raise TypeError(f"Scene: expected (vertices, triangles=None, edges=None, *, device=None, ...), got {len(positional)} positional arguments")
    if positional and (positional[0] is None or isinstance(positional[0], str)):
        hint = ": the device is a keyword, Scene(vertices, triangles, device=...)" if positional[0] is not None else ""
        raise TypeError(f"vertices: expected an (n, 3) array, got {positional[0]!r}{hint}")
    return (tuple(positional) + (None, None, None))[:3], device
