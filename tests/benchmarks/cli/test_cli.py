"""The ``ogcp`` command line, run in-process through ``ogcp.benchmarks.cli.app.main``."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, q1, sample_contacts
from tests.cli_run import run_cli

STATS_KEYS = {
    "created",
    "visited",
    "created_per_level",
    "visited_per_level",
    "q1_evaluations",
    "effective_branching_factor",
    "trace",
    "wall_seconds",
    "cpu_seconds",
}


@pytest.fixture(scope="module")
def box24_best() -> float:
    """Brute-force optimal Q1 over all 3-subsets of the CLI's default box set (n=24, seed 0)."""
    contacts = sample_contacts(builtin_mesh("box"), 24, seed=0)
    return max(q1(contacts.subset_wrenches(np.array(g))) for g in itertools.combinations(range(24), 3))


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory):
    """One ``plan box -n 24 -m 3 --json -o FILE`` run: (status, stdout, stderr, output path)."""
    path = tmp_path_factory.mktemp("plan") / "out.json"
    status, out, err = run_cli(["plan", "box", "-n", "24", "-m", "3", "--json", "-o", str(path)])
    return status, out, err, path


def test_contacts_command_writes_loadable_deterministic_file(tmp_path, capsys):
    first, second = tmp_path / "a.json", tmp_path / "b.json"
    assert main(["contacts", "box", "-n", "20", "--seed", "3", "-o", str(first)]) == 0
    assert "wrote 20 contacts" in capsys.readouterr().err
    assert main(["contacts", "box", "-n", "20", "--seed", "3", "-o", str(second)]) == 0
    assert first.read_bytes() == second.read_bytes()
    assert json.loads(first.read_text())["schema"] == "ogcp.contacts/1"
    contacts = ContactSet.load(first)
    assert len(contacts) == 20
    expected = sample_contacts(builtin_mesh("box"), 20, seed=3)
    assert np.array_equal(contacts.positions, expected.positions)
    assert contacts.source["name"] == "box" and contacts.source["seed"] == 3
    assert not list(tmp_path.glob("*.tmp"))


def test_plan_json_schema_and_optimality(plan_run, box24_best):
    status, out, _, _ = plan_run
    assert status == 0
    lines = out.strip().splitlines()
    assert len(lines) == 1
    record = json.loads(lines[0])
    assert record["schema"] == "ogcp.plan/1"
    assert record["method"] == "astar"
    grasp = record["grasp"]
    assert len(grasp) == 3 and grasp == sorted(grasp) and len(set(grasp)) == 3
    assert all(isinstance(i, int) and 0 <= i < 24 for i in grasp)
    assert STATS_KEYS <= set(record["stats"])
    stats = record["stats"]
    assert stats["created"] == sum(stats["created_per_level"]) and stats["visited"] == sum(stats["visited_per_level"])
    assert len(stats["trace"]) == stats["visited"]
    assert len(record["contacts"]["positions"]) == 3 and len(record["contacts"]["normals"]) == 3
    contacts = sample_contacts(builtin_mesh("box"), 24, seed=0)
    np.testing.assert_array_equal(record["contacts"]["positions"], contacts.positions[grasp])
    assert abs(record["q1"] - box24_best) < 1e-9
    assert abs(record["q1"] - q1(contacts.subset_wrenches(np.array(grasp)))) < 1e-9
    assert abs(record["bound"] - record["q1"]) < 1e-12
    assert record["q_ows"] >= record["q1"] > 0


def test_output_file_equals_printed_json(plan_run):
    _, out, _, path = plan_run
    assert json.loads(path.read_text()) == json.loads(out)


def test_plan_from_contact_file_matches_plan_from_object(tmp_path, plan_run):
    path = tmp_path / "box24.json"
    assert run_cli(["contacts", "box", "-n", "24", "--seed", "0", "-o", str(path)])[0] == 0
    status, out, _ = run_cli(["plan", str(path), "-m", "3", "--json"])
    assert status == 0
    from_file, from_object = json.loads(out), json.loads(plan_run[1])
    assert abs(from_file["q1"] - from_object["q1"]) < 1e-12
    assert from_file["grasp"] == from_object["grasp"]


def test_readable_summary(capsys, plan_run):
    assert main(["plan", "box", "-n", "24", "-m", "3"]) == 0
    text = capsys.readouterr().out
    assert "created" in text and "visited" in text
    grasp = json.loads(plan_run[1])["grasp"]
    assert str(grasp) in text
    for index in grasp:
        assert f"{index:5d}:" in text
    with pytest.raises(json.JSONDecodeError):
        json.loads(text)


def test_record_tree_writes_the_search_tree(capsys):
    assert main(["plan", "box", "-n", "24", "-m", "3", "--record-tree", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    tree = record["tree"]
    assert len(tree["parent"]) == len(tree["level"]) == len(tree["f"]) == record["stats"]["created"]
    assert sum(tree["visited"]) == record["stats"]["visited"]
    assert tree["path"][0] == 0 and tree["parent"][0] == -1


def _contact_json(tmp_path, bad_normal) -> str:
    normals = [[0.0, 0.0, 1.0], bad_normal, [1.0, 0.0, 0.0]]
    data = {
        "schema": "ogcp.contacts/1",
        "positions": [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]],
        "normals": normals,
        "com": [0.0, 0.0, 0.0],
        "torque_scale": 0.1,
        "mu": 0.5,
        "cone_edges": 8,
    }
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))  # json.dumps writes float("nan") as the token NaN
    assert ("NaN" in path.read_text()) == any(np.isnan(bad_normal))
    return str(path)


ERROR_CASES = {
    "missing file": (["plan", "nope.obj"], "not found"),
    "unknown object": (["plan", "teapot"], "amphora, box, donut, sphere"),
    "unknown method": (["plan", "box", "-n", "8", "--method", "bfs"], "astar, dijkstra, es, es-pruned, hfts, wastar"),
    "unknown successor": (["plan", "box", "-n", "8", "--successor", "xx"], "fc, ru"),
    "unknown heuristic": (["plan", "box", "-n", "8", "--heuristic", "xx"], "fc, none, ru"),
    "m > |C|": (["plan", "box", "-n", "5", "-m", "6"], "exceeds the number of contacts"),
    "m = 1": (["plan", "box", "-n", "8", "-m", "1"], "m must be an integer >= 2"),
    "negative eps": (["plan", "box", "-n", "8", "--method", "wastar", "--eps", "-1"], "eps: expected a number >= 0"),
    "negative eps astar": (["plan", "box", "-n", "8", "--eps", "-1"], "eps: expected a number >= 0"),
    "branching 1": (["plan", "box", "-n", "8", "--branching", "1"], "branching: expected an integer >= 2"),
    "dijkstra heuristic": (["plan", "box", "-n", "8", "--method", "dijkstra", "--heuristic", "fc"], "no heuristic"),
    "astar eps": (["plan", "box", "-n", "8", "--method", "astar", "--eps", "0.3"], "applies to method 'wastar'"),
    "bad max spread": (["plan", "box", "-n", "8", "--max-spread", "0"], "max_spread: expected a number > 0"),
    "tree of es": (["plan", "box", "-n", "8", "--method", "es", "--record-tree"], "applies to methods astar"),
    "memory limit of es": (["plan", "box", "-n", "8", "--method", "es", "--memory-limit", "2"], "applies to methods"),
}


@pytest.mark.parametrize("argv, message", ERROR_CASES.values(), ids=list(ERROR_CASES))
def test_errors_exit_2_with_one_line(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("ogcp: error:"), captured.err
    assert message in lines[0]
    assert "Traceback" not in captured.err and captured.out == ""
    assert not list(tmp_path.iterdir())  # nothing written on failure


def _assert_one_error_line(capsys, argv, message) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("ogcp: error:"), captured.err
    assert message in lines[0] and "Traceback" not in captured.err


def test_non_mesh_file_errors(capsys, tmp_path):
    garbage = tmp_path / "junk.stl"
    garbage.write_bytes(b"\x00\xffjunk bytes\x13\x37" * 9)
    _assert_one_error_line(capsys, ["plan", str(garbage)], str(garbage))
    text = tmp_path / "nofaces.obj"
    text.write_text("this is not a mesh\n")
    _assert_one_error_line(capsys, ["plan", str(text)], str(text))
    _assert_one_error_line(capsys, ["contacts", str(text), "-o", str(tmp_path / "o.json")], str(text))


@pytest.mark.parametrize("bad_normal, message", [([np.nan, 0.0, 1.0], "NaN"), ([0.0, 0.0, 0.0], "zero length")])
def test_bad_contact_file(capsys, tmp_path, bad_normal, message):
    path = _contact_json(tmp_path, bad_normal)
    _assert_one_error_line(capsys, ["plan", path, "-m", "2"], message)


def test_contact_count_with_contact_file(capsys, tmp_path):
    path = tmp_path / "c.json"
    assert main(["contacts", "box", "-n", "10", "-o", str(path)]) == 0
    capsys.readouterr()
    _assert_one_error_line(capsys, ["plan", str(path), "-n", "10"], "does not apply to a contact file")
    # A contact file's wrenches are fixed: a friction or cone flag would be silently ignored.
    _assert_one_error_line(capsys, ["plan", str(path), "--mu", "2"], "--mu does not apply to a contact file")
    _assert_one_error_line(capsys, ["plan", str(path), "--cone-edges", "16"], "--cone-edges does not apply")


def test_output_that_cannot_be_written_is_refused_before_planning(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    _assert_one_error_line(capsys, ["plan", "box", "-n", "8", "-o", str(blocker / "plan.json")], "is a file")


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "box", "-n", "abc"],
        ["plan", "box", "-n", "0"],
        ["plan", "box", "--eps", "x"],
        ["plan", "box", "--time-limit", "0"],
        ["contacts", "box", "-n", "8", "--cone-edges", "2", "-o", "x.json"],
        ["plan", "box", "--jobs", "100000", "--method", "es"],
        ["frobnicate"],
        [],
    ],
)
def test_argparse_errors_exit_2(capsys, argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert "error" in capsys.readouterr().err


def test_building_the_parser_imports_neither_mujoco_nor_matplotlib():
    code = (
        "import sys; from ogcp.benchmarks.cli import build_parser; build_parser();"
        "loaded = [m for m in ('mujoco', 'matplotlib', 'coacd') if m in sys.modules];"
        "assert not loaded, loaded"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
