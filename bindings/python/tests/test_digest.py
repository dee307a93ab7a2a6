"""Digests and pairs equal to the C API's for the same scene: the C library is called here
directly through ctypes, bypassing the Rust and pyo3 layers; and the digest is the xxHash64
(seed 0) of the canonical little-endian int32 pairs, checked with an XXH64 written here."""

import ctypes
import os
import struct

import numpy as np
import pytest

import minkq
from oracle import degenerate_soup, rolled_sheet


def load_library() -> ctypes.CDLL:
    """The libminkq the extension loaded (a repaired wheel's minkq.libs/libminkq-<hash>.so.N,
    or the build tree's libminkq.so.N, N the ABI version), as /proc/self/maps names it; else
    MINKQ_LIB_DIR's."""
    from minkq import _native  # noqa: F401  (loads the library)

    with open("/proc/self/maps") as maps:
        loaded = sorted({line.split()[-1] for line in maps if "/libminkq" in line})
    candidates = loaded[:1]
    if os.environ.get("MINKQ_LIB_DIR"):
        candidates.append(os.path.join(os.environ["MINKQ_LIB_DIR"], "libminkq.so"))
    for path in candidates:
        if os.path.exists(path):
            return declare(ctypes.CDLL(path))
    pytest.skip(f"no libminkq in {candidates}")


class Buffer(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("byte_stride", ctypes.c_size_t), ("count", ctypes.c_size_t), ("memory", ctypes.c_uint)]


class SceneDesc(ctypes.Structure):
    _fields_ = [("flags", ctypes.c_uint32), ("vertices", Buffer), ("triangles", Buffer), ("edges", Buffer)]


class QueryDesc(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_uint), ("mode", ctypes.c_uint), ("flags", ctypes.c_uint32), ("radius", ctypes.c_float)]


class QueryStats(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint64) for name in ("nodes_visited", "node_tests", "primitive_tests", "candidates")]


class QueryInfo(ctypes.Structure):
    # The whole struct of ABI 2: the library writes all of it (stats zeroed when not asked for),
    # so a shorter mirror would let it write past this buffer.
    _fields_ = [("count", ctypes.c_uint64), ("digest", ctypes.c_uint64), ("stats", QueryStats)]


MIRRORED_ABI_VERSION = 2


def declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Prototypes for the functions used here, so ctypes converts every argument to its C type
    (without them a Python int is passed as a C int, whatever the parameter's width)."""
    p, size, u32 = ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint32
    for name, restype, argtypes in [
        ("minkq_abi_version", u32, []),
        ("minkq_device_create", ctypes.c_int, [ctypes.c_char_p, p]),
        ("minkq_device_release", None, [p]),
        ("minkq_scene_create", ctypes.c_int, [p, ctypes.POINTER(SceneDesc), p]),
        ("minkq_scene_release", None, [p]),
        ("minkq_scene_query", ctypes.c_int, [p, ctypes.POINTER(QueryDesc), p, size, ctypes.c_uint, ctypes.POINTER(QueryInfo)]),
    ]:
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes
    if lib.minkq_abi_version() != MIRRORED_ABI_VERSION:
        pytest.fail(f"libminkq ABI {lib.minkq_abi_version()}, this ctypes mirror is of ABI {MIRRORED_ABI_VERSION}: update it")
    return lib


KIND = {"vt": 0, "ee": 1}
MODE = {"box": 0, "sphere": 1, "capsule_ray": 2, "capsule_exact": 3}
LEAF_EXACT, CANONICAL, DIGEST = 1, 2, 4


class CScene:
    """A scene made and queried through the C API alone."""

    def __init__(self, lib, xyz, tris):
        self.lib, self.xyz, self.tris = lib, np.ascontiguousarray(xyz), np.ascontiguousarray(tris)
        self.device = ctypes.c_void_p()
        assert lib.minkq_device_create(b"cpu", ctypes.byref(self.device)) == 0
        desc = SceneDesc(
            1 | 2 | 4,
            Buffer(self.xyz.ctypes.data, 12, len(self.xyz), 0),
            Buffer(self.tris.ctypes.data, 12, len(self.tris), 0),
            Buffer(None, 0, 0, 0),
        )
        self.scene = ctypes.c_void_p()
        assert lib.minkq_scene_create(self.device, ctypes.byref(desc), ctypes.byref(self.scene)) == 0

    def c_query(self, kind, mode, r, flags):
        q = QueryDesc(KIND[kind], MODE[mode], flags | DIGEST, ctypes.c_float(r))
        info = QueryInfo()
        status = self.lib.minkq_scene_query(self.scene, ctypes.byref(q), None, ctypes.c_size_t(0), 0, ctypes.byref(info))
        assert status in (0, 5)  # SUCCESS, or CAPACITY with the exact count
        out = np.empty((info.count, 2), np.int32)
        status = self.lib.minkq_scene_query(self.scene, ctypes.byref(q), out.ctypes.data_as(ctypes.c_void_p), ctypes.c_size_t(len(out)), 0, ctypes.byref(info))
        assert status == 0
        return out, info.digest

    def close(self):
        self.lib.minkq_scene_release(self.scene)
        self.lib.minkq_device_release(self.device)


def xxh64(data: bytes) -> int:
    """XXH64 with seed 0, from the specification."""
    p1, p2, p3, p4, p5 = 0x9E3779B185EBCA87, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9, 0x85EBCA77C2B2AE63, 0x27D4EB2F165667C5
    mask = (1 << 64) - 1

    def rotl(x, r):
        return ((x << r) | (x >> (64 - r))) & mask

    def round_(acc, lane):
        return (rotl((acc + lane * p2) & mask, 31) * p1) & mask

    n, i = len(data), 0
    if n >= 32:
        v = [(p1 + p2) & mask, p2, 0, (-p1) & mask]
        while i + 32 <= n:
            lanes = struct.unpack_from("<4Q", data, i)
            v = [round_(a, b) for a, b in zip(v, lanes)]
            i += 32
        h = (rotl(v[0], 1) + rotl(v[1], 7) + rotl(v[2], 12) + rotl(v[3], 18)) & mask
        for lane in v:
            h = (((h ^ round_(0, lane)) * p1) + p4) & mask
    else:
        h = p5
    h = (h + n) & mask
    while i + 8 <= n:
        (lane,) = struct.unpack_from("<Q", data, i)
        h = ((rotl(h ^ round_(0, lane), 27) * p1) + p4) & mask
        i += 8
    if i + 4 <= n:
        (word,) = struct.unpack_from("<I", data, i)
        h = ((rotl(h ^ ((word * p1) & mask), 23) * p2) + p3) & mask
        i += 4
    while i < n:
        h = (rotl(h ^ ((data[i] * p5) & mask), 11) * p1) & mask
        i += 1
    h ^= h >> 33
    h = (h * p2) & mask
    h ^= h >> 29
    h = (h * p3) & mask
    return h ^ (h >> 32)


def test_xxh64_matches_the_specification():
    assert xxh64(b"") == 0xEF46DB3751D8E999
    assert xxh64(b"a") == 0xD24EC4F1A98C6E5B
    assert xxh64(b"abc") == 0x44BC2CF5AD770999


@pytest.mark.parametrize("make, r", [(lambda: rolled_sheet(14, 1), 0.03), (lambda: degenerate_soup(80, 2), 0.04)])
def test_pairs_and_digests_equal_the_c_api(device, make, r):
    xyz, tris = make()
    c_scene = CScene(load_library(), xyz, tris)
    try:
        scene = minkq.Scene(xyz, tris, device=device)
        for kind, mode in [("vt", "box"), ("vt", "sphere"), ("ee", "box"), ("ee", "capsule_ray"), ("ee", "capsule_exact")]:
            for leaf_exact in (False, True):
                pairs, digest = scene.query_digest(kind, r, mode=mode, leaf_exact=leaf_exact)
                c_pairs, c_digest = c_scene.c_query(kind, mode, r, LEAF_EXACT if leaf_exact else 0)
                assert np.array_equal(pairs, c_pairs), (kind, mode, leaf_exact)
                assert digest == c_digest, (kind, mode, leaf_exact)
                assert digest == xxh64(pairs.astype("<i4").tobytes())
                out = np.empty((len(pairs), 2), np.int32)
                got, got_digest = scene.query_digest(kind, r, mode=mode, leaf_exact=leaf_exact, out=out)
                assert (len(got), got_digest) == (len(pairs), digest)
                assert len(pairs) > 0
    finally:
        c_scene.close()


def test_digest_of_the_default_demo_scene_equals_the_c_api(device):
    """The default `minkq demo` scene (twisted sheet 388 x 388): VT leaf_exact pairs and digest
    through the bindings equal the C API's."""
    from minkq import demo

    xyz, tris = demo.twisted_sheet(demo.DEFAULT_SIZE, 3.0)
    r = float(np.float32(demo.DEFAULT_FACTOR * demo.mean_edge_length(xyz, demo.derive_edges(tris))))
    c_scene = CScene(load_library(), xyz, tris)
    try:
        pairs, digest = minkq.Scene(xyz, tris, device=device).query_digest("vt", r, mode="sphere", leaf_exact=True)
        c_pairs, c_digest = c_scene.c_query("vt", "sphere", r, LEAF_EXACT)
        assert len(pairs) == demo.REFERENCE_CONTACTS["vt"]
        assert digest == c_digest and np.array_equal(pairs, c_pairs)
    finally:
        c_scene.close()
