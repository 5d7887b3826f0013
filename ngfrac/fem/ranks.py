"""Sums over the ranks of a distributed mesh (a no-op on one process; mpi4py only through
the mesh's communicator)."""
from __future__ import annotations

import math

import ngsolve as ngs

__all__ = ["sum_over_ranks"]


def sum_over_ranks(mesh: ngs.Mesh, values: list[float]) -> list[float]:
    """The sums over the ranks of ``mesh``'s communicator of per-rank ``values``; the same
    on every rank (each rank's values gathered and summed with :func:`math.fsum` in rank
    order). ``values`` unchanged on one process."""
    comm = mesh.comm
    if comm.size == 1:
        return values
    gathered = comm.mpi4py.allgather(values)
    return [math.fsum(rank_values[i] for rank_values in gathered) for i in range(len(values))]
