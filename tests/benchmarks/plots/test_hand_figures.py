"""Fig. 10 (each plan's hand on its grasp), sim_grasps (tips and weakest push) and the per-mesh camera."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from ogcp.benchmarks import plots
from ogcp.benchmarks.plots.data import load_run
from ogcp.benchmarks.plots.grasp_figures import NoGraspCells, upright
from ogcp.benchmarks.plots.hand_figures import HAND_FITS, NoHandCells, fig10_hand_grasps
from ogcp.benchmarks.plots.raster import look
from ogcp.benchmarks.plots.sim_figures_3d import (
    NoSimulatedCells,
    _tip_radius,
    sim_grasps,
    simulated_grasps,
    tip_centres,
)
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.sim_eval.inputs.plan_input import plan_input

matplotlib.use("Agg")
SDH_SUITE = """
schema_version = 1
name = "tiny-sdh"
objects = ["box"]
contacts = 40
m = [3]
simulate = false

[[methods]]
method = "astar"
hand = "sdh"
label = "A* SDH"
"""
SDH_SIM_SUITE = (
    SDH_SUITE.replace("simulate = false", "")
    + """
[simulation]
enabled = true
directions = 0
threads = 1
"""
)
SIM_SUITE = """
schema_version = 1
name = "tiny-sim"
objects = ["box"]
contacts = 20
m = [3]

[[methods]]
method = "astar"
label = "A*"

[simulation]
enabled = true
"""


def test_look_turns_the_picture_up_to_the_given_axis():
    assert np.allclose(look(35.0, 25.0), look(35.0, 25.0, up=(0, 0, 2)))
    handedness = np.linalg.det(look(35.0, 25.0))  # (right, up, into the scene) is left-handed
    for up in np.vstack([np.eye(3), -np.eye(3)]):
        rotation = look(35.0, 25.0, up=up)
        assert np.allclose(rotation @ rotation.T, np.eye(3)) and np.isclose(np.linalg.det(rotation), handedness)
        assert rotation[1] @ up > 0.85 and abs(rotation[0] @ up) < 1e-12  # up shows as up, never sideways


def test_a_mesh_with_a_flat_base_stands_on_it():
    # A tall square pyramid standing on y = 0: its base faces -y and its top is a point.
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1], [0.5, 3, 0.5]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]])
    assert upright(vertices, faces).tolist() == [0.0, 1.0, 0.0]
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    hull = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1]])
    hull = np.vstack([hull, [[2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]])
    assert upright(cube, hull).tolist() == [0.0, 0.0, 1.0]  # the same base on every side: z stays


@pytest.fixture(scope="module")
def sdh_run(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("sdh") / "run"
    SuiteRunner(parse_suite(SDH_SUITE), folder, log=lambda _: None).run()
    return folder


@pytest.fixture(scope="module")
def sim_run(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("sim") / "run"
    SuiteRunner(parse_suite(SIM_SUITE), folder, log=lambda _: None).run()
    return folder


def test_fig10_draws_one_hand_panel_per_object_and_writes_its_files(sdh_run, tmp_path):
    figure = fig10_hand_grasps(load_run(sdh_run))
    assert [ax.get_title().split(":")[0] for ax in figure.axes] == ["box"]
    assert "pads within" in figure.axes[0].get_title()
    # The drawn pads sit on their contacts: the hand is fitted, not the recorded sample placed rigidly.
    [posed] = HAND_FITS
    assert posed.title == "box: A* SDH" and posed.fit.residuals.shape == (3,)
    assert posed.fit.realised and posed.fit.residuals.max() < 1e-3
    report = plots.plot_run(sdh_run, tmp_path / "out", only=["fig10_hand_grasps"], formats=["png"], dpi=60)
    assert [p.name for p in report.written] == ["fig10_hand_grasps.png"]


def test_runs_without_hand_or_simulation_skip_quietly_by_default_and_with_a_note_on_request(sdh_run, tmp_path):
    assert issubclass(NoHandCells, NoGraspCells) and issubclass(NoSimulatedCells, NoGraspCells)
    with pytest.raises(NoSimulatedCells):
        sim_grasps(load_run(sdh_run))
    report = plots.plot_run(sdh_run, tmp_path / "out", only=["sim_grasps"], formats=["png"], dpi=60)
    assert report.written == () and any(n.startswith("sim_grasps: skipped") for n in report.notes)


def test_sim_grasps_draws_the_realized_tips_or_says_it_used_the_planned_ones(sim_run):
    data = load_run(sim_run)
    with pytest.raises(NoHandCells):
        fig10_hand_grasps(data)
    title = sim_grasps(data).axes[0].get_title()
    assert title.startswith("box: A* best") and "weakest" in title and "planned" not in title
    # An ogcp.sim/1 record has no realized contacts: the tips go on the planned ones, said in the title.
    cells = []
    for cell in data.cells:
        if cell.simulation is not None:
            grasps = tuple(dataclasses.replace(g, realized={}) for g in cell.simulation.grasps)
            cell = dataclasses.replace(cell, simulation=dataclasses.replace(cell.simulation, grasps=grasps))
        cells.append(cell)
    old = plots.RunData(data.directory, tuple(cells), (), None)
    assert "tips at planned contacts" in sim_grasps(old).axes[0].get_title()


def test_sim_grasps_draws_the_settled_tips_and_older_records_their_start(sim_run):
    data = load_run(sim_run)
    [(cell, grasp)] = simulated_grasps(data)
    rebuilt = plan_input(cell.plan)
    radius = _tip_radius(cell, rebuilt)
    centres, points, normals, source = tip_centres(grasp, rebuilt.contacts, radius)
    # Recorded by the simulation: the tips after preload and settling, in the mesh's frame, each
    # still touching its realized contact (a tip radius from it, give or take the contact's squeeze).
    assert source == "settled" and len(grasp.realized["settled_centres"]) == len(grasp.grasp)
    np.testing.assert_allclose(np.linalg.norm(centres - points, axis=1), radius, rtol=0.1)
    assert not np.allclose(centres, points - radius * normals, atol=1e-9)  # not the start positions
    started = dataclasses.replace(grasp, realized={k: v for k, v in grasp.realized.items() if k != "settled_centres"})
    assert tip_centres(started, rebuilt.contacts, radius)[3] == "start"
    cells = [
        dataclasses.replace(c, simulation=dataclasses.replace(c.simulation, grasps=(started,)))
        if c.simulation is not None
        else c
        for c in data.cells
    ]
    title = sim_grasps(plots.RunData(data.directory, tuple(cells), (), None)).axes[0].get_title()
    assert "tips at start positions" in title


def test_fig10_draws_the_hand_as_it_settled_when_the_cell_was_simulated(tmp_path):
    folder = tmp_path / "run"
    SuiteRunner(parse_suite(SDH_SIM_SUITE), folder, log=lambda _: None).run()
    data = load_run(folder)
    (cell,) = [c for c in data.cells if c.simulation is not None]
    (simulated,) = cell.simulation.grasps
    figure = fig10_hand_grasps(data)
    [posed] = HAND_FITS
    assert posed.settled and figure.axes[0].get_title().split("\n")[1].startswith("settled, pads within")
    assert posed.fit.joint_angles == pytest.approx(simulated.hand["settled_joint_angles"])
    assert posed.fit.translation == pytest.approx(simulated.hand["palm_position"])
    # A grasp the simulation found unreachable is drawn as its fit (made with the object) left the
    # hand and says so, not fitted again here without the object as if it were fine.
    angles = np.asarray(simulated.hand["settled_joint_angles"]) + 0.05
    fit = {**simulated.hand["fit"], "realised": False, "joint_angles": angles.tolist(), "penetration": 0.004}
    block = {k: v for k, v in simulated.hand.items() if k != "settled_joint_angles"} | {"fit": fit}
    grasps = (dataclasses.replace(simulated, hand=block),)
    unreachable = dataclasses.replace(cell, simulation=dataclasses.replace(cell.simulation, grasps=grasps))
    cells = tuple(unreachable if c is cell else c for c in data.cells)
    figure = fig10_hand_grasps(plots.RunData(data.directory, cells, (), None))
    [posed] = HAND_FITS
    caption = figure.axes[0].get_title().split("\n")[1]
    assert posed.how == "unreachable" and not posed.settled
    assert caption.startswith("unreachable in simulation, pads within") and "a link 4.0 mm in the object" in caption
    assert posed.fit.joint_angles == pytest.approx(angles)
    assert posed.fit.translation == pytest.approx(fit["palm_position"])


def test_the_tips_versus_hand_figure_has_one_bar_group_per_case(tmp_path):
    from ogcp.benchmarks.plots.style import save_figure
    from ogcp.benchmarks.plots.tips_hand import fig_tips_vs_hand

    rows = [
        {"tips_valid": True, "realised": True, "hand_valid": True},
        {"tips_valid": True, "realised": False, "hand_valid": False},
    ]
    cases = [
        {"hand": "sdh", "object": "box", "m": 3, "rows": rows},
        {"hand": "shadow_hand", "object": "box", "m": 3, "rows": rows[:1]},
    ]
    figure = fig_tips_vs_hand(cases)
    (ax,) = figure.axes
    heights = [patch.get_height() for patch in ax.patches]
    assert heights == [1.0, 1.0, 0.5, 1.0, 0.5, 1.0]  # tips, realised, held; per case in order
    assert [t.get_text() for t in ax.get_xticklabels()] == ["sdh\nbox, m=3", "shadow\nhand\nbox, m=3"]
    paths = save_figure(figure, tmp_path, "tips_vs_hand")
    assert [p.suffix for p in paths] == [".pdf", ".png"] and b"/FontFile2" in paths[0].read_bytes()
