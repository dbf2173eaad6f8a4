"""Fault corpus for the inputs added after the first hardening round: ``ogcp.grasps/1`` files, the
grasp converter, and results folders read by ``export``, ``view``, ``plot`` and ``report``.

Every case: exit status 2, one line on stderr, and no output file half written.
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.benchmarks.studies import convert_grasps

GOOD: dict[str, Any] = {
    "schema": "ogcp.grasps/1",
    "object": {"mesh": "box"},
    "mu": 0.5,
    "grasps": [
        {
            "label": "a",
            "contacts": [
                {"position": [0.0776, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0]},
                {"position": [-0.0776, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]},
            ],
        }
    ],
}


def _grasps(**changes: Any) -> dict[str, Any]:
    data = json.loads(json.dumps(GOOD))
    data.update(changes)
    return data


def _contact(data: dict[str, Any], key: str, value: list[float]) -> dict[str, Any]:
    data["grasps"][0]["contacts"][0][key] = value
    return data


def _millimetres() -> dict[str, Any]:
    data = _grasps()
    for contact in data["grasps"][0]["contacts"]:
        contact["position"] = [1000.0 * x for x in contact["position"]]
    return data


#: name -> (file content, a phrase the one line must hold)
GRASPS_CASES: dict[str, tuple[str | bytes, str]] = {
    "truncated": (json.dumps(GOOD)[:60], "not valid JSON"),
    "another schema": (json.dumps(_grasps(schema="ogcp.grasps/9")), "'ogcp.grasps/1', got 'ogcp.grasps/9'"),
    "NaN position": (json.dumps(GOOD).replace("0.0776", "NaN", 1), "position: expected 3 finite numbers"),
    "inf normal": (json.dumps(GOOD).replace("-1.0", "Infinity", 1), "normal: expected 3 finite numbers"),
    "off the mesh": (json.dumps(_contact(_grasps(), "position", [0.5, 0.0, 0.0])), "outside the object's surface"),
    "inside the mesh": (json.dumps(_contact(_grasps(), "position", [0.0, 0.0, 0.0])), "inside the object's surface"),
    "normal not unit": (json.dumps(_contact(_grasps(), "normal", [-2.0, 0.0, 0.0])), "expected a unit vector"),
    "normal outward": (json.dumps(_contact(_grasps(), "normal", [1.0, 0.0, 0.0])), "points out of the object"),
    "unknown object": (json.dumps(_grasps(object={"mesh": "no-such-object"})), "unknown object"),
    "millimetres": (json.dumps(_millimetres()), "look like millimetres"),
    "unknown contact model": (json.dumps(_grasps(contact_model="squishy")), "valid choices: hard, soft"),
    "conflicting contact model": (
        json.dumps(_grasps(contact_model="hard", torsional_friction=0.02)),
        "needs the soft contact model",
    ),
    "no grasps": (json.dumps(_grasps(grasps=[])), "expected a non-empty list of grasps"),
    "empty file": ("", "not a plan file"),
    "a mesh": (b"solid box\n\x96\x00", "not a plan file (expected ogcp.plan JSON"),
}


def _ogcp(argv: list[str]) -> tuple[int, list[str]]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, err.getvalue().splitlines()


@pytest.mark.parametrize("case", sorted(GRASPS_CASES))
def test_a_bad_grasps_file_is_refused_in_one_line_and_writes_nothing(tmp_path: Path, case: str) -> None:
    content, phrase = GRASPS_CASES[case]
    source = tmp_path / "grasps.json"
    source.write_bytes(content if isinstance(content, bytes) else content.encode())
    out = tmp_path / "sim.json"
    status, lines = _ogcp(["evaluate", str(source), "--directions", "2", "-o", str(out)])
    assert status == 2 and len(lines) == 1 and lines[0].startswith("ogcp: error: ")
    assert phrase in lines[0], lines[0]
    assert not out.exists()


def test_grasps_of_different_m_and_repeated_labels_are_accepted(tmp_path: Path) -> None:
    # Documented (docs/external_grasps.md): grasps may differ in m; labels need not be unique.
    data = _grasps()
    extra = {"position": [0.0, 0.0517, 0.0], "normal": [0.0, -1.0, 0.0]}
    data["grasps"].append({"label": "a", "contacts": [*data["grasps"][0]["contacts"], extra]})
    source = tmp_path / "grasps.json"
    source.write_text(json.dumps(data), encoding="utf-8")
    status, _ = _ogcp(["evaluate", str(source), "--directions", "2", "-o", str(tmp_path / "sim.json")])
    record = json.loads((tmp_path / "sim.json").read_text(encoding="utf-8"))
    assert status == 0 and [len(g["grasp"]) for g in record["grasps"]] == [2, 3]


def _converter_inputs(folder: Path) -> dict[str, Path]:
    (folder / "columns.csv").write_text("a,b,c\n1,2,3\n", encoding="utf-8")
    (folder / "empty.csv").write_text("", encoding="utf-8")
    np.save(folder / "shape.npy", np.zeros((3, 5)))
    np.save(folder / "none.npy", np.zeros((0, 2, 6)))
    return {
        "wrong columns": folder / "columns.csv",
        "empty table": folder / "empty.csv",
        "wrong shape": folder / "shape.npy",
        "no grasps": folder / "none.npy",
        "missing file": folder / "missing.csv",
    }


@pytest.mark.parametrize("case", ["wrong columns", "empty table", "wrong shape", "no grasps", "missing file"])
def test_a_bad_converter_input_is_refused_in_one_line(tmp_path: Path, capsys, case: str) -> None:
    source = _converter_inputs(tmp_path)[case]
    out = tmp_path / "grasps.json"
    status = convert_grasps.main([str(source), "-o", str(out), "--mesh", "box", "--mu", "0.5"])
    lines = capsys.readouterr().err.splitlines()
    assert status == 2 and len(lines) == 1 and str(source.name) in lines[0]
    assert not out.exists()


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny finished suite run (A* and ES on the box, no simulation)."""
    folder = tmp_path_factory.mktemp("run")
    suite = folder / "tiny.toml"
    suite.write_text(
        'schema_version = 1\nname = "tiny"\nobjects = ["box"]\ncontacts = 20\nm = [3]\n'
        '[[methods]]\nmethod = "astar"\n[[methods]]\nmethod = "es"\n',
        encoding="utf-8",
    )
    assert _ogcp(["suite", str(suite), "--out", str(folder / "run"), "-q"])[0] == 0
    return folder / "run"


def _damaged(run: Path, tmp_path: Path, how: str) -> Path:
    copy = tmp_path / how
    shutil.copytree(run, copy)
    results = copy / "results.jsonl"
    if how == "truncated":
        results.write_bytes(results.read_bytes()[:-40])
    elif how == "no manifest":
        (copy / "manifest.json").unlink()
    elif how == "other schema":
        lines = [json.loads(line) for line in results.read_text(encoding="utf-8").splitlines()]
        results.write_text("".join(json.dumps({**r, "schema": "ogcp.cell/9"}) + "\n" for r in lines), encoding="utf-8")
    return copy


def test_a_truncated_last_line_is_named_and_the_rest_exported(finished_run: Path, tmp_path: Path) -> None:
    run = _damaged(finished_run, tmp_path, "truncated")
    status, lines = _ogcp(["export", str(run)])
    assert status == 0 and lines == [lines[0]] and "last line is incomplete" in lines[0]
    assert len((run / "grasps.csv").read_text(encoding="utf-8").splitlines()) == 2  # header and the whole cell


def test_a_run_without_manifest_still_exports_and_plots(finished_run: Path, tmp_path: Path) -> None:
    run = _damaged(finished_run, tmp_path, "no manifest")
    assert _ogcp(["export", str(run)])[0] == 0
    assert _ogcp(["plot", str(run), "--out", str(tmp_path / "figures")])[0] == 0
    assert any((tmp_path / "figures").glob("*.pdf"))


def test_cells_of_another_schema_are_refused_in_one_line(finished_run: Path, tmp_path: Path) -> None:
    run = _damaged(finished_run, tmp_path, "other schema")
    status, lines = _ogcp(["export", str(run)])
    assert status == 2 and len(lines) == 1 and "schema 'ogcp.cell/9', this ogcp reads 'ogcp.cell/1'" in lines[0]
    assert not (run / "grasps.csv").exists()


def test_view_of_a_results_file_points_to_report(finished_run: Path) -> None:
    status, lines = _ogcp(["view", str(finished_run / "results.jsonl"), "--no-open"])
    assert status == 2 and len(lines) == 1 and f"ogcp report {finished_run}" in lines[0]


def test_an_output_that_cannot_be_written_is_one_line(finished_run: Path, tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("", encoding="utf-8")
    status, lines = _ogcp(["export", str(finished_run), "--out", str(blocker / "tables")])
    assert status == 2 and len(lines) == 1 and lines[0].startswith("ogcp: error: ")
