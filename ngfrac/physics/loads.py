"""Load kinds: what a ``[[loads]]`` entry prescribes on its boundary (``loads[i].kind``).

Each kind is one class in :data:`LOAD_KINDS`: whether it prescribes u (a Dirichlet boundary)
or a traction sigma n (a Neumann boundary, whose work enters the u-step undegraded), the
shape of its value, and what it refuses. The scene's ``Load`` section validates a load
through its kind (:class:`ngfrac.scene.sections.Load`, :func:`ngfrac.scene.validation.check_model_fits`);
the elastic models ask it for the traction (:func:`ngfrac.physics.elastic.traction_of`). A
new kind is a subclass here with its name in :data:`LOAD_KINDS`.
"""
from __future__ import annotations

from typing import Any, ClassVar

import ngsolve as ngs

__all__ = ["LOAD_KINDS", "Displacement", "LoadKind", "Pressure", "Traction"]


class LoadKind:
    """What one ``loads[i].kind`` prescribes (subclass per kind).

    A load's ``value`` is an expression (``to_coefficient(t)``) or, for a vector, a tuple of
    them (the scene's ``Components``: ``free`` flags, ``text``).
    """

    name: ClassVar[str]
    dirichlet: ClassVar[bool] = False
    """Whether the load prescribes u (a Dirichlet boundary); otherwise a traction."""
    scalar: ClassVar[bool] = False
    """Whether the value is one expression whatever the model (otherwise of u's shape)."""

    def value_problem(self, value: Any) -> tuple[Any, str] | None:
        """What is wrong with a value whatever the model: (the value as the message shows
        it, what is allowed), or None."""
        return None

    def model_problem(self, model_kind: str, n_components: int) -> str | None:
        """Why the kind does not fit a model with ``n_components`` components of u (the
        message after ``loads[i].kind = '...'``), or None."""
        return None

    def traction(self, value: Any, mesh: ngs.Mesh, t: ngs.Parameter) -> Any:
        """The traction sigma n of a Neumann load with this value."""
        raise TypeError(f"a {self.name!r} load prescribes u, not a traction")


class Displacement(LoadKind):
    """``kind = "displacement"`` (the default): u prescribed; ``"free"`` leaves a component
    unconstrained."""

    name = "displacement"
    dirichlet = True


class Traction(LoadKind):
    """``kind = "traction"``: sigma n = value, of a displacement's shape, no ``"free"``."""

    name = "traction"

    def value_problem(self, value: Any) -> tuple[Any, str] | None:
        if isinstance(value, tuple) and any(value.free):
            return value.text, "a traction gives every component (use \"0\", not \"free\")"
        return None

    def traction(self, value: Any, mesh: ngs.Mesh, t: ngs.Parameter) -> Any:
        if isinstance(value, tuple):  # one expression per component
            return ngs.CoefficientFunction(tuple(entry.to_coefficient(t) for entry in value))
        return value.to_coefficient(t)


class Pressure(LoadKind):
    """``kind = "pressure"``: one expression p, the traction -p n (plane and 3D models)."""

    name = "pressure"
    scalar = True

    def value_problem(self, value: Any) -> tuple[Any, str] | None:
        if isinstance(value, tuple):
            return ([str(e) for e in value],
                    "a pressure is one expression p(x, y, t) (it acts as -p n), not a list")
        return None

    def model_problem(self, model_kind: str, n_components: int) -> str | None:
        if n_components == 1:
            return (f"needs a plane or 3D model, but model.kind = {model_kind!r} has no normal "
                    "displacement; use kind = 'traction' (the out-of-plane shear stress)")
        return None

    def traction(self, value: Any, mesh: ngs.Mesh, t: ngs.Parameter) -> Any:
        return -value.to_coefficient(t) * ngs.specialcf.normal(mesh.dim)


LOAD_KINDS: dict[str, LoadKind] = {kind.name: kind() for kind in (Displacement, Traction, Pressure)}
"""The values of ``loads[i].kind``, in the order messages list them."""
