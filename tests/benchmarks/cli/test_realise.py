"""``ogcp plan --realise N``: planned grasps the hand cannot realise are excluded and the plan made again."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from ogcp.sim_eval.evaluate import GraspEvaluator
from tests.cli_run import run_cli

GRIPPER = ["box", "-n", "40", "-m", "2", "--diagonal", "0.08", "--contact-model", "soft", "--hand", "parallel_gripper"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["plan", "box", "-n", "20", "--realise", "2"], "realise: applies only with a hand"),
        (["plan", *GRIPPER, "--method", "hfts", "--realise", "2"], "--realise applies to methods astar, dijkstra"),
        (["plan", *GRIPPER, "--realise", "51"], "realise: expected an integer <= 50, got 51"),
        (["plan", *GRIPPER, "--realise", "0"], "realise: expected an integer >= 1, got 0"),
        (["plan", *GRIPPER, "--method", "es", "--checkpoint", "ck", "--realise", "2"], "a checkpoint holds one run"),
    ],
)
def test_realise_is_refused_in_one_line_where_it_cannot_apply(argv, message):
    status, _, err = run_cli(argv)
    assert status == 2 and message in err and err.count("\n") == 1, err


def test_a_grasp_the_hand_cannot_realise_is_excluded_and_the_plan_made_again(tmp_path, monkeypatch):
    """The first fit is made to fail (its residuals 10 mm): the second plan is the best other grasp,
    realised, and the record says which grasp was rejected and why."""
    real = GraspEvaluator.fit_hand
    calls: list[tuple[int, ...]] = []

    def first_fails(self, mesh, contacts, grasp, parts=None):
        fit = real(self, mesh, contacts, grasp, parts)
        calls.append(tuple(sorted(grasp)))
        return dataclasses.replace(fit, residuals=fit.residuals + 0.01) if len(calls) == 1 else fit

    monkeypatch.setattr(GraspEvaluator, "fit_hand", first_fails)
    once, again = tmp_path / "once.json", tmp_path / "again.json"
    assert run_cli(["plan", *GRIPPER, "-o", str(once)])[0] == 0
    status, out, err = run_cli(["plan", *GRIPPER, "--realise", "3", "-o", str(again)])
    assert status == 0, err
    first, record = json.loads(once.read_text()), json.loads(again.read_text())
    block = record["realise"]
    assert block["attempts"] == 2 and block["realised"] and len(calls) == 2
    (rejected,) = block["rejected"]
    assert rejected["grasp"] == sorted(first["grasp"]) and "cannot reach its contact" in rejected["reason"]
    assert sorted(record["grasp"]) != rejected["grasp"] and record["q1"] <= first["q1"] + 1e-12
    assert "planning again without it" in err and "realise: plan 2 realised by the hand's fit" in out
    # The plan it returns is simulated like any other.
    status, _, err = run_cli(["evaluate", str(again), "--directions", "0", "--decomposition", "convex_hull"])
    assert status == 0, err


def test_a_grasp_realised_at_once_needs_one_plan(tmp_path):
    path = tmp_path / "p.json"
    status, _, err = run_cli(["plan", *GRIPPER, "--realise", "3", "-o", str(path)])
    assert status == 0, err
    block = json.loads(path.read_text())["realise"]
    assert block == {"attempts": 1, "realised": True, "rejected": []}
    assert np.isfinite(json.loads(path.read_text())["q1"])


def test_a_suite_method_table_takes_realise(tmp_path):
    """``realise = N`` in a suite's method table: part of the cell's parameters (and id), and the
    cell's plan carries the ``realise`` block; a table without it keeps the id it had."""
    from ogcp.benchmarks.suite.parse import parse_suite
    from ogcp.benchmarks.suite.runner import SuiteRunner
    from ogcp.benchmarks.suite.store import RESULTS

    text = """schema_version = 1
name = "realise"
objects = ["box"]
contacts = 40
m = [2]
diagonal = 0.08
contact_model = "soft"

[[methods]]
method = "astar"
hand = "parallel_gripper"
label = "A* gripper"

[[methods]]
method = "astar"
hand = "parallel_gripper"
realise = 3
label = "A* gripper, realised"
"""
    suite = parse_suite(text)
    plain, realised = suite.cells
    assert "realise" not in plain.canonical()["variant"] and realised.canonical()["variant"]["realise"] == 3
    assert plain.id != realised.id
    summary = SuiteRunner(suite, tmp_path / "run").run()
    assert summary.ran == 2 and summary.errors == 0
    records = {
        json.loads(line)["params"]["label"]: json.loads(line)
        for line in (tmp_path / "run" / RESULTS).read_text().splitlines()
    }
    assert "realise" not in records["A* gripper"]["plan"]
    assert records["A* gripper, realised"]["plan"]["realise"]["attempts"] == 1
