"""Type stubs for the extension module minkq._native (bindings/python/src/lib.rs). Use the
typed wrappers in the minkq package; this layer expects arrays already checked by it."""

from typing import Optional, Tuple

import numpy as np
import numpy.typing as npt

ABI_VERSION: int

class Device:
    name: str
    backend: str
    def __init__(self, spec: str) -> None: ...

class Scene:
    vertex_count: int
    triangle_count: int
    edge_count: int
    def __init__(
        self,
        device: Device,
        vertices: npt.NDArray[np.float32],
        triangles: npt.NDArray[np.int32],
        edges: Optional[npt.NDArray[np.int32]],
        vt: bool,
        ee: bool,
        drop_incident: bool,
    ) -> None: ...
    def refit(self, vertices: npt.NDArray[np.float32]) -> None: ...
    def edges_into(self, out: npt.NDArray[np.int32]) -> None: ...
    def query_into(
        self,
        out: npt.NDArray[np.int32],
        kind: str,
        mode: str,
        radius: float,
        leaf_exact: bool,
        canonical: bool,
        digest: bool,
    ) -> Tuple[int, Optional[int]]: ...

class Bvh:
    box_count: int
    def __init__(self, device: Device, boxes: npt.NDArray[np.float32]) -> None: ...
    def refit(self, boxes: npt.NDArray[np.float32]) -> None: ...
    def query_into(
        self,
        out: npt.NDArray[np.int32],
        shape: str,
        queries: npt.NDArray[np.float32],
        mode: str,
        radius: float,
        canonical: bool,
        digest: bool,
    ) -> Tuple[int, Optional[int]]: ...

def cuda_device_count() -> int: ...
def version() -> Tuple[int, int, int]: ...
def abi_version() -> int: ...
def _raise_status(status: int, message: str) -> None: ...
