"""Friction facets: one column of panels per mu value when a run sweeps ``mu = [...]``.

A suite with ``mu = [0.3, 0.5, 0.8]`` runs each problem once per friction coefficient, so
mu is part of the plotting problem key. Per-problem figures then lay their panels out as a
grid: a row per problem without its mu (and whatever else splits a problem's panels), a
column per mu value, each panel titled ``box, mu = 0.3``. A run with one mu value keeps
the plain one-panel-per-problem layout, panel for panel.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from typing import TYPE_CHECKING

from benchmarks.suite.record import PROBLEM_FIELDS, Problem

from .data import RunData, problem_names
from .style import new_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Position of mu in a :data:`~benchmarks.suite.record.Problem` tuple.
MU = PROBLEM_FIELDS.index("mu")


def mu_values(run: RunData) -> list[float]:
    """The run's distinct friction coefficients, ascending (cells without one are left out)."""
    return sorted({float(c.problem[MU]) for c in run.cells if c.problem[MU] is not None})


def faceted(run: RunData) -> bool:
    """Whether the run's figures facet by mu: it holds cells at two or more mu values."""
    return len(mu_values(run)) > 1


def without_mu(problem: Problem) -> Problem:
    """``problem`` with its mu blanked: the key of a facet row."""
    return (*problem[:MU], None, *problem[MU + 1 :])


def mu_order(mu: float | None) -> tuple[bool, float]:
    """Sort key of mu values: ascending, a missing mu last."""
    return (mu is None, float(mu) if mu is not None else 0.0)


def mu_label(mu: float | None) -> str:
    """A facet's title part, ``mu = 0.3``."""
    return f"mu = {mu:g}" if mu is not None else "mu = ?"


def row_names(run: RunData) -> dict[Problem, str]:
    """Per problem the name of its facet row: its short name as if mu did not tell problems apart."""
    problems = list(dict.fromkeys(c.problem for c in run.cells))
    bases = problem_names(without_mu(p) for p in problems)
    return {p: bases[without_mu(p)] for p in problems}


def facet_names(run: RunData) -> dict[Problem, str]:
    """Panel titles per problem: :meth:`RunData.problem_names`, or ``box, mu = 0.3`` when faceted."""
    if not faceted(run):
        return run.problem_names()
    # The row name leaves mu out, so the title does not say mu=0.3 twice.
    return {p: f"{name}, {mu_label(p[MU])}" for p, name in row_names(run).items()}


def facet_figure(
    run: RunData, keys: Sequence[tuple[Problem, Hashable]], panel_height: float
) -> tuple[Figure, list[Axes]]:
    """The figure of a per-problem figure's panels, one axes per key in the order of ``keys``.

    Args:
        run: The run (it decides whether to facet).
        keys: Per panel its problem and what else tells the problem's panels apart (e.g. a
            constraint; ``None`` when a problem has one panel).
        panel_height: Height of one row [in].

    Returns:
        Without faceting, :func:`~benchmarks.plots.style.new_figure` with one panel per key.
        With it, a grid of a row per distinct ``(problem without mu, extra)`` and a column per
        mu value of ``keys``; grid cells no key fills are removed.
    """
    if not faceted(run):
        return new_figure(len(keys), panel_height=panel_height)
    rows = list(dict.fromkeys((without_mu(problem), extra) for problem, extra in keys))
    columns = sorted({problem[MU] for problem, _ in keys}, key=mu_order)
    figure, grid = new_figure(len(rows) * len(columns), panel_height=panel_height, max_columns=len(columns))
    chosen = [grid[rows.index((without_mu(p), extra)) * len(columns) + columns.index(p[MU])] for p, extra in keys]
    for ax in grid:
        if ax not in chosen:
            ax.remove()
    return figure, chosen
