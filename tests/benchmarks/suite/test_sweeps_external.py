"""Friction sweeps (``mu = [...]``) and external grasps (``method = "external"``) in suites.

The runs stay small: 20 contacts on the built-in box, A* only, and one cheaply simulated
external file (no sphere directions, one thread, the box's hull as its decomposition).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ogcp.benchmarks import compare
from ogcp.benchmarks.plots import data as plot_data
from ogcp.benchmarks.suite.config import EXTERNAL_METHOD
from ogcp.benchmarks.suite.parse import load_suite, parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.select import parse_selection
from ogcp.benchmarks.suite.store import RESULTS
from ogcp.planner import builtin_mesh
from ogcp.planner.infra import OgcpError
from ogcp.planner.methods.registry import method_spec
from ogcp.planner.objects import file_sha256
from ogcp.planner.records.grasps import GRASPS_SCHEMA

#: The quick suite's cell ids (since the searches' Γ^fc defaults became w = 2, t = 100): a scalar mu keeps
#: every id that suites gave before they took mu lists.
QUICK_IDS = {
    "00d1ece61cedfdfb",
    "0971e1c8265dcebf",
    "0c434e40a1a88dd8",
    "2fea9979585e5ada",
    "3ff063bc2ef0fb85",
    "409f7a98405809e3",
    "41115d344c5e794b",
    "44185837f10db402",
    "55d45c9bf5fd9c39",
    "66b13f07e3d045b0",
    "77eb9efb85efb623",
    "a6b55326d6bb4285",
    "b00c55dd27ba8835",
}
SWEEP = """schema_version = 1
objects = ["box"]
contacts = 20
m = 3
mu = {mu}
tip_radius = 0

[[methods]]
method = "astar"
label = "A*"
"""
SIMULATION = """
[simulation]
enabled = true
directions = 0
threads = 1

[simulation.decomposition]
method = "convex_hull"
"""
# The built-in box is centred on the origin: its x faces lie at +-HALF[0].
HALF = np.ptp(np.asarray(builtin_mesh("box").vertices), axis=0) / 2


def _records(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / RESULTS).read_text().splitlines() if line.strip()]


# -- friction sweeps -------------------------------------------------------------------------------


def test_quick_suite_keeps_its_cell_ids():
    assert {c.id for c in load_suite("quick").cells} == QUICK_IDS


def test_a_scalar_mu_and_a_one_value_list_are_the_same_cells():
    assert [c.id for c in parse_suite(SWEEP.format(mu="0.5")).cells] == [
        c.id for c in parse_suite(SWEEP.format(mu="[0.5]")).cells
    ]


def test_mu_lists_are_checked_like_other_sweeps():
    with pytest.raises(OgcpError, match=r"mu: repeated values"):
        parse_suite(SWEEP.format(mu="[0.3, 0.3]"))
    with pytest.raises(OgcpError, match=r"mu\[1\]"):
        parse_suite(SWEEP.format(mu="[0.3, -1]"))
    grouped = SWEEP.replace("mu = {mu}\n", "").replace("[[methods]]", "[[group]]\nmu = [0.2, 0.4]\n[[group.methods]]")
    assert sorted(c.mu for c in parse_suite(grouped).cells) == [0.2, 0.4]


def test_the_simulation_takes_each_cells_mu_and_refuses_a_list():
    with pytest.raises(OgcpError, match=r"simulation\.mu: expected one number .* mu = \[\.\.\.\]"):
        parse_suite(SWEEP.format(mu="[0.3, 0.8]") + "[simulation]\nmu = [0.3, 0.8]\n")


def test_mu_sweep_runs_distinct_cells_and_only_selects_mu(tmp_path):
    suite = parse_suite(SWEEP.format(mu="[0.3, 0.8]"))
    assert [c.mu for c in suite.cells] == [0.3, 0.8] and len({c.id for c in suite.cells}) == 2
    with pytest.raises(OgcpError, match=r"--only mu=0\.4: .* mu = 0\.3, 0\.8"):
        parse_selection(["mu=0.4"], suite.cells)
    out = tmp_path / "out"
    assert SuiteRunner(suite, out, only=("mu=0.3",)).run().ran == 1
    assert [r["params"]["mu"] for r in _records(out)] == [0.3]
    assert SuiteRunner(suite, out, resume=True).run().ran == 1
    records = {r["params"]["mu"]: r for r in _records(out)}
    assert sorted(records) == [0.3, 0.8] and all(r["status"] == "ok" for r in records.values())
    assert [records[mu]["plan"]["contact_set"]["mu"] for mu in (0.3, 0.8)] == [0.3, 0.8]
    assert records[0.3]["plan"]["q1"] < records[0.8]["plan"]["q1"]  # wider cones, stronger grasp


# -- external grasps -------------------------------------------------------------------------------


def _grasps_file(folder: Path, mesh: str = "box") -> Path:
    """Two grasps on the box's x faces: a pinch (score 0.2) and a three-finger grasp (score 0.9, the best)."""
    x, y = float(HALF[0]), float(HALF[1]) / 2

    def contact(px: float, py: float) -> dict:
        return {"position": [px, py, 0.0], "normal": [-np.sign(px), 0.0, 0.0]}

    record = {
        "schema": GRASPS_SCHEMA,
        "object": {"mesh": mesh},
        "mu": 0.5,
        "method": "mine",
        "grasps": [
            {"label": "pinch", "score": 0.2, "contacts": [contact(x, 0.0), contact(-x, 0.0)]},
            {"label": "tripod", "score": 0.9, "contacts": [contact(x, 0.0), contact(-x, y), contact(-x, -y)]},
        ],
    }
    path = folder / "mine.json"
    path.write_text(json.dumps(record))
    return path


def _external_suite(folder: Path, objects: str = '["box"]', simulate: bool = True) -> Path:
    path = folder / "external.toml"
    path.write_text(
        "schema_version = 1\ncontacts = 20\nm = 3\ntip_radius = 0\n"
        f'[[group]]\nname = "planners"\nobjects = {objects}\nsimulate = false\n'
        '[[group.methods]]\nmethod = "astar"\nlabel = "A*"\n'
        f'[[group]]\nname = "external"\nobjects = {objects}\n'
        '[[group.methods]]\nmethod = "external"\ngrasps = "mine.json"\n' + (SIMULATION if simulate else "")
    )
    return path


def test_external_cells_are_read_with_the_files_hash(tmp_path):
    grasps = _grasps_file(tmp_path)
    suite = load_suite(_external_suite(tmp_path, '["box", "donut"]', simulate=False))
    (cell,) = [c for c in suite.cells if c.method == EXTERNAL_METHOD]
    assert (cell.object.spec, cell.contacts, cell.m, cell.mu, cell.label) == ("box", 5, 3, 0.5, "mine")
    assert dict(cell.variant) == {"grasps": file_sha256(grasps)} and cell.contact_seed is None
    assert "tip_radius" not in cell.params() and cell.params()["contact_seed"] is None
    grasps.write_text(grasps.read_text().replace('"mine"', '"theirs"'))
    changed = load_suite(tmp_path / "external.toml")
    assert cell.id not in {c.id for c in changed.cells}  # a changed file is a new cell


def test_external_grasps_refuse_an_object_the_group_does_not_list(tmp_path):
    _grasps_file(tmp_path)
    with pytest.raises(OgcpError, match=r"grasps are on 'box', which group\[1\]\.objects does not list \(donut\)"):
        load_suite(_external_suite(tmp_path, '["donut"]'))
    with pytest.raises(OgcpError, match=r"unknown key 'eps'"):
        parse_suite('schema_version = 1\nobjects = ["box"]\n[[methods]]\nmethod = "external"\neps = 1\n')
    with pytest.raises(OgcpError, match=r"methods\[0\]\.grasps: grasps file not found"):
        parse_suite(
            'schema_version = 1\nobjects = ["box"]\n[[methods]]\nmethod = "external"\ngrasps = "none.json"\n',
            base=tmp_path,
        )
    with pytest.raises(OgcpError, match=r"valid choices: astar, .*, wastar; or external with grasps"):
        parse_suite('schema_version = 1\nobjects = ["box"]\n[[methods]]\nmethod = "mine"\n')


def test_external_suite_runs_and_is_read_by_compare_and_plots(tmp_path):
    _grasps_file(tmp_path)
    out = tmp_path / "out"
    summary = SuiteRunner(load_suite(_external_suite(tmp_path)), out).run()
    assert summary.ran == 2 and summary.errors == 0
    (record,) = [r for r in _records(out) if r["params"]["method"] == EXTERNAL_METHOD]
    assert record["status"] == "ok", record["error"]
    plan = record["plan"]
    assert (plan["method"], plan["status"], plan["label"], len(plan["grasp"])) == ("external", "external", "tripod", 3)
    assert 0 < plan["q1"] <= plan["q_ows"] == plan["bound"]
    assert [g["label"] for g in record["simulation"]["grasps"]] == ["pinch", "tripod"]
    assert record["simulation"]["object"]["external"]["grasps"][1]["q1"] == pytest.approx(plan["q1"])
    text, status = compare.compare_dirs(out, out)
    assert status == 0, text
    run = plot_data.load_run(out)
    (external,) = [c for c in run.cells if c.method == EXTERNAL_METHOD]
    assert (external.label, external.q1, external.object) == ("mine", plan["q1"], "box")
    assert external.simulation is not None


def test_ogcp_plan_names_where_external_grasps_belong():
    with pytest.raises(OgcpError, match=r"method 'external' plans nothing: .*ogcp evaluate.*planners: astar"):
        method_spec("external")
