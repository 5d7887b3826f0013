"""The checks of a :class:`~ngfrac.scene.sections.Scene` that relate two sections or more: loads
on boundaries of the geometry, cracks inside the domain, a model of the domain's dimension,
loads and body force of the model's shape, every component of u prescribed somewhere,
PF-CZM's parameters, the toughness positive and the expressions finite.

Each section checks its own values (:mod:`ngfrac.scene.sections`); :func:`validate_scene` is
what ``Scene.__post_init__`` runs after them. Every problem raises a one-line
:class:`~ngfrac.scene.coercion.SceneError`.
"""
from __future__ import annotations

import difflib
import math
from typing import TYPE_CHECKING

import numpy as np

from ..physics.crack_models import PFCZM
from ..physics.loads import LOAD_KINDS
from .checks import check_times, crack_problems, nonfinite_value
from .coercion import Components, SceneError
from .expressions import Expression
from .units import unit_system

if TYPE_CHECKING:
    from .sections import Load, Material, Model, Scene

__all__ = ["check_model_fits", "validate_scene"]


def _vector_text(name: str, n: int) -> str:
    """``[ux, uy]`` or ``[ux, uy, uz]`` for n = 2, 3 (``name`` = "u" or "f")."""
    return "[" + ", ".join(f"{name}{c}" for c in "xyz"[:n]) + "]"


def validate_scene(scene: "Scene") -> None:
    """Every check that spans sections, in the order ``Scene.__post_init__`` has always run
    them (the first problem found is the one reported).

    Raises
    ------
    SceneError
        The first problem, in one line.
    """
    try:
        unit_system(scene.units)
    except ValueError as err:
        raise SceneError(str(err)) from None
    names = scene.geometry.boundary_names
    _check_dimension(scene)
    if not any(load.is_dirichlet for load in scene.loads):
        raise SceneError("loads: a scene needs at least one [[loads]] entry with kind = "
                         "'displacement' (a Dirichlet boundary); tractions alone leave u "
                         "undetermined up to a rigid motion")
    seen = set()
    for i, load in enumerate(scene.loads):
        if load.boundary not in names:
            close = difflib.get_close_matches(load.boundary, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"loads[{i}].boundary = {load.boundary!r} is not a boundary of the "
                             f"geometry{hint}; boundaries are {', '.join(names)}")
        if load.boundary in seen:
            raise SceneError(f"loads[{i}].boundary = {load.boundary!r} is loaded twice")
        seen.add(load.boundary)
        if "z" in load.value.names and scene.geometry.dim == 2:
            raise SceneError(f"loads[{i}].value = {load.value.text!r} uses z, but the domain is 2D")
    for name in scene.phase_field.damage_free:
        if name not in names:
            close = difflib.get_close_matches(name, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise SceneError(f"phase_field.damage_free: {name!r} is not a boundary of the "
                             f"geometry{hint}; boundaries are {', '.join(names)}")
    tip = scene.adaptivity.notch_tip
    if tip and len(tip) != scene.geometry.dim:
        raise SceneError(f"adaptivity.notch_tip = {list(tip)!r} has {len(tip)} coordinates, but "
                         f"the domain is {scene.geometry.dim}D; give one per axis")
    if "z" in scene.material.body_force.names and scene.geometry.dim == 2:
        raise SceneError(f"material.body_force = {scene.material.body_force.text!r} uses z, "
                         "but the domain is 2D")
    check_model_fits(scene.model, scene.material, scene.loads)
    _check_constrained(scene)
    _check_split(scene)
    for i, crack in enumerate(scene.cracks):
        if crack.dim != scene.geometry.dim:
            example = "[[x, y, z], ...] (a planar polygon)" if scene.geometry.dim == 3 else "[[x, y], ...]"
            raise SceneError(f"cracks[{i}].points = {[list(p) for p in crack.points]} has "
                             f"{crack.dim}D points, but geometry.kind = {scene.geometry.kind!r} "
                             f"is {scene.geometry.dim}D: give {example}")
        domain = scene.geometry.domain()
        for point in crack.points:
            if not domain.contains(point, tol=1e-12):
                raise SceneError(f"cracks[{i}].points: point {list(point)} lies outside the "
                                 f"domain {scene.geometry.describe()}")
    normals = [c.normal for c in scene.cracks] if scene.geometry.dim == 3 else []
    for problem in crack_problems(scene.geometry, [c.points for c in scene.cracks], normals):
        raise SceneError(problem)
    _check_gamma_positive(scene)
    _check_crack_model(scene)
    _check_finite_expressions(scene)


def check_model_fits(model: "Model", material: "Material", loads: tuple["Load", ...]) -> None:
    """What spans sections: loads, body force and moduli must fit the model.

    Mode III takes one expression per load and a scalar body force; the plane models take
    ``[ux, uy]`` (``"free"`` allowed in loads), ``[fx, fy]`` and a pair of moduli.
    """
    kind, n = model.kind, model.n_components
    for i, load in enumerate(loads):
        load_kind = LOAD_KINDS[load.kind]
        problem = load_kind.model_problem(kind, n)
        if problem is not None:
            raise SceneError(f"loads[{i}].kind = {load.kind!r} {problem}")
        if load_kind.scalar:
            continue  # one expression whatever the model (Load.validate)
        if n == 1 and isinstance(load.value, Components):
            raise SceneError(f"loads[{i}].value = {load.value.text} is a list, but model.kind = "
                             "'mode3' takes one expression (the out-of-plane displacement)")
        if n > 1 and not isinstance(load.value, Components):
            example = ", ".join(['\"0\"'] * (n - 1) + ['\"10*t\"'])
            raise SceneError(f"loads[{i}].value = {load.value.text!r} is one expression, but "
                             f"model.kind = {kind!r} needs {_vector_text('u', n)}, e.g. "
                             f"[{example}] (\"free\" leaves a component unconstrained)")
        if n > 1 and len(load.value) != n:
            raise SceneError(f"loads[{i}].value = {load.value.text} has {len(load.value)} "
                             f"entries, but model.kind = {kind!r} needs {n}: {_vector_text('u', n)}")
    force = material.body_force
    if n == 1 and isinstance(force, Components):
        raise SceneError(f"material.body_force = {force.text} is a list, but model.kind = "
                         "'mode3' takes one expression (the out-of-plane force)")
    if n > 1 and not isinstance(force, Components) and not (force.is_constant and force.value() == 0):
        raise SceneError(f"material.body_force = {force.text!r} is one expression, but "
                         f"model.kind = {kind!r} needs {_vector_text('f', n)}")
    if n > 1 and isinstance(force, Components) and len(force) != n:
        raise SceneError(f"material.body_force = {force.text} has {len(force)} entries, but "
                         f"model.kind = {kind!r} needs {n}: {_vector_text('f', n)}")
    if n > 1 and material.moduli not in (("mu", "lam"), ("E", "nu")):
        given = ", ".join(material.moduli) or "none"
        raise SceneError(f"material: model.kind = {kind!r} needs the elastic moduli lam and mu, "
                         f"or E and nu (given: {given})")


def _check_finite_expressions(scene: "Scene") -> None:
    """Loads on their boundary, the body force in the domain, at a few times in [0, t_end]."""
    times = check_times(scene.time.n_ticks * scene.time.dt)
    checks = []
    for i, load in enumerate(scene.loads):
        where = scene.geometry.domain().boundary_points(load.boundary)
        checks.append((f"loads[{i}].value", load.value, where, f"on boundary {load.boundary!r}"))
    checks.append(("material.body_force", scene.material.body_force,
                   scene.geometry.domain().sample_points(), "in the domain"))
    for key, value, where, place in checks:
        parts = value if isinstance(value, Components) else (value,)
        for k, part in enumerate(parts):
            if not isinstance(part, Expression):
                continue  # "free"
            bad = nonfinite_value(part, where, times)
            if bad:
                name = f"{key}[{k}]" if isinstance(value, Components) else key
                raise SceneError(f"{name} = {part.text!r} is {bad} {place}: an expression must "
                                 f"be finite for 0 <= t <= t_end")


def _check_dimension(scene: "Scene") -> None:
    """A 3D model needs a 3D domain (a box, a solid), a 3D domain a 3D model (the geometry
    kind words the message: :meth:`~ngfrac.scene.geometry_section.GeometryKind.dimension_problem`)."""
    model = scene.model
    models_2d = tuple(k for k in model.KINDS if k not in model.KINDS_3D)
    problem = scene.geometry.kind_of.dimension_problem(scene.geometry, model.kind,
                                                       model.KINDS_3D, models_2d)
    if problem is not None:
        raise SceneError(problem)


def _check_constrained(scene: "Scene") -> None:
    """Quasi-static u (alpha1 = 0) needs every component of u prescribed on some boundary;
    otherwise a rigid translation solves the homogeneous problem (a singular matrix)."""
    if scene.phase_field.alpha1 > 0:
        return  # the alpha1/dt mass term makes the u-problem definite
    dirichlet = [load for load in scene.loads if load.is_dirichlet]
    names = ("z",) if scene.model.n_components == 1 else "xyz"[: scene.model.n_components]
    for i, c in enumerate(names):
        if all(load.free[i] for load in dirichlet):
            raise SceneError(f"loads: u{c} is prescribed on no boundary (every displacement "
                             f"load leaves it 'free'), so with phase_field.alpha1 = 0 the "
                             "u-problem is singular; prescribe it on one boundary")


def _check_split(scene: "Scene") -> None:
    """A split (ngfrac.physics.splits) and a crack pressure need a vector model."""
    split, kind = scene.material.split, scene.model.kind
    scalar = scene.model.n_components == 1  # mode III
    if scene.phase_field.pressurized and scalar:
        raise SceneError(f"phase_field.crack_pressure = {scene.phase_field.crack_pressure.text!r} "
                         "needs a plane or 3D model: mode III has no opening")
    if split != "none" and scalar:
        raise SceneError(f"material.split = {split!r} needs a plane or 3D model, but "
                         f"model.kind = {kind!r} has no tension or compression: set split = 'none'")


def _check_crack_model(scene: "Scene") -> None:
    """PF-CZM needs a strength, a constant toughness and eps below its limit; the Rankine
    drive an isotropic u-step."""
    pf, material = scene.phase_field, scene.material
    if pf.drive == "rankine" and material.split != "none" and material.split_mode == "full":
        raise SceneError(f"phase_field.drive = 'rankine' takes the isotropic u-step, but "
                         f"material.split = {material.split!r} degrades psi+ only: set "
                         "material.split = 'none' or material.split_mode = 'hybrid'")
    if pf.model != "PF-CZM":
        return
    if math.isnan(material.strength):
        raise SceneError("material.strength is missing: phase_field.model = 'PF-CZM' needs "
                         "the tensile strength f_t > 0")
    if not material.gamma.is_constant:
        raise SceneError(f"material.gamma = {material.gamma.text!r} is not allowed with "
                         "phase_field.model = 'PF-CZM': its a1 = 4 E G_f/(pi eps f_t^2) "
                         "needs one G_f; give a number")
    try:
        PFCZM(material.young, material.gamma.value(), material.strength, pf.epsilon,
              pf.softening)
    except ValueError:
        limit = PFCZM(material.young, material.gamma.value(), material.strength,
                      1e-300, pf.softening).epsilon_limit()
        raise SceneError(f"phase_field.epsilon = {pf.epsilon!r} is not allowed: PF-CZM with "
                         f"the {pf.softening} law needs epsilon <= {limit:.4g} (g convex; "
                         "4 l_ch/(pi a1_min), l_ch = E G_f/f_t^2): lower it") from None


def _check_gamma_positive(scene: "Scene") -> None:
    gamma = scene.material.gamma
    dim = scene.geometry.dim
    if "z" in gamma.names and dim == 2:
        raise SceneError(f"material.gamma = {gamma.text!r} uses z, but the domain is 2D")
    coordinates = scene.geometry.domain().sample_points()
    names = "xyz"[:dim]
    values = np.broadcast_to(gamma.evaluate_numpy(dict(zip(names, coordinates))),
                             coordinates[0].shape)
    bad = nonfinite_value(gamma, coordinates)
    if bad:
        raise SceneError(f"material.gamma = {gamma.text!r} is {bad} in the domain: the "
                         "toughness must be finite and > 0 everywhere")
    worst = int(np.argmin(values))
    if values[worst] <= 0:
        where = ", ".join(f"{c[worst]:.3g}" for c in coordinates)
        raise SceneError(f"material.gamma = {gamma.text!r} is {values[worst]:.3g} <= 0 at "
                         f"({', '.join(names)}) = ({where}); the toughness must be "
                         "> 0 everywhere")

