"""The typed Python surface over minkq._native, gathered from the modules of its concerns:
argument checks with messages naming the argument (minkq._args); numpy arrays, and arrays of
other libraries read in place through DLPack or the CUDA array interface (minkq._interop), in
and out; output arrays sized from the exact counts (minkq._results); devices (minkq._device),
mesh scenes (minkq._scene, their stream-ordered calls in minkq._stream_ordered, their
geometries in minkq._geometry) and box BVHs (minkq._bvh)."""

from ._args import KINDS, MODES
from ._bvh import BVH
from ._conventions import PairBuffer
from ._device import Device, abi_version, cuda_device_count, version
from ._geometry import ELEMENTS, Geometry
from ._results import QueryInfo, WorkStats
from ._scene import Scene

__all__ = [
    "BVH",
    "KINDS",
    "MODES",
    "Device",
    "ELEMENTS",
    "Geometry",
    "PairBuffer",
    "QueryInfo",
    "Scene",
    "WorkStats",
    "abi_version",
    "cuda_device_count",
    "version",
]
