"""DexGraspBench's test as a figure: success rate per method and Q1 of the grasps that pass or fail.

It reads cells simulated with ``protocol = "dexgraspbench"`` (``[simulation]`` of a suite):
per grasp its planned Q1 and ``hold_tests["dexgraspbench"]["success"]`` (false whenever one of
ogcp's gates failed). One panel per problem, a column per friction facet (mu and contact
model, :mod:`.facets`), so a paper can show how the verdicts move with the contact model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ogcp.sim_eval.protocols.metrics import binned_roc, roc_auc

from .data import CellData, RunData
from .external import by_problem_with_external
from .facets import facet_figure, facet_names
from .figures import MAX_PANELS
from .grasp_figures import NoGraspCells
from .style import method_colour, shared_legend, styled

if TYPE_CHECKING:
    from matplotlib.figure import Figure

NEEDS = 'needs cells simulated with protocol = "dexgraspbench" ([simulation] of the suite)'


class NoProtocolCells(NoGraspCells):
    """The run has no cell simulated with DexGraspBench's test: like the object pictures, the
    figure is an extra of such runs, noted as skipped only when asked for by name."""


def protocol_outcomes(cell: CellData) -> list[tuple[float, bool]]:
    """``(planned Q1, success)`` of every grasp of the cell that DexGraspBench's test judged.

    Grasps that could not be simulated (an error, not a failed gate) are left out, as their
    evaluation drops grasps that raised; a grasp whose Q1 is unknown counts as Q1 = 0.
    """
    out = []
    for g in cell.simulation.grasps if cell.simulation is not None else ():
        test = g.hold_tests.get("dexgraspbench") if isinstance(g.hold_tests, dict) else None
        if not isinstance(test, dict) or "success" not in test:
            continue
        out.append((float(g.q1) if g.q1 is not None else 0.0, test["success"] is True))
    return out


def auc_text(outcomes: list[tuple[float, bool]]) -> str:
    """``AUC 0.71 (theirs 0.78), n=20``: Q1 against success, exact and DexGraspBench's binned way."""
    if not outcomes:
        return "n=0"
    q1 = np.array([q for q, _ in outcomes])
    success = np.array([s for _, s in outcomes])
    exact = roc_auc(q1, success)
    theirs = binned_roc(-q1, success).auc
    if not (np.isfinite(exact) and np.isfinite(theirs)):
        return f"one outcome only, n={len(outcomes)}"
    return f"AUC {exact:.2f} (theirs {theirs:.2f}), n={len(outcomes)}"


@styled
def sim_protocol(run: RunData, notes: list[str] | None = None) -> Figure:
    """DexGraspBench success rate per method, one panel per problem (a column per mu and contact model).

    Each bar is a cell's fraction of grasps that passed every load and every gate, labelled
    ``k/n``; the title gives the AUC of Q1 against success over the panel's distinct grasps,
    exact (Mann-Whitney) and DexGraspBench's binned way.
    """
    groups: dict[Any, list[tuple[CellData, list[tuple[float, bool]]]]] = {}
    for problem, cells in by_problem_with_external(run).items():
        for cell in cells:
            outcomes = protocol_outcomes(cell)
            if outcomes:
                groups.setdefault(problem, []).append((cell, outcomes))
    if not groups:
        raise NoProtocolCells(NEEDS)
    if len(groups) > MAX_PANELS and notes is not None:
        notes.append(f"sim_protocol: drew the first {MAX_PANELS} of {len(groups)} panels")
    groups = dict(list(groups.items())[:MAX_PANELS])
    names = facet_names(run)
    figure, axes = facet_figure(run, [(problem, None) for problem in groups], panel_height=2.0)
    for ax, (problem, entries) in zip(axes, groups.items()):
        unique: dict[tuple[Any, ...], tuple[float, bool]] = {}
        for row, (cell, outcomes) in enumerate(entries):
            rate = sum(s for _, s in outcomes) / len(outcomes)
            colour = method_colour(cell.method, cell.eps, cell.constraint)
            ax.barh(row, rate, color=colour, label=cell.label, height=0.7)
            ax.text(min(rate, 1.0) + 0.02, row, f"{sum(s for _, s in outcomes)}/{len(outcomes)}", va="center")
            for index, outcome in enumerate(outcomes):
                unique.setdefault((cell.id, index), outcome)
        ax.set_yticks(range(len(entries)), [cell.label for cell, _ in entries])
        ax.invert_yaxis()
        ax.set_xlim(0.0, 1.25)  # room for the k/n labels
        ax.set_xticks(np.linspace(0.0, 1.0, 6))
        ax.set_xlabel("DexGraspBench success rate")
        ax.set_title(f"{names[problem]}\n{auc_text(list(unique.values()))}")
        ax.grid(True, axis="x")
    shared_legend(figure, axes)
    return figure
