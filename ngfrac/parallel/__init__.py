"""Runs over several processes (MPI): the communicator a run asks for reductions, the mesh
distribution, the solvers that work on distributed matrices and the global crack tip.

Nothing here imports mpi4py until an MPI communicator is asked for (:func:`world` in a job
launched with ``mpirun -np N``, N > 1, or :class:`MPICommunicator`); the serial run uses
:data:`SERIAL`, whose every method is the serial code path.
"""
from .communicator import (SERIAL, Communicator, MPICommunicator, ParallelError, Serial,
                           launched_rank, launched_size, world)
from .launcher import mpiexec_command

__all__ = ["SERIAL", "Communicator", "MPICommunicator", "ParallelError", "Serial",
           "launched_rank", "launched_size", "mpiexec_command", "world"]
