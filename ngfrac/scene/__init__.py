"""The run description: scene sections as frozen dataclasses, loading TOML with ``--set``
overrides, expressions in x, y, z and t, and the checks of a scene before anything runs."""
from .expressions import Expression, ExpressionError
from .loading import apply_overrides, load_scene, parse_override, read_scene_data
from .coercion import Components, SceneError
from .geometry_section import BoundarySelector, Crack, Geometry, Shape
from .sections import (LISTS, MODELS, MODELS_3D, SECTIONS, Adaptivity, Discretization, Load,
                       Material, Model, Output, PhaseField, Scene, TimeSettings)

__all__ = ["MODELS", "MODELS_3D", "SECTIONS", "LISTS", "Adaptivity", "BoundarySelector", "Shape",
           "Components", "Crack", "Discretization",
           "Expression", "ExpressionError", "Geometry", "Load", "Material", "Model", "Output",
           "PhaseField", "Scene", "SceneError", "TimeSettings", "apply_overrides", "load_scene",
           "parse_override", "read_scene_data"]
