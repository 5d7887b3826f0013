"""The serial/MPI seam: the protocol, Serial's answers, and that both communicators answer
every question of it (the MPI one is checked by its class: making one needs mpirun)."""
from __future__ import annotations

import inspect

import pytest

from ngfrac.parallel.communicator import MPICommunicator
from ngfrac.solve.communicator import SERIAL, Communicator, Serial


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
