"""Paper figures and tables from a suite run (``ogcp plot RUN --out DIR``).

Only this package (and the CLI handler that calls it) imports matplotlib; the planner and
the simulator never do. Every figure builder takes a :class:`RunData` and returns a
:class:`matplotlib.figure.Figure` without saving it, or raises :class:`SkipFigure` when the
run lacks its cells; :func:`plot_run` draws them all, saves PDF (Type 42 fonts) and PNG, and
writes the Fig. 9 time table as Markdown, CSV and LaTeX.

The names below load their modules on first use (PEP 562), so that ``ogcp plot --help`` reads the
figure names (:mod:`ogcp.benchmarks.plots.names`) without loading numpy and the suite's records.

Example:
    >>> from ogcp.benchmarks.plots import plot_run
    >>> report = plot_run("runs/quick", "runs/quick/figures")  # doctest: +SKIP
    >>> print(*report.written, *report.notes, sep="\\n")  # doctest: +SKIP
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.benchmarks.plots.data import CellData, RunData, SkipFigure, load_run
    from ogcp.benchmarks.plots.figures import (
        fig4_q1_histograms,
        fig6_states_per_level,
        fig7_iterations_f,
        fig8_wastar_tradeoff,
    )
    from ogcp.benchmarks.plots.grasp_figures import fig3_grasps
    from ogcp.benchmarks.plots.hand_figures import fig10_hand_grasps
    from ogcp.benchmarks.plots.names import NAMES, TABLE
    from ogcp.benchmarks.plots.protocol import sim_protocol
    from ogcp.benchmarks.plots.report import FIGURES, PlotReport, plot_run
    from ogcp.benchmarks.plots.sim_figures_3d import sim_grasps
    from ogcp.benchmarks.plots.simulation import sim_fidelity, sim_q1_vs_resistance, sim_survival, survival
    from ogcp.benchmarks.plots.style import DOUBLE_COLUMN, SINGLE_COLUMN, method_colour, save_figure
    from ogcp.benchmarks.plots.tables import TimeTable, time_table
    from ogcp.benchmarks.plots.tree import fig5_search_tree, layout_tree

#: Public name -> the module that defines it.
_EXPORTS = {
    "DOUBLE_COLUMN": "ogcp.benchmarks.plots.style",
    "FIGURES": "ogcp.benchmarks.plots.report",
    "NAMES": "ogcp.benchmarks.plots.names",
    "SINGLE_COLUMN": "ogcp.benchmarks.plots.style",
    "TABLE": "ogcp.benchmarks.plots.names",
    "CellData": "ogcp.benchmarks.plots.data",
    "PlotReport": "ogcp.benchmarks.plots.report",
    "RunData": "ogcp.benchmarks.plots.data",
    "SkipFigure": "ogcp.benchmarks.plots.data",
    "TimeTable": "ogcp.benchmarks.plots.tables",
    "fig3_grasps": "ogcp.benchmarks.plots.grasp_figures",
    "fig10_hand_grasps": "ogcp.benchmarks.plots.hand_figures",
    "fig4_q1_histograms": "ogcp.benchmarks.plots.figures",
    "fig5_search_tree": "ogcp.benchmarks.plots.tree",
    "fig6_states_per_level": "ogcp.benchmarks.plots.figures",
    "fig7_iterations_f": "ogcp.benchmarks.plots.figures",
    "fig8_wastar_tradeoff": "ogcp.benchmarks.plots.figures",
    "layout_tree": "ogcp.benchmarks.plots.tree",
    "load_run": "ogcp.benchmarks.plots.data",
    "method_colour": "ogcp.benchmarks.plots.style",
    "plot_run": "ogcp.benchmarks.plots.report",
    "save_figure": "ogcp.benchmarks.plots.style",
    "sim_fidelity": "ogcp.benchmarks.plots.simulation",
    "sim_grasps": "ogcp.benchmarks.plots.sim_figures_3d",
    "sim_q1_vs_resistance": "ogcp.benchmarks.plots.simulation",
    "sim_survival": "ogcp.benchmarks.plots.simulation",
    "sim_protocol": "ogcp.benchmarks.plots.protocol",
    "survival": "ogcp.benchmarks.plots.simulation",
    "time_table": "ogcp.benchmarks.plots.tables",
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
    "fig10_hand_grasps",
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
