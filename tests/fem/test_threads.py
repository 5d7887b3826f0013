"""NGFRAC_THREADS caps NGSolve's threads when a run starts (for several runs side by side);
importing ngfrac changes nothing in the session."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

import ngfrac

THREADS = "with ngs.TaskManager():\n    print(ngs.GetNumThreads())\n"


def probe(code: str, value: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, NGFRAC_THREADS=value)
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=120)


def test_set_threads_reads_the_environment():
    result = probe("import ngfrac, ngsolve as ngs\nprint(ngfrac.set_threads())\n" + THREADS, "1")
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["1", "1"]


def test_importing_ngfrac_changes_nothing():
    """Neither the thread count nor matplotlib (not imported, backend not chosen)."""
    code = ("import sys, ngsolve as ngs\n" + THREADS.replace("print(", "before = (") +
            "import ngfrac, ngfrac.runner, ngfrac.cli, ngfrac.io.writers, ngfrac.io.plotting\n" +
            THREADS.replace("print(", "after = (") +
            "assert after == before, (before, after)\n"
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'\n")
    result = probe(code, "1")
    assert result.returncode == 0, result.stderr


def test_a_bad_value_is_named_and_ignored():
    result = probe("import ngfrac\nprint(ngfrac.set_threads())\n", "two")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "None"
    assert "NGFRAC_THREADS = 'two' ignored" in result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize("n", [0, -1, 1.5, True, "2"])
def test_an_explicit_count_must_be_a_positive_integer(n):
    with pytest.raises(ValueError, match="not a positive integer"):
        ngfrac.set_threads(n)
