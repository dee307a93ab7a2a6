"""Arguments on their way to minkq._native: host arrays converted once to minkq's dtypes (or used
in place when they have them), arrays of other libraries checked and described in place
(minkq._interop), output and count arrays checked, and the names, modes and radii of queries
checked, each with a message naming the argument."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional, Tuple

import numpy as np

from ._errors import IndexOutOfRangeError
from ._interop import Like, checked, checked_count, has_protocol, host_copy, like, view

if TYPE_CHECKING:
    from typing import Literal

    import numpy.typing as npt

    from ._device import Device

    Kind = Literal["vt", "ee", "vv", "ev"]
    Mode = Literal["box", "sphere", "capsule_ray", "capsule_exact"]
    Shape = Literal["sphere", "capsule", "box"]
    Pairs = npt.NDArray[np.int32]

    from typing import Protocol, Union

    class SupportsDLPack(Protocol):
        """An array of another library read through DLPack (Warp, PyTorch, CuPy, JAX)."""

        def __dlpack__(self, *, stream: Any = ...) -> Any: ...

        def __dlpack_device__(self) -> Tuple[int, int]: ...

    class SupportsCudaArrayInterface(Protocol):
        """An array of another library read through the CUDA array interface (Numba, CuPy)."""

        @property
        def __cuda_array_interface__(self) -> Any: ...

    Foreign = Union[SupportsDLPack, SupportsCudaArrayInterface]
    """Arrays of other libraries: results made like them are of their library, hence Any."""
    Array = Union["npt.ArrayLike", Foreign]
    """What an array argument takes: numpy arrays and sequences, and arrays of other libraries."""

KINDS = ("vt", "ee", "vv", "ev")
MODES = ("box", "sphere", "capsule_ray", "capsule_exact")
FLOAT32, FLOAT64 = np.dtype(np.float32), np.dtype(np.float64)


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
    array = _array(value, name, dtype, trailing)
    if array.dtype != dtype:
        array = _converted(array, name, dtype)
    if array.ndim != 1 + len(trailing) or array.shape[1:] != trailing:
        wanted = ", ".join(["n"] + [str(d) for d in trailing])
        raise ValueError(f"{name}: expected shape ({wanted}), got {array.shape}")
    if not (array.flags.c_contiguous and array.flags.aligned):
        array = np.require(array, requirements=("C", "A"))  # strided input: a contiguous copy
    return array


def _array(value: Any, name: str, dtype: np.dtype, trailing: Tuple[int, ...]) -> np.ndarray:
    """``value`` as a numpy array, itself if it is one, in the dtype numpy reads it in (an empty
    sequence as an empty (0, *trailing) array of ``dtype``)."""
    if isinstance(value, np.ndarray):
        return value
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name}: expected an array of {dtype.name}, got {type(value).__name__}: {e}") from None
    if array.size == 0:
        array = array.astype(dtype)
    if array.size == 0 and array.ndim == 1:
        array = array.reshape((0,) + trailing)
    return array


def _vertex_precision(name: str, found: np.dtype, scene: Optional[np.dtype], where: str, converts: str) -> np.dtype:
    """The dtype vertices of dtype ``found`` are passed in to a scene of precision ``scene``
    (None: a new scene, float64 from float64 values, float32 from narrower floats and
    integers); TypeError naming the argument where that would round: double values for a
    float32 scene, floats wider than double, and, unless ``converts`` is empty (then they are
    converted exactly), other dtypes for a float64 scene (``converts`` says why not)."""
    if found.kind == "f" and found.itemsize > 8:
        raise TypeError(
            f"{name}: expected float32 or float64 values, got {found}{where}: minkq does not round wider floats; "
            "convert them to float64 yourself"
        )
    double = found.kind == "f" and found.itemsize == 8
    if scene is None:
        return FLOAT64 if double else FLOAT32
    if scene == FLOAT32 and double:
        raise TypeError(
            f"{name}: got {found} values{where} for a scene created from float32 vertices, which would round "
            "them to float32 and could lose a pair within r in double: create the scene from float64 vertices "
            "to have every pair within r in double reported, or pass float32 values"
        )
    if scene == FLOAT64 and found != FLOAT64 and converts:
        raise TypeError(
            f"{name}: expected float64 values, the dtype of the scene's vertices, got {found}{where}: {converts}"
        )
    return scene


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
                        f"{name}[{', '.join(map(str, at))}] = {array[at]} does not fit in {dtype.name}: minkq indices "
                        f"are {dtype.name} (0 to {info.max})"
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
        array = view(value, name, self.device, self.stream)
        dtype = np.dtype(dtype)
        if dtype.kind == "i" and array.dtype != dtype and array.dtype.kind in "iu" and self.stream is None:
            # Other integer indices (PyTorch's int64 faces): converted as numpy's are, range
            # checked, through a host copy (indices are read once, when the scene is built).
            return _rows(host_copy(value), name, dtype, trailing)
        array = checked(array, name, dtype, trailing)
        self.views.append(array)
        return array.descriptor()

    def vertices(self, value: Any, name: str, scene: Optional[np.dtype], *, convert: bool = True) -> Tuple[Any, np.dtype]:
        """Vertex rows (n, 3) for a scene of precision ``scene`` (FLOAT32 or FLOAT64; None for a
        new scene: FLOAT64 from float64 values, FLOAT32 from any other), and that precision.
        Host values for a float64 scene are converted to float64 (exactly: from float32 and
        narrower) when ``convert`` (the blocking calls); arrays of other libraries, and host
        arrays where not ``convert`` (the stream-ordered calls), must have the scene's dtype.
        Double values for a float32 scene raise TypeError rather than be rounded."""
        if has_protocol(value):
            array = view(value, name, self.device, self.stream)
            if scene is None and array.dtype not in (FLOAT32, FLOAT64):
                raise TypeError(f"{name}: expected a float32 or float64 array, got {array.dtype.name} ({array.kind}, {array.where})")
            never = "arrays of other libraries are read in place, never converted: pass a float64 array"
            scene = _vertex_precision(name, array.dtype, scene, f" ({array.kind}, {array.where})", never)
            array = checked(array, name, scene, (3,))
            self.views.append(array)
            return array.descriptor(), scene
        host = _array(value, name, FLOAT32, (3,))
        never = "" if convert else "the stream-ordered calls read their arrays in place, never converted"
        scene = _vertex_precision(name, host.dtype, scene, "", never)
        return _rows(host, name, scene, (3,)), scene

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
