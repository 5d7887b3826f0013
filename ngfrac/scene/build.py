"""The objects a scene describes, built once per scene: its elastic model and its crack model
(the domain is :meth:`ngfrac.scene.geometry_section.Geometry.domain`, built once per geometry
section).

:attr:`Scene.elastic_model <ngfrac.scene.sections.Scene.elastic_model>` and
:attr:`Scene.crack_model <ngfrac.scene.sections.Scene.crack_model>` keep what
:func:`build_elastic_model` and :func:`build_crack_model` make, so the stepper, the mesh
adapter (serial and distributed), the checks and the writers of one scene share one object
of each; :func:`elastic_model_of` and :func:`crack_model_of` return those.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..physics.crack_models import PFCZM, CrackModel, crack_model
from ..physics.elastic import ELASTIC_MODELS, ElasticModel
from .validation import check_model_fits

if TYPE_CHECKING:
    from .sections import Scene

__all__ = ["build_crack_model", "build_elastic_model", "crack_model_of", "elastic_model_of"]


def build_elastic_model(scene: "Scene") -> ElasticModel:
    """A new elastic model of ``model.kind`` (checks that loads and moduli fit it)."""
    check_model_fits(scene.model, scene.material, scene.loads)
    kind = scene.model.kind
    if kind in ELASTIC_MODELS:
        return ELASTIC_MODELS[kind].of(scene.material)
    raise ValueError(f"model {kind!r} is not implemented")  # scene validation prevents this


def build_crack_model(scene: "Scene") -> CrackModel:
    """A new crack model of ``phase_field.model``
    (:data:`ngfrac.physics.crack_models.CRACK_MODELS`); PF-CZM from ``material.E`` (or lam,
    mu; mode III: mu), ``material.gamma`` (G_f), ``material.strength`` (f_t),
    ``phase_field.epsilon`` and ``phase_field.softening``."""
    pf, material = scene.phase_field, scene.material
    if pf.model == PFCZM.name:
        return PFCZM(material.young, material.gamma.value(), material.strength, pf.epsilon,
                     pf.softening)
    return crack_model(pf.model)


def elastic_model_of(scene: "Scene") -> ElasticModel:
    """The elastic model the scene asks for: the one built once
    (:attr:`~ngfrac.scene.sections.Scene.elastic_model`)."""
    return scene.elastic_model


def crack_model_of(scene: "Scene") -> CrackModel:
    """The crack model of ``phase_field.model``: the one built once
    (:attr:`~ngfrac.scene.sections.Scene.crack_model`)."""
    return scene.crack_model
