"""The PEP 517 backend of the minkq wheel: maturin's, with its repair switched on and the C++
library's sources carried in the sdist.

Wheels. Built through pip (``pip install ./bindings/python``, ``pip wheel``), maturin's backend
passes ``--compatibility off``: a plain ``linux`` wheel, not repaired, whose extension needs the
system's libtbb and libxxhash and the libminkq build folder. This backend passes an empty
``--compatibility`` instead (maturin's default: the oldest manylinux tag the linked libraries
allow), so that ``auditwheel = "repair"`` in pyproject.toml copies libminkq, TBB and xxHash
into ``minkq.libs/`` and points the extension's rpath there. A ``--compatibility`` given by the
caller (``--config-settings build-args="--compatibility linux"``, or MATURIN_PEP517_ARGS) is
left as it is.

Sdists. maturin's sdist holds the Rust workspace (bindings/) but not the C++ library, which
lives above it; minkq-sys finds that only in a checkout. :func:`build_sdist` adds the sources
CMake needs (``_CPP_SOURCES``: the top-level ``CMakeLists.txt`` and the folders and files it
reads) under ``minkq-src/`` in the sdist, and :func:`build_wheel`,
building from such an sdist without MINKQ_LIB_DIR, builds libminkq there with CMake first (CPU
backend unless MINKQ_WITH_CUDA; tests and examples off) and hands the build to minkq-sys
through MINKQ_LIB_DIR. Everything else is maturin's own backend.
"""

from __future__ import annotations

import gzip
import io
import os
import subprocess
import tarfile
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional

import maturin
from maturin import *  # noqa: F401,F403  (the other PEP 517 hooks, unchanged)

# What CMake needs of the repository for the library alone (MINKQ_BUILD_TESTS/EXAMPLES=OFF):
# the top-level CMakeLists.txt adds capi/, core/ and packaging/ (whose install rules name
# LICENSE, CHANGELOG.md and README.md), and reads VERSION.
_CPP_SOURCES = ("CMakeLists.txt", "capi", "core", "packaging", "VERSION", "LICENSE", "CHANGELOG.md", "README.md")
_CPP_DIR = "minkq-src"


def _with_repair(config_settings: Optional[Mapping[str, Any]]) -> Dict[str, Any]:
    args: List[str] = list(maturin.get_maturin_pep517_args(config_settings))
    if "--compatibility" not in args and "--manylinux" not in args:
        args.append("--compatibility")  # no value: maturin's automatic manylinux tag
    settings = dict(config_settings or {})
    settings.pop("build-args", None)
    settings["maturin.build-args"] = args
    return settings


def _library_from_sdist_sources() -> None:
    """In an unpacked sdist (the working directory) that carries minkq-src/ and no
    MINKQ_LIB_DIR: builds libminkq with CMake and sets MINKQ_LIB_DIR to it."""
    sources = Path(_CPP_DIR).resolve()
    if os.environ.get("MINKQ_LIB_DIR") or not (sources / "capi" / "minkq.h").exists():
        return
    build = Path("target", "minkq-cmake").resolve()
    cuda = os.environ.get("MINKQ_WITH_CUDA", "OFF")
    subprocess.run(
        ["cmake", "-S", str(sources), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release", f"-DMINKQ_WITH_CUDA={cuda}",
         "-DMINKQ_BUILD_TESTS=OFF", "-DMINKQ_BUILD_EXAMPLES=OFF", "-DMINKQ_WITH_MPI=OFF"],
        check=True,
    )
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 2)
    subprocess.run(["cmake", "--build", str(build), "--target", "minkq", "-j", jobs], check=True)
    os.environ["MINKQ_LIB_DIR"] = str(build / "capi")


def build_wheel(
    wheel_directory: str, config_settings: Optional[Mapping[str, Any]] = None, metadata_directory: Optional[str] = None
) -> str:
    _library_from_sdist_sources()
    return maturin.build_wheel(wheel_directory, _with_repair(config_settings), metadata_directory)


def build_sdist(sdist_directory: str, config_settings: Optional[Mapping[str, Any]] = None) -> str:
    name = maturin.build_sdist(sdist_directory, config_settings)
    root = Path(__file__).resolve().parents[3]  # bindings/python/pep517/ -> the repository
    if not (root / "capi" / "minkq.h").exists():
        return name  # not a checkout (an sdist's own copy): nothing to add
    path = Path(sdist_directory, name)
    with tarfile.open(path, "r:gz") as old:
        members = [(m, old.extractfile(m).read() if m.isfile() else None) for m in old.getmembers()]
    top = members[0][0].name.split("/")[0]
    files = sorted(
        p for entry in _CPP_SOURCES if (root / entry).exists()
        for p in ([root / entry] if (root / entry).is_file() else (root / entry).rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    )
    buffer = io.BytesIO()
    with gzip.GzipFile(fileobj=buffer, mode="wb", mtime=0) as gz, tarfile.open(fileobj=gz, mode="w", format=tarfile.PAX_FORMAT) as new:
        for member, data in members:
            new.addfile(member, io.BytesIO(data) if data is not None else None)
        for p in files:
            info = tarfile.TarInfo(f"{top}/{_CPP_DIR}/{p.relative_to(root).as_posix()}")
            data = p.read_bytes()
            info.size, info.mode, info.mtime = len(data), 0o755 if os.access(p, os.X_OK) else 0o644, 0
            new.addfile(info, io.BytesIO(data))
    path.write_bytes(buffer.getvalue())
    return name
