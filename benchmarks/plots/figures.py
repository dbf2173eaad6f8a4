"""The paper's search figures: Fig. 4 (Q1 histograms), 6 (states per level), 7 (f trace), 8 (WA* trade-off).

Every builder takes a :class:`~ogcp.benchmarks.plots.data.RunData`, returns the figure
without saving it (tests inspect it), and raises :class:`~ogcp.benchmarks.plots.data.SkipFigure`
with a one-line reason when the run lacks the cells the figure needs.
"""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from ogcp.planner.methods.registry import OPTIMAL_METHODS, SEARCH_METHODS

from .data import CellData, RunData, SkipFigure, frozen, number
from .facets import facet_figure, facet_names
from .style import (
    LEGEND_ROW,
    METHOD_TITLES,
    method_colour,
    new_figure,
    series_colour,
    shared_legend,
    styled,
    variant_colours,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Most panels a figure draws; the rest are left out with a note.
MAX_PANELS = 12
#: Ratio of largest to smallest positive value above which an axis goes logarithmic.
LOG_RATIO = 50.0
#: Fraction of the Fig. 4 panel height the histogram bars may use.
BAR_SHARE = 0.55
#: Search parameters that define a successor/heuristic variant (Fig. 7).
VARIANT_KEYS = ("branching", "successor", "heuristic", "heuristic_branching")
#: Parameters that never split a series (they vary within one, or do not change the search).
NOT_A_SERIES = ("seed", "record_tree")


Panel = TypeVar("Panel")


def _cap(panels: list[Panel], notes: list[str] | None, what: str) -> list[Panel]:
    if len(panels) > MAX_PANELS and notes is not None:
        notes.append(f"{what}: drew the first {MAX_PANELS} of {len(panels)} panels")
    return panels[:MAX_PANELS]


# ---------------------------------------------------------------- Fig. 4
@styled
def fig4_q1_histograms(run: RunData, notes: list[str] | None = None) -> Figure:
    """ES Q1 histogram per problem with A*'s optimum, WA*'s Q1 and bound per eps, and HFTS's spread.

    A run with several mu values gets a column of panels per mu (see :mod:`.facets`).

    Needs: an ``es`` cell (it records the histogram) per problem; A*, WA* and HFTS cells of
    the same problem and constraint add their markers.
    """
    names = facet_names(run)
    panels = []
    for problem, cells in run.by_problem().items():
        for es in (c for c in cells if c.method == "es" and c.plan_view.histogram is not None):
            others = [c for c in cells if c.constraint == es.constraint and c is not es]
            title = names[problem] + (f" ({es.constraint})" if es.constraint else "")
            panels.append((es, others, title))
    if not panels:
        raise SkipFigure("needs an ES cell (method es) with its Q1 histogram")
    panels = _cap(panels, notes, "fig4")
    figure, axes = facet_figure(run, [(es.problem, es.constraint) for es, _, _ in panels], panel_height=1.9)
    for ax, (es, others, title) in zip(axes, panels):
        _histogram_panel(ax, es, others, title)
    shared_legend(figure, axes)
    return figure


def _histogram_panel(ax: Axes, es: CellData, others: list[CellData], title: str) -> None:
    hist = es.plan_view.histogram
    assert hist is not None  # fig4 draws a panel only for an ES cell with a histogram
    edges, counts = hist.bin_edges, hist.counts
    wastar = _wastar_by_eps(others)
    ax.bar(
        edges[:-1],
        counts,
        width=np.diff(edges),
        align="edge",
        linewidth=0,
        alpha=0.8,
        color=method_colour("es", constraint=es.constraint),
        label="ES: grasps per Q1 bin",
    )
    positive = counts[counts > 0]
    # The bars keep to the lower part of the panel; the markers above them have the rest.
    if len(positive) and positive.max() / positive.min() > LOG_RATIO:
        ax.set_yscale("log")
        ax.set_ylim(0.5, 0.5 * (2 * positive.max()) ** (1 / BAR_SHARE))
    elif len(positive):
        ax.set_ylim(0, positive.max() / BAR_SHARE)
    fraction, zero = hist.force_closure_fraction, hist.zero
    summary = [
        f"FC {100 * fraction:.2f} %" if fraction is not None else None,
        f"Q1 = 0: {zero:,}" if zero is not None else None,
    ]
    ax.set_title("\n".join([title, ", ".join(s for s in summary if s)]))
    ax.set_xlabel("$Q_1$")
    ax.set_ylabel("grasps")
    # Axis up to the highest bar or marker, not to Q_OWS (the histogram's range), which can
    # be several times the optimum and squeeze the distribution into a corner.
    reach = [float(edges[np.flatnonzero(counts)[-1] + 1])] if np.any(counts) else []
    reach += [c.q1 for c in others if c.q1 is not None] + [
        c.plan_view.bound or 0.0 for c in others if c.method != "hfts"
    ]
    reach += [q1 or 0.0 for c in others for q1 in c.plan_view.run_q1s]
    ax.set_xlim(0, min(edges[-1], max(reach, default=edges[-1])) * 1.08)
    # Markers sit in axes coordinates vertically, so a log count axis does not move them.
    across = ax.get_xaxis_transform()
    optimal = [c for c in others if c.method in ("astar", "dijkstra") and not c.variant.get("symmetry")]
    best = next((c for c in optimal if c.method == "astar" and c.plain), None) or next(iter(optimal), None)
    if best is not None and best.q1 is not None:
        ax.axvline(
            best.q1,
            color=method_colour(best.method, constraint=best.constraint),
            linewidth=1.3,
            label=f"{METHOD_TITLES[best.method]} (optimum)",
        )
    elif es.q1 is not None:
        ax.axvline(
            es.q1, color=method_colour("es", constraint=es.constraint), linestyle=":", linewidth=1.3, label="ES optimum"
        )
    values = np.array([q1 for c in others if c.method == "hfts" for q1 in c.plan_view.run_q1s if q1 is not None])
    if len(values):
        colour = method_colour("hfts", constraint=es.constraint)
        ax.plot(
            [values.min(), values.max()],
            [0.95, 0.95],
            transform=across,
            color=colour,
            linewidth=1.3,
            label="HFTS runs: min-max, mean",
        )
        ax.plot(values, np.full(len(values), 0.95), "|", transform=across, color=colour, markersize=5)
        ax.plot([values.mean()], [0.95], "D", transform=across, color=colour, markersize=3)
    step = min(0.08, (0.95 - BAR_SHARE) / max(len(wastar), 1))
    for i, cell in enumerate(wastar):
        q1 = cell.q1
        assert q1 is not None  # _wastar_by_eps keeps cells with a Q1
        plan = cell.plan_view
        bound = plan.bound if plan.bound is not None else plan.eps_bound
        y, colour = 0.95 - step * (i + 1), method_colour("wastar", cell.eps, cell.constraint)
        ends = [q1, bound if bound is not None else q1]
        ax.plot(
            ends,
            [y, y],
            transform=across,
            color=colour,
            linewidth=1.3,
            label=f"WA* eps={cell.eps:g}: Q1 (o) to bound (|)",
        )
        ax.plot(ends[:1], [y], "o", transform=across, color=colour, markersize=3)
        ax.plot(ends[1:], [y], "|", transform=across, color=colour, markersize=6)


def _wastar_by_eps(cells: list[CellData]) -> list[CellData]:
    """One WA* cell per eps (plain variants first), by increasing eps."""
    chosen: dict[float, CellData] = {}
    for cell in sorted((c for c in cells if c.method == "wastar" and c.q1 is not None), key=lambda c: not c.plain):
        if cell.eps is not None:
            chosen.setdefault(cell.eps, cell)
    return [chosen[eps] for eps in sorted(chosen)]


# ---------------------------------------------------------------- Fig. 6
@styled
def fig6_states_per_level(run: RunData, notes: list[str] | None = None) -> Figure:
    """Created and visited states per level, with and without symmetry removal, b* in the legend.

    Needs: two search cells of one problem that differ only in ``symmetry`` (true / false).
    """
    names = run.problem_names()
    panels = []
    for problem, cells in run.by_problem().items():
        pairs: dict[Any, dict[bool, CellData]] = {}
        for cell in cells:
            if cell.method in SEARCH_METHODS and cell.stats.get("created_per_level"):
                key = (cell.method, frozen(cell.variant, ("symmetry", *NOT_A_SERIES)))
                pairs.setdefault(key, {}).setdefault(bool(cell.variant.get("symmetry")), cell)
        for pair in pairs.values():
            if len(pair) == 2:
                panels.append((names[problem], pair))
    if not panels:
        raise SkipFigure("needs search cells of one problem with symmetry = true and symmetry = false")
    panels = _cap(panels, notes, "fig6")
    figure, axes = new_figure(len(panels), panel_height=2.1 + LEGEND_ROW * 4, max_columns=2)
    for ax, (name, pair) in zip(axes, panels):
        method = pair[True].method
        ax.set_title(f"{name}: {pair[False].label}")
        for removed in (True, False):
            cell = pair[removed]
            colour = method_colour(method, cell.eps, cell.constraint) if removed else "#555555"
            which = "with" if removed else "without"
            branching = number(cell.stats.get("effective_branching_factor"))
            b_text = f"b*={branching:.2f}" if branching is not None else "b*=n/a"
            for kind, style, marker, fill in (("created", "--", "o", "none"), ("visited", "-", "s", colour)):
                counts = np.asarray(cell.stats.get(f"{kind}_per_level") or [], dtype=float)
                label = f"{kind}, {which} symmetry removal" + (f" ({b_text})" if kind == "created" else "")
                ax.plot(
                    np.arange(len(counts)),
                    counts,
                    linestyle=style,
                    marker=marker,
                    color=colour,
                    markerfacecolor=fill,
                    label=label,
                )
        ax.set_yscale("log")
        ax.set_xlabel("search level")
        ax.set_ylabel("states")
        ax.grid(True, which="major")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=1)
    return figure


# ---------------------------------------------------------------- Fig. 7
def _trace(cell: CellData) -> np.ndarray | None:
    try:
        trace = np.asarray(cell.stats.get("trace"), dtype=float)
    except (TypeError, ValueError):
        return None
    return trace if trace.ndim == 2 and trace.shape[1] == 2 and len(trace) else None


@styled
def fig7_iterations_f(run: RunData, notes: list[str] | None = None) -> Figure:
    """f of the expanded state against the iteration, per successor/heuristic variant, b* in the legend.

    Needs: A* or Dijkstra cells of one problem (no constraint, no symmetry removal) that
    differ in method, successor, heuristic or branching; several seeds per variant are drawn
    faintly behind the run with the median number of iterations.
    """
    from matplotlib.collections import LineCollection

    names = run.problem_names()
    panels: list[tuple[str, list[list[CellData]]]] = []
    for problem, cells in run.by_problem().items():
        groups: dict[tuple[Any, ...], list[CellData]] = {}
        for cell in cells:
            if (
                cell.method in ("astar", "dijkstra")
                and not cell.constraint
                and not cell.variant.get("symmetry")
                and _trace(cell) is not None
            ):
                key = (cell.method, *(repr(cell.variant.get(k)) for k in VARIANT_KEYS))
                groups.setdefault(key, []).append(cell)
        if len(groups) >= 2:
            panels.append((names[problem], list(groups.values())))
    if not panels:
        raise SkipFigure("needs A*/Dijkstra cells of one problem that differ in successor, heuristic or method")
    panels = _cap(panels, notes, "fig7")
    rows = max(len(variants) for _, variants in panels)
    figure, axes = new_figure(len(panels), panel_height=2.1 + LEGEND_ROW * rows, max_columns=2)
    for ax, (name, variants) in zip(axes, panels):
        longest = 1
        colours = variant_colours([members[0].method for members in variants])
        for colour, members in zip(colours, variants):
            style = "--" if members[0].method == "dijkstra" else "-"
            # Every member has a trace (checked when grouping); the filter tells the type checker.
            traces = [trace for trace in map(_trace, members) if trace is not None]
            order = np.argsort([len(t) for t in traces], kind="stable")
            median = order[len(order) // 2]
            others = [traces[j] for j in order if j != median]
            if others:
                ax.add_collection(LineCollection(others, colors=colour, linewidths=0.4, alpha=0.2))
            branching = [number(c.stats.get("effective_branching_factor")) for c in members]
            b = [v for v in branching if v is not None]
            label = Counter(c.label for c in members).most_common(1)[0][0]
            extra = [f"b*={np.median(b):.2f}" if b else "b*=n/a"] + (
                [f"{len(members)} runs"] if len(members) > 1 else []
            )
            trace = traces[median]
            ax.plot(trace[:, 0], trace[:, 1], linestyle=style, color=colour, label=f"{label} ({', '.join(extra)})")
            longest = max(longest, *(len(t) for t in traces))
        if longest > 200:
            ax.set_xscale("symlog", linthresh=10)
        ax.autoscale_view()
        ax.set_title(name)
        ax.set_xlabel("iteration")
        ax.set_ylabel("f(s) of the expanded state")
        ax.grid(True)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=1)
    return figure


# ---------------------------------------------------------------- Fig. 8
@styled
def fig8_wastar_tradeoff(run: RunData, notes: list[str] | None = None) -> Figure:
    """Search time, visited states and Q1 relative to the optimum against eps (A* at eps = 0).

    Needs: WA* cells of one problem at two or more eps (or one eps and the matching A* cell);
    the optimum comes from A*, Dijkstra or ES cells of the problem (else the best Q1 found).
    """
    names = run.problem_names()
    series = []
    for problem, cells in run.by_problem().items():
        groups: dict[Any, list[CellData]] = {}
        for cell in cells:
            if cell.method == "wastar" and cell.eps is not None and cell.q1 is not None:
                groups.setdefault((cell.constraint, frozen(cell.variant, ("eps", *NOT_A_SERIES))), []).append(cell)
        for (constraint, key), members in groups.items():
            members = members + [
                c
                for c in cells
                if c.method == "astar"
                and c.constraint == constraint
                and frozen(c.variant, NOT_A_SERIES) == key
                and c.q1 is not None
            ]
            if len({0.0 if c.method == "astar" else c.eps for c in members}) >= 2:
                optimal = [
                    c.q1
                    for c in cells
                    if c.method in OPTIMAL_METHODS
                    and c.constraint == constraint
                    and not c.variant.get("symmetry")
                    and c.q1 is not None
                ]
                series.append((problem, constraint, key, members, max(optimal) if optimal else None))
    if not series:
        raise SkipFigure("needs WA* cells of one problem at two or more eps (or one eps and the matching A*)")
    labels = _series_labels(series, names)
    figure, axes = new_figure(3, width=7.16, panel_height=2.1)
    fallback = False
    for i, ((problem, constraint, key, members, optimum), label) in enumerate(zip(series, labels)):
        by_eps: dict[float, list[CellData]] = {}
        for cell in members:
            by_eps.setdefault(0.0 if cell.method == "astar" else cell.eps, []).append(cell)  # type: ignore[arg-type]
        eps = np.array(sorted(by_eps))
        times = [_median(c.wall_seconds() for c in by_eps[e]) for e in eps]
        visited = [_median(number(c.stats.get("visited")) for c in by_eps[e]) for e in eps]
        q1 = np.array([_median(c.q1 for c in by_eps[e]) for e in eps], dtype=float)
        if optimum is None:
            optimum, fallback = float(np.nanmax(q1)), True
        colour = series_colour(i)
        axes[0].plot(eps, np.array(times, dtype=float), "o-", color=colour, label=label)
        axes[1].plot(eps, np.array(visited, dtype=float), "o-", color=colour, label=label)
        axes[2].plot(eps, q1 / optimum if optimum > 0 else q1, "o-", color=colour, label=label)
        q_ows = by_eps[eps[-1]][0].plan_view.q_ows
        if q_ows is not None and optimum > 0:
            guarantee = np.clip((q_ows - (1 + eps) * (q_ows - optimum)) / optimum, 0, None)
            axes[2].plot(
                eps, guarantee, ":", color=colour, linewidth=0.8, label="(1+eps) guarantee" if i == 0 else None
            )
    axes[0].set_ylabel("search time [s]")
    axes[1].set_ylabel("visited states")
    axes[1].set_yscale("log")
    axes[2].set_ylabel("$Q_1$ / best found" if fallback else "$Q_1$ / optimum")
    axes[2].set_ylim(bottom=0)
    for ax in axes:
        ax.set_xlabel("eps (0: A*)")
        ax.grid(True)
    shared_legend(figure, axes, columns=4)
    return figure


def _series_labels(series: list[Any], names: dict[Any, str]) -> list[str]:
    """Problem name, constraint, and the parameters that tell one problem's series apart."""
    labels = []
    for problem, constraint, key, _, _ in series:
        siblings = [s[2] for s in series if s[0] == problem and s[1] == constraint]
        differing = [k for k, v in key if any(dict(other).get(k) != v for other in siblings)]
        parts = [names[problem], constraint, *(f"{k}={dict(key)[k].strip(chr(39))}" for k in differing)]
        labels.append(" ".join(p for p in parts if p))
    return labels


def _median(values: Any) -> float:
    finite = [v for v in values if v is not None]
    return float(np.median(finite)) if finite else float("nan")
