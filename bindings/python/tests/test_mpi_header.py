"""minkq.mpi's ctypes declarations against the C headers they mirror (mpi/minkq_mpi.h and
capi/minkq.h): a C probe compiled with mpicc against the real headers prints the size of each
struct, the offset, size and kind (floating or not) of each field the module declares, the
value of each constant and the size of each C type of its function signatures, and every one
must equal the module's; the signatures themselves must be the headers' (checked when the
probe compiles). Skipped, with the reason, without mpicc or where the headers are not beside
these tests (an installed copy)."""

import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest

import minkq.mpi

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
HEADER = os.path.join(ROOT, "mpi", "minkq_mpi.h")

_FLOATING = (ctypes.c_float, ctypes.c_double)


def _include_dirs():
    """The headers' folders, and where a build may generate headers they include."""
    dirs = [os.path.join(ROOT, "capi"), os.path.join(ROOT, "mpi")]
    lib_dir = os.environ.get("MINKQ_LIB_DIR")
    if lib_dir:
        dirs += [lib_dir, os.path.join(lib_dir, "..", "mpi")]
    return dirs


def _signature_types(functions):
    return sorted({t for result, parameters in functions.values() for t in (result, *parameters)} - {"void"})


def declarations(structs, constants, functions):
    """What the module declares, as the probe prints it: one line per struct size, field,
    constant and C type of the signatures."""
    lines = []
    for c_name, struct in structs.items():
        lines.append(f"sizeof {c_name} {ctypes.sizeof(struct)}")
        for field, kind in struct._fields_:
            floating = int(kind in _FLOATING)
            lines.append(f"field {c_name}.{field} {getattr(struct, field).offset} {ctypes.sizeof(kind)} {floating}")
    lines += [f"constant {name} {value}" for name, value in constants.items()]
    lines += [f"type {t} {ctypes.sizeof(minkq.mpi._ctype(t))}" for t in _signature_types(functions)]
    return lines


def probe_source(structs, constants, functions):
    """C that prints, from the headers, the lines declarations() makes from the module; a field
    or constant the headers lack, or a function whose signature differs, does not compile."""
    out = ["#include <stddef.h>", "#include <stdio.h>", '#include "minkq_mpi.h"',
           "#define FLOATING(x) _Generic((x), float: 1, double: 1, long double: 1, default: 0)",
           "int main(void) {"]
    for c_name, struct in structs.items():
        out.append(f'  printf("sizeof {c_name} %zu\\n", sizeof({c_name}));')
        for field, _ in struct._fields_:
            member = f"(({c_name}*)0)->{field}"
            out.append(f'  printf("field {c_name}.{field} %zu %zu %d\\n", offsetof({c_name}, {field}), '
                       f"sizeof({member}), FLOATING({member}));")
    for name in constants:
        out.append(f'  printf("constant {name} %lld\\n", (long long)({name}));')
    for t in _signature_types(functions):
        out.append(f'  printf("type {t} %zu\\n", sizeof({t}));')
    for name, (result, parameters) in functions.items():
        pointer = f"{result} (*)({', '.join(parameters) or 'void'})"
        out.append(f'  _Static_assert(__builtin_types_compatible_p(__typeof__(&{name}), {pointer}), '
                   f'"{name} is not {pointer}");')
    out += ["  return 0;", "}"]
    return "\n".join(out) + "\n"


def from_headers(structs, constants, functions, tmp_path):
    """The probe's lines, compiled and run; AssertionError with the compiler's output if it
    does not compile."""
    source = tmp_path / "probe.c"
    source.write_text(probe_source(structs, constants, functions))
    binary = tmp_path / "probe"
    flags = [f"-I{d}" for d in _include_dirs()]
    build = subprocess.run(["mpicc", "-std=c11", *flags, str(source), "-o", str(binary)],
                           capture_output=True, text=True)
    assert build.returncode == 0, f"the probe does not compile against the headers:\n{build.stderr}"
    run = subprocess.run([str(binary)], capture_output=True, text=True, check=True)
    return run.stdout.splitlines()


def _functions():
    return {**minkq.mpi._C_FUNCTIONS, **minkq.mpi._C_CORE_FUNCTIONS}


@pytest.fixture
def probe_ready():
    if not os.path.exists(HEADER):
        pytest.skip(f"{HEADER} is not beside these tests (an installed copy)")
    if shutil.which("mpicc") is None:
        pytest.skip("no mpicc (minkq_mpi.h includes mpi.h)")


def test_ctypes_declarations_match_the_headers(probe_ready, tmp_path):
    structs, constants, functions = minkq.mpi._C_STRUCTS, minkq.mpi._C_CONSTANTS, _functions()
    header, module = from_headers(structs, constants, functions, tmp_path), declarations(structs, constants, functions)
    drift = [f"header: {h} | minkq.mpi: {m}" for h, m in zip(header, module) if h != m]
    assert len(header) == len(module) and not drift, "minkq.mpi differs from the headers:\n" + "\n".join(drift)


class _DriftedQueryDesc(ctypes.Structure):
    # minkq_query_desc with its radius declared as a double.
    _fields_ = [("kind", ctypes.c_int), ("mode", ctypes.c_int), ("flags", ctypes.c_uint32), ("radius", ctypes.c_double)]


@pytest.mark.parametrize(
    "drift",
    [
        pytest.param(lambda s, c: ({**s, "minkq_query_desc": _DriftedQueryDesc}, c), id="a field's type"),
        pytest.param(lambda s, c: (s, {**c, "MINKQ_QUERY_COUNT": 32}), id="a flag's value"),
        pytest.param(lambda s, c: (s, {**c, "MINKQ_ABI_VERSION": 1}), id="the ABI version"),
        pytest.param(lambda s, c: ({**s, "minkq_mpi_rank_info": type("Short", (ctypes.Structure,), {
            "_fields_": minkq.mpi._RankInfo._fields_[:-1]})}, c), id="a missing field"),
    ],
)
def test_a_drifted_declaration_fails_the_check(probe_ready, tmp_path, drift):
    # The check itself: each kind of drift from the headers is seen.
    structs, constants = drift(minkq.mpi._C_STRUCTS, minkq.mpi._C_CONSTANTS)
    assert from_headers(structs, constants, {}, tmp_path) != declarations(structs, constants, {})


def test_a_field_the_header_lacks_does_not_compile(probe_ready, tmp_path):
    class Renamed(ctypes.Structure):
        _fields_ = [("lo", ctypes.c_uint64)] + minkq.mpi._Stats._fields_[1:]

    with pytest.raises(AssertionError, match="does not compile"):
        from_headers({"minkq_query_stats": Renamed}, {}, {}, tmp_path)


@pytest.mark.parametrize(
    "name, signature",
    [
        ("minkq_mpi_scene_set_skin", ("minkq_status", ("minkq_mpi_scene*", "float"))),
        ("minkq_mpi_result_count", ("int", ("const minkq_mpi_result*",))),
        ("minkq_mpi_scene_refit", ("minkq_status", ("minkq_mpi_scene*", "const minkq_buffer*"))),
        ("minkq_device_create", ("minkq_status", ("minkq_device**",))),
    ],
)
def test_a_drifted_signature_does_not_compile(probe_ready, tmp_path, name, signature):
    with pytest.raises(AssertionError, match=f"{name} is not"):
        from_headers({}, {}, {name: signature}, tmp_path)


def test_each_c_type_has_its_ctypes_type():
    # What the signatures are made of, and a C type the module does not know.
    assert minkq.mpi._ctype("const minkq_mpi_scene_desc*")._type_ is minkq.mpi._Desc
    assert minkq.mpi._ctype("minkq_buffer") is minkq.mpi._Buffer
    assert minkq.mpi._ctype("minkq_mpi_scene**")._type_ is ctypes.c_void_p
    assert minkq.mpi._ctype("const minkq_mpi_result*") is ctypes.c_void_p
    assert minkq.mpi._ctype("void") is None
    with pytest.raises(ValueError, match="no ctypes type for the C type 'float'"):
        minkq.mpi._ctype("float")


def test_double_vertices_are_refused_not_rounded():
    # Before any MPI call or library load: the distributed scene is float32 only.
    v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    with pytest.raises(TypeError, match="vertices: got float64 values for a minkq.mpi scene"):
        minkq.mpi.Scene(None, v, [[0, 1, 2]], [0, 1, 2], [0], [1, 1, 1], [1])
    # float32 and integer coordinates convert exactly.
    assert minkq.mpi._vertices(np.array(v, np.float32), "vertices").dtype == np.float32
    assert minkq.mpi._vertices(np.array(v, np.int32), "vertices").tolist() == v
