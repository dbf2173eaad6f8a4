"""Figures a reader can read: no tick labels on top of each other, no marks hidden under others, symbols named."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import load_run
from ogcp.benchmarks.plots.sim_figures_3d import direction_name
from ogcp.benchmarks.plots.style import _overlapping, untangle_tick_labels
from tests.benchmarks.test_plots import synthetic_records, write_run

matplotlib.use("Agg")


def _tangled(figure: Figure) -> list[str]:
    FigureCanvasAgg(figure)
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    return [
        f"{ax.get_title()} {name}"
        for ax in figure.axes
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis))
        if _overlapping(axis, renderer)
    ]


def test_overlapping_tick_labels_are_thinned_until_none_touch() -> None:
    figure = Figure(figsize=(1.3, 1.0))
    ax = figure.add_subplot()
    ax.plot(np.linspace(123456.7, 987654.3, 5), np.linspace(0.001234, 0.009876, 5))
    ax.ticklabel_format(style="plain", useOffset=False)  # long labels on a narrow axis
    figure2 = Figure(figsize=(0.8, 0.8))
    ax2 = figure2.add_subplot()
    ax2.loglog([2.0, 9.0], [2.0, 9.0])  # less than a decade: labelled minor ticks
    assert _tangled(figure) and _tangled(figure2)  # the case this guards against exists
    for fig in (figure, figure2):
        untangle_tick_labels(fig)
        assert _tangled(fig) == []
        assert all(len([t for t in a.get_ticklabels() if t.get_text()]) >= 2 for a in (fig.axes[0].xaxis,))


def test_simulation_figures_have_no_tangled_labels_and_no_hidden_marks(tmp_path: Path) -> None:
    run = load_run(write_run(tmp_path, synthetic_records()))
    for figure in (plots.sim_fidelity(run), plots.sim_q1_vs_resistance(run), plots.sim_survival(run)):
        assert _tangled(figure) == []
    scatter = plots.sim_q1_vs_resistance(run)
    ax = scatter.axes[0]
    # A*'s grasp is ES's best: ES draws the dot first, A* a ring (bigger, hollow, A*'s colour) at
    # that grasp's Q1; its legend entry is still a dot.
    es_dot = next(c for c in ax.collections if c.get_label() == "ES")
    a_star = next(c for c in ax.collections if c.get_label() == "A*")
    assert len(a_star.get_offsets()) == 0
    (ring,) = [c for c in ax.collections if len(c.get_offsets()) and len(c.get_facecolors()) == 0]
    assert ring.get_offsets()[0][0] == es_dot.get_offsets()[0][0] == 0.35
    assert ring.get_sizes()[0] > es_dot.get_sizes()[0]
    assert np.allclose(ring.get_edgecolors()[0][:3], a_star.get_facecolors()[0][:3])
    legend = [t.get_text() for legend in scatter.legends for t in legend.get_texts()]
    assert "ring: same grasp as a dot" in legend


def test_direction_symbols_are_named_in_words() -> None:
    assert direction_name("+fx") == "force +x" and direction_name("-tz") == "torque -z"
    assert direction_name("s22") == "sphere dir. 22" and direction_name("q1-weakest") == "Q1's weakest direction"
