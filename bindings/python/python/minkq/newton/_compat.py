"""The private parts of Newton and Warp that minkq.newton uses, in one place.

Newton's ``TriMeshCollisionDetector``, the kernels and helpers it launches, the modules
:func:`minkq.newton.install` patches and ``SolverVBD``'s epsilon attribute (``newton._src``),
and Warp's capture pause and CPU capture state (``warp._src``) are not public API and move
between releases. This module is the only one in minkq.newton that names them; the others
import from here, so a release that moves them needs a change here only.

Supported: Newton 1.8.x (the detector mirrors Newton 1.8.0's) with Warp 1.19.x: the versions
bindings/test.sh pins (newton 1.8.0, warp-lang 1.19.0) and runs the tests with.
"""

from __future__ import annotations

from typing import Any

import warp as wp
from newton._src.geometry import tri_mesh_collision as newton_tri_mesh_collision
from newton._src.geometry.bvh import compute_bvh_group_roots
from newton._src.geometry.kernels import (
    compute_edge_aabbs,
    compute_edge_groups,
    compute_tri_aabbs,
    compute_tri_groups,
    init_triangle_collision_data_kernel,
)

__all__ = [
    "DETECTOR_MODULES",
    "SOLVER_EPSILON_ATTRIBUTE",
    "capture_pause",
    "capture_resume",
    "compute_bvh_group_roots",
    "compute_edge_aabbs",
    "compute_edge_groups",
    "compute_tri_aabbs",
    "compute_tri_groups",
    "cpu_graph_being_captured",
    "init_triangle_collision_data_kernel",
    "newton_tri_mesh_collision",
    "solver_vbd_class",
]

# The modules whose ``TriMeshCollisionDetector`` install() replaces: where SolverVBD and the
# CollisionPipeline look it up, and the VBD package's name for the class (Newton's tests use it).
DETECTOR_MODULES = (
    "newton._src.solvers.vbd.solver_vbd",
    "newton._src.sim.collide",
    "newton._src.solvers.vbd.tri_mesh_collision",
)

# SolverVBD's attribute for ``particle_edge_parallel_epsilon``, read by its force kernels.
SOLVER_EPSILON_ATTRIBUTE = "_self_contact_edge_edge_parallel_epsilon"


def solver_vbd_class() -> Any:
    """Newton's ``SolverVBD`` (imported when first needed: the solvers are a heavy import)."""
    from newton._src.solvers.vbd.solver_vbd import SolverVBD

    return SolverVBD


# Looked up in warp._src.context at each call, not bound at import, so that a test can
# replace them there.
def capture_pause(device: Any) -> Any:
    """Warp's ``capture_pause``: suspends the graph capture in progress on ``device``."""
    from warp._src import context

    return context.capture_pause(device=device)


def capture_resume(graph: Any, device: Any) -> None:
    """Warp's ``capture_resume``: resumes the capture ``capture_pause`` suspended."""
    from warp._src import context

    context.capture_resume(graph, device=device)


def cpu_graph_being_captured() -> Any:
    """The Graph object a CPU graph capture is recording into, or None (Warp keeps it on its
    runtime)."""
    runtime = getattr(getattr(wp, "_src", None), "context", None)
    runtime = getattr(runtime, "runtime", None)
    return getattr(runtime, "_apic_graph", None)
