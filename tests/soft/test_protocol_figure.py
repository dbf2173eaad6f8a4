"""The DexGraspBench figure and the friction facets of a hard/soft sweep simulated with their protocol."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import pytest

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import RunData, SkipFigure, load_run
from ogcp.benchmarks.plots.protocol import auc_text, protocol_outcomes
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner

matplotlib.use("Agg")

SUITE = """schema_version = 1
objects = ["box"]
contacts = 14
m = 2
tip_radius = 0
contact_model = ["hard", "soft"]

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "hfts"
runs = 3
iterations = 5
label = "HFTS"

[simulation]
enabled = true
protocol = "{protocol}"
directions = 0
threads = 1

[simulation.decomposition]
method = "convex_hull"
"""


def _run(folder: Path, protocol: str) -> RunData:
    SuiteRunner(parse_suite(SUITE.format(protocol=protocol)), folder, log=lambda _: None).run()
    return load_run(folder)


@pytest.fixture(scope="module")
def dexgraspbench(tmp_path_factory: pytest.TempPathFactory) -> RunData:
    return _run(tmp_path_factory.mktemp("dgb") / "run", "dexgraspbench")


def test_every_judged_grasp_counts_and_soft_pinches_fare_no_worse(dexgraspbench):
    by_model: dict[str, list[tuple[float, bool]]] = {}
    for cell in dexgraspbench.cells:
        outcomes = protocol_outcomes(cell)
        assert outcomes, cell.label  # every simulated grasp is judged by their test
        by_model.setdefault(cell.params.get("contact_model", "hard"), []).extend(outcomes)
    # m = 2: hard A* returns a grasp of Q1 = 0; soft A* the best soft pinch (Q1 > 0).
    assert max(q for q, _ in by_model["hard"]) == 0.0 < max(q for q, _ in by_model["soft"])
    assert sum(s for _, s in by_model["soft"]) >= sum(s for _, s in by_model["hard"])


def test_the_figure_has_a_column_per_contact_model(dexgraspbench, tmp_path):
    figure = plots.sim_protocol(dexgraspbench)
    titles = sorted(ax.get_title().splitlines()[0] for ax in figure.axes if ax.get_title())
    assert titles == ["box, mu = 0.5, hard", "box, mu = 0.5, soft 0.02 m"]
    assert all("n=" in ax.get_title() for ax in figure.axes if ax.get_title())
    report = plots.plot_run(dexgraspbench, tmp_path / "figures", only=["sim_protocol"], formats=["pdf"])
    assert [p.name for p in report.written] == ["sim_protocol.pdf"]


def test_a_resistance_run_has_no_protocol_figure(tmp_path):
    run = _run(tmp_path / "run", "resistance")
    with pytest.raises(SkipFigure, match="dexgraspbench"):
        plots.sim_protocol(run)
    titles = {ax.get_title() for ax in plots.sim_survival(run).axes}
    assert any(t.startswith("mu = 0.5, soft 0.02 m: ") for t in titles)


def test_auc_text_gives_both_aucs():
    assert auc_text([(0.1, False), (0.3, True), (0.2, True), (0.0, False)]) == "AUC 1.00 (theirs 1.00), n=4"
    assert auc_text([(0.1, True)]).startswith("one outcome only") and auc_text([]) == "n=0"
