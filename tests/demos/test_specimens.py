"""The standard specimens of phase-field fracture (issue #12, item 4) in a quick mode: each
demo runs and shows one physical fact; z keeps its bounds. ``--runslow`` runs the full demos.

The quick runs are coarser (larger epsilon, P1 or a smaller vertex cap, fixed steps) than the
demos; the numbers quoted in the comments were measured on those quick runs.
"""

import dataclasses

import ngsolve as ngs
import numpy as np
import pytest

from ngfrac import load_scene
from ngfrac.scene import Geometry
from ngfrac.scene.sections import Shape
from ngfrac.io.plotting import read_history
from ngfrac.physics.crack_models import largest_principal_stress

from .loading import DEMOS, ROOT, load_demo

SPECIMENS = ("l_panel", "three_point_bending", "compact_tension", "three_hole_beam")
"""The specimen demos this file runs (tests/demos/test_demos.py runs the others)."""

QUICK = {
    # epsilon = 10 mm (the demo's 5), fixed steps of 0.01 mm to 0.42 mm, a 20 mm first mesh
    # (597 vertices), at most 2,000: 42 steps, 17 s CPU. PF-CZM (Cornelissen, Rankine drive):
    # sigma_1 passes f_t at the corner at t = 0.04 mm, the force peaks at 0.110 kN/mm at
    # 0.27 mm and the crack has run ~50 mm by 0.42. The paper's single pass, not the demo's
    # staggered one: the run stays the one measured above, and what it checks (the elastic
    # phase, the nucleus, the slope, the path) the coupling does not decide (the alternate
    # passes took 155 s CPU here instead of 17 s, one run at load ~2; the couplings have tests
    # of their own, tests/physics/test_pfczm.py).
    "l_panel": ["phase_field.epsilon=10", "time.dt=1e-2", "time.adaptive=false",
                "time.t_end=0.42", "adaptivity.max_vertices=2000", "adaptivity.hmin=2",
                "adaptivity.hmax=20", "output.vtk_every=0", 'discretization.coupling="paper"'],
    # epsilon = 0.06 mm (the demo's 0.03, the paper's other value), P1, fixed steps of 5e-4 mm,
    # at most 3,000 vertices: 120 steps, 10.9 s CPU on one core. Peak near t = 0.048 mm.
    # The paper's single pass, as before the demo's switch to the staggered pass (session 26):
    # at these coarse steps the staggered crack runs further per step and one tip of its track
    # strays 0.063 mm = 1.05 epsilon off x = 4 (measured), past check_three_point_bending's
    # epsilon; the full demo's path is checked by test_three_point_bending_full.
    "three_point_bending": ["phase_field.epsilon=0.06", "discretization.order=1",
                            "time.dt=5e-4", "time.adaptive=false", "time.t_end=0.06",
                            "adaptivity.max_vertices=3000", "adaptivity.hmin=0.01",
                            "output.vtk_every=0", 'discretization.coupling="paper"'],
    # epsilon = 1 mm (the demo's 0.5), P1, fixed steps of 5e-3 mm, at most 3,000 vertices:
    # 90 steps, 7.6 s CPU on one core. Peak near t = 0.335 mm, the crack then runs ~5.7 mm.
    # (Steps of 0.01 mm overshot the peak without a split: 3.45 kN/mm against 3.14; with the
    # hybrid split at most 2,000 vertices one tip of the track strayed 1.1 mm = 1.1 epsilon
    # off y = 0.)
    # The paper's single pass, as before the demo's switch to the staggered pass (session 26),
    # so that the numbers in check_compact_tension stay those of this run.
    "compact_tension": ["phase_field.epsilon=1", "discretization.order=1", "time.dt=5e-3",
                        "time.adaptive=false", "time.t_end=0.45",
                        "adaptivity.max_vertices=3000", "adaptivity.hmin=0.1",
                        "output.vtk_every=0", 'discretization.coupling="paper"'],
    # A smaller check than the demo's (the crack reaches a hole only by t ~ 0.2 mm, after
    # more than a minute at P1): the demo's epsilon (0.1 mm) and hybrid split, P1, fixed
    # steps of 5e-3 mm to t = 0.2, at most 2,500 vertices: 40 steps, 4.9 s CPU on one core.
    # The paper's single pass, as before the demo's switch to the staggered pass (session 27):
    # what check_three_hole_beam_start checks (elastic slope, the crack leaving the notch, no
    # stray zone) the coupling does not decide, and the staggered quick run also passes (tip
    # (4.36, 1.55), slope within 0.79 %; 8.5 s CPU against 7.5 s beside another run).
    "three_hole_beam": ["discretization.order=1", "time.dt=5e-3", "time.adaptive=false",
                        "time.t_end=0.2", "adaptivity.max_vertices=2500",
                        "output.vtk_every=0", 'discretization.coupling="paper"'],
}




class Bounds:
    """Checks 0 <= z <= 1 at every Lagrange node and keeps the last stepper. With PF-CZM it
    also records, per step, (t, largest sigma_1, largest z): the elastic phase's check."""

    def __init__(self):
        self.stepper = None
        self.steps = 0
        self.onset = []

    def __call__(self, stepper):
        values = stepper.z_node_values()
        assert values.min() >= 0.0 and values.max() <= 1.0, (values.min(), values.max())
        if stepper.scene.phase_field.model == "PF-CZM":
            self.onset.append((stepper.t, largest_stress(stepper), float(values.max())))
        self.stepper = stepper
        self.steps += 1


def largest_stress(stepper):
    """The largest principal stress of the sound material, sigma_1 of C:e(u) (what the Rankine
    drive sees), over the whole mesh: with P1 or P2 displacements the stress is linear on each
    triangle and sigma_1 convex in it, so its maximum is at an element's vertex."""
    mesh, u = stepper.fields.mesh, stepper.fields.u
    sigma_1 = largest_principal_stress(stepper.model.stress(u), 2)
    corners = ngs.IntegrationRule([(0, 0), (1, 0), (0, 1)], [0, 0, 0])
    return float(np.max(sigma_1(mesh.MapToAllElements(corners, ngs.VOL))))


def run_demo(name, out, overrides, bounds=None):
    bounds = Bounds() if bounds is None else bounds
    load_demo(name).main(out, overrides, on_step=bounds)
    return read_history(out / "history.csv"), bounds.stepper


def crack_samples(scene, spacing):
    """Points along the scene's cracks, ``spacing`` apart (to refine the band of z0)."""
    points = []
    for crack in scene.cracks:
        for p, q in zip(crack.points[:-1], crack.points[1:]):
            n = int(np.ceil(np.linalg.norm(np.subtract(q, p)) / spacing)) + 1
            points += [list(r) for r in np.linspace(p, q, n)]
    return points


def elastic_stiffness(scene, loaded, component, maxh, order, refinements, opposite=None,
                      degradation=None):
    """Force per unit displacement of the boundary ``loaded`` along ``component`` (0: x,
    1: y), the other displacement loads held at zero and ``free`` components free: twice the
    elastic energy of the solution for a unit displacement (plane strain or, with
    ``model.kind = "plane_stress"``, lambda* = 2 lambda mu/(lambda + 2 mu); sound material),
    on a mesh of size ``maxh`` refined ``refinements`` times near the domain's vertices.

    ``opposite``: a boundary moved by -1 at the same time (a symmetric pair: the force on
    each is then the energy); ``degradation``: a CoefficientFunction multiplying the
    stiffness (an initial crack's (1 - z0)^2 + eta), refined also near the cracks' points."""
    domain = scene.geometry.domain()
    mesh = domain.build_mesh(maxh)
    corners = np.array([[v.p.x, v.p.y] for v in domain.shape.vertices]
                       + (crack_samples(scene, maxh / 4) if degradation is not None else []))
    for level in range(refinements):
        radius = 3 * maxh * 0.5 ** level
        for el in mesh.Elements(ngs.VOL):
            points = np.array([mesh[v].point for v in el.vertices])
            near = np.min(np.linalg.norm(points[:, None, :] - corners[None], axis=2)) < radius
            mesh.SetRefinementFlag(el, bool(near))
        mesh.Refine()
    held = {0: [], 1: []}
    for load in scene.loads:
        for k, value in enumerate(load.value):
            if value != "free":
                held[k].append(load.boundary)
    fes = ngs.VectorH1(mesh, order=order, dirichletx="|".join(held[0]),
                       dirichlety="|".join(held[1]))
    lam, mu = scene.material.lame
    if scene.model.kind == "plane_stress":
        lam = 2 * lam * mu / (lam + 2 * mu)
    u, v = fes.TnT()

    def strain(w):
        return ngs.Sym(ngs.Grad(w))

    def stress(w):
        return 2 * mu * strain(w) + lam * ngs.Trace(strain(w)) * ngs.Id(2)

    weight = 1 if degradation is None else degradation
    a = ngs.BilinearForm(weight * ngs.InnerProduct(stress(u), strain(v)) * ngs.dx).Assemble()
    g = ngs.GridFunction(fes)
    unit = [0.0, 0.0]
    unit[component] = 1.0
    g.Set(ngs.CF(tuple(unit)), definedon=mesh.Boundaries(loaded))
    if opposite is not None:
        # (Set with definedon zeroes the dofs outside its region: the two sets are added.)
        other = ngs.GridFunction(fes)
        other.Set(ngs.CF(tuple(-c for c in unit)), definedon=mesh.Boundaries(opposite))
        g.vec.data += other.vec
    residual = -(a.mat * g.vec)
    g.vec.data += a.mat.Inverse(fes.FreeDofs(), "sparsecholesky") * residual
    energy2 = ngs.Integrate(weight * ngs.InnerProduct(stress(g), strain(g)), mesh)
    return energy2 if opposite is None else energy2 / 2


# -- the L-shaped panel -----------------------------------------------------------------------

L_CORNER = np.array([250.0, 250.0])


def check_l_panel(history, stepper, onset=None):
    scene = stepper.scene
    eps = scene.phase_field.epsilon
    f_t = scene.material.strength
    # PF-CZM's elastic phase: while the largest principal stress of the sound material is
    # below f_t everywhere, z is exactly 0 at every node (the drive <sigma_1>^2/E stays below
    # the constant source 2 G_f/(pi eps), and the obstacle solve keeps z at its bound); it
    # fails if the source, the drive or a1 were wrong (AT2 damages at any load) and with P2 z
    # (docs/theory.md: measured with discretization.order_z=2, z = 0.003 at sigma_1 = 0.55 f_t).
    # Quick run: sigma_1 (at the re-entrant corner, singular, on the 20 mm first mesh) is 0.27,
    # 0.55 and 0.82 f_t in the first three steps, z exactly 0; above f_t from t = 0.04 mm.
    if onset is not None:
        below = [(t, s1, z) for t, s1, z in onset if s1 < f_t]
        assert below, f"sigma_1 reached f_t in the first step: {onset[:2]}"
        assert all(z == 0.0 for _, _, z in below), [(t, s1 / f_t, z) for t, s1, z in below if z]
        assert max(z for _, _, z in onset) > 0.5, "the panel never cracked"
    # No initial crack: the crack set first appears at the re-entrant corner, where the
    # elastic stresses are singular (r^-0.456). Quick run: 2.2 mm from the corner.
    nucleus = stepper.nucleus
    assert nucleus is not None, "no crack nucleated"
    distance = np.linalg.norm(nucleus[:2] - L_CORNER)
    assert distance < 2 * eps, f"nucleus {nucleus} is {distance:.1f} mm from the corner"
    # The initial slope is the elastic stiffness of the panel: the first step solves u on the
    # sound panel (z = 0). Reference: P3 on h = 10 mm refined twice at the vertices (plane
    # stress): 0.6037 kN/mm per mm. The quick run's first mesh (h = 20 mm, P2) is 0.8 % stiffer
    # (measured: 0.6084); 3 % bounds that discretization error.
    u, force = history["uy_load"], history["Fy_load"]
    reference = elastic_stiffness(scene, "load", 1, maxh=10.0, order=3, refinements=2)
    slope = force[1] / u[1]
    assert abs(slope / reference - 1) < 0.03, f"slope {slope:.4f}, elastic {reference:.4f}"
    # The crack then runs from the corner into the vertical leg (towards x = 0), near the
    # corner's height (Winkler's cracks curve up to y ~ 250-300 mm), and the force falls.
    # Quick run: tip at x = 200, y = 254 by u = 0.42 mm; force 0.110 kN at the peak, 0.081 then.
    grown = np.isfinite(history["tip_x"])
    assert np.nanmin(history["tip_x"]) < L_CORNER[0] - 4 * eps, np.nanmin(history["tip_x"])
    assert np.all(np.abs(history["tip_y"][grown] - 265.0) < 35.0), history["tip_y"][grown]
    peak = int(np.argmax(force))
    assert force[-1] < 0.95 * force[peak], f"peak {force[peak]:.4f}, end {force[-1]:.4f} kN"


# -- three-point bending -----------------------------------------------------------------------

def check_three_point_bending(history, stepper):
    scene = stepper.scene
    eps = scene.phase_field.epsilon
    demo = load_demo("three_point_bending")
    deflection, force = -history["uy_load"], -history["Fy_load"]
    # Linear at first: the beam is elastic until the damage at the notch tip localizes. F/u
    # stays within 1 % of its first value while F < 0.35 P_c (quick run: 0.04 %; full run:
    # 0.05 %); later AT2's band localizes at the notch tip and F/u falls before the crack grows.
    p_c = demo.lefm_onset(scene)
    early = (deflection > 0) & (force < 0.35 * p_c) & (np.arange(len(force)) < np.argmax(force))
    slope = force[early] / deflection[early]
    assert early.sum() >= 5 and np.all(np.abs(slope / slope[0] - 1) < 0.01), slope
    # The peak is near the Griffith load of the sharp notch (Srawley's K_I for S/W = 4):
    # P_c = 0.0322 kN/mm with G_c, 0.0335 with the band's gamma (1 + h/(2 eps)) for its core
    # of h = 0.01 mm. As for SENT (tests/demos/test_demos.py), the phase field's peak lies
    # within 15 % of that: quick run 0.0369 kN/mm (+10 % on 0.0335), 0.0291 at u = 0.06 mm;
    # full run 0.03245 kN/mm at u = 0.03875 mm (-1.6 % on its 0.0330), 0.0042 at u = 0.06 mm
    # (with the paper's single pass in adaptive steps 0.0341, +3.2 %).
    h_core = max(scene.adaptivity.hmin, eps / 10)
    p_eff = p_c * np.sqrt(1 + h_core / (2 * eps))
    peak = int(np.argmax(force))
    assert 0.85 * p_c < force[peak] < 1.15 * p_eff, f"peak {force[peak]:.4f}, LEFM {p_c:.4f}"
    assert force[-1] < 0.95 * force[peak], f"no drop: peak {force[peak]:.4f}, end {force[-1]:.4f}"
    # The crack starts at the notch tip (4, 0.4) and runs up the symmetry line x = 4 (the
    # supports differ only in ux, which the beam barely uses): every tip within the band's
    # half width epsilon of that line. Quick run: tip up to y = 0.88 mm, |x - 4| <= 0.037 mm
    # (0.62 epsilon: the ridge's end wanders by about an element, h ~ 0.015, of the band);
    # full run: to y = 1.59 mm, |x - 4| <= 0.018 mm (0.61 epsilon).
    tip_x, tip_y = history["tip_x"], history["tip_y"]
    grown = np.isfinite(tip_y) & (tip_y > demo.NOTCH + eps)
    assert np.nanmax(tip_y) > demo.NOTCH + 3 * eps, f"the crack grew only to y = {np.nanmax(tip_y)}"
    assert np.all(np.abs(tip_x[grown] - 4.0) < eps), tip_x[grown]


# -- compact tension ---------------------------------------------------------------------------

CT_TIP = np.array([20.0, 0.0])
CT_F_CONTACT = 9.40
"""f(0.5) of this specimen loaded through 2 mm contact arcs: from the elastic compliance's
slope (P3, slits to a = 19.5, 20, 20.5 mm: G = P^2/2 dC/da; demos/compact_tension.toml);
ASTM E399's 9.66 is for pins at the load line."""


def sharp_crack_stiffness(scene, tip, maxh=2.0):
    """Pin force per pin displacement of the specimen with a sharp crack to x = ``tip`` (a
    slit 0.02 mm wide from the notch; no slit for tip <= 15, the notch alone): elastic, P3,
    h = ``maxh`` refined twice at the vertices (the slit's tip among them)."""
    shapes = list(scene.geometry.shapes)
    if tip > 15.0:
        shapes.append(Shape(type="rectangle", corner=[14.9, -0.01], size=[tip - 14.9, 0.02],
                            op="cut"))
    geometry = Geometry(kind="occ", shapes=shapes, boundaries=list(scene.geometry.boundaries),
                        split_points=[list(p) for p in scene.geometry.split_points])
    sharp = dataclasses.replace(scene, geometry=geometry, cracks=())
    return elastic_stiffness(sharp, "pin_top", 1, maxh=maxh, order=3, refinements=2,
                             opposite="pin_bottom")


def check_compact_tension(history, stepper):
    scene = stepper.scene
    eps = scene.phase_field.epsilon
    demo = load_demo("compact_tension")
    u, force = history["uy_pin_top"], history["Fy_pin_top"]
    # The initial slope: the first step solves u on the phase field of the pre-crack. It is
    # softer than the notch alone (no pre-crack) and stiffer than a sharp crack 2 epsilon
    # longer than the pre-crack (AT2's z0 = exp(-d/eps) degrades about epsilon beyond the
    # tip); elastic P3 references (within 0.2 % of h/2's). Quick run (P1, hybrid): 12.93
    # between 9.13 (a = 22 mm) and 18.35 (a = 15 mm) (13.46 without a split); the sharp pre-crack (a = 20 mm) gives 11.46, the
    # full demo's first step (P2, eps = 0.5) 12.29, P2 with eps = 1 10.99: AT2's band on
    # these meshes is neither the sharp crack nor converged, so only the bounds are asserted.
    slope = force[1] / u[1]
    softest = sharp_crack_stiffness(scene, CT_TIP[0] + 2 * eps)
    stiffest = sharp_crack_stiffness(scene, 15.0)
    assert softest < slope < stiffest, f"slope {slope:.3f} not in ({softest:.3f}, {stiffest:.3f})"
    # The peak is near the Griffith load of the sharp crack: ASTM E399's P_c = 2.694 kN/mm,
    # 2.77 with this specimen's f (contact arcs, CT_F_CONTACT), times sqrt(1 + h/(2 eps))
    # for the band's toughness with its core h. As for SENT and 3PB, within 15 % of that:
    # quick run 3.152 kN/mm (+11 %), full run (staggered, steps of 2.5e-4 mm) 2.715 kN/mm
    # (-4.3 %, 1.008 P_c; 2.930 with the paper's single pass in adaptive steps). The force then
    # falls: quick run to 80 % of the peak by t = 0.45 mm, full run to 56 % by 0.35 mm.
    p_c = demo.lefm_onset(scene)
    h_core = max(scene.adaptivity.hmin, eps / 10)
    p_eff = p_c * demo.astm_f(0.5) / CT_F_CONTACT * np.sqrt(1 + h_core / (2 * eps))
    peak = int(np.argmax(force))
    assert 0.85 * p_c < force[peak] < 1.15 * p_eff, f"peak {force[peak]:.3f}, LEFM {p_c:.3f}"
    assert force[-1] < 0.95 * force[peak], f"no drop: peak {force[peak]:.3f}, end {force[-1]:.3f}"
    # The crack starts at the pre-crack's tip (20, 0) and runs along the symmetry line y = 0
    # (the pins load the specimen symmetrically): every tip within the band's half width
    # epsilon of it. Quick run: to x = 25.7, |y| <= 0.59 mm (0.59 epsilon); full run: to
    # x = 27.1, |y| <= 0.16 mm (0.31 epsilon).
    tip_x, tip_y = history["tip_x"], history["tip_y"]
    grown = np.isfinite(tip_x)
    first = np.flatnonzero(grown & (tip_x > CT_TIP[0] + 0.5 * eps))[0]
    assert tip_x[first] < CT_TIP[0] + 2 * eps, f"the crack appeared at x = {tip_x[first]:.2f}"
    assert np.nanmax(tip_x) > CT_TIP[0] + 4 * eps, f"the crack grew only to x = {np.nanmax(tip_x)}"
    assert np.all(np.abs(tip_y[grown]) < eps), tip_y[grown]


# -- the asymmetric beam with three holes -----------------------------------------------------

def check_three_hole_beam_start(history, stepper):
    eps = stepper.scene.phase_field.epsilon
    demo = load_demo("three_hole_beam")
    deflection, force = -history["uy_load"], -history["Fy_load"]
    # Linear at first (F/u within 1 % of its first value while F < 0.3 kN/mm; quick run:
    # 0.66 %), as the beam is elastic until the notch tip's band localizes.
    early = (deflection > 0) & (force < 0.3)
    slope = force[early] / deflection[early]
    assert early.sum() >= 5 and np.all(np.abs(slope / slope[0] - 1) < 0.01), slope
    # The crack leaves the notch tip (4, 1): by t = 0.2 mm the tip has moved more than 2
    # epsilon from it, upward (the notch's direction) and off the notch's line towards the
    # load and the holes (x > 4: the notch is 6 mm left of the load, mode I+II), and nothing
    # else has cracked yet (no stray damage zone: no toughened zone keeps the beam's middle
    # or supports intact, the hybrid split does: they are in compression or below the notch's
    # stresses). Quick run: tip (4.099, 1.283), 3.0 epsilon from the notch tip; no other zone.
    tip = np.array([history["tip_x"][-1], history["tip_y"][-1]])
    assert np.linalg.norm(tip - demo.NOTCH_TIP) > 2 * eps, f"tip {tip}: the crack did not grow"
    assert tip[1] > demo.NOTCH_TIP[1] and tip[0] > demo.NOTCH_TIP[0], f"tip {tip}"
    assert np.all(history["n_damage_zones"] == 0), history["n_damage_zones"]


CHECKS = {"l_panel": check_l_panel, "three_point_bending": check_three_point_bending,
          "compact_tension": check_compact_tension,
          "three_hole_beam": check_three_hole_beam_start}


def test_every_specimen_has_a_check():
    assert set(SPECIMENS) == set(CHECKS) == set(QUICK)
    for name in SPECIMENS:
        assert (DEMOS / f"{name}.toml").exists() and (DEMOS / f"{name}.py").exists(), name


@pytest.mark.parametrize("name", SPECIMENS)
def test_specimen_quick(name, tmp_path, one_thread):
    bounds = Bounds()
    history, stepper = run_demo(name, tmp_path / name, QUICK[name], bounds)
    assert stepper is not None and len(history["t"]) > 20
    if name == "l_panel":
        check_l_panel(history, stepper, bounds.onset)
    else:
        CHECKS[name](history, stepper)


@pytest.mark.slow
def test_l_panel_full(tmp_path, one_thread):
    # The full demo (PF-CZM, Cornelissen, Rankine drive, eps = 5 mm, P2 u, P1 z, adaptive
    # under 8,000 vertices, staggered, fixed steps of 2.5e-4 mm to u = 0.4 mm). Winkler's
    # experiment peaks at 6.7-7.6 kN for the 100 mm panel (series A 7.22 kN): measured 0.07305
    # kN/mm (7.305 kN) at u = 0.1588 mm (docs/validation.md, "The time step"; the staggered
    # pass's limit for small steps 7.25-7.29 kN), 613 s CPU at a load of 1-2 (session 25).
    bounds = Bounds()
    history, stepper = run_demo("l_panel", tmp_path / "lp", ["output.vtk_every=0"], bounds)
    check_l_panel(history, stepper, bounds.onset)
    u, force = history["uy_load"], history["Fy_load"]
    peak = int(np.argmax(force))
    assert 0.067 <= force[peak] <= 0.076, force[peak]  # inside Winkler's band
    assert 0.15 < u[peak] < 0.17, u[peak]
    # The crack rises from the corner and then runs at y ~ 265 mm: measured tip y 249.3..265.5
    # mm, tip at x = 92.6 mm by u = 0.4 mm, the force there 26 % of the peak.
    grown = np.isfinite(history["tip_x"])
    assert np.nanmin(history["tip_x"]) < 110 and np.all(history["tip_y"][grown] < 268), \
        (np.nanmin(history["tip_x"]), np.nanmax(history["tip_y"]))


@pytest.mark.slow
def test_three_point_bending_full(tmp_path, one_thread):
    # The full demo (epsilon = 0.03 mm, P2, adaptive under 8,000 vertices). The published
    # number of this specimen is LEFM's: a sharp notch of a/W = 0.2 in a beam of S/W = 4 starts
    # to grow at P_c = 0.0322 kN/mm (Srawley's K_I, 0.5 %). The tolerance is the SENT test's
    # (15 % about the band's Griffith load): AT2 damages the ligament before the peak and the
    # band's toughness is gamma (1 + h/(2 eps)). The crack runs up the symmetry line.
    # Measured (hybrid, staggered, fixed steps of 2.5e-5 mm, session 26): peak 0.03245 kN/mm,
    # 2,400 steps, 864 s CPU (871 s wall, another run beside it for 9 minutes). With the
    # paper's single pass in adaptive steps (session 14): 0.0341 kN/mm, 207 s CPU.
    history, stepper = run_demo("three_point_bending", tmp_path / "tpb", ["output.vtk_every=0"])
    check_three_point_bending(history, stepper)


@pytest.mark.slow
def test_compact_tension_full(tmp_path, one_thread):
    # The full demo (epsilon = 0.5 mm, P2, adaptive under 8,000 vertices). The published
    # number of this specimen is LEFM's: ASTM E399's K_I gives the sharp crack of a/W = 0.5
    # the Griffith load P_c = 2.694 kN/mm; the tolerance is the SENT test's (15 % about the
    # band's Griffith load, with this specimen's f of the contact arcs). The crack runs along
    # y = 0. Measured (hybrid, uniform G_c, staggered, fixed steps of 2.5e-4 mm, session 26):
    # peak 2.715 kN/mm at t = 0.2595 mm, 1,400 steps, 439 s CPU (443 s wall beside one other
    # job). With the paper's single pass in adaptive steps (session 14): 2.930 kN/mm, 56 s CPU.
    history, stepper = run_demo("compact_tension", tmp_path / "ct", ["output.vtk_every=0"])
    check_compact_tension(history, stepper)


@pytest.mark.slow
def test_three_hole_beam_full(tmp_path, one_thread):
    # The full demo (epsilon = 0.1 mm, P2, adaptive under 8,000 vertices). The published
    # fact of this specimen is qualitative: which hole the crack from the notch runs into
    # (Ambati et al. 2015: the middle one for their case). Criterion (three_hole_beam.
    # hole_reached): the first hole whose edge a crack tip comes within 2 epsilon of.
    # Measured (hybrid formulation with Miehe's split, no toughened zone beyond the pads;
    # staggered, fixed steps of 2.5e-4 mm, session 27): the crack leaves the notch at
    # t = 0.133 mm, curves up and towards the load (tip (4.14, 1.43) at the peak, 0.4857 kN/mm
    # at t = 0.141), rises over the lower hole's top left ((5.14, 3.08) at t = 0.148) and
    # turns down into it: a tip on its edge ((5.89, 2.51)) at t = 0.14825; 800 steps, 436 s
    # CPU on one core beside one other job. (The paper's single pass in adaptive steps,
    # session 14: the same hole at t = 0.1745, peak 0.543 kN/mm, 273 steps.) The lower hole,
    # not the published middle one, is asserted as measured; docs/validation.md lists what
    # was tried.
    history, stepper = run_demo("three_hole_beam", tmp_path / "thb", ["output.vtk_every=0"])
    demo = load_demo("three_hole_beam")
    eps = stepper.scene.phase_field.epsilon
    tips = demo.tip_track(history)
    assert len(tips) and np.linalg.norm(tips[0] - demo.NOTCH_TIP) < 2 * eps, tips[:3]
    hole, reached = demo.hole_reached(history, eps)
    assert reached and hole == "lower", (hole, reached)
    # On its way the crack stays between the notch and the holes' column (4 <= x <= 6).
    before = tips[: np.flatnonzero(np.linalg.norm(tips - demo.HOLES[hole], axis=1)
                                   < demo.RADIUS + 2 * eps)[0] + 1]
    assert np.all((before[:, 0] > demo.NOTCH_TIP[0] - eps) & (before[:, 0] < 6.0 + eps)), before
