"""The ``ogcp export`` command (registered by :mod:`ogcp.benchmarks.cli.app`).

Exit status: 0 when the tables are written, 2 on invalid input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def register(commands: Any) -> None:
    """Add the ``export`` sub-command to the ``ogcp`` parser.

    Args:
        commands: The sub-parsers object of the ``ogcp`` parser.
    """
    export = commands.add_parser(
        "export", help="write tidy tables (grasps, directions) and their column dictionary from a suite run"
    )
    export.add_argument("run", type=Path, metavar="RUN", help="results folder of ogcp suite")
    # The choices are spelled out here rather than imported: ogcp.benchmarks.export loads the record readers.
    export.add_argument(
        "--format", default="csv", choices=("csv", "parquet"), help="table format (parquet needs pyarrow; default csv)"
    )
    export.add_argument("--out", type=Path, default=None, metavar="DIR", help="where the tables go (default: RUN)")
    export.set_defaults(handler=run_export)


def run_export(args: argparse.Namespace) -> int:
    """Handler of ``ogcp export``."""
    from ogcp.benchmarks.export import export_run  # lazy: ogcp --help never loads the record readers
    from ogcp.benchmarks.suite.store import ResultStore

    for path in export_run(args.run, args.out, args.format):
        print(path)
    for problem in ResultStore(args.run).read().problems:  # what the tables leave out, and why
        print(f"ogcp: note: {problem}", file=sys.stderr)
    return 0
