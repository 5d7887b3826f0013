"""The ``mpiexec`` that starts an MPI run of ngfrac: the launcher of the MPI that mpi4py loads,
with the flags Open MPI needs to start more processes than cores (and to run as root)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Mapping

__all__ = ["mpiexec_command"]


def mpiexec_command(python: str = sys.executable,
                    env: Mapping[str, str] | None = None) -> list[str] | None:
    """The command that launches ``python`` under MPI, without ``-np``, or None.

    The candidates are the ``mpiexec`` next to ``python`` (an MPI wheel's), then ``mpiexec``
    and ``mpirun`` on the PATH; the first whose ``--version`` names the MPI library that
    mpi4py loads in ``python`` is taken (a launcher of another MPI starts N unconnected serial
    runs). Open MPI gets ``--oversubscribe`` and, as root, ``--allow-run-as-root``; MPICH
    oversubscribes by default. Asks mpi4py in a subprocess: nothing here imports it.

    Parameters
    ----------
    python : str
        The interpreter of the runs.
    env : mapping, optional
        The environment of the probing subprocesses (default: this process's).

    Returns
    -------
    list of str or None
        None when mpi4py is missing in ``python`` or no launcher of its MPI is found.
    """
    probe = subprocess.run([python, "-c", "from mpi4py import MPI; "
                            "print(MPI.Get_library_version())"], capture_output=True, text=True,
                           timeout=60, env=None if env is None else dict(env))
    if probe.returncode != 0:
        return None
    library = probe.stdout
    candidates = [str(Path(python).parent / "mpiexec"), shutil.which("mpiexec"),
                  shutil.which("mpirun")]
    for candidate in candidates:
        if not candidate or not os.access(candidate, os.X_OK):
            continue
        version = subprocess.run([candidate, "--version"], capture_output=True, text=True,
                                 timeout=60).stdout
        if "MPICH" in library and "HYDRA" in version.upper():
            return [candidate]
        if "Open MPI" in library and "Open MPI" in version:
            as_root = ["--allow-run-as-root"] if os.geteuid() == 0 else []  # else it refuses
            return [candidate, "--oversubscribe", *as_root]
    return None
