"""Running the ``ogcp`` command line in-process, for the tests: its exit status, stdout and stderr."""

from __future__ import annotations

import contextlib
import io

from ogcp.benchmarks.cli.app import main


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """``ogcp ARGV`` in this process: (exit status, what it printed, what it said on stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()
