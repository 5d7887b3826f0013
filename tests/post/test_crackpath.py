"""Crack paths, kink angles and the LEFM reference solution (ngfrac.post.crackpath)."""
import math

import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngfrac.post.crackpath import (CrackPath, connected_part, crack_path_rows, deviation_from_line,
                                  final_ridge, history_path, kink_angle, mts_kink_angle, ridge_path,
                                  sharp_crack_solution, stress_intensity_from_jump, tip_and_direction)
from ngfrac.scene import Scene


def test_mts_kink_angle_limits_and_criterion():
    assert mts_kink_angle(1.0, 0.0) == 0.0
    # pure mode II: -2 atan(1/sqrt(2)) = -70.53 degrees
    assert mts_kink_angle(0.0, 1.0) == pytest.approx(-70.5288, abs=1e-3)
    assert mts_kink_angle(0.0, -1.0) == pytest.approx(70.5288, abs=1e-3)
    for k2 in (0.1, 0.44, 1.0, 3.0):
        theta = math.radians(mts_kink_angle(1.0, k2))
        # the hoop stress is stationary there: K_I sin + K_II (3 cos - 1) = 0
        assert math.sin(theta) + k2 * (3 * math.cos(theta) - 1) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError):
        mts_kink_angle(-1.0, 0.5)


def kinked_crack_z(mesh, tip, angle_deg, eps):
    """exp(-d/eps) of the slit from (0, tip_y) to tip and a ray from tip at angle_deg."""
    a = math.radians(angle_deg)
    direction = (math.cos(a), math.sin(a))
    s = ngs.IfPos((ngs.x - tip[0]) * direction[0] + (ngs.y - tip[1]) * direction[1],
                  (ngs.x - tip[0]) * direction[0] + (ngs.y - tip[1]) * direction[1], 0)
    ray = ngs.sqrt((ngs.x - tip[0] - s * direction[0]) ** 2
                   + (ngs.y - tip[1] - s * direction[1]) ** 2)
    slit = ngs.sqrt(ngs.IfPos(ngs.x - tip[0], (ngs.x - tip[0]) ** 2, 0) + (ngs.y - tip[1]) ** 2)
    z = ngs.GridFunction(ngs.H1(mesh, order=2))
    z.Set(ngs.exp(-ngs.IfPos(ray - slit, slit, ray) / eps))
    return z


@pytest.mark.parametrize("angle", [-37.5, -22.5, 15.0])
def test_ridge_path_finds_a_straight_kink(angle):
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.01))
    tip, eps = (0.5, 0.5), 0.02
    z = kinked_crack_z(mesh, tip, angle, eps)
    origin, reference = tip_and_direction([[0.0, 0.5], [0.5, 0.5]])
    path = ridge_path(mesh, z, origin, reference, np.linspace(eps, 6 * eps, 21))
    assert len(path.points) == 21
    assert kink_angle(path, eps, 6 * eps) == pytest.approx(angle, abs=0.5)


def test_ridge_path_skips_arcs_without_crack():
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.02))
    z = ngs.GridFunction(ngs.H1(mesh, order=1))  # nothing cracked
    path = ridge_path(mesh, z, (0.5, 0.5), (1.0, 0.0), [0.05, 0.1])
    assert path.points.shape == (0, 2)
    with pytest.raises(ValueError, match="did not grow"):
        kink_angle(path, 0.05, 0.1)


def _slit_scene(eps=0.02):
    return Scene.from_dict({
        "model": {"kind": "mode3"}, "phase_field": {"epsilon": eps, "alpha2": 1e-3},
        "geometry": {"width": 1.0, "height": 1.0}, "cracks": [{"points": [[0.0, 0.5], [0.5, 0.5]]}],
        "loads": [{"boundary": "top", "value": "t"}], "time": {"dt": 0.01, "t_end": 0.01}})


def test_final_ridge_follows_the_kink_and_leaves_out_stray_damage():
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.01))
    eps = 0.02
    kinked = kinked_crack_z(mesh, (0.5, 0.5), -30.0, eps)
    # stray damage at the clamped corner (1, 1): z = 1 there, not connected to the crack
    corner = ngs.exp(-ngs.sqrt((ngs.x - 1) ** 2 + (ngs.y - 1) ** 2) / eps)
    z = ngs.GridFunction(kinked.space)
    z.Set(ngs.IfPos(kinked - corner, kinked, corner))
    ridge = final_ridge(_slit_scene(eps), mesh, z)
    r = ridge.distances
    # arcs every eps/2 from 2 eps until the ray leaves the square (x = 1 at r = 0.577); the
    # corner's damage (r = 0.71 from the tip) is on later arcs, after a jump
    assert r[0] == pytest.approx(2 * eps, abs=1e-9) and 0.55 < r[-1] < 0.6
    assert np.all(np.diff(r) > 0)
    # on the ray: the cusp of exp(-d/eps) is interpolated by P2 on h = 0.01, so the sampled
    # maximum may sit a fraction of h off it (measured: at most 1.1e-3); the last arc passes
    # beyond where the ray leaves the square and finds the edge's largest z (8e-3 off it)
    deviation = np.abs(deviation_from_line(ridge, -30.0))
    assert np.max(deviation[:-1]) < 2e-3 and deviation[-1] < eps / 2
    assert np.all(np.linalg.norm(ridge.points - [1.0, 1.0], axis=1) > 0.4), "corner taken"


def test_connected_part_stops_at_the_first_jump():
    path = CrackPath(np.zeros(2), np.array([1.0, 0.0]),
                     np.array([[0.1, 0.0], [0.2, 0.0], [0.7, 0.3], [0.8, 0.3]]))
    np.testing.assert_array_equal(connected_part(path, 0.15).points, [[0.1, 0.0], [0.2, 0.0]])
    assert len(connected_part(path, 1.0).points) == 4


def test_crack_path_rows_layout():
    history = {"step": np.array([0.0, 1.0, 2.0]), "t": np.array([0.0, 0.1, 0.2]),
               "tip_x": np.array([0.5, np.nan, 0.6]), "tip_y": np.array([0.5, np.nan, 0.45])}
    ridge = CrackPath(np.array([0.5, 0.5]), np.array([1.0, 0.0]), np.array([[0.55, 0.48]]))
    header, rows = crack_path_rows(history, ridge, step=2, t=0.2)
    assert header == ["kind", "step", "t", "x", "y"]
    assert rows == [["tip", 0, 0.0, 0.5, 0.5], ["tip", 2, 0.2, 0.6, 0.45],
                    ["ridge", 2, 0.2, 0.55, 0.48]]
    header3, rows3 = crack_path_rows({**history, "tip_z": np.array([0.05, np.nan, 0.05])}, None, 2, 0.2)
    assert header3 == ["kind", "step", "t", "x", "y", "z"] and len(rows3) == 2
    assert final_ridge(Scene.from_dict({**_slit_scene().to_dict(), "cracks": []}), None, None) is None


def test_history_path_leaves_out_jumps():
    # a weak spot at (0.1, 0.5) and a corner at (1, 1) take the tip over for a while
    history = {"tip_x": np.array([0.5, 0.1, 0.52, 0.54, 0.56, 1.0, 1.0]),
               "tip_y": np.array([0.5, 0.5, 0.49, 0.48, 0.47, 1.0, 1.0])}
    path = history_path(history, (0.5, 0.5), (1.0, 0.0), max_jump=0.1)
    np.testing.assert_allclose(path.points, [[0.52, 0.49], [0.54, 0.48], [0.56, 0.47]])
    assert kink_angle(path, 0.0, 1.0) == pytest.approx(math.degrees(math.atan2(-1, 2)))
    assert len(history_path(history, (0.5, 0.5), (1.0, 0.0)).points) == 5


def test_angles_are_relative_to_the_initial_crack():
    path = CrackPath(np.array([0.0, 0.0]), np.array([0.0, 1.0]),
                     np.array([[0.1, 1.0], [0.2, 2.0]]))
    # reference +y; points to the right of it are clockwise, so negative
    assert kink_angle(path, 0.0, 3.0) == pytest.approx(-math.degrees(math.atan(0.1)))


def test_stress_intensity_from_jump_recovers_k():
    mu, kappa, k1, k2 = 2.0, 1.8, 3.0, -0.7
    r = np.linspace(0.005, 0.05, 30)
    shape = (kappa + 1) / mu * np.sqrt(r / (2 * np.pi))
    # the next terms of the Williams series are r^(3/2)
    jump = np.column_stack([shape * (k2 + 4.0 * r), shape * (k1 - 2.0 * r)])
    assert stress_intensity_from_jump(r, jump, mu, kappa) == pytest.approx((k1, k2), abs=1e-9)


def sharp_scene(tip_x, top=("0", "t")):
    return Scene.from_dict({
        "model": {"kind": "plane_strain"},
        "material": {"E": 1.0, "nu": 0.3, "gamma": 1.0},
        "phase_field": {"epsilon": 0.02, "alpha2": 1.0},
        "geometry": {"width": 1.0, "height": 1.0},
        "cracks": [{"points": [[0.0, 0.5], [tip_x, 0.5]]}],
        "loads": [{"boundary": "bottom", "value": ["0", "0"]},
                  {"boundary": "top", "value": list(top)}],
        "time": {"dt": 1.0, "t_end": 1.0},
    })


@pytest.mark.parametrize("top", [("0", "t"), ("t", "t")])
def test_sharp_crack_g_matches_the_compliance(top):
    """G from K (Irwin) equals -dE/da at fixed displacement (central difference)."""
    a, da = 0.5, 0.01
    sharp = sharp_crack_solution(sharp_scene(a, top))
    minus = sharp_crack_solution(sharp_scene(a - da, top)).energy
    plus = sharp_crack_solution(sharp_scene(a + da, top)).energy
    compliance = -(plus - minus) / (2 * da)
    assert sharp.G == pytest.approx(compliance, rel=0.01), (sharp, compliance)
    # the reactions do the work: E = 1/2 (Fx ux + Fy uy) at t = 1
    work = sum(sharp.reactions[f"F{c}_top"] for c, value in zip("xy", top) if value == "t")
    assert sharp.energy == pytest.approx(0.5 * work, rel=1e-8)
    if top == ("0", "t"):
        assert abs(sharp.K_II) < 1e-3 * sharp.K_I  # symmetric: pure mode I
    else:
        assert sharp.K_II > 0 and sharp.kink_deg < 0  # the upper face slides in +x


def test_sharp_crack_of_a_notch_cut_out_of_the_geometry():
    """A scene whose notch is a slit in an occ square (the SENT/SENS demos) has no [[cracks]]:
    given the slit's centre line and the square, the LEFM solution is the rectangle scene's."""
    data = sharp_scene(0.5).to_dict()
    del data["cracks"]
    data["geometry"] = {"kind": "occ", "mesh_size": 0.05, "shapes": [
        {"type": "rectangle", "corner": [0.0, 0.0], "size": [1.0, 1.0]},
        {"type": "rectangle", "corner": [0.0, 0.499], "size": [0.5, 0.002], "op": "cut"}],
        "boundaries": [{"name": "bottom", "box": [[-0.001, -0.001], [1.001, 0.001]]},
                       {"name": "top", "box": [[-0.001, 0.999], [1.001, 1.001]]}]}
    slit = Scene.from_dict(data)
    with pytest.raises(ValueError, match=r"^the scene has no \[\[cracks\]\]: give the sharp crack"):
        sharp_crack_solution(slit)
    with pytest.raises(ValueError, match=r"^geometry.kind = 'occ' is not a rectangle: give"):
        sharp_crack_solution(slit, crack=[[0.0, 0.5], [0.5, 0.5]])
    cut = sharp_crack_solution(slit, crack=[[0.0, 0.5], [0.5, 0.5]], box=[[0.0, 0.0], [1.0, 1.0]])
    band = sharp_crack_solution(sharp_scene(0.5))
    # the same mesh and system; threaded sparse Cholesky differs in round-off only
    for name in ("K_I", "G", "energy"):
        assert getattr(cut, name) == pytest.approx(getattr(band, name), rel=1e-9), name
    assert cut.reactions == pytest.approx(band.reactions, rel=1e-9)
