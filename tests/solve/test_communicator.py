"""The serial/MPI seam: the protocol, Serial's answers, and that both communicators answer
every question of it (the MPI one is checked by its class: making one needs mpirun)."""
from __future__ import annotations

import inspect
from types import SimpleNamespace

import pytest

from ngfrac.parallel.communicator import MPICommunicator
from ngfrac.solve.communicator import SERIAL, Communicator, ParallelError, Serial


def protocol_methods() -> set[str]:
    return {name for name, value in vars(Communicator).items()
            if inspect.isfunction(value) and not name.startswith("_")}


@pytest.mark.parametrize("cls", [Serial, MPICommunicator])
def test_every_question_of_the_protocol_has_an_answer(cls):
    missing = sorted(name for name in protocol_methods() if not callable(getattr(cls, name, None)))
    assert not missing, f"{cls.__name__} lacks {missing}"
    for name in protocol_methods():
        asked = inspect.signature(getattr(Communicator, name)).parameters
        answered = inspect.signature(getattr(cls, name)).parameters
        assert list(asked) == list(answered), (cls.__name__, name, list(asked), list(answered))


def test_serial_does_on_one_process_what_rank_0_does():
    assert SERIAL.on_root(lambda: 42) == 42
    assert SERIAL.read_on_root(lambda: "read") == "read"
    with pytest.raises(KeyError, match="missing"):
        SERIAL.read_on_root(lambda: {}["missing"])  # errors propagate as they are


def test_serial_writers_are_the_default_ones_then_the_given_ones(tmp_path):
    defaults, given = ["history", "vtk"], ["progress"]
    writers = SERIAL.run_writers(lambda: list(defaults), None, tmp_path, None, given, False)
    assert writers == ["history", "vtk", "progress"]


def test_serial_resume_is_the_checkpoints_own():
    class Stored:
        def resume(self, scene):
            return ("stepper of", scene)

    assert SERIAL.resume(Stored(), "scene") == ("stepper of", "scene")


def test_serial_starts_from_anything_and_lets_the_substeps_run_concurrently():
    SERIAL.check_start("a mesh", "a state")  # accepts any given mesh or state
    assert SERIAL.concurrent_substeps(True) and not SERIAL.concurrent_substeps(False)


def test_an_mpi_start_refuses_a_given_mesh_or_a_serial_state_in_one_line():
    class State:
        class mesh:
            class comm:
                size = 1

    job = SimpleNamespace(size=3)  # MPICommunicator's answers read only its size here
    for mesh, state in [("a mesh", None), (None, State())]:
        with pytest.raises(ParallelError, match="a given mesh or serial state is not supported"):
            MPICommunicator.check_start(job, mesh, state)
    MPICommunicator.check_start(job, None, None)
    assert MPICommunicator.concurrent_substeps(job, True) is False


def test_an_mpi_job_refuses_pf_czm_in_one_line_not_with_a_type_error():
    """The MPI check asks the scene's own crack model (PF-CZM needs its parameters: built by
    name it raised TypeError) and refuses its obstacle z-update in one line."""
    from tests.physics.test_pfczm import bar_scene

    job = SimpleNamespace(size=3, is_root=False, _warned_p1=True)
    with pytest.raises(ParallelError, match="only the paper's projection runs distributed"):
        MPICommunicator.check(job, bar_scene(0.1))
