"""Paper figures and tables from a suite run (``ogcp plot RUN --out DIR``).

Only this package (and the CLI handler that calls it) imports matplotlib; the planner and
the simulator never do. Every figure builder takes a :class:`RunData` and returns a
:class:`matplotlib.figure.Figure` without saving it, or raises :class:`SkipFigure` when the
run lacks its cells; :func:`plot_run` draws them all, saves PDF (Type 42 fonts) and PNG, and
writes the Fig. 9 time table as Markdown, CSV and LaTeX.

The names below load their modules on first use (PEP 562), so that ``ogcp plot --help`` reads the
figure names (:mod:`benchmarks.plots.names`) without loading numpy and the suite's records.

Example:
    >>> from benchmarks.plots import plot_run
    >>> report = plot_run("runs/quick", "runs/quick/figures")  # doctest: +SKIP
    >>> print(*report.written, *report.notes, sep="\\n")  # doctest: +SKIP
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from benchmarks.plots.data import CellData, RunData, SkipFigure, load_run
    from benchmarks.plots.figures import (
        fig4_q1_histograms,
        fig6_states_per_level,
        fig7_iterations_f,
        fig8_wastar_tradeoff,
    )
    from benchmarks.plots.grasp_figures import fig3_grasps
    from benchmarks.plots.hand_figures import fig10_sdh_grasps
    from benchmarks.plots.names import NAMES, TABLE
    from benchmarks.plots.protocol import sim_protocol
    from benchmarks.plots.report import FIGURES, PlotReport, plot_run
    from benchmarks.plots.sim_figures_3d import sim_grasps
    from benchmarks.plots.simulation import sim_fidelity, sim_q1_vs_resistance, sim_survival, survival
    from benchmarks.plots.style import DOUBLE_COLUMN, SINGLE_COLUMN, method_colour, save_figure
    from benchmarks.plots.tables import TimeTable, time_table
    from benchmarks.plots.tree import fig5_search_tree, layout_tree

#: Public name -> the module that defines it.
_EXPORTS = {
    "DOUBLE_COLUMN": "benchmarks.plots.style",
    "FIGURES": "benchmarks.plots.report",
    "NAMES": "benchmarks.plots.names",
    "SINGLE_COLUMN": "benchmarks.plots.style",
    "TABLE": "benchmarks.plots.names",
    "CellData": "benchmarks.plots.data",
    "PlotReport": "benchmarks.plots.report",
    "RunData": "benchmarks.plots.data",
    "SkipFigure": "benchmarks.plots.data",
    "TimeTable": "benchmarks.plots.tables",
    "fig3_grasps": "benchmarks.plots.grasp_figures",
    "fig10_sdh_grasps": "benchmarks.plots.hand_figures",
    "fig4_q1_histograms": "benchmarks.plots.figures",
    "fig5_search_tree": "benchmarks.plots.tree",
    "fig6_states_per_level": "benchmarks.plots.figures",
    "fig7_iterations_f": "benchmarks.plots.figures",
    "fig8_wastar_tradeoff": "benchmarks.plots.figures",
    "layout_tree": "benchmarks.plots.tree",
    "load_run": "benchmarks.plots.data",
    "method_colour": "benchmarks.plots.style",
    "plot_run": "benchmarks.plots.report",
    "save_figure": "benchmarks.plots.style",
    "sim_fidelity": "benchmarks.plots.simulation",
    "sim_grasps": "benchmarks.plots.sim_figures_3d",
    "sim_q1_vs_resistance": "benchmarks.plots.simulation",
    "sim_survival": "benchmarks.plots.simulation",
    "sim_protocol": "benchmarks.plots.protocol",
    "survival": "benchmarks.plots.simulation",
    "time_table": "benchmarks.plots.tables",
}

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
    "fig3_grasps",
    "fig4_q1_histograms",
    "fig5_search_tree",
    "fig6_states_per_level",
    "fig7_iterations_f",
    "fig8_wastar_tradeoff",
    "fig10_sdh_grasps",
    "layout_tree",
    "load_run",
    "method_colour",
    "plot_run",
    "save_figure",
    "sim_fidelity",
    "sim_grasps",
    "sim_protocol",
    "sim_q1_vs_resistance",
    "sim_survival",
    "survival",
    "time_table",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
