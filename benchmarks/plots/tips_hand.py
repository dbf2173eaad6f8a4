"""Tips versus hand on the same grasps: of the A* optima planned under a hand, how many hold with free
fingertip spheres, how many the hand realises, and how many it holds when it closes.

The input is the cases of :mod:`ogcp.benchmarks.studies.hand_fit` (``hand_fit.json``): per
(hand, object, m) the rows of each contact seed with ``tips_valid``, ``realised`` and ``hand_valid``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .style import DOUBLE_COLUMN, SERIES_COLOURS, SINGLE_COLUMN, new_figure, shared_legend, styled

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Most cases drawn at one column's width.
ONE_COLUMN_CASES = 4
#: The three bars of a case: (row key, legend label).
BARS = (
    ("tips_valid", "valid with fingertips"),
    ("realised", "realised by the hand"),
    ("hand_valid", "held by the hand"),
)


@styled
def fig_tips_vs_hand(cases: Sequence[dict[str, Any]]) -> Figure:
    """Grouped bars per case: the share of planned grasps valid with tips, realised and held by the hand.

    Args:
        cases: ``{"hand", "object", "m", "rows": [{"tips_valid", "realised", "hand_valid"}, ...]}``.

    Returns:
        A one-column figure (two columns beyond :data:`ONE_COLUMN_CASES` cases); each bar is
        labelled with its count, the legend below the panel.
    """
    width = SINGLE_COLUMN if len(cases) <= ONE_COLUMN_CASES else DOUBLE_COLUMN
    figure, (ax,) = new_figure(1, width=width, panel_height=2.0)
    width = 0.8 / len(BARS)
    positions = np.arange(len(cases))
    for k, (key, label) in enumerate(BARS):
        counts = np.array([sum(bool(r[key]) for r in case["rows"]) for case in cases])
        totals = np.array([max(len(case["rows"]), 1) for case in cases])
        at = positions + (k - (len(BARS) - 1) / 2) * width
        bars = ax.bar(at, counts / totals, width, label=label, color=SERIES_COLOURS[k])
        ax.bar_label(bars, labels=[str(c) for c in counts], fontsize=6, padding=1)
    ax.set_xticks(positions, [_label(case) for case in cases], fontsize=6)
    ax.set_ylim(0, 1.12)
    ax.set_ylabel("share of planned grasps")
    shared_legend(figure, [ax], columns=len(BARS))
    return figure


def _label(case: dict[str, Any]) -> str:
    """A case's tick label; a hand's name breaks at its underscores, so long names keep to their group."""
    hand = "\n".join(str(case["hand"]).split("_"))
    return f"{hand}\n{case['object']}, m={case['m']}"
