"""Fig. 5: the search tree as a circular plot (radius = level, children inside the parent's sector).

A plan carries its tree under ``"tree"`` when the search recorded it: parallel lists
``parent`` (index of the creating state; -1 or null for the root), ``level`` and
``visited`` (expanded or not), optionally ``f``, plus the solution path as state indices
(``path``; ``solution_path`` and ``solution`` are read too). Each state gets an angular
sector proportional to the number of leaves below it, split among its children in the
order they were created, so angle orders the states of a level by their parents.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .data import CellData, RunData, SkipFigure
from .style import METHOD_TITLES, add_legend, new_figure, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Most trees drawn in one figure.
MAX_TREES = 4
PATH_KEYS = ("path", "solution_path", "solution")
VISITED_COLOUR = "#56B4E9"
STEM_COLOUR = "#9A9A9A"
PATH_COLOUR = "#8B0000"


@dataclass(frozen=True)
class TreeLayout:
    """Polar coordinates of a recorded search tree.

    Attributes:
        angle: Sector centre per state [rad].
        width: Sector width per state [rad].
        level: Level (depth) per state.
        visited: Whether each state was expanded.
        path: Solution path as state indices (may be empty).
    """

    angle: np.ndarray
    width: np.ndarray
    level: np.ndarray
    visited: np.ndarray
    path: tuple[int, ...]


def layout_tree(tree: dict[str, Any]) -> TreeLayout:
    """Sectors of a recorded tree.

    Raises:
        ValueError: When the lists are missing, of different lengths, or a parent is invalid.
    """
    parent = [-1 if p is None else int(p) for p in tree["parent"]]
    level = np.asarray(tree["level"], dtype=int)
    visited = np.asarray([bool(v) for v in tree["visited"]], dtype=bool)
    n = len(parent)
    if n == 0 or len(level) != n or len(visited) != n:
        raise ValueError(f"parent/level/visited have lengths {n}/{len(level)}/{len(visited)}")
    if any(p >= n or p < -1 or p == i for i, p in enumerate(parent)):
        raise ValueError("a parent index is out of range")
    children: list[list[int]] = [[] for _ in range(n)]
    roots: list[int] = []
    for i, p in enumerate(parent):
        (roots if p < 0 else children[p]).append(i)
    # Deepest first, so every child's leaf count is final before its parent adds it up.
    order = sorted(range(n), key=lambda i: -level[i])
    leaves = np.ones(n)
    for i in order:
        if children[i]:
            leaves[i] = sum(leaves[c] for c in children[i])
    start, width = np.zeros(n), np.zeros(n)
    total = sum(leaves[r] for r in roots) or 1.0
    offset, pending = 0.0, []
    for r in roots:
        start[r], width[r] = offset, 2 * math.pi * leaves[r] / total
        offset += width[r]
        pending.append(r)
    seen = set(pending)
    while pending:
        node = pending.pop()
        offset = start[node]
        for child in children[node]:
            if child in seen:
                raise ValueError("the parent links contain a cycle")
            seen.add(child)
            start[child], width[child] = offset, width[node] * leaves[child] / leaves[node]
            offset += width[child]
            pending.append(child)
    if len(seen) != n:
        raise ValueError("some states are not connected to a root")
    listed: list[Any] = next((tree[k] for k in PATH_KEYS if isinstance(tree.get(k), list)), [])
    path = tuple(int(i) for i in listed if isinstance(i, int) and 0 <= i < n)
    return TreeLayout(start + width / 2, width, level, visited, path)


@styled
def fig5_search_tree(run: RunData, notes: list[str] | None = None) -> Figure:
    """Circular plot of every recorded search tree (at most ``MAX_TREES``).

    Needs: a search cell whose plan has a ``"tree"`` (``record_tree = true`` in the suite,
    with a planner that records it).
    """
    names = run.problem_names()
    trees: list[tuple[CellData, TreeLayout]] = []
    for cell in run.cells:
        tree = cell.plan_view.tree
        if tree is None:
            continue
        try:
            trees.append((cell, layout_tree(tree)))
        except (KeyError, TypeError, ValueError) as exc:
            if notes is not None:
                notes.append(f"fig5: search tree of cell {cell.id} unreadable ({exc}); left out")
    if not trees:
        raise SkipFigure("no plan records a search tree (a search cell with record_tree = true)")
    if len(trees) > MAX_TREES and notes is not None:
        notes.append(f"fig5: drew {MAX_TREES} of {len(trees)} recorded search trees")
    trees = trees[:MAX_TREES]
    figure, axes = new_figure(len(trees), panel_height=3.2 if len(trees) == 1 else 3.0, max_columns=2, polar=True)
    for ax, (cell, layout) in zip(axes, trees):
        _draw_tree(ax, cell, layout, names[cell.problem])
    handles, labels = axes[0].get_legend_handles_labels()
    add_legend(figure, handles, labels, 3)
    return figure


def _draw_tree(ax: Axes, cell: CellData, tree: TreeLayout, name: str) -> None:
    from matplotlib.collections import LineCollection

    radius = tree.level + 1.0  # the root sits on a ring, not on the pole, so its sector shows
    visited = tree.visited
    ax.bar(
        tree.angle[visited],
        0.9,
        width=tree.width[visited] * 0.96,
        bottom=radius[visited] - 0.45,
        color=VISITED_COLOUR,
        edgecolor="white",
        linewidth=0.2,
        label=f"visited ({int(visited.sum())})",
    )
    stems = [[(a, r - 0.45), (a, r + 0.35)] for a, r in zip(tree.angle[~visited], radius[~visited])]
    ax.add_collection(
        LineCollection(
            stems, colors=STEM_COLOUR, linewidths=0.4, label=f"created, not visited ({int((~visited).sum())})"
        )
    )
    if tree.path:
        index = list(tree.path)
        ax.plot(
            tree.angle[index],
            radius[index],
            color=PATH_COLOUR,
            linewidth=2.0,
            marker="o",
            markersize=2.5,
            label="solution path",
        )
    top = int(tree.level.max()) + 2
    ax.set_ylim(0, top)
    ax.set_yticks(np.arange(1, top), labels=[])
    ax.set_xticks([])
    ax.grid(True, linewidth=0.3)
    ax.spines["polar"].set_visible(False)
    method = METHOD_TITLES.get(cell.method, cell.method)
    ax.set_title(f"{name}: {method}, created {len(tree.level)}, visited {int(visited.sum())}")
