"""ngfrac: phase-field crack propagation on adaptive NGSolve/Netgen meshes.

The model is the irreversible gradient flow of Kimura and Takaishi (Francfort-Marigo energy
with Ambrosio-Tortorelli regularization); see docs/theory.md.

Typical use::

    from ngfrac import load_scene, PhaseFieldStepper
    stepper = PhaseFieldStepper(load_scene("demos/mode3_slit.toml"))
    for record in stepper.run():
        ...

Threads: NGSolve uses all cores inside ``TaskManager``; its idle threads spin, so two runs
side by side slow each other down badly. Set ``NGFRAC_THREADS=1`` (any positive integer) in
the environment to cap the threads of each run before starting several at once.
"""
import logging as _logging
import os as _os

import ngsolve as _ngs

from .scene.checks import ResolutionWarning, resolution_warnings
from .scene.expressions import Expression, ExpressionError
from .mesh.domains import MeshingError
from .io.output import ngfrac_version as _ngfrac_version
from .runner import RunSummary, run_scene
from .scene import Scene, SceneError, load_scene
from .solve.stepper import PhaseFieldStepper, SolverError, StepRecord

__all__ = ["Expression", "ExpressionError", "MeshingError", "PhaseFieldStepper", "ResolutionWarning",
           "RunSummary", "Scene", "SceneError", "SolverError", "StepRecord", "load_scene",
           "resolution_warnings", "run_scene"]
__version__ = _ngfrac_version()
"""From the installed package metadata, i.e. setup.cfg's ``version`` (the one place it is set)."""


def _threads_from_environment() -> None:
    value = _os.environ.get("NGFRAC_THREADS", "").strip()
    if not value:
        return
    if not value.isdigit() or int(value) < 1:
        _logging.getLogger(__name__).warning(
            "NGFRAC_THREADS = %r ignored: expected a positive integer, e.g. NGFRAC_THREADS=1", value)
        return
    _ngs.SetNumThreads(int(value))


_threads_from_environment()
