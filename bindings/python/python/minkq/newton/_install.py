"""minkq.newton's :func:`install` and :func:`uninstall`: the detector swapped into Newton, and
``SolverVBD``'s edge-edge epsilon (see the package's documentation)."""

from __future__ import annotations

from typing import Any, Optional

from ._compat import DETECTOR_MODULES, SOLVER_EPSILON_ATTRIBUTE, solver_vbd_class
from ._detector import TriMeshCollisionDetector


# ---- Swapping it into Newton -------------------------------------------------------------------

_originals: dict = {}


def _patch_solver_epsilon(epsilon: Optional[float]) -> None:
    """Wraps ``SolverVBD._init_particle_system`` (where Newton stores
    ``particle_edge_parallel_epsilon`` for its self-contact force kernels) so that solvers built
    from now on use ``epsilon`` there; Newton's value stays readable as
    ``solver.newton_edge_edge_parallel_epsilon``."""
    solver = solver_vbd_class()
    original = _originals.setdefault("SolverVBD._init_particle_system", solver.__dict__["_init_particle_system"])
    if epsilon is None:
        solver._init_particle_system = original
        return
    value = float(epsilon)

    def _init_particle_system(self, *args, **kwargs):
        original(self, *args, **kwargs)
        if SOLVER_EPSILON_ATTRIBUTE in self.__dict__:  # self-contact on
            self.newton_edge_edge_parallel_epsilon = self.__dict__[SOLVER_EPSILON_ATTRIBUTE]
            setattr(self, SOLVER_EPSILON_ATTRIBUTE, value)

    _init_particle_system.__wrapped__ = original
    _init_particle_system.__doc__ = original.__doc__
    solver._init_particle_system = _init_particle_system


def install(edge_edge_parallel_epsilon: Optional[float] = 0.0) -> None:
    """Makes Newton's ``SolverVBD`` and ``CollisionPipeline`` (soft self-contact) construct this
    detector instead of their own, and makes ``SolverVBD``'s self-contact force kernels evaluate
    every edge-edge contact the detector reports: solvers built from now on pass
    ``edge_edge_parallel_epsilon`` (default 0: see the module's documentation) to Warp's
    ``closest_point_edge_edge`` instead of their ``particle_edge_parallel_epsilon`` (None keeps
    Newton's). :func:`uninstall` undoes both. Call it before creating the solver or pipeline;
    calling it again replaces the epsilon."""
    import importlib

    for name in DETECTOR_MODULES:
        module = importlib.import_module(name)
        _originals.setdefault(name, module.TriMeshCollisionDetector)
        module.TriMeshCollisionDetector = TriMeshCollisionDetector
    _patch_solver_epsilon(edge_edge_parallel_epsilon)


def uninstall() -> None:
    """Restores Newton's own detector and ``SolverVBD``'s epsilon handling where :func:`install`
    replaced them (solvers already built keep what they were built with)."""
    import importlib

    for name, original in list(_originals.items()):
        if name == "SolverVBD._init_particle_system":
            solver_vbd_class()._init_particle_system = original
        else:
            importlib.import_module(name).TriMeshCollisionDetector = original
        del _originals[name]
