"""Paper figures and tables from a suite run (``ogcp plot RUN --out DIR``).

Only this package (and the CLI handler that calls it) imports matplotlib; the planner and
the simulator never do. Every figure builder takes a :class:`RunData` and returns a
:class:`matplotlib.figure.Figure` without saving it, or raises :class:`SkipFigure` when the
run lacks its cells; :func:`plot_run` draws them all, saves PDF (Type 42 fonts) and PNG, and
writes the Fig. 9 time table as Markdown, CSV and LaTeX.

Example:
    >>> from benchmarks.plots import plot_run
    >>> report = plot_run("runs/quick", "runs/quick/figures")  # doctest: +SKIP
    >>> print(*report.written, *report.notes, sep="\\n")  # doctest: +SKIP
"""

from __future__ import annotations

from .data import CellData, RunData, SkipFigure, load_run
from .figures import fig4_q1_histograms, fig6_states_per_level, fig7_iterations_f, fig8_wastar_tradeoff
from .report import FIGURES, NAMES, TABLE, PlotReport, plot_run
from .simulation import sim_fidelity, sim_q1_vs_resistance, sim_survival, survival
from .style import DOUBLE_COLUMN, SINGLE_COLUMN, method_colour, save_figure
from .tables import TimeTable, time_table
from .tree import fig5_search_tree, layout_tree

__all__ = [
    "DOUBLE_COLUMN",
    "FIGURES",
    "NAMES",
    "SINGLE_COLUMN",
    "TABLE",
    "CellData",
    "PlotReport",
    "RunData",
    "SkipFigure",
    "TimeTable",
    "fig4_q1_histograms",
    "fig5_search_tree",
    "fig6_states_per_level",
    "fig7_iterations_f",
    "fig8_wastar_tradeoff",
    "layout_tree",
    "load_run",
    "method_colour",
    "plot_run",
    "save_figure",
    "sim_fidelity",
    "sim_q1_vs_resistance",
    "sim_survival",
    "survival",
    "time_table",
]
