"""The stepper from a script: a clear error after the end, a scene that cannot be swapped."""
import dataclasses

import pytest
from ngfrac.testing.scenes import quick_slit

from ngfrac import PhaseFieldStepper


@pytest.fixture(scope="module")
def finished():
    stepper = PhaseFieldStepper(quick_slit("time.t_end=2e-3", "time.dt=1e-3",
                                           "discretization.order=1"))
    records = list(stepper.run())
    return stepper, records


def test_step_after_the_end_says_so(finished):
    stepper, records = finished
    assert len(records) == 2 and stepper.finished
    with pytest.raises(RuntimeError, match="at its end time t = 0.002"):
        stepper.step()


def test_the_scene_of_a_live_stepper_cannot_be_swapped(finished):
    stepper, _ = finished
    longer = dataclasses.replace(stepper.scene, time=dataclasses.replace(stepper.scene.time, t_end=1.0))
    with pytest.raises(AttributeError, match="make a new PhaseFieldStepper"):
        stepper.scene = longer
    assert stepper.scene.time.t_end == pytest.approx(2e-3)


def test_a_script_writes_snapshots_from_its_own_loop(tmp_path):
    """The user guide's example: VTK and results.h5 snapshots without run_scene."""
    from ngfrac.io.output import VTKSeries
    from ngfrac.io.results import ResultsWriter, open_results
    from ngfrac.runner import write_snapshot

    stepper = PhaseFieldStepper(quick_slit("time.t_end=4e-3", "time.dt=1e-3", "discretization.order=1"))
    series = VTKSeries(tmp_path / "vtk", subdivision=0)
    with ResultsWriter(tmp_path / "results.h5", stepper.scene) as results:
        for record in stepper.run():
            results.append(record)
            if record.step % 2 == 0:
                write_snapshot(series, stepper)
                results.write_snapshot(stepper)
    assert sorted(p.name for p in (tmp_path / "vtk").glob("*.vtu")) == ["fields_00000.vtu",
                                                                       "fields_00001.vtu"]
    stored = open_results(tmp_path / "results.h5")
    assert list(stored.snapshot_steps()) == [2, 4]
