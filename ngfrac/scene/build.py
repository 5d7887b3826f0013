"""The objects a scene describes, built in one place: its elastic model and its crack model
(the domain is :meth:`ngfrac.scene.Geometry.domain`)."""
from __future__ import annotations

from ..physics.crack_models import CrackModel, crack_model
from ..physics.elastic import ELASTIC_MODELS, ElasticModel
from .sections import Scene

__all__ = ["crack_model_of", "elastic_model_of"]


def elastic_model_of(scene: Scene) -> ElasticModel:
    """The elastic model the scene asks for (checks that loads and moduli fit it)."""
    scene.model.check(scene.material, scene.loads)
    kind = scene.model.kind
    if kind in ELASTIC_MODELS:
        return ELASTIC_MODELS[kind].of(scene.material)
    raise ValueError(f"model {kind!r} is not implemented")  # scene validation prevents this


def crack_model_of(scene: Scene) -> CrackModel:
    """The crack model of ``phase_field.model`` (:data:`ngfrac.physics.crack_models.CRACK_MODELS`)."""
    return crack_model(scene.phase_field.model)
