"""The ``ogcp`` command line: thin argument parsing over the Python API.

Every invalid input ends in one line on stderr (``ogcp: error: ...``) and exit status 2.
Each command module registers its sub-parser and handler. Building the parser imports light
modules only (defaults, option declarations, names), so ``ogcp --help`` answers at once; the
handlers import their heavy dependencies (numpy, trimesh, the numba kernels, MuJoCo, matplotlib),
so ``ogcp plan`` never pays for MuJoCo or matplotlib. ``tests/benchmarks/cli/test_startup.py``
keeps it so; ``benchmarks/perf/cli_startup.py`` times it.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from ogcp import __version__
from ogcp.benchmarks.cli import assets, export, plan, plot, report, simulate, suite
from ogcp.planner.infra.errors import OgcpError

#: The command modules, in the order ``ogcp --help`` lists their commands.
COMMAND_MODULES = (plan, simulate, assets, suite, plot, report, export)


class _Parser(argparse.ArgumentParser):
    """argparse with ogcp's one-line errors: ``ogcp: error: argument --mu: ...; see ogcp plan --help``.

    The sub-command parsers are of the same class (argparse makes them so), so every usage
    error is one line like the errors of the handlers, with where to read the usage instead of it.
    """

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"ogcp: error: {message}; see {self.prog} --help\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``ogcp`` command."""
    parser = _Parser(prog="ogcp", description="Optimal grasp contact planning and benchmarking.")
    parser.add_argument("--version", action="version", version=f"ogcp {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMAND_MODULES:
        module.register(commands)
    return parser


#: Set (to anything) to let an unexpected exception print its traceback instead of one line.
TRACEBACK_VARIABLE = "OGCP_TRACEBACK"


def _one_line_warning(message: Warning | str, category: type[Warning], *_: object, **__: object) -> str:
    # A warning is a notice to the user (a cache entry rebuilt, a mesh not watertight): one line,
    # like errors, not Python's file:line and source line.
    first = (str(message).strip().splitlines() or [""])[0]
    return f"ogcp: warning: {first}\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``ogcp`` console script."""
    warnings.formatwarning = _one_line_warning
    args = build_parser().parse_args(argv)
    try:
        if os.environ.get("MUJOCO_GL"):  # else MuJoCo is not imported here: `ogcp plan` never pays for it
            from ogcp.sim_eval.gl_backend import check_mujoco_gl

            check_mujoco_gl()
        return int(args.handler(args))
    except OgcpError as exc:
        print(f"ogcp: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ogcp: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug in ogcp: one line still, and the way to see where
        if os.environ.get(TRACEBACK_VARIABLE):
            raise
        said = (str(exc).strip().splitlines() or [""])[0]
        print(
            f"ogcp: error: internal error ({type(exc).__name__}: {said}), a bug in ogcp: please report it with the "
            f"command; {TRACEBACK_VARIABLE}=1 shows where",
            file=sys.stderr,
        )
        return 2


if __name__ == "__main__":
    sys.exit(main())
