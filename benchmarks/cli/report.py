"""The ``ogcp report`` and ``ogcp view`` commands: self-contained HTML pages with 3D grasp views.

``ogcp report RUN [--out FILE] [--no-plot]`` writes ``RUN/report.html``: the run's tables, its
figures and an interactive 3D view of every planned or simulated grasp. Without figures in
``RUN/figures`` it draws them first (``ogcp plot RUN --format png``) unless ``--no-plot``.
``ogcp view RESULT.json [--out FILE] [--no-open]`` writes the 3D view of one plan, simulation
or cell record next to it and opens it in a browser when there is one.
Both print the path written (stdout) and one note per thing left out (stderr).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def register(commands: Any) -> None:
    """Add the ``report`` and ``view`` sub-commands to the ``ogcp`` parser.

    Args:
        commands: The sub-parsers object of the ``ogcp`` parser.
    """
    report = commands.add_parser("report", help="one self-contained HTML file: tables, figures, 3D grasp views")
    report.add_argument(
        "run", type=Path, metavar="RUN", help="results folder of ogcp suite (results.jsonl + manifest.json)"
    )
    report.add_argument("--out", type=Path, default=None, metavar="FILE", help="HTML file (default RUN/report.html)")
    report.add_argument(
        "--no-plot", action="store_true", help="do not draw missing figures first (the report notes their absence)"
    )
    report.set_defaults(handler=run_report)
    view = commands.add_parser("view", help="interactive 3D view (HTML) of one plan, simulation or cell record")
    view.add_argument("result", type=Path, metavar="RESULT", help="JSON of ogcp plan, ogcp evaluate or one cell")
    view.add_argument(
        "--out", type=Path, default=None, metavar="FILE", help="HTML file (default: RESULT with the suffix .html)"
    )
    view.add_argument("--no-open", action="store_true", help="only write the file, do not open a browser")
    view.set_defaults(handler=run_view)


def _notes(notes: tuple[str, ...]) -> None:
    for note in notes:
        print(f"ogcp: note: {note}", file=sys.stderr)


def run_report(args: argparse.Namespace) -> int:
    """Handler of ``ogcp report``."""
    figures = args.run / "figures"
    if not args.no_plot and (args.run / "results.jsonl").is_file() and not any(figures.glob("*.png")):
        import matplotlib

        matplotlib.use("Agg")  # files only: never open a window, work without a display

        from ogcp.benchmarks.plots import plot_run

        # The report inlines PNGs only; PDFs are ogcp plot's job.
        drawn = plot_run(args.run, figures, formats=["png"])
        _notes(drawn.notes)
    from ogcp.benchmarks.report import write_report

    result = write_report(args.run, args.out, figures)
    _notes(result.notes)
    print(result.path)
    size = result.path.stat().st_size / 1e6
    print(f"{result.grasps} grasps in 3D, {size:.1f} MB", file=sys.stderr)
    return 0


def run_view(args: argparse.Namespace) -> int:
    """Handler of ``ogcp view``."""
    from ogcp.benchmarks.report import write_view

    result = write_view(args.result, args.out)
    _notes(result.notes)
    print(result.path)
    if not args.no_open:
        import webbrowser

        # Headless machines have no browser: the path above is the answer there.
        try:
            webbrowser.open(result.path.resolve().as_uri())
        except webbrowser.Error:
            pass
    return 0
