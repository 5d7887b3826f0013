"""A solver failure in the middle of a run raises a SolverError that says what to change, and
the last checkpoint stays valid: it loads, and a restart from it finishes the run exactly."""

import pytest

from ngfrac.runner import CHECKPOINT

from ngfrac.testing import stress_cases as sc

pytestmark = [pytest.mark.stress, pytest.mark.usefixtures("one_thread")]


@pytest.fixture(scope="module", params=["u", "z"])
def failure(request, tmp_path_factory):
    """run_scene with a checkpoint every 2 steps and NaN in the u- or z-solve of step 5,
    then a restart from the checkpoint (see stress_cases.run_failure)."""
    patches = pytest.MonkeyPatch()

    def patch(cls, name, function):
        patches.setattr(cls, name, function)
        return patches.undo

    folder = tmp_path_factory.mktemp(f"failure_{request.param}") / "run"
    try:
        result = sc.run_failure(request.param, folder, patch)
    finally:
        patches.undo()
    return request.param, folder, result


def test_failure_keeps_the_last_checkpoint(failure):
    sub_step, folder, result = failure
    found = sc.failure_problems(result, sub_step)
    assert not found, f"{result.error!r}\n" + "\n".join(found)
    assert (folder / CHECKPOINT).exists() and not (folder / "checkpoint.tmp").exists()
    assert result.restarted_step == sc.failure_scene().time.n_steps


def test_error_names_the_failing_step(failure):
    _, _, result = failure
    found = sc.failing_step_problems(result)
    assert not found, "\n".join(found)
