"""The z-sub-problem of one step and the non-repair projection.

    alpha2 (zt - z_old)/dt = eps div(gamma grad zt) - gamma zt/eps + W (1 - zt)   (AT2)
    z = min(1, max(zt, z_old))        at the Lagrange nodes of z

The crack model supplies the surface terms and the drive (:mod:`ngfrac.physics.crack_models`;
AT1 adds a constant source; a model with another degradation g gives the drive
``-1/2 g'(zt) W`` linearized at z_old,
:meth:`~ngfrac.physics.crack_models.CrackModel.drive_factors`). The sub-step's linear algebra
is the communicator's z-system (:meth:`ngfrac.solve.communicator.Communicator.z_system`, of the
terms :class:`~ngfrac.solve.z_system.ZForms`): on one process
:class:`~ngfrac.solve.z_system.AssembledSystem` (K and M once per mesh, the drive per step,
the surface energy from K), on a distributed mesh
:class:`ngfrac.parallel.z_system.DistributedSystem`. The projection (and the descent along it)
is the same for both.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import ngsolve as ngs

from ..physics.crack_models import CrackModel
from ..scene import Scene
from .context import StepContext
from ..mesh.fields import MeshFields
from .z_system import ZForms, ZSystem


class PhaseFieldProblem:
    """Forms and solver of the z-sub-step on one :class:`MeshFields`, and the projection.

    Parameters
    ----------
    fields : MeshFields
        z holds z_old during a step; the sub-step's solution goes to :attr:`z_trial`.
    scene : Scene
    crack_model : CrackModel
    gamma : float or ngsolve.CoefficientFunction
        The toughness.
    drive : ngsolve.CoefficientFunction
        W, the elastic drive (sigma:e at u_prev or u; 2 psi+ with a split; PF-CZM's Rankine
        drive: :meth:`ngfrac.solve.u_problem.DisplacementProblem.drive`).
    context : StepContext
        The step's 1/dt, threads and timer.
    u_drive : ngsolve.GridFunction, optional
        The u of the drive (u_prev or u); with ``phase_field.crack_pressure`` p the right-hand
        side gets ``-p u_drive . grad w``, the z-derivative of the work term ``int p u.grad z``.
    """

    def __init__(self, fields: MeshFields, scene: Scene, crack_model: CrackModel, gamma: Any,
                 drive: ngs.CoefficientFunction, context: StepContext,
                 u_drive: ngs.GridFunction | None = None) -> None:
        self.fields, self.context = fields, context
        pf = scene.phase_field
        update = crack_model.resolve_z_update(scene.discretization.z_update)
        self.update = update
        """The z-update in use: "projection", "descent" or "obstacle"."""
        self.z_trial = ngs.GridFunction(fields.fes_z, "z_trial")
        factors = crack_model.drive_factors(fields.z)  # z holds z_old during a step
        implicit, explicit = (drive, None) if factors is None else (factors[0] * drive,
                                                                    factors[1] * drive)
        pressurized = pf.pressurized and u_drive is not None
        self.system: ZSystem = context.comm.z_system(ZForms(
            fields, context, crack_model, gamma, pf.epsilon, pf.alpha2, implicit, explicit,
            pf.crack_pressure.to_coefficient(context.time) if pressurized else None, u_drive,
            scene.discretization.z_solver, update))
        """The communicator's z-system (:meth:`~ngfrac.solve.communicator.Communicator.z_system`):
        on one process :class:`~ngfrac.solve.z_system.AssembledSystem`."""
        self.shortened = 0
        """Projections the descent shortened (``discretization.z_update = "descent"``)."""

    def solve(self, step: int | str = "?") -> int:
        """The z-sub-step into :attr:`z_trial`; returns the CG iterations (0 for a direct
        solve; the active-set iterations with ``z_update = "obstacle"``). Raises
        :class:`SolverError`."""
        iterations = self.system.solve(self.z_trial, step)
        fixed = self.fields.damage_free_dofs
        if fixed.any():  # phase_field.damage_free: the solves leave them at 0; kept whatever the solver
            self.z_trial.vec.FV().NumPy()[fixed] = 0.0
        return iterations

    @property
    def rhs(self) -> ngs.BaseVector:
        """The right-hand side of the last sub-step."""
        return self.system.rhs

    def surface_energy(self) -> tuple[float, float] | None:
        """(E_surf, crack_length) of the current z from the z-system's assembled K and source
        (:meth:`~ngfrac.solve.z_system.AssembledSystem.surface_energy`); None on a distributed
        mesh, whose matrices are not local."""
        return self.system.surface_energy()

    def trial_values(self) -> np.ndarray:
        """The sub-step's solution at the Lagrange nodes."""
        return self.fields.nodes.values(self.z_trial)

    def bound_by(self, lower: ngs.GridFunction | None) -> None:
        """Make ``lower`` the non-repair bound of the following sub-steps instead of z_old
        (``coupling = "alternate"``: the step's z^{k-1} while z holds the last pass's z);
        None restores z_old."""
        self.lower = lower
        if hasattr(self.system, "lower"):  # the obstacle's bound (one process)
            self.system.lower = lower

    lower: ngs.GridFunction | None = None
    """The bound set by :meth:`bound_by`; None: z_old."""

    def project(self) -> tuple[np.ndarray, np.ndarray]:
        """Non-repair: z = min(1, max(z_trial, z_old)) at the nodes (z_old, or the bound of
        :meth:`bound_by`; with ``z_update = "descent"`` the energy minimizer between z_old and
        that projection); returns (z_old, z) at the nodes and sets the field z."""
        nodes = self.fields.nodes
        old = nodes.values(self.fields.z)
        lower = old if self.lower is None else nodes.values(self.lower)
        new = np.minimum(1.0, np.maximum(self.trial_values(), lower))
        if self.update == "descent":
            new = self._descent(old, new)
        nodes.assign(self.fields.z, new)
        return old, new

    def _descent(self, old: np.ndarray, projected: np.ndarray) -> np.ndarray:
        """z_old + theta (P - z_old) with theta in [0, 1] minimizing the z-step's energy.

        The z-step minimizes G(z) = 1/2 z.A z - f.z (A, f: the assembled z-forms, which hold
        z_old). Every point between z_old and the projection P is feasible (both are), G is
        quadratic along the segment, so the exact minimizer over it never exceeds G(z_old).
        """
        direction_nodes = projected - old
        if not np.any(direction_nodes):
            return projected
        z_old = self.fields.z.vec.CreateVector()
        z_old.data = self.fields.z.vec  # z still holds z_old here
        direction = ngs.GridFunction(self.fields.fes_z)
        self.fields.nodes.assign(direction, direction_nodes)
        a_d = (self.system.matrix * direction.vec).Evaluate()
        curvature = ngs.InnerProduct(direction.vec, a_d)
        slope = ngs.InnerProduct(z_old, a_d) - ngs.InnerProduct(self.rhs, direction.vec)
        theta = 1.0 if curvature <= 0 else min(1.0, max(0.0, -slope / curvature))
        if theta < 1.0:
            self.shortened += 1
            self.context.timer.add("z: shortened projections", 0.0)
        return old + theta * direction_nodes

