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
"""
from __future__ import annotations

import math
import threading
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field
from typing import Any, Iterator

import ngsolve as ngs

from .ranks import sum_over_ranks

__all__ = ["ThreadPolicy", "integrate", "single_thread", "threaded"]


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
    with ngs.TaskManager():  # outside one, GetNumThreads() says 1 whatever is configured
        threads = ngs.GetNumThreads()
    ngs.SetNumThreads(1)
    try:
        yield
    finally:
        ngs.SetNumThreads(threads)


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

    def assembly(self, preconditioner: object = None) -> AbstractContextManager:
        """Threads for an assembly, unless it also sets up a registered preconditioner
        (BDDC factorizes inside the assembly) or runs beside another (:meth:`concurrently`)."""
        if self._section.is_set():
            return nullcontext()
        return threaded() if preconditioner is None else self.solves()


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
    with threaded():
        for component in components:
            per_element = ngs.Integrate(component, mesh, vb, **kwargs)
            values.append(math.fsum(per_element.NumPy()))
    values = sum_over_ranks(mesh, values)  # a distributed mesh: each rank's elements
    return values[0] if cf.dim == 1 else values
