"""``ngfrac`` commands run in the test's own process, reported as a new process reports them
(tests/io/test_cli.py, tests/io/test_output_folder.py): the exit status, stdout, and stderr with
the log records and warnings a new process would print there."""
from __future__ import annotations

import contextlib
import logging
import subprocess
import warnings
from typing import Any, Iterator

from ngfrac import cli


@contextlib.contextmanager
def logging_and_warnings_as_in_a_new_process() -> Iterator[list[warnings.WarningMessage]]:
    """Root logging unconfigured (``cli.main``'s ``basicConfig`` then writes to stderr, where
    pytest's handlers would keep the records) and Python's default warning filters, recorded."""
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    root.handlers.clear()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                             ResourceWarning):
                warnings.simplefilter("ignore", category)
            yield caught
    finally:
        root.handlers[:] = handlers
        root.setLevel(level)


def ngfrac_here(capfd: Any, *args: Any) -> subprocess.CompletedProcess:
    """``ngfrac ARGS`` in this process (:func:`ngfrac.cli.main`), returned as
    ``subprocess.run`` of ``python -m ngfrac ARGS`` returns it: the status main returns (or
    argparse exits with), stdout, and stderr with the log records and the warnings a new
    process would print there. An exception that would be a traceback raises here.
    ``capfd`` is pytest's fixture."""
    capfd.readouterr()
    with logging_and_warnings_as_in_a_new_process() as caught:
        try:
            code = cli.main([str(arg) for arg in args])
        except SystemExit as end:
            code = end.code
    out, err = capfd.readouterr()
    err += "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line)
                   for w in caught)
    return subprocess.CompletedProcess(["ngfrac", *args], code, out, err)
