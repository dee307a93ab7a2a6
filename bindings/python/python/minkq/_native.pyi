"""Type stubs for the extension module minkq._native (bindings/python/src/lib.rs). Use the
typed wrappers in the minkq package; this layer expects arrays already checked by it: numpy
arrays (the buffer protocol) or raw descriptors (address, byte_stride, count, device memory)
that minkq._interop built from DLPack / CUDA array interface objects it keeps alive. The
*_async methods take the cudaStream_t they are enqueued on as an int (``stream_address``; 0:
CUDA's default stream; ignored on the CPU)."""

from typing import Any, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

Raw = Tuple[int, int, int, bool]

ABI_VERSION: int

class Device:
    name: str
    backend: str
    def __init__(self, spec: str) -> None: ...

# Vertex rows: (n, 3) float32, or float64 for a scene created with float64=True
# (MINKQ_SCENE_FLOAT64), which reads every vertex buffer as doubles.
Vertices = Union[npt.NDArray[np.float32], npt.NDArray[np.float64], Raw]

class Scene:
    vertex_count: int
    triangle_count: int
    edge_count: int
    # Whether whole-scene moves read doubles (MINKQ_SCENE_FLOAT64; for a scene of geometries,
    # every moving geometry is float64).
    float64: bool
    geometry_count: int
    def __init__(
        self,
        device: Device,
        vertices: Vertices,
        triangles: Union[npt.NDArray[np.int32], Raw],
        edges: Optional[Union[npt.NDArray[np.int32], Raw]],
        vt: bool,
        ee: bool,
        vv: bool,
        ev: bool,
        drop_incident: bool,
        float64: bool,
    ) -> None: ...
    # A scene of geometries: minkq._geometry._NativeGeometry descriptions (read by attribute:
    # vertices, triangles, edges, thickness, float64, vt, ee, vv, ev, self_pairs, drop_incident,
    # static, world (-1: every world), group, mask).
    @staticmethod
    def from_geometries(device: Device, geometries: List[Any]) -> "Scene": ...
    # (first global id, count) of "vertex", "triangle" or "edge".
    def geometry_range(self, g: int, element: str) -> Tuple[int, int]: ...
    def refit_geometry(self, g: int, vertices: Vertices) -> None: ...
    def rebuild_geometry(self, g: int, vertices: Vertices) -> None: ...
    def refit_geometry_swept(self, g: int, x0: Vertices, x1: Vertices) -> None: ...
    def rebuild_geometry_swept(self, g: int, x0: Vertices, x1: Vertices) -> None: ...
    def refit(self, vertices: Vertices) -> None: ...
    def rebuild(self, vertices: Vertices) -> None: ...
    def refit_swept(self, x0: Vertices, x1: Vertices) -> None: ...
    def rebuild_swept(self, x0: Vertices, x1: Vertices) -> None: ...
    def is_swept(self) -> bool: ...
    def tree_growth(self) -> float: ...
    def edges_into(self, out: npt.NDArray[np.int32]) -> None: ...
    def query_into(
        self,
        out: Union[npt.NDArray[np.int32], Raw],
        kind: str,
        mode: str,
        radius: float,
        leaf_exact: bool,
        canonical: bool,
        digest: bool,
    ) -> Tuple[int, Optional[int]]: ...
    def query_vt_ee_into(
        self,
        vt_out: Union[npt.NDArray[np.int32], Raw],
        ee_out: Union[npt.NDArray[np.int32], Raw],
        vt_mode: str,
        ee_mode: str,
        radius: float,
        leaf_exact: bool,
        canonical: bool,
        digest: bool,
    ) -> Tuple[Tuple[int, Optional[int]], Tuple[int, Optional[int]]]: ...
    def work(self, kind: str, mode: str, radius: float, leaf_exact: bool) -> Tuple[int, int, int, int]: ...
    def count(self, kind: str, mode: str, radius: float, leaf_exact: bool) -> int: ...
    def reserve(self, refit: bool, rebuild: bool, swept: bool, canonical_capacity: int) -> None: ...
    def refit_async(self, vertices: Vertices, stream_address: int) -> None: ...
    def rebuild_async(self, vertices: Vertices, stream_address: int) -> None: ...
    def refit_swept_async(self, x0: Vertices, x1: Vertices, stream_address: int) -> None: ...
    def rebuild_swept_async(self, x0: Vertices, x1: Vertices, stream_address: int) -> None: ...
    def query_async(
        self,
        out: Union[npt.NDArray[np.int32], Raw],
        count: Union[npt.NDArray[np.uint64], Raw],
        kind: str,
        mode: str,
        radius: float,
        leaf_exact: bool,
        canonical: bool,
        stream_address: int,
    ) -> None: ...
    def query_vt_ee_async(
        self,
        vt_out: Union[npt.NDArray[np.int32], Raw],
        vt_count: Union[npt.NDArray[np.uint64], Raw],
        ee_out: Union[npt.NDArray[np.int32], Raw],
        ee_count: Union[npt.NDArray[np.uint64], Raw],
        vt_mode: str,
        ee_mode: str,
        radius: float,
        leaf_exact: bool,
        canonical: bool,
        stream_address: int,
    ) -> None: ...
    def async_status(self, stream_address: int) -> None: ...

class Bvh:
    box_count: int
    def __init__(self, device: Device, boxes: Union[npt.NDArray[np.float32], Raw]) -> None: ...
    def refit(self, boxes: Union[npt.NDArray[np.float32], Raw]) -> None: ...
    def rebuild(self, boxes: Union[npt.NDArray[np.float32], Raw]) -> None: ...
    def tree_growth(self) -> float: ...
    def query_into(
        self,
        out: Union[npt.NDArray[np.int32], Raw],
        shape: str,
        queries: Union[npt.NDArray[np.float32], Raw],
        mode: str,
        radius: float,
        canonical: bool,
        digest: bool,
    ) -> Tuple[int, Optional[int]]: ...
    def count(self, shape: str, queries: Union[npt.NDArray[np.float32], Raw], mode: str, radius: float) -> int: ...

def cuda_device_count() -> int: ...
def version() -> Tuple[int, int, int]: ...
def abi_version() -> int: ...
def _raise_status(status: int, message: str) -> None: ...
def _exception(status: int, message: str, needed: Optional[int] = None) -> MinkqError: ...

# The exceptions (src/errors.rs), re-exported by minkq._errors.
class MinkqError(Exception):
    status: int
    status_name: str
    message: str
    def __init__(self, message: str, status: Optional[int] = None) -> None: ...

class InvalidArgumentError(MinkqError, ValueError): ...
class NonFiniteError(MinkqError, ValueError): ...
class IndexOutOfRangeError(MinkqError, ValueError): ...
class SizeOverflowError(MinkqError, OverflowError): ...

class CapacityError(MinkqError):
    needed: int
    def __init__(self, message: str, needed: int = 0) -> None: ...

class UnsupportedError(MinkqError): ...
class OutOfMemoryError(MinkqError, MemoryError): ...
class DeviceError(MinkqError, RuntimeError): ...
class InternalError(MinkqError, RuntimeError): ...
