"""Runs a Newton example with minkq's collision detector installed.

    python -m minkq.newton.examples <example_name> [the example's options]
    python -m minkq.newton.examples --list        # Newton's examples (those using self-contact marked)
    python -m minkq.newton.examples cloth_twist --viewer null --num-frames 10

:func:`minkq.newton.install` first, then Newton's own entry point (``python -m newton.examples``:
``newton.examples.main``) with the same arguments, so the example itself runs unmodified, graph
capture included, on the CPU or a CUDA device (where the detector records only device work;
not yet run on a GPU).
"""

from __future__ import annotations

import sys
from typing import List, Optional

USAGE = """usage: python -m minkq.newton.examples <example_name> [options]
       python -m minkq.newton.examples --list

Runs Newton's example <example_name> (as `python -m newton.examples <example_name>` does) with
minkq.newton.install() applied: SolverVBD and CollisionPipeline build minkq's
TriMeshCollisionDetector. `python -m minkq.newton.examples <example_name> --help` lists the
example's options (e.g. --viewer null --num-frames 10 --device cpu)."""


def self_contact_examples() -> List[str]:
    """Newton's examples whose source enables VBD particle self-contact (where the detector is used)."""
    import ast
    import importlib.util

    import newton.examples

    names = []
    for name, module in newton.examples.get_examples().items():
        spec = importlib.util.find_spec(module)
        if spec is None or spec.origin is None:
            continue
        with open(spec.origin, encoding="utf-8") as source:
            tree = ast.parse(source.read())
        for node in ast.walk(tree):
            if isinstance(node, ast.keyword) and node.arg == "particle_enable_self_contact":
                hit = isinstance(node.value, ast.Constant) and node.value.value is True
            elif isinstance(node, ast.Dict):
                hit = any(
                    isinstance(k, ast.Constant) and k.value == "particle_enable_self_contact"
                    and isinstance(v, ast.Constant) and v.value is True
                    for k, v in zip(node.keys, node.values)
                )
            else:
                continue
            if hit:
                names.append(name)
                break
    return names


def main(argv: Optional[List[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(USAGE)
        return 0 if argv else 2
    import newton.examples

    examples = newton.examples.get_examples()
    if argv[0] == "--list":
        marked = set(self_contact_examples())
        print("Newton's examples (* : VBD particle self-contact, where minkq's detector is used):")
        for name in examples:
            print(f"  {'*' if name in marked else ' '} {name}")
        return 0
    if argv[0] not in examples:
        print(f"minkq.newton.examples: unknown example {argv[0]!r} (--list prints Newton's examples)", file=sys.stderr)
        return 2

    from . import install

    install()
    # Newton's own entry point, as `python -m newton.examples <name> ...` runs it.
    sys.argv = ["newton.examples", *argv]
    newton.examples.main()
    return 0


if __name__ == "__main__":
    sys.exit(main())
