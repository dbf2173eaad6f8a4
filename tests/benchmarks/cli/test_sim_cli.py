"""``ogcp evaluate`` and ``ogcp decompose`` as a user runs them."""

from __future__ import annotations

import json

import pytest

from tests.cli_run import run_cli


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plan") / "p.json"
    status, _, err = run_cli(["plan", "box", "-n", "40", "-m", "3", "-o", str(path)])
    assert status == 0, err
    return path


def test_evaluate_prints_measured_against_predicted(plan_file):
    status, out, _ = run_cli(["evaluate", str(plan_file), "--directions", "4", "--decomposition", "convex_hull"])
    assert status == 0
    assert "predicted     measured  unit" in out and "q1-weakest" in out and "N·m" in out
    assert "median fidelity" in out
    # Where the tips really started, and how far the collision surface is from the mesh.
    assert "realized contacts:" in out and "collision surface:" in out and "median Q1 change" in out


def test_refinement_flags_reach_the_settings(plan_file):
    from ogcp.benchmarks.cli.app import build_parser
    from ogcp.benchmarks.cli.simulate import _decomposition

    never = _decomposition(build_parser().parse_args(["evaluate", str(plan_file), "--refine"]))
    assert never.refine_thresholds == () and never.ladder == (never.threshold,)
    finer = _decomposition(
        build_parser().parse_args(
            ["evaluate", str(plan_file), "--refine", "0.03", "0.01", "--contact-tolerance", "0.001"]
        )
    )
    assert finer.ladder == (0.05, 0.03, 0.01) and finer.contact_tolerance == 0.001
    status, _, err = run_cli(["evaluate", str(plan_file), "--refine", "0.001"])
    assert status == 2 and "refine_thresholds" in err and err.count("\n") == 1


def test_evaluate_json_is_the_sim_schema(plan_file, tmp_path):
    target = tmp_path / "sim.json"
    status, out, _ = run_cli(
        ["evaluate", str(plan_file), "--directions", "2", "--decomposition", "convex_hull", "--json", "-o", str(target)]
    )
    assert status == 0
    record = json.loads(out)
    assert record == json.loads(target.read_text())
    assert record["schema"] == "ogcp.sim/2"
    grasp = record["grasps"][0]
    assert len(grasp["measured"]) == len(grasp["predicted"]) == 12 + 2 + 1
    assert "median_fidelity" in grasp and record["settings"]["directions"] == 2
    assert record["settings"]["decomposition"]["method"] == "convex_hull"


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such plan file"),
        ("{not json", "not valid JSON"),
        ('{"schema": "ogcp.contacts/1"}', "expected a plan"),
    ],
)
def test_evaluate_rejects_bad_plan_files(tmp_path, content, message):
    path = tmp_path / "bad.json"
    if content is not None:
        path.write_text(content)
    status, out, err = run_cli(["evaluate", str(path)])
    assert status == 2 and out == ""
    assert err.startswith("ogcp: error:") and message in err and err.count("\n") == 1


def test_evaluate_rejects_unknown_settings(plan_file, tmp_path):
    settings = tmp_path / "s.json"
    settings.write_text('{"ramp_speed": 3}')
    status, _, err = run_cli(["evaluate", str(plan_file), "--settings", str(settings)])
    assert status == 2 and "ramp_speed" in err and "ramp_time" in err


def test_decompose_fills_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    status, out, _ = run_cli(["decompose", "box", "--decomposition", "convex_hull", "--json"])
    assert status == 0
    meta = json.loads(out)
    assert meta["hull_count"] == 1 and str(tmp_path) in meta["cache_path"]
