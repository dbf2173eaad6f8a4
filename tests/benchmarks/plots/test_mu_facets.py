"""Friction facets: a run with ``mu = [...]`` gets a column of panels per mu in the histogram and simulation figures."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import pytest
from matplotlib.figure import Figure

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import RunData, load_run
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner

matplotlib.use("Agg")
#: The box with 20 contacts, A* and ES, cheaply simulated (no sphere directions, one thread, the hull).
SUITE = """schema_version = 1
name = "tiny-mu"
objects = ["box"]
contacts = 20
m = [3]
mu = {mu}

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "es"
label = "ES"

[simulation]
enabled = true
directions = 0
threads = 1

[simulation.decomposition]
method = "convex_hull"
"""
#: The figures that facet by mu, and how many panels one problem draws in each.
FACETED = {
    "fig4_q1_histograms": 1,
    "sim_q1_vs_resistance": 1,
    "sim_fidelity": 1,
    "sim_survival": 2,
}


def _run(folder: Path, mu: str) -> RunData:
    SuiteRunner(parse_suite(SUITE.format(mu=mu)), folder, log=lambda _: None).run()
    return load_run(folder)


@pytest.fixture(scope="module")
def swept(tmp_path_factory: pytest.TempPathFactory) -> RunData:
    return _run(tmp_path_factory.mktemp("swept") / "run", "[0.3, 0.8]")


@pytest.fixture(scope="module")
def single(tmp_path_factory: pytest.TempPathFactory) -> RunData:
    return _run(tmp_path_factory.mktemp("single") / "run", "0.5")


def _figure(name: str, run: RunData) -> Figure:
    figure = getattr(plots, name)(run)
    assert isinstance(figure, Figure)
    return figure


@pytest.mark.parametrize("name", sorted(FACETED))
def test_a_mu_sweep_gets_a_column_of_panels_per_mu(swept: RunData, name: str) -> None:
    figure = _figure(name, swept)
    titles = [ax.get_title() for ax in figure.axes]
    assert len(titles) == 2 * FACETED[name]
    for mu in ("0.3", "0.8"):
        assert sum(f"mu = {mu}" in title for title in titles) == FACETED[name], titles
    # Columns: every panel of mu = 0.3 sits left of every panel of mu = 0.8.
    left = max(ax.get_position().x0 for ax, t in zip(figure.axes, titles) if "mu = 0.3" in t)
    right = min(ax.get_position().x0 for ax, t in zip(figure.axes, titles) if "mu = 0.8" in t)
    assert left < right


def test_methods_keep_their_colours_across_facets(swept: RunData) -> None:
    per_method = [ax for ax in _figure("sim_survival", swept).axes if ax.get_title().endswith("per method")]
    colours = [
        {line.get_label(): line.get_color() for line in ax.lines if "(n=" in line.get_label()} for ax in per_method
    ]
    labels = [{label.split(" (n=")[0]: colour for label, colour in c.items()} for c in colours]
    assert labels[0] == labels[1] == {"A*": plots.method_colour("astar"), "ES": plots.method_colour("es")}


@pytest.mark.parametrize("name", sorted(FACETED))
def test_a_single_mu_keeps_the_plain_layout(single: RunData, name: str) -> None:
    figure = _figure(name, single)
    assert len(figure.axes) == FACETED[name]
    assert not any("mu" in ax.get_title() for ax in figure.axes)
