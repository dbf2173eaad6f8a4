"""The ``ogcp plot`` command: paper figures and the time table from a suite run.

``ogcp plot RUN [--out DIR] [--only NAME ...] [--format pdf png] [--dpi 200] [--unit s|min]``
prints every file written (stdout) and one note per skipped cell or figure (stderr).
Exit status 0; 2 with one line ``ogcp: error: ...`` when RUN holds no results.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

# The names only: the figure modules (numpy, the records; matplotlib when drawing) load in the handler.
from ogcp.benchmarks.cli.options import typed, valid
from ogcp.benchmarks.plots.names import NAMES
from ogcp.planner.config.options import Option

#: PNG resolution: 10 dpi is the plots' own floor; 1200 dpi is twice print quality, and a figure
#: at 10^6 dpi asked matplotlib for more memory than any machine has.
DPI = Option("int", 200, "PNG resolution", minimum=10, maximum=1200)


def register(commands: Any) -> None:
    """Add the ``plot`` sub-command to the ``ogcp`` parser.

    Args:
        commands: The sub-parsers object of the ``ogcp`` parser.
    """
    plot = commands.add_parser("plot", help="paper figures (PDF + PNG) and the time table from a suite run")
    plot.add_argument(
        "run", type=Path, metavar="RUN", help="results folder of ogcp suite (results.jsonl + manifest.json)"
    )
    plot.add_argument("--out", type=Path, default=None, metavar="DIR", help="output folder (default RUN/figures)")
    plot.add_argument("--only", nargs="+", default=None, metavar="NAME", help=f"draw only these: {', '.join(NAMES)}")
    plot.add_argument(
        "--format",
        dest="formats",
        nargs="+",
        default=["pdf", "png"],
        metavar="FMT",
        help="figure formats: pdf, png, svg (default pdf png)",
    )
    plot.add_argument("--dpi", type=typed(DPI), default=DPI.default, help=f"PNG resolution; {valid(DPI)} (default 200)")
    plot.add_argument("--unit", default=None, help="time unit of the table: s or min (default: by magnitude)")
    plot.set_defaults(handler=run_plot)


def run_plot(args: argparse.Namespace) -> int:
    """Handler of ``ogcp plot``."""
    import matplotlib

    matplotlib.use("Agg")  # files only: never open a window, work without a display

    from ogcp.benchmarks.plots import plot_run

    out = args.out if args.out is not None else args.run / "figures"
    report = plot_run(args.run, out, only=args.only, formats=args.formats, dpi=args.dpi, unit=args.unit)
    for note in report.notes:
        print(f"ogcp: note: {note}", file=sys.stderr)
    for path in report.written:
        print(path)
    print(f"{len(report.written)} files written to {out}", file=sys.stderr)
    return 0
