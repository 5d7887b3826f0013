"""u_solver = 'cg' (CG with BDDC, ngfrac.fem.linear) against the sparse direct solver."""
import numpy as np
import pytest

from ngfrac import PhaseFieldStepper, Scene
from ngfrac.scene import SceneError


def sent_like(u_solver, split="none", order=2):
    """A slit plate pulled apart: the band (z = 1 on the slit, eta = 1e-6) makes the u-matrix
    ill-conditioned, and the slit grows within the run."""
    return Scene.from_dict({
        "model": {"kind": "plane_strain"},
        "material": {"lam": 121.15, "mu": 80.77, "gamma": 2.7e-3, "split": split},
        "phase_field": {"epsilon": 0.04, "alpha2": 1e-7},
        "geometry": {"width": 1.0, "height": 1.0, "mesh_size": 0.03},
        "cracks": [{"points": [[0.0, 0.5], [0.5, 0.5]]}],
        "loads": [{"boundary": "bottom", "value": ["0", "0"]},
                  {"boundary": "top", "value": ["0", "t"]}],
        "time": {"dt": 5e-4, "t_end": 1e-2},
        "discretization": {"order": order, "u_solver": u_solver},
        "output": {"vtk_every": 0},
    })


def history(scene):
    stepper = PhaseFieldStepper(scene)
    rows = np.array([(r.E_el, r.E_surf, r.forces["Fy_top"], r.tip_x) for r in stepper.run()])
    return rows, stepper


@pytest.mark.parametrize("split", ["none", "amor"])
def test_cg_matches_the_direct_solver(split):
    order = 2 if split == "none" else 1  # with a split, P1 keeps the Newton runs short
    direct, _ = history(sent_like("sparsecholesky", split, order))
    iterative, stepper = history(sent_like("cg", split, order))
    assert direct[-1, 3] > 0.55, "the slit did not grow: the test needs a growing crack"
    np.testing.assert_allclose(iterative[:, :3], direct[:, :3], rtol=1e-6)
    if split == "none":
        assert 0 < stepper.u_problem.iterations < 1000


def test_u_solver_is_validated():
    with pytest.raises(SceneError, match="u_solver"):
        sent_like("gmres")
