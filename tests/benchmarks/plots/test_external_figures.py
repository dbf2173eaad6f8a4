"""External grasps (suite ``method = "external"``) beside A* in the per-method figures."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import load_run
from ogcp.benchmarks.plots.external import by_problem_with_external, host_problems, is_external
from ogcp.benchmarks.plots.grasp_figures import fig3_grasps, grasp_cells
from ogcp.benchmarks.plots.simulation import sim_q1_vs_resistance
from ogcp.benchmarks.suite.parse import load_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.planner import builtin_mesh
from ogcp.planner.records.grasps import GRASPS_SCHEMA

matplotlib.use("Agg")
# The built-in box is centred on the origin: its x faces lie at +-HALF[0].
HALF = np.ptp(np.asarray(builtin_mesh("box").vertices), axis=0) / 2
SUITE = """schema_version = 1
contacts = 20
m = 3
tip_radius = 0

[[group]]
name = "planners"
objects = ["box", "donut"]

[[group.methods]]
method = "astar"
label = "A*"

[[group]]
name = "external"
objects = ["box"]

[[group.methods]]
method = "external"
grasps = "mine.json"

[simulation]
enabled = true
directions = 0
threads = 1

[simulation.decomposition]
method = "convex_hull"
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    """A* on the box and the donut, and a three-finger grasps file on the box, all simulated."""
    folder = tmp_path_factory.mktemp("external")
    x, y = float(HALF[0]), float(HALF[1]) / 2

    def contact(px: float, py: float) -> dict:
        return {"position": [px, py, 0.0], "normal": [-np.sign(px), 0.0, 0.0]}

    grasps = [{"label": "tripod", "contacts": [contact(x, 0.0), contact(-x, y), contact(-x, -y)]}]
    record = {"schema": GRASPS_SCHEMA, "object": {"mesh": "box"}, "mu": 0.5, "method": "mine", "grasps": grasps}
    (folder / "mine.json").write_text(json.dumps(record))
    (folder / "suite.toml").write_text(SUITE)
    summary = SuiteRunner(load_suite(folder / "suite.toml"), folder / "out", log=lambda _: None).run()
    assert summary.errors == 0
    return folder / "out"


def test_an_external_cell_joins_the_planners_problem_of_its_object(run):
    data = load_run(run)
    (external,) = [c for c in data.cells if is_external(c)]
    astar = {c.object: c for c in data.cells if c.method == "astar"}
    assert external.problem != astar["box"].problem  # its own contacts: never a planner's problem
    assert host_problems(data) == {external.id: astar["box"].problem}
    groups = by_problem_with_external(data)
    assert list(groups) == [astar["box"].problem, astar["donut"].problem]
    assert groups[astar["box"].problem] == [astar["box"], external]
    # The planners' problems keep their plain names: the external |C| and seed do not tell them apart.
    assert data.problem_names()[astar["box"].problem] == "box"


def test_fig3_puts_the_external_grasp_beside_a_star(run):
    data = load_run(run)
    assert [(c.object, c.method) for c in grasp_cells(data)] == [
        ("box", "astar"),
        ("box", "external"),
        ("donut", "astar"),
    ]
    titles = [ax.get_title() for ax in fig3_grasps(data).axes if ax.get_visible() and ax.get_title()]
    assert [t.split(",")[0] for t in titles] == ["box m=3: A*", "box m=3: mine (external)", "donut m=3: A*"]


def test_simulation_figures_draw_the_external_grasps_in_the_a_star_panel(run, tmp_path):
    data = load_run(run)
    figure = sim_q1_vs_resistance(data)
    titled = [ax for ax in figure.axes if ax.get_title()]
    assert [ax.get_title().split("\n")[0] for ax in titled] == ["box", "donut"]
    labels = [text.get_text() for legend in figure.legends for text in legend.get_texts()]
    assert "A*" in labels and "mine" in labels
    report = plots.plot_run(run, tmp_path / "figures", only=["fig3_grasps", "sim_survival"], formats=["png"], dpi=50)
    assert sorted(p.name for p in report.written) == ["fig3_grasps.png", "sim_survival.png"]
