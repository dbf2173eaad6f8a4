"""Fig. 3 grasp pictures: the z-buffer hides what is behind the mesh; one panel per problem; files."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import load_run
from ogcp.benchmarks.plots.grasp_figures import NoGraspCells, fig3_grasps
from ogcp.benchmarks.plots.raster import fit_view, look, render_mesh
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner

matplotlib.use("Agg")
SUITE = """
schema_version = 1
name = "tiny-grasps"
objects = ["box", "donut"]
contacts = 20
m = [3]
simulate = false

[[methods]]
method = "astar"
label = "A*"
"""


def test_z_buffer_hides_a_point_behind_a_triangle_and_shows_one_in_front():
    # A triangle in the plane z = 0, seen from above (+z): depth grows towards -z.
    vertices = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    view = fit_view(np.array([[-1.2, -1.2, 0.0], [1.2, 1.2, 0.0]]), look(0.0, 90.0), 80, 80)
    raster = render_mesh(vertices, np.array([[0, 1, 2]]), view)
    assert np.isfinite(raster.depth).any() and raster.rgba[..., 3].max() == 1.0
    points = np.array([[0.0, 0.0, -0.5], [0.0, 0.0, 0.5], [1.1, 1.1, -0.5], [0.0, 0.0, 0.0]])
    # Behind the triangle: hidden; in front: shown; beside it: shown; on it: shown.
    assert raster.visible(points, tolerance=1e-3).tolist() == [False, True, True, True]
    runs = raster.visible_runs([0.0, 0.0, 0.5], [0.0, 0.0, -0.5], samples=11)
    assert len(runs) == 1  # only the half above the triangle


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("grasps") / "run"
    SuiteRunner(parse_suite(SUITE), folder, log=lambda _: None).run()
    return folder


def test_one_panel_per_object_and_m(run):
    figure = fig3_grasps(load_run(run))
    titles = [ax.get_title() for ax in figure.axes]
    assert [t.split(":")[0] for t in titles] == ["box m=3", "donut m=3"]


def test_plot_run_writes_the_grasp_figure_with_truetype_fonts(run, tmp_path):
    report = plots.plot_run(run, tmp_path / "out", only=["fig3_grasps"], dpi=100)
    assert [p.name for p in report.written] == ["fig3_grasps.pdf", "fig3_grasps.png"]
    pdf = (tmp_path / "out" / "fig3_grasps.pdf").read_bytes()
    assert b"/FontFile2" in pdf and b"/Type3" not in pdf
    assert (tmp_path / "out" / "fig3_grasps.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_run_without_astar_cells_leaves_the_figure_out_quietly(run, tmp_path):
    data = load_run(run)
    hfts_only = plots.RunData(data.directory, tuple(c for c in data.cells if c.method == "hfts"), (), None)
    with pytest.raises(NoGraspCells):
        fig3_grasps(hfts_only)
