"""The PEP 517 backend of the minkq wheel: maturin's, with its repair switched on.

Built through pip (``pip install ./bindings/python``, ``pip wheel``), maturin's backend passes
``--compatibility off``: a plain ``linux`` wheel, not repaired, whose extension needs the
system's libtbb and libxxhash and the libminkq build folder. This backend passes an empty
``--compatibility`` instead (maturin's default: the oldest manylinux tag the linked libraries
allow), so that ``auditwheel = "repair"`` in pyproject.toml copies libminkq, TBB and xxHash
into ``minkq.libs/`` and points the extension's rpath there. A ``--compatibility`` given by the
caller (``--config-settings build-args="--compatibility linux"``, or MATURIN_PEP517_ARGS) is
left as it is. Everything else is maturin's own backend.
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, Optional

import maturin
from maturin import *  # noqa: F401,F403  (the other PEP 517 hooks, unchanged)


def _with_repair(config_settings: Optional[Mapping[str, Any]]) -> Dict[str, Any]:
    args: List[str] = list(maturin.get_maturin_pep517_args(config_settings))
    if "--compatibility" not in args and "--manylinux" not in args:
        args.append("--compatibility")  # no value: maturin's automatic manylinux tag
    settings = dict(config_settings or {})
    settings.pop("build-args", None)
    settings["maturin.build-args"] = args
    return settings


def build_wheel(
    wheel_directory: str, config_settings: Optional[Mapping[str, Any]] = None, metadata_directory: Optional[str] = None
) -> str:
    return maturin.build_wheel(wheel_directory, _with_repair(config_settings), metadata_directory)
