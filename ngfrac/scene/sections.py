"""The scene sections and the Scene: everything one run needs, as frozen dataclasses.

A scene file has the sections ``[model]``, ``[material]``, ``[phase_field]``,
``[geometry]``, ``[[cracks]]``, ``[[loads]]``, ``[time]``, ``[discretization]``,
``[output]`` and ``[adaptivity]``; docs/user-guide.md lists every key. Each section is a frozen
dataclass that validates its own values (the geometry and the cracks are in
:mod:`ngfrac.scene.geometry_section`); :class:`Scene` checks what spans sections (loads on
existing boundaries, cracks inside the domain, toughness positive everywhere:
:mod:`ngfrac.scene.validation`). Plain values are coerced into the field types by
:mod:`ngfrac.scene.coercion`. Every problem raises :class:`~ngfrac.scene.coercion.SceneError`
with one line that names the key, the value and what is allowed.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Mapping

from ..fem.linear import AUTO_REUSE_VERTICES, U_SOLVERS, Z_SOLVERS
from ..physics.crack_models import CRACK_MODELS, SOFTENING_LAWS
from ..physics.elastic import ELASTIC_MODELS
from ..physics.loads import LOAD_KINDS  # noqa: F401 (re-exported: the values of loads[i].kind)
from .build import build_crack_model, build_elastic_model
from .coercion import (FREE, REQUIRED, Components, SceneError, Section,  # noqa: F401 (re-exported)
                       build_section, dotted_key, require, unknown_key_message)
from .expressions import Expression
from .geometry_section import (SHAPE_TYPES_2D, SHAPE_TYPES_3D, BoundarySelector,  # noqa: F401
                               Crack, Geometry, Shape, occ_domain_of)
from .units import SCENE_UNITS
from .validation import validate_scene

if TYPE_CHECKING:
    from ..physics.crack_models import CrackModel
    from ..physics.elastic import ElasticModel

MODELS = tuple(ELASTIC_MODELS)
"""Model names a scene may choose (``model.kind``)."""

MODELS_3D = tuple(kind for kind, model in ELASTIC_MODELS.items() if model.n_components == 3)
"""Models of a 3D domain (``geometry.kind = "box"``); the others are 2D."""


@dataclass(frozen=True)
class Model(Section):
    """Which equations to solve.

    ``mode3``: anti-plane shear, u scalar (out of plane). ``plane_strain`` and
    ``plane_stress``: u = (ux, uy) in the plane, ``sigma = 2 mu e + lambda tr(e) I`` with the 3D
    Lame constants (plane strain) or ``lambda* = 2 lambda mu / (lambda + 2 mu)`` (plane stress).
    ``elasticity_3d``: u = (ux, uy, uz) on a 3D domain (``geometry.kind = "box"``).
    """

    SECTION: ClassVar[str] = "model"
    KINDS: ClassVar[tuple[str, ...]] = MODELS
    """The values of ``kind`` (:data:`MODELS`); the cross-section checks read them here."""
    KINDS_3D: ClassVar[tuple[str, ...]] = MODELS_3D
    """The 3D ones (:data:`MODELS_3D`)."""
    kind: str = "mode3"

    def validate(self) -> None:
        if self.kind not in MODELS:
            close = difflib.get_close_matches(self.kind, MODELS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"model.kind = {self.kind!r} is not a known model{hint}; "
                             f"choose one of {', '.join(MODELS)}")

    @property
    def n_components(self) -> int:
        """Components of u: 1 for mode III, 2 for the plane models, 3 in 3D."""
        return ELASTIC_MODELS[self.kind].n_components


@dataclass(frozen=True)
class Material(Section):
    """Elastic moduli and fracture toughness.

    The moduli are one pair, ``lam`` and ``mu`` (3D Lame constants) or ``E`` and ``nu``;
    mode III may give ``mu`` alone (and without any modulus uses mu = 1). Keys not given are
    NaN. ``gamma`` is Griffith's G_c, a number or an expression in x, y; ``body_force`` is f in
    ``-div sigma = f``: one expression for mode III, ``[fx, fy]`` for the plane models.
    """

    SECTION: ClassVar[str] = "material"
    PAIRS: ClassVar[tuple[tuple[str, ...], ...]] = ((), ("mu",), ("mu", "lam"), ("E", "nu"))
    DEFAULT_MU: ClassVar[float] = 1.0
    """Mode III shear modulus when the scene gives no modulus."""
    mu: float = math.nan
    lam: float = math.nan
    E: float = math.nan
    nu: float = math.nan
    gamma: Expression = Expression("1.0")
    body_force: Expression | Components = Expression("0.0")
    """Body force f, expressions in x, y, t (mode III: out of plane)."""
    split: str = "none"
    """Tension/compression split of the elastic energy: "none" (the paper's model), "amor"
    (volumetric-deviatoric) or "miehe" (spectral); see :mod:`ngfrac.physics.splits`."""
    split_mode: str = "full"
    """How the split enters: "full" (psi+ degraded in the u-step, Newton) or "hybrid"
    (Ambati et al. 2015: isotropic u-step, linear; z driven by 2 psi+, not where psi+ < psi-)."""
    strength: float = math.nan
    """The tensile strength f_t of ``phase_field.model = "PF-CZM"`` (mode III: the shear
    strength); NaN = not given."""

    def validate(self) -> None:
        s = self.SECTION
        if self.moduli not in self.PAIRS:
            given = ", ".join(f"{dotted_key(s, k)} = {getattr(self, k)!r}" for k in self.moduli)
            raise SceneError(f"{given} is not allowed: give exactly one pair of elastic moduli, "
                             "lam and mu, or E and nu (mode3 may give mu alone)")
        if "mu" in self.moduli:
            require(self.mu > 0, s, "mu", self.mu, "the shear modulus must be > 0")
        if "lam" in self.moduli:
            require(3 * self.lam + 2 * self.mu > 0, s, "lam", self.lam,
                    f"must be > -2 mu/3 = {-2 * self.mu / 3:g} (a Poisson ratio above -1)")
        if "E" in self.moduli:
            require(self.E > 0, s, "E", self.E, "Young's modulus must be > 0")
            require(-1 < self.nu < 0.5, s, "nu", self.nu, "Poisson's ratio must be in (-1, 0.5)")
        if isinstance(self.body_force, Components):
            require(len(self.body_force) > 0 and not any(self.body_force.free), s, "body_force",
                    self.body_force.text, "give one expression per component, none 'free'")
        if "t" in self.gamma.names:
            raise SceneError(f"material.gamma = {self.gamma.text!r} may not depend on t")
        require(self.split in ("none", "amor", "miehe"), s, "split", self.split,
                "choose 'none' (the paper's model), 'amor' or 'miehe'")
        require(self.split_mode in ("full", "hybrid"), s, "split_mode", self.split_mode,
                "choose 'full' (psi+ degraded, Newton) or 'hybrid' (Ambati et al.)")
        require(self.split_mode == "full" or self.split != "none", s, "split_mode",
                self.split_mode, "'hybrid' needs a split: set material.split = 'amor' or 'miehe'")
        require(math.isnan(self.strength) or (self.strength > 0 and math.isfinite(self.strength)),
                s, "strength", self.strength, "the tensile strength f_t must be > 0")

    @property
    def moduli(self) -> tuple[str, ...]:
        """The elastic moduli the scene gives, in field order (mu, lam, E, nu)."""
        return tuple(k for k in ("mu", "lam", "E", "nu") if not math.isnan(getattr(self, k)))

    @property
    def lame(self) -> tuple[float, float]:
        """The 3D Lame constants (lambda, mu); from E, nu:
        ``lambda = E nu / ((1 + nu)(1 - 2 nu))``, ``mu = E / (2 (1 + nu))``."""
        if self.moduli == ("E", "nu"):
            E, nu = self.E, self.nu
            return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        if self.moduli == ("mu", "lam"):
            return self.lam, self.mu
        raise ValueError(f"material gives {self.moduli or 'no moduli'}, not lam and mu or E and nu")

    @property
    def young(self) -> float:
        """Young's modulus E: given, or ``mu (3 lam + 2 mu)/(lam + mu)``; with mu alone (mode
        III) mu itself, the modulus of the shear onset (PF-CZM's l_ch = mu G_f/f_t^2)."""
        if self.moduli == ("E", "nu"):
            return self.E
        if self.moduli == ("mu", "lam"):
            return self.mu * (3 * self.lam + 2 * self.mu) / (self.lam + self.mu)
        return self.shear_modulus

    @property
    def shear_modulus(self) -> float:
        """mu, from whichever moduli are given (1 when none is)."""
        if self.moduli == ("E", "nu"):
            return self.lame[1]
        return self.DEFAULT_MU if math.isnan(self.mu) else self.mu


@dataclass(frozen=True)
class PhaseField(Section):
    """Parameters of the Ambrosio-Tortorelli gradient flow.

    ``alpha1 du/dt = div((1-z)^2 sigma) + f``, ``alpha2 dz/dt = (...)_+``; the u-stiffness is
    ``(1-z)^2 + residual_stiffness`` so the u-problem stays elliptic where z = 1. ``model``
    is the crack model, the surface term (:mod:`ngfrac.physics.crack_models`): ``"AT2"`` (the paper's),
    ``"AT1"`` (an elastic threshold) or ``"PF-CZM"`` (Wu's cohesive model: needs
    ``material.strength``; ``softening`` its law). ``drive`` is what drives z: ``"energy"``
    (sigma:e, or 2 psi+ with a split) or ``"rankine"`` (PF-CZM: ``<sigma_1>^2/E``).
    """

    SECTION: ClassVar[str] = "phase_field"
    epsilon: float = REQUIRED  # type: ignore[assignment]
    alpha2: float = REQUIRED  # type: ignore[assignment]
    alpha1: float = 0.0
    residual_stiffness: float = 1e-6
    model: str = "AT2"
    crack_pressure: Expression = Expression("0.0")
    """p(t) inside the crack (the pressurized-crack work term ``int p u.grad z``); 0 = none."""
    softening: str = "linear"
    """PF-CZM's softening law: "linear", "exponential" or "cornelissen"."""
    drive: str = "energy"
    """W of the z-equation: "energy" (sigma:e; 2 psi+ with a split) or "rankine" (PF-CZM)."""
    damage_free: tuple[str, ...] = ()
    """Boundaries (``geometry.boundaries`` names) where z = 0: a homogeneous Dirichlet
    condition on z, so no damage on these edges or faces (e.g. a hole's edge, a loading pad)."""

    def validate(self) -> None:
        s = self.SECTION
        require(self.crack_pressure.names <= {"t"}, s, "crack_pressure", self.crack_pressure.text,
                "an expression in t only (a pressure uniform in the crack)")
        require(self.epsilon > 0, s, "epsilon", self.epsilon, "the regularization length must be > 0")
        require(self.alpha2 > 0, s, "alpha2", self.alpha2, "the time constant of z must be > 0")
        require(self.alpha1 >= 0, s, "alpha1", self.alpha1, "must be >= 0 (0 = quasi-static u)")
        require(0 < self.residual_stiffness < 1e-1, s, "residual_stiffness",
                self.residual_stiffness, "must be in (0, 0.1); 1e-6 is typical")
        require(self.model in CRACK_MODELS, s, "model", self.model,
                f"choose {' or '.join(repr(m) for m in CRACK_MODELS)}")
        require(self.softening in SOFTENING_LAWS, s, "softening", self.softening,
                f"choose {' or '.join(repr(m) for m in SOFTENING_LAWS)}")
        require(self.drive in ("energy", "rankine"), s, "drive", self.drive,
                "choose 'energy' (sigma:e) or 'rankine' (<sigma_1>^2/E, PF-CZM)")
        require(self.drive == "energy" or self.model == "PF-CZM", s, "drive", self.drive,
                "'rankine' is PF-CZM's drive: set phase_field.model = 'PF-CZM'")
        require(len(set(self.damage_free)) == len(self.damage_free), s, "damage_free",
                list(self.damage_free), "names a boundary twice; give each once")

    @property
    def pressurized(self) -> bool:
        """Whether a crack pressure is set (``crack_pressure`` not the constant 0)."""
        p = self.crack_pressure
        return not (p.is_constant and p.value() == 0)


@dataclass(frozen=True)
class Load(Section):
    """A load on one named boundary, expressions in x, y, t (3D also z).

    ``kind = "displacement"`` (the default): a Dirichlet displacement. Mode III: one
    expression, ``value = "10*t"``. Plane models: one per component, ``value = ["0", "10*t"]``;
    ``"free"`` leaves a component unconstrained (rollers: ``value = ["free", "0"]``).
    ``kind = "traction"``: a Neumann traction sigma n = value, of the same shape as a
    displacement (no ``"free"``). ``kind = "pressure"``: one expression p, the traction
    -p n (plane and 3D models).
    """

    SECTION: ClassVar[str] = "loads"
    boundary: str = REQUIRED  # type: ignore[assignment]
    value: Expression | Components = REQUIRED  # type: ignore[assignment]
    kind: str = "displacement"

    def validate(self) -> None:
        s = self.SECTION
        require(self.kind in LOAD_KINDS, s, "kind", self.kind,
                f"choose {', '.join(repr(k) for k in LOAD_KINDS)}")
        problem = LOAD_KINDS[self.kind].value_problem(self.value)
        if problem is not None:
            require(False, s, "value", *problem)
        if isinstance(self.value, Components):
            require(len(self.value) > 0, s, "value", [], "give [ux, uy]")
            require(not all(self.value.free), s, "value", self.value.text,
                    "every component is free, so the load constrains nothing; remove it")

    @property
    def is_dirichlet(self) -> bool:
        """Whether the load prescribes u (``kind = "displacement"``; the kind's ``dirichlet``)."""
        return LOAD_KINDS[self.kind].dirichlet

    @property
    def free(self) -> tuple[bool, ...]:
        """Which components are left free (mode III: never; a traction or pressure prescribes
        no component of u, so all are free)."""
        if not self.is_dirichlet:
            n = len(self.value) if isinstance(self.value, Components) else 1
            return (True,) * n
        return self.value.free if isinstance(self.value, Components) else (False,)


@dataclass(frozen=True)
class TimeSettings(Section):
    """Time steps on the grid t = n dt (n an integer), up to t_end.

    Fixed: every step is dt. ``adaptive = true``: a step is dt 2^j with 0 <= j <=
    ``max_doublings``; it doubles while the largest change of z at a node stays below
    ``dz_target``/4 and halves (the step is redone) when it exceeds ``dz_target``. Steps of
    2^j dt start at multiples of 2^j dt, so every multiple of dt_max = dt 2^max_doublings (the
    output times) is hit exactly and times stay exact products.
    """

    SECTION: ClassVar[str] = "time"
    dt: float = REQUIRED  # type: ignore[assignment]
    t_end: float = REQUIRED  # type: ignore[assignment]
    adaptive: bool = False
    max_doublings: int = 4
    dz_target: float = 0.01

    def validate(self) -> None:
        s = self.SECTION
        require(self.dt > 0, s, "dt", self.dt, "the time step must be > 0")
        require(self.t_end > 0, s, "t_end", self.t_end, "the end time must be > 0")
        require(0 <= self.max_doublings <= 12, s, "max_doublings", self.max_doublings,
                "must be in 0..12 (the largest step is dt * 2**max_doublings)")
        require(0 < self.dz_target <= 1, s, "dz_target", self.dz_target, "must be in (0, 1]")

    @property
    def n_ticks(self) -> int:
        """End of the run on the grid t = n dt: t_end/dt rounded up."""
        return max(1, math.ceil(self.t_end / self.dt - 1e-9))

    @property
    def n_steps(self) -> int:
        """Number of steps of a fixed-step run (an upper bound for an adaptive one)."""
        return self.n_ticks

    @property
    def output_ticks(self) -> int:
        """Grid points between two output times of an adaptive run (1 for fixed steps)."""
        return 2 ** self.max_doublings if self.adaptive else 1


Z_UPDATES = ("auto", "projection", "descent", "obstacle")
"""The values of ``discretization.z_update``."""

COUPLINGS = ("paper", "staggered", "alternate")
"""The values of ``discretization.coupling``."""


@dataclass(frozen=True)
class Discretization(Section):
    """Finite elements and solvers.

    ``order`` is the polynomial order of u; ``order_z`` that of z (1 or 2: the bounds and
    the non-repair condition are enforced at the Lagrange nodes, which is exact for P1/P2).
    ``coupling = "paper"`` solves z with the previous u (the paper's eq. 7);
    ``"staggered"`` uses the u just computed; ``"alternate"`` repeats the staggered u- and
    z-sub-steps within the step, each pass from the last one's fields, until a pass changes z
    at no node by more than ``alternate_tolerance`` (at most ``alternate_passes`` passes;
    each pass's z-step is linearized at the last pass's z, its z_old, so with alpha2 > 0 the
    viscous term vanishes at the fixed point, and bounded below by the step's z^{k-1}).
    ``z_update = "projection"`` is the paper's ``z = min(1, max(z_trial, z_old))`` at the
    nodes; ``"descent"`` moves from z_old towards that projection only as far as the
    z-step's quadratic energy keeps decreasing (exact line search, never worse than z_old),
    which with ``coupling = "staggered"`` makes every step an energy descent; ``"obstacle"`` minimizes the z-step's energy under ``z >= z_old``
    (an active-set method); ``"auto"`` (the default) is the crack model's choice:
    ``"projection"`` for AT2 and ``"obstacle"`` for AT1. ``threaded_solves = false`` (the
    default) runs factorizations and solves outside NGSolve's TaskManager so that a run is
    bitwise reproducible with any thread count (:mod:`ngfrac.fem.threads`); ``true``
    threads them too. ``concurrent_substeps = true`` runs the u- and the z-sub-step of a step
    at the same time, each on one core with one NGSolve thread (with ``coupling = "paper"``
    they are independent: z uses the previous u); bitwise the same results as one thread,
    for two cores (docs/benchmarks.md, section 13). Serial on a distributed (MPI) mesh and
    with a tension/compression split.
    """

    SECTION: ClassVar[str] = "discretization"
    order: int = 2
    order_z: int = 0
    u_solver: str = "auto"
    z_solver: str = "sparsecholesky"
    coupling: str = "paper"
    alternate_tolerance: float = 1e-4
    alternate_passes: int = 100
    z_update: str = "auto"
    threaded_solves: bool = False
    concurrent_substeps: bool = False

    def validate(self) -> None:
        s = self.SECTION
        require(not self.concurrent_substeps or self.coupling == "paper", s,
                "concurrent_substeps", True, "it needs coupling = 'paper' (with 'staggered' "
                "the z-sub-step waits for the new u)")
        require(not (self.concurrent_substeps and self.threaded_solves), s,
                "concurrent_substeps", True, "threaded_solves = true excludes it (the two "
                "sub-steps on one NGSolve thread each, or one after the other on all)")
        require(1 <= self.order <= 6, s, "order", self.order, "must be an integer in 1..6")
        require(self.order_z in (0, 1, 2), s, "order_z", self.order_z,
                "must be 1 or 2 (0 = min(order, 2))")
        require(self.u_solver in U_SOLVERS, s, "u_solver", self.u_solver,
                f"choose 'auto' (reused_cholesky on 3D meshes of {AUTO_REUSE_VERTICES:,} vertices "
                "or more, else sparsecholesky), 'sparsecholesky', 'umfpack', 'reused_cholesky' (CG "
                "preconditioned with an earlier factorization) or 'cg' (with BDDC)")
        require(self.z_solver in Z_SOLVERS, s, "z_solver", self.z_solver,
                "choose 'cg', 'sparsecholesky', 'umfpack' or 'reused_cholesky' (CG "
                "preconditioned with an earlier factorization)")
        require(self.coupling in COUPLINGS, s, "coupling", self.coupling,
                "choose 'paper' (z uses the previous u), 'staggered' (z uses the new u) or "
                "'alternate' (staggered passes until z settles)")
        require(self.alternate_tolerance > 0, s, "alternate_tolerance", self.alternate_tolerance,
                "must be > 0 (the largest change of z at a node that ends the passes)")
        require(self.alternate_passes >= 1, s, "alternate_passes", self.alternate_passes,
                "must be an integer >= 1")
        require(self.z_update in Z_UPDATES, s, "z_update", self.z_update,
                "choose 'auto', 'projection' (the paper's min(1, max(z_trial, z_old))), "
                "'descent' (the projection, shortened where it would raise the z-step's "
                "energy) or 'obstacle' (the z-step minimized under z >= z_old)")

    def z_order_for(self, crack_model: "CrackModel") -> int:
        """The order of z: ``order_z``; unset (0), the crack model's ``default_z_order``
        (PF-CZM: 1), else that of u, at most 2."""
        return self.order_z or crack_model.default_z_order or min(self.order, 2)


VTK_FORMATS = ("auto", "subdivided", "vertices")
"""Values of ``output.vtk_format``."""


@dataclass(frozen=True)
class Output(Section):
    """What to write and how often (0 = never; for VTK: only the last step)."""

    SECTION: ClassVar[str] = "output"
    vtk_every: int = 10
    history_every: int = 1
    vtk_subdivision: int = -1
    """Subdivision of each element in VTK files; -1 means order - 1."""
    vtk_format: str = "auto"
    """``"subdivided"``: NGSolve's ASCII output, each element refined ``vtk_subdivision``
    times (P2 fields faithfully); ``"vertices"``: compressed binary, one point per vertex,
    other fields at the element centroids (fast, small); ``"auto"``: vertices in 3D, subdivided in
    2D."""
    checkpoint_every: int = 50
    """A checkpoint (checkpoint.h5, written atomically) every N steps; 0 = never."""
    results: bool = True
    """Write results.h5 (history and field snapshots with their meshes, at the VTK steps)."""

    def validate(self) -> None:
        s = self.SECTION
        require(self.vtk_every >= 0, s, "vtk_every", self.vtk_every,
                "must be >= 0 (0: only the last step)")
        require(self.history_every >= 1, s, "history_every", self.history_every, "must be >= 1")
        require(-1 <= self.vtk_subdivision <= 5, s, "vtk_subdivision", self.vtk_subdivision,
                "must be in -1..5 (-1 = order - 1)")
        require(self.checkpoint_every >= 0, s, "checkpoint_every", self.checkpoint_every,
                "must be >= 0 (0 = never)")
        require(self.vtk_format in VTK_FORMATS, s, "vtk_format", self.vtk_format,
                f"choose one of {', '.join(repr(f) for f in VTK_FORMATS)}")


SIZE_FIELDS = ("bands", "equidistributed")
"""Values of ``adaptivity.size_field``."""


@dataclass(frozen=True)
class Adaptivity(Section):
    """Mesh adaptation driven by an a-posteriori estimator on z (refinement and coarsening).

    Sizes are 0 for "derived from epsilon": ``h_crack`` (where z >= 0.9, the crack core)
    defaults to max(hmin, epsilon/10), ``h_band`` (where z >= 0.1) to epsilon/4, ``h_tip``
    (within ``tip_margin`` of the tip) to h_band, ``hmax`` to a tenth of the shorter side,
    ``tip_margin`` to 4 epsilon. ``tip_lane`` (2D) also asks for h_crack in a wedge of length
    ``tip_margin`` ahead of the tip along the crack, so the core runs in fine elements.
    ``relax_core`` (off by default; on in the SENT/SENS demos): after a transfer, one
    z-sub-step at the transferred u restores the open crack (kept where z >= 1/2 and the
    sub-step gives z >= 0.95, outside the tip disc), which interpolation at the new nodes
    lowers where they miss its ridge, so force curves do not jump after a mesh change.

    ``size_field`` says where the sizes come from: ``"bands"`` (the default) equidistributes
    the estimator and then asks for h_crack in the core, h_band in the band and the tip lane,
    and under the cap coarsens the coarsest parts first; ``"equidistributed"`` keeps only the
    estimator's equidistribution (on size levels) and the tip disc, and under the cap scales
    every size alike (the Fig. 2 demo's setting; docs/benchmarks.md, section 11, compares them).

    ``notch_tip`` (a point, 2D or 3D; empty by default) is for a notch cut out of the
    geometry instead of an initial crack: until the crack set has a tip, the tip disc
    (``h_tip`` within ``tip_margin``) is kept at this point, so the notch's tip is resolved
    from the first mesh on and not only once z >= 0.1 has formed on the coarse start mesh.

    ``initial_passes`` is how many new meshes resolve the initial cracks' profile before the
    first step (0 = by dimension: :data:`ngfrac.mesh.adapter.INITIAL_PASSES`, 3 in 2D and 2 in
    3D); a scene without initial cracks stops after the first (z0 = 0: every further pass would
    make the same mesh).
    """

    SECTION: ClassVar[str] = "adaptivity"
    enabled: bool = False
    estimator: str = "zz"
    every: int = 1
    max_vertices: int = 5000
    hmin: float = 2e-3
    hmax: float = 0.0
    h_crack: float = 0.0
    h_band: float = 0.0
    h_tip: float = 0.0
    tip_margin: float = 0.0
    tip_lane: bool = True
    relax_core: bool = False
    size_field: str = "bands"
    initial_passes: int = 0
    notch_tip: tuple[float, ...] = ()

    def validate(self) -> None:
        s = self.SECTION
        require(self.estimator in ("zz", "residual"), s, "estimator", self.estimator,
                "choose 'zz' or 'residual'")
        require(self.size_field in SIZE_FIELDS, s, "size_field", self.size_field,
                "choose 'bands' or 'equidistributed'")
        require(self.every >= 1, s, "every", self.every, "must be >= 1 (steps between checks)")
        require(self.initial_passes >= 0, s, "initial_passes", self.initial_passes,
                "must be >= 0 (0 = by dimension: 3 in 2D, 2 in 3D)")
        require(self.max_vertices >= 100, s, "max_vertices", self.max_vertices, "must be >= 100")
        require(self.hmin > 0, s, "hmin", self.hmin, "must be > 0")
        for name in ("hmax", "h_crack", "h_band", "h_tip", "tip_margin"):
            value = getattr(self, name)
            require(value >= 0, s, name, value, "must be >= 0 (0 = derived from epsilon)")
        require(self.hmax == 0 or self.hmax >= self.hmin, s, "hmax", self.hmax, "must be >= hmin")
        require(len(self.notch_tip) in (0, 2, 3), s, "notch_tip", list(self.notch_tip),
                "give the point as [x, y] (2D) or [x, y, z] (3D)")


SECTIONS: dict[str, type] = {
    "model": Model, "material": Material, "phase_field": PhaseField, "geometry": Geometry,
    "time": TimeSettings, "discretization": Discretization, "output": Output,
    "adaptivity": Adaptivity,
}
LISTS: dict[str, type] = {"cracks": Crack, "loads": Load}


@dataclass(frozen=True)
class Scene:
    """A complete, validated run description. Build it with :func:`load_scene`,
    :meth:`Scene.from_dict` or in code: sections may be given as dicts of their keys, loads and
    cracks as lists, and every section coerces plain numbers, strings and lists. Validation
    also refuses crack geometry Netgen cannot mesh (:func:`ngfrac.scene.checks.crack_problems`) and
    expressions that are NaN or infinite on their boundary or domain for 0 <= t <= t_end.
    ``dataclasses.replace`` returns a new scene, validated again."""

    name: str
    geometry: Geometry
    phase_field: PhaseField
    time: TimeSettings
    loads: tuple[Load, ...]
    cracks: tuple[Crack, ...] = ()
    model: Model = field(default_factory=Model)
    material: Material = field(default_factory=Material)
    discretization: Discretization = field(default_factory=Discretization)
    output: Output = field(default_factory=Output)
    adaptivity: Adaptivity = field(default_factory=Adaptivity)
    units: str = SCENE_UNITS
    """The unit system of the scene's numbers (:data:`ngfrac.scene.units.UNIT_SYSTEMS`): labels
    and units attributes only, the computation is the same."""

    def __post_init__(self) -> None:
        self._coerce_sections()
        validate_scene(self)  # what spans sections (ngfrac.scene.validation)

    def _coerce_sections(self) -> None:
        """Sections given as tables (dicts) are built; lists of loads and cracks become tuples."""
        if not isinstance(self.name, str):
            raise SceneError(f"name = {self.name!r} must be a string")
        for section, cls in SECTIONS.items():
            value = getattr(self, section)
            if isinstance(value, Mapping):
                object.__setattr__(self, section, build_section(cls, value, section))
            elif not isinstance(value, cls):
                raise SceneError(f"{section} = {value!r} must be a {cls.__name__} (or a table of "
                                 "its keys)")
        for section, cls in LISTS.items():
            items = getattr(self, section)
            if isinstance(items, (cls, Mapping, str)) or not isinstance(items, (list, tuple)):
                raise SceneError(f"{section} = {items!r} must be a list of {cls.__name__}")
            built = []
            for i, item in enumerate(items):
                if isinstance(item, Mapping):
                    item = build_section(cls, item, f"{section}[{i}]")
                elif not isinstance(item, cls):
                    raise SceneError(f"{section}[{i}] = {item!r} must be a {cls.__name__} (or a "
                                     "table of its keys)")
                built.append(item)
            if not isinstance(items, tuple) or any(a is not b for a, b in zip(built, items)):
                object.__setattr__(self, section, tuple(built))

    BUILT: ClassVar[tuple[str, ...]] = ("elastic_model", "crack_model")
    """What a scene builds once and keeps (copies and pickles leave it out)."""

    @functools.cached_property
    def elastic_model(self) -> "ElasticModel":
        """The elastic model of ``model.kind``, built once per scene
        (:func:`ngfrac.scene.build.build_elastic_model`): every part of a run asks this one."""
        return build_elastic_model(self)

    @functools.cached_property
    def crack_model(self) -> "CrackModel":
        """The crack model of ``phase_field.model``, built once per scene
        (:func:`ngfrac.scene.build.build_crack_model`): every part of a run asks this one."""
        return build_crack_model(self)

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave out the built models; the copy builds its own."""
        return {k: v for k, v in self.__dict__.items() if k not in self.BUILT}

    @property
    def mesh_size(self) -> float:
        """Maximal element size of the uniform mesh."""
        return self.geometry.mesh_size or self.phase_field.epsilon / 2

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], name: str = "scene") -> "Scene":
        """Validate a nested mapping (as read from TOML) into a Scene."""
        if not isinstance(data, Mapping):
            raise SceneError("a scene must be a table of sections")
        allowed = ["name", "units", *SECTIONS, *LISTS]
        for key in data:
            if key not in allowed:
                raise SceneError(unknown_key_message("", key, allowed))
        kwargs: dict[str, Any] = {"name": str(data.get("name", name)),
                                  "units": data.get("units", SCENE_UNITS)}
        for section, section_cls in SECTIONS.items():
            value = data.get(section, {})
            if section_cls in (Geometry, PhaseField, TimeSettings) and section not in data:
                raise SceneError(f"missing section [{section}]; it is required")
            kwargs[section] = build_section(section_cls, value, section)
        for section, item_cls in LISTS.items():
            items = data.get(section, [])
            if isinstance(items, Mapping):
                items = [items]
            if not isinstance(items, list):
                raise SceneError(f"{section} must be an array of tables ([[{section}]])")
            kwargs[section] = tuple(build_section(item_cls, item, f"{section}[{i}]")
                                    for i, item in enumerate(items))
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """The resolved scene as plain TOML-able data (defaults filled in)."""
        def plain(value: Any) -> Any:
            if isinstance(value, Expression):
                return value.text
            if isinstance(value, tuple):
                return [plain(v) for v in value]
            return value

        def section(obj: Any) -> dict[str, Any]:
            values = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
            # NaN marks an optional number the scene did not give (material moduli)
            return {k: plain(v) for k, v in values.items()
                    if not (isinstance(v, float) and math.isnan(v))}

        out: dict[str, Any] = {"name": self.name, "units": self.units}
        for name in SECTIONS:
            out[name] = section(getattr(self, name))
        out["geometry"] = self.geometry.to_dict()
        for name in LISTS:
            out[name] = [section(item) for item in getattr(self, name)]
        return out

