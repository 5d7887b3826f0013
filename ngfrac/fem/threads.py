"""Threads that do not change results: NGSolve's TaskManager only where its result is bitwise
independent of the schedule.

With two or more NGSolve threads, some kernels sum in an order that depends on which thread
finishes first (measured with ngsolve 6.2.2608; docs/theory.md, "Reproducibility"):

- the ``sparsecholesky`` factorization, whenever NGSolve's thread count is above one, even
  outside a TaskManager; its triangular solves inside a TaskManager (even repeated solves
  with one factor differ in the last bits); BDDC, which factorizes inside the assembly;
- ``Integrate`` (a threaded reduction): differs in the last bit.

Assembly (``BilinearForm.Assemble``, ``LinearForm.Assemble``), ``GridFunction.Set``,
matrix-vector products and element-wise integrals are bitwise reproducible with threads. So
ngfrac enters the TaskManager only around those (:func:`threaded`), factorizes and solves with
one thread (:func:`single_thread`), and sums integrals element by element (:func:`integrate`). A run
of a scene then gives the same bits every time with a given thread count.
``discretization.threaded_solves = true`` runs a whole step inside the TaskManager instead:
faster on many cores, not reproducible bitwise.

NGSolve's idle workers spin: with another busy process on the machine a threaded kernel can
be far slower than on one thread (docs/benchmarks.md, "Threads on a busy machine"). So the
assemblies of a step go through a :class:`ThreadChooser`: per kind of
kernel it uses the threads or one thread, whichever took less wall time lately, and tries the
other again after 8, 16, ..., 512 calls. Assembly gives the same bits with any thread count,
so the choice changes timings only.

Netgen meshes volumes in a TaskManager of its own, on 4 threads unless its meshing
parameters say otherwise, whatever NGSolve's thread count: :func:`meshing_threads` gives it the
configured count, and :data:`MESHING_CHOOSER` picks threads or one thread per vertex made, as
for assembly (the mesh is the same either way).
"""
from __future__ import annotations

import math
import threading
import time
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

import ngsolve as ngs

from .ranks import sum_over_ranks

__all__ = ["ChooserCall", "MESHING_CHOOSER", "ThreadChooser", "ThreadPolicy",
           "configured_threads", "integrate", "meshing_threads", "netgen_meshing", "note_threads",
           "single_thread", "threaded"]

_configured: int | None = None
"""NGSolve's thread count as configured (:func:`configured_threads`)."""


def configured_threads() -> int:
    """NGSolve's configured thread count.

    Outside a TaskManager ``GetNumThreads()`` says 1 whatever is configured, and entering one
    starts its workers (costly on a busy machine): it is entered once per process to read the
    count, and :func:`note_threads` (called by :func:`ngfrac.set_threads`) keeps it current.
    A script that changes the count itself calls :func:`ngfrac.set_threads`, not
    ``ngsolve.SetNumThreads``.
    """
    global _configured
    if _configured is None:
        with ngs.TaskManager():
            _configured = int(ngs.GetNumThreads())
    return _configured


def note_threads(n: int) -> None:
    """Record that NGSolve's thread count was set to ``n``."""
    global _configured
    _configured = int(n)


def meshing_threads(use: bool = True) -> dict[str, Any]:
    """Netgen meshing parameters that mesh on NGSolve's configured thread count.

    Netgen meshes volumes (3D Delaunay, volume optimization) in a TaskManager of its own with
    ``MeshingParameters.nthreads`` threads, 4 by default, whatever ``SetNumThreads`` or
    NGFRAC_THREADS say; these keywords (for ``MeshingParameters`` or ``GenerateMesh``) make
    it use the configured count, or one thread when ``use`` is false or one is configured.
    The mesh is the same with any count (tests/mesh/test_3d_adaptive.py).
    """
    n = configured_threads() if use else 1
    return {"parallel_meshing": n > 1, "nthreads": n}


@contextmanager
def threaded() -> Iterator[None]:
    """NGSolve's threads for the enclosed kernels (a no-op inside an active TaskManager).

    Use it only around kernels whose result does not depend on the schedule: assembly,
    ``GridFunction.Set``, matrix-vector products, element-wise integrals.
    """
    with ngs.TaskManager():
        yield


@contextmanager
def single_thread() -> Iterator[None]:
    """One NGSolve thread for the enclosed code (call it outside any TaskManager).

    Sparse factorizations and solves inside it are bitwise reproducible.
    """
    threads = configured_threads()
    ngs.SetNumThreads(1)
    try:
        yield
    finally:
        ngs.SetNumThreads(threads)


@dataclass
class _Timings:
    """Recent wall times of one kind of kernel with threads and with one thread."""

    threaded: float = math.nan
    single: float = math.nan
    single_seconds: float = math.nan
    """The last one-thread call's wall time, not divided by its work."""
    calls: int = 0
    interval: int = 8
    next_trial: int = 0


@dataclass
class ChooserCall:
    """One call of a :class:`ThreadChooser`: its decision, and the work done that its wall
    time is divided by before calls are compared (e.g. the vertices Netgen made)."""

    threaded: bool
    """Whether this call runs with threads."""
    work: float = 1.0


class ThreadChooser:
    """Threads where they pay: per kind of kernel (a key), NGSolve's threads or one thread,
    whichever took less wall time lately.

    The first call of a key runs on one thread and is not timed (a first assembly also builds
    the matrix graph; ``warm_up=False`` leaves that out); the next times one thread. A kernel
    that took less than ``small`` seconds there stays on one thread (threads cannot pay for
    their start, and beside a busy process one threaded call can cost a time slice of the
    scheduler). Otherwise the next call times the threads; then the faster mode runs, and the
    other is tried again after ``interval`` calls, the interval doubling (8 to 512) while the
    choice holds and starting again at 8 when it flips. A wall time is an exponential average
    (half weight to the newest), per unit of the work the caller reports
    (:class:`ChooserCall`; one unit unless told). With one configured thread nothing is
    entered.

    Parameters
    ----------
    enter : callable, optional
        The context of a threaded kernel (:func:`threaded`); replaceable for tests, or
        :func:`contextlib.nullcontext` for a kernel that takes the decision itself
        (:attr:`ChooserCall.threaded`, e.g. Netgen's meshing threads).
    clock : callable, optional
        Seconds (:func:`time.perf_counter`).
    threads : callable, optional
        The configured thread count (:func:`configured_threads`).
    warm_up : bool
        Whether a key's first call runs untimed.
    small : float
        Seconds on one thread below which a kernel is not tried on threads
        (:attr:`SMALL`).
    """

    FIRST_INTERVAL = 8
    MAX_INTERVAL = 512
    SMALL = 5e-4
    """Between a 2D P2 vector assembly of 136 vertices (0.2 ms on one thread: two threads
    gained nothing on a quiet machine) and one of 511 (0.9 ms: 0.65-0.94 of the time on
    two); ``benchmarks/assembly_threads.py``, docs/benchmarks.md section 14."""

    def __init__(self, enter: Callable[[], AbstractContextManager] | None = None,
                 clock: Callable[[], float] = time.perf_counter,
                 threads: Callable[[], int] | None = None, warm_up: bool = True,
                 small: float = SMALL) -> None:
        self.enter = threaded if enter is None else enter
        self.warm_up = warm_up
        self.small = small
        self.clock = clock
        self.threads = configured_threads if threads is None else threads
        self.timings: dict[str, _Timings] = {}
        self._lock = threading.Lock()

    def _plan(self, t: _Timings) -> tuple[bool, str]:
        """Whether the next call runs threaded, and why: "warm-up" (not timed), "first" (a
        mode's first timing), "small" (too short for threads), "trial" (the slower mode tried
        again) or "best"."""
        if t.calls == 1 and self.warm_up:
            return False, "warm-up"
        if math.isnan(t.single):
            return False, "first"
        if t.single_seconds < self.small:
            return False, "small"
        if math.isnan(t.threaded):
            return True, "first"
        best = t.threaded <= t.single
        if t.calls >= t.next_trial:
            return not best, "trial"
        return best, "best"

    @contextmanager
    def __call__(self, key: str) -> Iterator[ChooserCall]:
        """The context of one kernel of kind ``key``; it gives the call's
        :class:`ChooserCall`."""
        call = ChooserCall(threaded=False)
        if self.threads() <= 1:
            yield call
            return
        with self._lock:
            t = self.timings.setdefault(key, _Timings())
            t.calls += 1
            use, why = self._plan(t)
            best_before = t.threaded <= t.single
        call.threaded = use
        start = self.clock()
        with self.enter() if use else nullcontext():
            yield call
        seconds = self.clock() - start
        elapsed = seconds / max(call.work, 1e-300)
        if why == "warm-up":
            return
        with self._lock:
            if not use:
                t.single_seconds = seconds
            old = t.threaded if use else t.single
            new = elapsed if math.isnan(old) else 0.5 * (old + elapsed)
            if use:
                t.threaded = new
            else:
                t.single = new
            if why == "trial":
                flipped = (t.threaded <= t.single) != best_before
                t.interval = self.FIRST_INTERVAL if flipped else min(2 * t.interval,
                                                                     self.MAX_INTERVAL)
            if why == "trial" or (why == "first" and not math.isnan(t.single + t.threaded)):
                t.next_trial = t.calls + t.interval

    def uses_threads(self, key: str) -> bool | None:
        """Whether the kernel ``key`` runs threaded now (None before it was timed both ways,
        False while it is too short for threads)."""
        t = self.timings.get(key)
        if t is not None and t.single_seconds < self.small:
            return False
        if t is None or math.isnan(t.single) or math.isnan(t.threaded):
            return None
        return t.threaded <= t.single


@dataclass(frozen=True)
class ThreadPolicy:
    """Where a run uses NGSolve's threads (``discretization.threaded_solves``).

    Reproducible (the default): assembly in the TaskManager, factorizations, solves,
    estimators and remeshing with one thread. Threaded: the whole step in the TaskManager.
    Concurrent: as reproducible, but the u- and the z-sub-step run side by side, each on one
    NGSolve thread (:meth:`concurrently`); the same bits as the default.
    """

    threaded_solves: bool = False
    concurrent: bool = False
    """Run the u- and z-sub-steps at the same time in two Python threads
    (``discretization.concurrent_substeps``), inside :meth:`concurrently`."""
    _section: threading.Event = field(default_factory=threading.Event, compare=False, repr=False)
    chooser: ThreadChooser = field(default_factory=ThreadChooser, compare=False, repr=False)
    """Threads or one thread per kind of assembly (:class:`ThreadChooser`)."""

    @contextmanager
    def concurrently(self) -> Iterator[None]:
        """The context of kernels that run in two Python threads at once: one NGSolve thread
        for the whole of it, and inside it :meth:`solves` and :meth:`assembly` enter nothing
        (two OS threads must not enter the TaskManager, and ``SetNumThreads`` is global).
        NGSolve releases the GIL in assembly and factorization, so the two use two cores."""
        with single_thread():
            self._section.set()
            try:
                yield
            finally:
                self._section.clear()

    def step(self) -> AbstractContextManager:
        """The context of a whole step: the TaskManager when solves are threaded, else none."""
        return threaded() if self.threaded_solves else nullcontext()

    def solves(self) -> AbstractContextManager:
        """The context of factorizations, solves, estimators and remeshing."""
        if self.threaded_solves or self._section.is_set():
            return nullcontext()
        return single_thread()

    def assembly(self, preconditioner: object = None, kind: str = "assembly") -> AbstractContextManager:
        """Threads for an assembly where they pay (:class:`ThreadChooser`, per ``kind``), unless
        it also sets up a registered preconditioner (BDDC factorizes inside the assembly) or
        runs beside another (:meth:`concurrently`). With ``threaded_solves`` the whole step is
        threaded already."""
        if self._section.is_set():
            return nullcontext()
        if preconditioner is not None:
            return self.solves()
        return threaded() if self.threaded_solves else self.chooser(kind)


SHARED_CHOOSER = ThreadChooser()
"""The chooser of kernels outside a stepper's policy (:func:`integrate`, transfers)."""

MESHING_CHOOSER = ThreadChooser(enter=nullcontext, warm_up=False)
"""Netgen's volume meshing on threads or on one (:func:`meshing_threads`), by wall time per
vertex made: beside a busy process two meshing threads took 2.2x the time of one
(docs/benchmarks.md, "Threads on a busy machine")."""


@contextmanager
def netgen_meshing(dim: int) -> Iterator[ChooserCall]:
    """The context of one Netgen meshing of dimension ``dim``: its call's decision
    (``meshing_threads(call.threaded)`` are the keywords to mesh with), and the caller sets
    ``call.work`` to the vertices made. A volume is meshed through :data:`MESHING_CHOOSER`;
    Netgen does not thread 2D meshing, which runs on one thread untimed."""
    if dim != 3:
        yield ChooserCall(threaded=False)
        return
    with MESHING_CHOOSER("netgen 3d") as call:
        yield call


def integrate(cf: Any, mesh: ngs.Mesh, order: int | None = None, vb: Any = ngs.VOL,
              definedon: Any = None) -> float | list[float]:
    """``Integrate(cf, mesh)`` with a result that does not depend on the thread count.

    Each component is integrated element by element (threaded, bitwise reproducible) and the
    element values are summed with :func:`math.fsum` (correctly rounded, order independent);
    on a distributed mesh the ranks' sums are summed the same way
    (:func:`ngfrac.fem.ranks.sum_over_ranks`).

    Parameters
    ----------
    cf : ngsolve.CoefficientFunction
        A scalar or a vector of ``cf.dim`` components.
    mesh : ngsolve.Mesh
    order : int, optional
        Quadrature order (NGSolve's default when None).
    vb : ngsolve.VorB
        ``VOL`` or ``BND``.
    definedon : ngsolve.Region, optional

    Returns
    -------
    float or list of float
        A float for a scalar ``cf``, else one float per component.
    """
    cf = ngs.CoefficientFunction(cf)
    kwargs: dict[str, Any] = {"element_wise": True}
    if order is not None:
        kwargs["order"] = order
    if definedon is not None:
        kwargs["definedon"] = definedon
    components = [cf] if cf.dim == 1 else [cf[i] for i in range(cf.dim)]
    values = []
    with SHARED_CHOOSER("integrate"):
        for component in components:
            per_element = ngs.Integrate(component, mesh, vb, **kwargs)
            values.append(math.fsum(per_element.NumPy()))
    values = sum_over_ranks(mesh, values)  # a distributed mesh: each rank's elements
    return values[0] if cf.dim == 1 else values
