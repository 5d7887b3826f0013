"""The objects a scene describes, built in one place: its elastic model and its crack model
(the domain is :meth:`ngfrac.scene.Geometry.domain`)."""
from __future__ import annotations

from ..physics.crack_models import PFCZM, CrackModel, crack_model
from ..physics.elastic import ELASTIC_MODELS, ElasticModel
from .sections import Scene
from .validation import check_model_fits

__all__ = ["crack_model_of", "elastic_model_of"]


def elastic_model_of(scene: Scene) -> ElasticModel:
    """The elastic model the scene asks for (checks that loads and moduli fit it)."""
    check_model_fits(scene.model, scene.material, scene.loads)
    kind = scene.model.kind
    if kind in ELASTIC_MODELS:
        return ELASTIC_MODELS[kind].of(scene.material)
    raise ValueError(f"model {kind!r} is not implemented")  # scene validation prevents this


def crack_model_of(scene: Scene) -> CrackModel:
    """The crack model of ``phase_field.model`` (:data:`ngfrac.physics.crack_models.CRACK_MODELS`);
    PF-CZM from ``material.E`` (or lam, mu; mode III: mu), ``material.gamma`` (G_f),
    ``material.strength`` (f_t), ``phase_field.epsilon`` and ``phase_field.softening``."""
    pf, material = scene.phase_field, scene.material
    if pf.model == PFCZM.name:
        return PFCZM(material.young, material.gamma.value(), material.strength, pf.epsilon,
                     pf.softening)
    return crack_model(pf.model)
