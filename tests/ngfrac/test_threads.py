"""NGFRAC_THREADS caps NGSolve's threads (for several runs side by side)."""
from __future__ import annotations

import os
import subprocess
import sys

PROBE = "import ngfrac, ngsolve as ngs\nwith ngs.TaskManager():\n    print(ngs.GetNumThreads())"


def probe(value: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, NGFRAC_THREADS=value)
    return subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                          timeout=120)


def test_threads_from_the_environment():
    result = probe("1")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "1"


def test_a_bad_value_is_named_and_ignored():
    result = probe("two")
    assert result.returncode == 0, result.stderr
    assert "NGFRAC_THREADS = 'two' ignored" in result.stderr
    assert "Traceback" not in result.stderr
