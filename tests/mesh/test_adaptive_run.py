"""A full adaptive run of the slit demo (quick sizes): cap, hmin, bounds, transfers."""

import numpy as np
import pytest

from ngfrac.mesh.adapter import AdaptivitySizes
from ngfrac.solve.stepper import PhaseFieldStepper
from ngfrac.fem.threads import single_thread
from ngfrac.mesh.transfer import evaluate, locate

from ngfrac.testing.scenes import demo_data, scene_from

CAP = 2500
HMIN = 2e-3


class TransferWatch:
    """Wraps ``stepper.adapt`` to compare z before and after each mesh change, and keeps the
    record of the state just before each change (``before``)."""

    def __init__(self, stepper):
        self.stepper = stepper
        self.original = stepper.adapt
        self.worst_decrease = 0.0
        self.before = []
        stepper.adapt = self

    def __call__(self, tip=None, reason="requested"):
        self.before.append(self.stepper.record())
        z_old = self.stepper.z
        record = self.original(tip, reason)
        new_nodes = self.stepper.nodes
        before = evaluate(z_old, locate(z_old.space.mesh, new_nodes.points))
        after = new_nodes.values(self.stepper.z)
        self.worst_decrease = max(self.worst_decrease,
                                  float(np.max(np.clip(before, 0, 1) - after)))
        return record


@pytest.fixture(scope="module")
def adaptive_run():
    """One adaptive run, on ONE NGSolve thread so that its trajectory is reproducible.

    With two threads the parallel assembly sums in varying order, and the adaptive run
    amplifies that round-off: when and where the mesh changes moves with it. Before the tip
    stopped being chased at the boundary (MeshAdapter.tip_stopped), one of three two-thread
    runs of this scene had a transfer that lowered the crack length by 0.63 %, after the crack
    had cut the plate; since then four two-thread runs had 11-13 changes and at most 0.20 %
    (issue #3's note has the command).
    """
    with single_thread():
        return _adaptive_run()


def _adaptive_run():
    # Steps of 2e-3 (76 steps, 10 mesh changes; 14 s of CPU against 19 s for 151 steps of
    # 1e-3 with 12 changes, at load ~5): every check below passed with both.
    scene = scene_from(demo_data(), "phase_field.epsilon=0.04", "time.dt=2e-3",
                       f"adaptivity.max_vertices={CAP}", f"adaptivity.hmin={HMIN}")
    stepper = PhaseFieldStepper(scene)
    watch = TransferWatch(stepper)
    records, z_min, z_max, decrease = [stepper.record()], 1.0, 0.0, 0.0
    previous = stepper.z_node_values()
    n_adapt = 0
    for record in stepper.run():
        values = stepper.z_node_values()
        z_min, z_max = min(z_min, values.min()), max(z_max, values.max())
        if record.n_adapt == n_adapt:  # same mesh: compare node by node
            decrease = max(decrease, float(np.max(previous - values)))
        n_adapt = record.n_adapt
        previous = values
        records.append(record)
    return scene, stepper, records, (z_min, z_max, decrease), watch


def test_a_row_with_a_mesh_change_reports_the_step_on_the_mesh_it_was_solved_on(adaptive_run):
    """The energies, crack length and tip of a step that ends with a mesh change are those of
    its solution on the old mesh. On the new mesh u is only interpolated, not in equilibrium:
    its elastic energy was off the curve for that one row (Fig. 2 demo: by up to 0.5 % of the
    largest E_el, docs/benchmarks.md section 12), while the next step's u-solve is back on it."""
    _, _, records, _, watch = adaptive_run
    rows = {r.step: r for r in records}
    assert len(watch.before) >= 5  # the run changes its mesh (10-13 times)
    for before in watch.before:
        row = rows[before.step]
        assert row.n_adapt == before.n_adapt + 1  # nv, ndof, n_adapt: the new mesh
        for name in ("E_el", "E_surf", "crack_length", "tip_x", "tip_y", "path_length"):
            assert getattr(row, name) == pytest.approx(getattr(before, name), rel=1e-12), name


def test_crack_crosses_on_an_adaptive_mesh(adaptive_run):
    scene, stepper, records, _, _ = adaptive_run
    assert max(r.tip_x for r in records) > 0.97
    assert len(stepper.adaptations) >= 5


def test_vertex_cap_is_never_exceeded(adaptive_run):
    _, stepper, records, _, _ = adaptive_run
    assert max(r.nv for r in records) <= CAP
    assert max(a.nv_after for a in stepper.adaptations) <= CAP


def test_hmin_is_respected(adaptive_run):
    # Netgen is asked for nothing below hmin; its realized longest edges stay above 0.75 hmin
    # (measured; the advancing front makes some elements smaller than the request).
    _, _, records, _, _ = adaptive_run
    smallest = min(r.hmin for r in records)
    assert smallest >= 0.75 * HMIN, smallest


def test_z_bounds_and_irreversibility(adaptive_run):
    _, _, _, (z_min, z_max, decrease), watch = adaptive_run
    assert z_min >= 0.0 and z_max <= 1.0
    assert decrease <= 0.0
    assert watch.worst_decrease <= 1e-12  # transfers never lower z at the new nodes


def test_transfers_keep_the_crack_length(adaptive_run):
    _, stepper, _, _, _ = adaptive_run
    drops = [1 - a.crack_length_after / a.crack_length_before for a in stepper.adaptations]
    assert max(drops) < 0.005, max(drops)


@pytest.mark.xfail(strict=False, reason=(
    "known defect (issue #13), pinned deterministically by tests/mesh/test_meshing.py::"
    "test_cap_keeps_the_core_finer_than_the_far_field_when_the_finest_sizes_overflow; whether "
    "this run's last mesh meets it depends on its trajectory (with the forms' quadrature of "
    "exact degree it did not, on this machine): under this binding cap (2,500) the last mesh after the crack cut "
    "the plate leaves its core near the far edge on elements of ~0.06-0.09: the finest sizes "
    "(hmin-floored estimator spots, h_lo) alone exceed the cap, so meshing.cap_vertices goes "
    "to stage 2, which scales the {h_lo, hmax} field of stage 1 at lambda = 8 and sends the "
    "core at h_crack = 1.5 h_lo to hmax. Scaling the requested field instead fixes this run "
    "(smallest element there 0.0103) but breaks the learned vertex density across stages "
    "(test_learned_density_makes_one_mesh_per_change: 947 of a 1,500 cap)"))
def test_mesh_follows_the_tip(adaptive_run):
    scene, stepper, records, _, _ = adaptive_run
    sizes = AdaptivitySizes.of(scene)
    grown = [a for a in stepper.adaptations if a.crack_length_before > records[0].crack_length + 0.2]
    assert grown, "no adaptation after the crack grew"
    # after the crack crossed, the fine elements lie along y = 0.5 all the way to the right
    from ngfrac.fem.elements import ElementGeometry
    geom = ElementGeometry.of(stepper.mesh)
    near_right_end = (geom.centroids[:, 0] > 0.9) & (np.abs(geom.centroids[:, 1] - 0.5) < 0.02)
    assert geom.diameters[near_right_end].min() < 2 * sizes.h_band


def test_tip_stops_at_the_far_edge_and_every_change_says_why(adaptive_run):
    scene, stepper, _, _, _ = adaptive_run
    sizes = AdaptivitySizes.of(scene)
    assert stepper.adapter.tip_stopped
    assert stepper.adapter.last_tip[0] >= 1.0 - sizes.h_band
    reasons = [a.reason for a in stepper.adaptations]
    assert all(reasons), reasons
    assert any(r == "tip moved" for r in reasons)
