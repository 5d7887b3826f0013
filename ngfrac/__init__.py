"""ngfrac: phase-field crack propagation on adaptive NGSolve/Netgen meshes.

The model is the irreversible gradient flow of Kimura and Takaishi (Francfort-Marigo energy
with Ambrosio-Tortorelli regularization); see docs/theory.md.

Typical use::

    from ngfrac import load_scene, PhaseFieldStepper
    stepper = PhaseFieldStepper(load_scene("demos/mode3_slit.toml"))
    for record in stepper.run():
        ...

Importing ngfrac changes nothing in the session (threads, matplotlib). Threads: NGSolve uses
all cores inside ``TaskManager`` and its idle threads spin, so two runs side by side slow each
other down badly; ``NGFRAC_THREADS=1`` (any positive integer) in the environment caps the
threads of each run, applied by :func:`run_scene` and ``ngfrac run`` when the run starts, or
by :func:`set_threads` in a script that drives the stepper itself.
"""
from .environment import set_threads
from .mesh.resolution import ResolutionWarning, resolution_warnings
from .scene.expressions import Expression, ExpressionError
from .geometry.domains import MeshingError
from .io.output import ngfrac_version as _ngfrac_version
from .runner import RunSummary, run_scene
from .scene import Scene, SceneError, load_scene
from .solve.stepper import PhaseFieldStepper, SolverError, StepRecord

__all__ = ["Expression", "ExpressionError", "MeshingError", "PhaseFieldStepper", "ResolutionWarning",
           "RunSummary", "Scene", "SceneError", "SolverError", "StepRecord", "load_scene",
           "resolution_warnings", "run_scene", "set_threads"]
__version__ = _ngfrac_version()
"""From the installed package metadata, i.e. setup.cfg's ``version`` (the one place it is set)."""

