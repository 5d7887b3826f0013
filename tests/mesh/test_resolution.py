"""The resolution check of an adaptive scene builds the scene's own crack model."""

from ngfrac import resolution_warnings
from ngfrac.mesh.resolution import estimated_vertices

from ngfrac.testing.scenes import demo_data, scene_from


def test_adaptive_pfczm_scene_gets_its_resolution_check():
    # Before the fix estimated_vertices called crack_model("PF-CZM") without E, G_f, f_t and
    # epsilon, so every adaptive PF-CZM run stopped with a TypeError before its first step.
    scene = scene_from(demo_data("l_panel"), "phase_field.model=PF-CZM", "material.gamma=9e-5",
                       "material.strength=2.7e-3", "adaptivity.enabled=true")
    assert scene.phase_field.model == "PF-CZM" and scene.adaptivity.enabled
    assert estimated_vertices(scene) > 0
    assert isinstance(resolution_warnings(scene), list)
