"""Simulation figures: Q1 against measured resistance, measured against predicted, survival curves.

They read the ``ogcp.sim/1`` record of simulated cells: per grasp ``valid``, ``q1``,
``measured_min`` and the per-direction ``predicted``, ``measured`` and ``censored``
lists. Only valid grasps (every preload gate passed) count. A censored direction held
to the end of the ramp, so its measured value is a lower bound; those points are drawn
hollow. External cells (another planner's grasps) are drawn in the panel of the planners'
problem on the same object (:mod:`.external`), beside A*, ES and HFTS.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .data import CellData, RunData, SkipFigure, number
from .external import by_problem_with_external
from .facets import facet_figure, facet_names, faceted, friction, mu_label, mu_order, row_names, soft_cells
from .figures import MAX_PANELS
from .style import method_colour, new_figure, series_colour, shared_legend, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Resistances spanning more than this ratio get log axes in the fidelity plot.
DECADE = 10.0
NEEDS = "needs simulated cells ([simulation] enabled = true in the suite) with valid grasps"


@dataclass(frozen=True)
class SimGrasp:
    """One valid simulated grasp.

    Attributes:
        grasp: Its sorted contact indices (the same grasp may come from several cells).
        q1: Its Q1.
        measured_min: Smallest measured resistance over the directions [N] (None if not all measured).
        min_censored: Whether that smallest value is a lower bound (the object never moved).
        predicted: Predicted resistance per direction [N].
        measured: Measured resistance per direction [N].
        censored: Censored flag per direction.
        fidelity: ``|measured / predicted - 1|`` per direction (NaN where undefined).
    """

    grasp: tuple[int, ...]
    q1: float | None
    measured_min: float | None
    min_censored: bool
    predicted: np.ndarray
    measured: np.ndarray
    censored: np.ndarray
    fidelity: np.ndarray


def valid_grasps(cell: CellData) -> list[SimGrasp]:
    """The cell's valid simulated grasps (none without a simulation record)."""
    out = []
    for g in cell.simulation.grasps if cell.simulation is not None else ():
        if not g.valid:
            continue
        measured, predicted, censored, fidelity = g.measured, g.predicted, g.censored, g.fidelity
        if len(censored) != len(measured):
            censored = np.zeros(len(measured), dtype=bool)
        if len(predicted) != len(measured):
            predicted = np.full(len(measured), np.nan)
        at_min = bool(len(measured) and np.isfinite(measured).all() and censored[int(np.argmin(measured))])
        # A grasp without indices counts as its own (the same grasp may come from several cells).
        grasp = tuple(sorted(g.grasp)) if g.grasp is not None else (id(g),)
        out.append(
            SimGrasp(
                grasp,
                g.q1,
                g.measured_min,
                at_min,
                predicted,
                measured,
                censored,
                fidelity if len(fidelity) == len(measured) else np.full(len(measured), np.nan),
            )
        )
    return out


def _simulated(run: RunData) -> dict[Any, list[tuple[CellData, list[SimGrasp]]]]:
    """Valid simulated grasps per problem and cell; external cells join the planners' problem of their object."""
    groups: dict[Any, list[tuple[CellData, list[SimGrasp]]]] = {}
    for problem, cells in by_problem_with_external(run).items():
        for cell in cells:
            grasps = valid_grasps(cell)
            if grasps:
                groups.setdefault(problem, []).append((cell, grasps))
    if not groups:
        raise SkipFigure(NEEDS)
    return dict(list(groups.items())[:MAX_PANELS])


def _colour(cell: CellData) -> str:
    return method_colour(cell.method, cell.eps, cell.constraint)


def _rank_correlations(x: list[float], y: list[float]) -> str:
    from scipy import stats

    if len(x) < 3 or len(set(x)) < 2 or len(set(y)) < 2:
        return f"n={len(x)}"
    rho = stats.spearmanr(x, y).statistic
    tau = stats.kendalltau(x, y).statistic
    return f"Spearman {rho:.2f}, Kendall {tau:.2f} (n={len(x)})"


@styled
def sim_q1_vs_resistance(run: RunData, notes: list[str] | None = None) -> Figure:
    """Scatter of Q1 against the minimum measured resistance, one panel per problem (a column per mu).

    The title gives Spearman and Kendall over the panel's valid grasps; hollow triangles
    are grasps whose weakest direction never slipped (a lower bound). A grasp that several
    methods returned (A*, WA* and ES often agree) is a dot of the first method ringed by the
    others, in their colours, so that no method's marks hide under another's.
    """
    groups = _simulated(run)
    names = facet_names(run)
    figure, axes = facet_figure(run, [(problem, None) for problem in groups], panel_height=2.0)
    lower_bounds = rings = False
    for ax, (problem, cells) in zip(axes, groups.items()):
        # A grasp returned by several methods (A* and ES) is one sample of the correlation; an
        # external cell's indices are into its own contacts, so grasps are told apart by problem too.
        unique: dict[tuple[Any, tuple[int, ...]], tuple[float, float]] = {}
        # How many methods have drawn each grasp: a repeat is a ring around the earlier marks.
        drawn: collections.Counter[tuple[Any, tuple[int, ...]]] = collections.Counter()
        for cell, grasps in cells:
            points = []
            for g in grasps:
                if g.q1 is None or g.measured_min is None:
                    continue
                key = (cell.problem, g.grasp)
                unique.setdefault(key, (g.q1, g.measured_min))
                points.append((g.q1, g.measured_min, g.min_censored, drawn[key]))
                drawn[key] += 1
            if not points:
                continue
            q1, low, cut, before = (np.array(v) for v in zip(*points))
            colour = _colour(cell)
            first = ~cut & (before == 0)
            ax.scatter(q1[first], low[first], s=9, color=colour, label=cell.label, linewidths=0)
            again = ~cut & (before > 0)
            if again.any():
                rings = True
                ax.scatter(
                    q1[again],
                    low[again],
                    s=9 * (1 + 0.9 * before[again]) ** 2,
                    facecolors="none",
                    edgecolors=colour,
                    linewidths=0.7,
                    label=None,  # the legend shows the method's dot, drawn above even when empty
                )
            if cut.any():
                lower_bounds = True
                ax.scatter(
                    q1[cut],
                    low[cut],
                    s=12,
                    marker="^",
                    facecolors="none",
                    edgecolors=colour,
                    linewidths=0.6,
                    label=None,
                )
        xs, ys = [q for q, _ in unique.values()], [low for _, low in unique.values()]
        ax.set_title(f"{names[problem]}\n{_rank_correlations(xs, ys)}")
        ax.set_xlabel("$Q_1$")
        ax.set_ylabel("min. measured resistance [N]")
        ax.grid(True)
    if lower_bounds:
        _censored_entry(axes[0])
    if rings:
        axes[0].scatter(
            [], [], s=20, facecolors="none", edgecolors="#555555", linewidths=0.7, label="ring: same grasp as a dot"
        )
    shared_legend(figure, axes)
    return figure


def _censored_entry(ax: Axes) -> None:
    ax.scatter(
        [],
        [],
        s=12,
        marker="^",
        facecolors="none",
        edgecolors="#555555",
        linewidths=0.6,
        label="held to the end (lower bound)",
    )


@styled
def sim_fidelity(run: RunData, notes: list[str] | None = None) -> Figure:
    """Measured against predicted resistance per direction, with y = x; log axes when the values span decades.

    One panel per problem; a run with several mu values gets a column of panels per mu.
    """
    groups = _simulated(run)
    names = facet_names(run)
    figure, axes = facet_figure(run, [(problem, None) for problem in groups], panel_height=2.1)
    lower_bounds = False
    for ax, (problem, cells) in zip(axes, groups.items()):
        values, fidelity = [], []
        for cell, grasps in cells:
            predicted = np.concatenate([g.predicted for g in grasps])
            measured = np.concatenate([g.measured for g in grasps])
            censored = np.concatenate([g.censored for g in grasps])
            fidelity += [f for g in grasps for f in g.fidelity if np.isfinite(f)]
            keep = np.isfinite(predicted) & np.isfinite(measured)
            colour = _colour(cell)
            held = keep & ~censored
            ax.scatter(predicted[held], measured[held], s=6, color=colour, alpha=0.6, linewidths=0, label=cell.label)
            if (keep & censored).any():
                lower_bounds = True
                ax.scatter(
                    predicted[keep & censored],
                    measured[keep & censored],
                    s=10,
                    marker="^",
                    facecolors="none",
                    edgecolors=colour,
                    linewidths=0.5,
                    label=None,
                )
            values += list(predicted[keep]) + list(measured[keep])
        positive = np.array([v for v in values if v > 0])
        # Log axes drop the few directions predicted to resist nothing; worth it when the rest span decades.
        if len(positive) >= 0.9 * len(values) and len(positive) and positive.max() / positive.min() > DECADE:
            ax.set_xscale("log")
            ax.set_yscale("log")
        if values:
            low = positive.min() if ax.get_xscale() == "log" else min(0.0, min(values))
            high = max(values)
            ax.plot([low, high], [low, high], "--", color="black", linewidth=0.7, label="y = x")
        median = f"median |meas/pred - 1| = {np.median(fidelity):.3f}" if fidelity else "no fidelity defined"
        ax.set_title(f"{names[problem]}\n{median}")
        ax.set_xlabel("predicted resistance [N]")
        ax.set_ylabel("measured resistance [N]")
        ax.grid(True)
    if lower_bounds:
        _censored_entry(axes[0])
    shared_legend(figure, axes)
    return figure


def survival(values: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Loads and the fraction of ``values`` that are >= each load, as a step curve.

    Returns:
        ``(loads, fraction)`` for ``step(..., where="pre")``: the fraction at ``loads[i]``
        holds on ``(loads[i-1], loads[i]]``, and 0 beyond the largest value.
    """
    v = np.sort(np.asarray(values, dtype=float))
    loads = np.concatenate([[0.0], v, [v[-1] * 1.05 if len(v) and v[-1] > 0 else 1.0]])
    fraction = np.array([np.count_nonzero(v >= load) for load in loads], dtype=float) / max(len(v), 1)
    fraction[-1] = 0.0
    return loads, fraction


@dataclass
class _Curves:
    """One facet's survival data: measured minima per method and per object, holding loads."""

    per_method: dict[str, tuple[CellData, list[float]]] = field(default_factory=dict)
    per_object: dict[str, list[float]] = field(default_factory=dict)
    holding: set[float] = field(default_factory=set)


@styled
def sim_survival(run: RunData, notes: list[str] | None = None) -> Figure:
    """Fraction of valid grasps still holding against load: (a) per method, (b) per object.

    For each load L the fraction of valid grasps with ``measured_min >= L``. A run with
    several mu values gets a column per mu: per method on top, per object below.
    """
    groups = _simulated(run)
    split = faceted(run)
    names = row_names(run) if split else run.problem_names()
    facets: dict[Any, _Curves] = {}
    for problem, cells in sorted(
        groups.items(), key=lambda item: mu_order(friction(item[0])) if split else (False, 0.0, 0.0)
    ):
        curves = facets.setdefault(friction(problem) if split else None, _Curves())
        for cell, grasps in cells:
            low = [g.measured_min for g in grasps if g.measured_min is not None]
            curves.per_method.setdefault(cell.label, (cell, []))[1].extend(low)
            curves.per_object.setdefault(names[problem], []).extend(low)
            load = number(cell.simulation.set_metrics.get("holding_load")) if cell.simulation is not None else None
            if load is not None:
                curves.holding.add(load)
    if not any(low for curves in facets.values() for low in curves.per_object.values()):
        raise SkipFigure("needs simulated grasps with a measured minimum resistance")
    # One colour per object in every column: the order the objects first appear in, over all facets.
    objects = list(dict.fromkeys(name for curves in facets.values() for name in curves.per_object))
    n = len(facets)
    # One facet keeps the two panels side by side; several stack them, a column per mu.
    figure, axes = new_figure(2 * n, panel_height=2.3, max_columns=max(n, 2))
    for j, (mu, curves) in enumerate(facets.items()):
        prefix = f"{mu_label(mu, soft_cells(run))}: " if split else ""
        _survival_panels((axes[j], axes[n + j]), curves, objects, prefix)
    return figure


def _survival_panels(axes: tuple[Axes, Axes], curves: _Curves, objects: list[str], prefix: str) -> None:
    for label, (cell, low) in curves.per_method.items():
        if low:
            axes[0].step(*survival(low), where="pre", color=_colour(cell), label=f"{label} (n={len(low)})")
    for name, low in curves.per_object.items():
        if low:
            colour = series_colour(objects.index(name))
            axes[1].step(*survival(low), where="pre", color=colour, label=f"{name} (n={len(low)})")
    for ax, what in zip(axes, ("per method", "per object")):
        for load in sorted(curves.holding):
            ax.axvline(load, color="#555555", linestyle=":", linewidth=0.7, label=f"holding load {load:g} N")
        ax.set_title(f"{prefix}grasps holding, {what}")
        ax.set_xlabel("load [N]")
        ax.set_ylabel("fraction of valid grasps")
        ax.set_ylim(0, 1.03)
        ax.set_xlim(left=0)
        ax.grid(True)
        ax.legend(loc="upper right")
