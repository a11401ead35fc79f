"""The command line run in the test's own process (``jaxrod.cli.main``), what it prints
captured, answered in the shape of ``subprocess.run``'s: the tests call the command line
in-process, so that it shares the programs their worker has compiled, except where the
process itself is the point (Ctrl-C, a resumed or a second process, the caches on disk)."""

from __future__ import annotations

import contextlib
import io
import subprocess

from jaxrod.cli import main


def run_cli(*argv) -> subprocess.CompletedProcess:
    """``jaxrod ARGV...``: its exit status, standard output and standard error."""
    argv = [str(a) for a in argv]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as stop:  # argparse: a usage error (2) or --help (0)
            code = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
    return subprocess.CompletedProcess(["jaxrod", *argv], code, out.getvalue(),
                                       err.getvalue())
