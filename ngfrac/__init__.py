"""ngfrac: phase-field crack propagation on adaptive NGSolve/Netgen meshes.

The model is the irreversible gradient flow of Kimura and Takaishi (Francfort-Marigo energy
with Ambrosio-Tortorelli regularization); see docs/theory.md.

Typical use::

    from ngfrac import load_scene, PhaseFieldStepper
    stepper = PhaseFieldStepper(load_scene("demos/mode3_slit.toml"))
    for record in stepper.run():
        ...
"""
from .expressions import Expression, ExpressionError
from .runner import RunSummary, run_scene
from .scene import Scene, SceneError, load_scene
from .stepper import PhaseFieldStepper, SolverError, StepRecord

__all__ = ["Expression", "ExpressionError", "PhaseFieldStepper", "RunSummary", "Scene",
           "SceneError", "SolverError", "StepRecord", "load_scene", "run_scene"]
__version__ = "0.1.0"
