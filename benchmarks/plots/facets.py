"""Friction facets: one column of panels per mu value and contact model when a run sweeps them.

A suite with ``mu = [0.3, 0.5, 0.8]`` (or ``contact_model = ["hard", "soft"]``) runs each
problem once per friction coefficient (contact model), so both are part of the plotting
problem key; a facet column is one (mu, contact model) pair, titled ``box, mu = 0.3, soft 0.02 m``
when the run has soft fingers. Per-problem figures then lay their panels out as a
grid: a row per problem without its mu (and whatever else splits a problem's panels), a
column per mu value, each panel titled ``box, mu = 0.3``. A run with one mu value keeps
the plain one-panel-per-problem layout, panel for panel.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from typing import TYPE_CHECKING

from ogcp.benchmarks.suite.record import PROBLEM_FIELDS, Problem

from .data import RunData, problem_names
from .style import new_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Position of mu and of the torsional friction coefficient in a :data:`~ogcp.benchmarks.suite.record.Problem` tuple.
MU = PROBLEM_FIELDS.index("mu")
TORSION = PROBLEM_FIELDS.index("torsional_friction")
#: A facet's key: mu and the torsional friction coefficient [m] (0 = hard fingers).
Friction = tuple[float | None, float]


def friction(problem: Problem) -> Friction:
    """The facet key of a problem: its mu and its contact model's torsional coefficient (0 = hard)."""
    mu, torsion = problem[MU], problem[TORSION]
    return (None if mu is None else float(mu), float(torsion) if torsion else 0.0)


def frictions(run: RunData) -> list[Friction]:
    """The run's distinct facet keys, in :func:`mu_order` (cells without a mu are left out)."""
    return sorted({friction(c.problem) for c in run.cells if c.problem[MU] is not None}, key=mu_order)


def faceted(run: RunData) -> bool:
    """Whether the run's figures facet by friction: cells at two or more mu values or contact models."""
    return len(frictions(run)) > 1


def soft_cells(run: RunData) -> bool:
    """Whether any cell of the run has soft fingers (then facet titles name the contact model)."""
    return any(friction(c.problem)[1] > 0 for c in run.cells)


def without_mu(problem: Problem) -> Problem:
    """``problem`` with its mu and contact model blanked: the key of a facet row."""
    blank = list(problem)
    blank[MU] = blank[TORSION] = None
    return tuple(blank)


def mu_order(key: Friction | float | None) -> tuple[bool, float, float]:
    """Sort key of facets: mu ascending (a missing mu last), then hard before soft, torsion ascending."""
    mu, torsion = key if isinstance(key, tuple) else (key, 0.0)
    return (mu is None, float(mu) if mu is not None else 0.0, torsion)


def mu_label(key: Friction | float | None, models: bool = False) -> str:
    """A facet's title part: ``mu = 0.3``; with ``models``, ``mu = 0.3, hard`` or ``mu = 0.3, soft 0.02 m``."""
    mu, torsion = key if isinstance(key, tuple) else (key, 0.0)
    text = f"mu = {mu:g}" if mu is not None else "mu = ?"
    if models:
        text += f", soft {torsion:g} m" if torsion > 0 else ", hard"
    return text


def row_names(run: RunData) -> dict[Problem, str]:
    """Per problem the name of its facet row: its short name as if friction did not tell problems apart."""
    problems = list(dict.fromkeys(c.problem for c in run.cells))
    bases = problem_names(without_mu(p) for p in problems)
    return {p: bases[without_mu(p)] for p in problems}


def facet_names(run: RunData) -> dict[Problem, str]:
    """Panel titles per problem: :meth:`RunData.problem_names`, or ``box, mu = 0.3`` when faceted."""
    if not faceted(run):
        return run.problem_names()
    models = soft_cells(run)
    # The row name leaves friction out, so the title does not say mu=0.3 twice.
    return {p: f"{name}, {mu_label(friction(p), models)}" for p, name in row_names(run).items()}


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
        Without faceting, :func:`~ogcp.benchmarks.plots.style.new_figure` with one panel per key.
        With it, a grid of a row per distinct ``(problem without mu, extra)`` and a column per
        mu value of ``keys``; grid cells no key fills are removed.
    """
    if not faceted(run):
        return new_figure(len(keys), panel_height=panel_height)
    rows = list(dict.fromkeys((without_mu(problem), extra) for problem, extra in keys))
    columns = sorted({friction(problem) for problem, _ in keys}, key=mu_order)
    figure, grid = new_figure(len(rows) * len(columns), panel_height=panel_height, max_columns=len(columns))
    chosen = [grid[rows.index((without_mu(p), extra)) * len(columns) + columns.index(friction(p))] for p, extra in keys]
    for ax in grid:
        if ax not in chosen:
            ax.remove()
    return figure, chosen
