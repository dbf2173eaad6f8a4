"""Suites name hands by built-in name or by a descriptor path relative to the suite file."""

from __future__ import annotations

import json

import pytest

from ogcp.benchmarks.suite.parse import load_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.planner.infra import OgcpError
from tests.planner.hands.hand_files import write_mesh_hand

SUITE = """schema_version = 1
name = "claw"
objects = ["sphere"]
diagonal = 0.08
contacts = 30
m = [3]
simulate = false

[[methods]]
method = "astar"
hand = "hands/claw.toml"
label = "A* claw"
"""


def test_a_suite_plans_with_a_descriptor_relative_to_its_file(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_mesh_hand(tmp_path / "suites" / "hands")
    (tmp_path / "suites" / "claw.toml").write_text(SUITE)
    monkeypatch.chdir(tmp_path)  # not the suite's folder: the path is the suite's, not the shell's
    suite = load_suite(tmp_path / "suites" / "claw.toml")
    (cell,) = suite.cells
    assert dict(cell.variant)["hand"] == str(descriptor.resolve())
    summary = SuiteRunner(suite, tmp_path / "run", log=lambda _: None).run()
    assert summary.errors == 0
    (line,) = (tmp_path / "run" / "results.jsonl").read_text().splitlines()
    plan = json.loads(line)["plan"]
    assert plan["hand"]["name"] == "claw" and plan["hand"]["descriptor"] == str(descriptor.resolve())


def test_a_suite_whose_hand_has_too_few_fingers_or_is_missing_is_refused(tmp_path):
    write_mesh_hand(tmp_path / "hands")
    (tmp_path / "four.toml").write_text(SUITE.replace("m = [3]", "m = [4]"))
    with pytest.raises(OgcpError, match="methods\\[0\\].hand: the claw hand has 3 fingers.*m includes 4"):
        load_suite(tmp_path / "four.toml")
    (tmp_path / "gone.toml").write_text(SUITE.replace("hands/claw.toml", "hands/none.toml"))
    with pytest.raises(OgcpError, match="none.toml: cannot read the hand descriptor"):
        load_suite(tmp_path / "gone.toml")
