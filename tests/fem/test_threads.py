"""NGFRAC_THREADS caps NGSolve's threads when a run starts (for several runs side by side);
importing ngfrac changes nothing in the session; the thread chooser keeps the faster of
threads and one thread per kind of kernel."""
from __future__ import annotations

import contextlib
import os
import subprocess
import sys

import pytest

import ngfrac
from ngfrac.fem.threads import ThreadChooser

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


class FakeKernels:
    """A clock and a threaded context for ThreadChooser: a kernel takes ``threaded`` or
    ``single`` seconds of the fake clock, as the chooser's choice."""

    def __init__(self, threaded: float, single: float) -> None:
        self.now, self.cost = 0.0, {True: threaded, False: single}
        self.inside, self.threaded_calls = False, 0

    def clock(self) -> float:
        return self.now

    @contextlib.contextmanager
    def enter(self):
        self.inside = True
        self.threaded_calls += 1
        try:
            yield
        finally:
            self.inside = False

    def run(self, chooser: ThreadChooser, calls: int, key: str = "u") -> None:
        for _ in range(calls):
            with chooser(key):
                self.now += self.cost[self.inside]


@pytest.mark.parametrize("threaded, single, most", [(0.05, 0.0002, False), (0.010, 0.025, True)],
                         ids=["busy machine", "quiet machine, large mesh"])
def test_the_chooser_keeps_the_faster_mode_and_rarely_tries_the_other(threaded, single, most):
    kernels = FakeKernels(threaded, single)
    chooser = ThreadChooser(enter=kernels.enter, clock=kernels.clock, threads=lambda: 2)
    kernels.run(chooser, 1000)
    assert chooser.uses_threads("u") is most
    others = kernels.threaded_calls if not most else 1000 - kernels.threaded_calls
    # a warm-up and a timing on one thread; then the busy machine's 0.2 ms kernel is too
    # short for threads (never tried), the quiet machine's 25 ms one is timed threaded once,
    # and the slower mode is tried again after 8, 16, ..., 512 calls: 8 trials
    assert others <= (0 if threaded > single else 10), others


def test_the_chooser_follows_a_machine_that_gets_busy():
    kernels = FakeKernels(threaded=0.010, single=0.025)
    chooser = ThreadChooser(enter=kernels.enter, clock=kernels.clock, threads=lambda: 2)
    kernels.run(chooser, 300)
    assert chooser.uses_threads("u") is True
    kernels.cost[True] = 0.5  # a busy neighbour: the threaded kernel collapses
    before = kernels.threaded_calls
    kernels.run(chooser, 300)
    assert chooser.uses_threads("u") is False
    # the running mode's average rises above the other's at once: a call or two
    assert kernels.threaded_calls - before <= 2


def test_one_configured_thread_enters_nothing():
    kernels = FakeKernels(threaded=0.01, single=0.02)
    chooser = ThreadChooser(enter=kernels.enter, clock=kernels.clock, threads=lambda: 1)
    kernels.run(chooser, 50)
    assert kernels.threaded_calls == 0 and chooser.uses_threads("u") is None


def test_the_chooser_compares_time_per_unit_of_work_and_decides_for_a_caller():
    """Netgen's meshing (MESHING_CHOOSER): no warm-up call, the caller reads the decision and
    reports the vertices made. Threaded meshes that take twice as long as the one-thread ones
    but have 4x the vertices are the faster mode per vertex."""
    now, calls = [0.0], []
    chooser = ThreadChooser(enter=contextlib.nullcontext, clock=lambda: now[0],
                            threads=lambda: 2, warm_up=False)
    for _ in range(20):
        with chooser("mesh") as call:
            calls.append(call.threaded)
            work = 4000 if call.threaded else 1000
            now[0] += 3e-4 * work / (2 if call.threaded else 1)  # 0.6 s against 0.3 s
            call.work = work
    assert calls[:2] == [False, True]  # the first call is timed: one thread, then threads
    assert chooser.uses_threads("mesh") is True and sum(calls) >= 18


def test_a_kernel_too_short_for_threads_is_tried_on_them_once_it_grows():
    """Below ThreadChooser.SMALL on one thread a kernel never enters the TaskManager; a mesh
    that grows it past that gets it timed on threads (and kept there if faster)."""
    kernels = FakeKernels(threaded=0.0002, single=0.0003)
    chooser = ThreadChooser(enter=kernels.enter, clock=kernels.clock, threads=lambda: 2)
    kernels.run(chooser, 100)
    assert kernels.threaded_calls == 0 and chooser.uses_threads("u") is False
    kernels.cost = {True: 0.004, False: 0.010}  # the mesh was refined
    kernels.run(chooser, 100)
    assert chooser.uses_threads("u") is True and kernels.threaded_calls >= 95


def test_assembly_gives_the_same_bits_on_two_threads_as_on_one():
    """What lets the chooser switch freely: a P2 elasticity matrix assembled in a two-thread
    TaskManager equals the one-thread matrix bit for bit (1,353 vertices, where threads pay)."""
    import ngsolve as ngs
    import numpy as np
    from netgen.geom2d import unit_square

    from ngfrac.fem.threads import configured_threads

    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.03))
    fes = ngs.VectorH1(mesh, order=2)
    u, v = fes.TnT()
    strain = lambda w: 0.5 * (ngs.Grad(w) + ngs.Grad(w).trans)  # noqa: E731
    gauss = ngs.exp(-((ngs.x - 0.5) ** 2 + (ngs.y - 0.5) ** 2) / 0.01)  # varies per element
    form = (1 + gauss) * ngs.InnerProduct(strain(u), strain(v)) * ngs.dx
    values = []
    try:
        for n in (1, 2):
            ngs.SetNumThreads(n)
            a = ngs.BilinearForm(form)
            with ngs.TaskManager() if n > 1 else contextlib.nullcontext():
                a.Assemble()
            values.append(np.array(a.mat.AsVector().FV()))
    finally:
        ngs.SetNumThreads(configured_threads())
    assert mesh.nv > 1000 and np.array_equal(values[0], values[1])
