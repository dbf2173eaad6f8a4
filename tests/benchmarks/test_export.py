"""``ogcp export``: tidy grasp and direction tables with a column dictionary, from records alone."""

from __future__ import annotations

import contextlib
import csv
import io
from pathlib import Path

import pytest

from ogcp.benchmarks import cli
from ogcp.benchmarks.export import CELL_COLUMNS, DIRECTION_COLUMNS, GRASP_COLUMNS, export_run
from ogcp.benchmarks.suite.record import CellError, CellRecord
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner.infra import OgcpError

PARAMS = {"object": "box", "contacts": 12, "contact_seed": 0, "m": 3, "mu": 0.5, "cone_edges": 8}


def _simulation() -> dict[str, object]:
    grasp = {
        "label": "best",
        "grasp": [1, 5, 10],
        "q1": 0.07,
        "valid": True,
        "directions": ["+fx", "-fx"],
        "direction_vectors": [[1, 0, 0, 0, 0, 0], [-1, 0, 0, 0, 0, 0]],
        "predicted": [18.5, 4.6],
        "measured": [19.0, None],
        "censored": [False, True],
        "fidelity": [0.027, None],
        "predicted_min": 4.6,
        "measured_min": None,
        "median_fidelity": 0.027,
    }
    return {"schema": "ogcp.sim/2", "grasps": [grasp, {**grasp, "label": "hfts-run-1", "valid": False}]}


def _run(folder: Path) -> Path:
    store = ResultStore(folder)
    folder.mkdir()
    plan = {"method": "astar", "q1": 0.07, "q_ows": 0.12, "bound": 0.07, "stats": {"cpu_seconds": 0.25}}
    simulated = CellRecord(
        "aaa", {**PARAMS, "method": "astar", "label": "A*"}, ("g",), plan=plan, simulation=_simulation()
    )
    failed = CellRecord(
        "bbb", {**PARAMS, "method": "es", "label": "ES"}, status="error", error=CellError("OgcpError", "boom", "")
    )
    for record in (failed, simulated):
        store.append(record.to_dict())
    return folder


def _table(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.DictReader(handle))


def test_export_writes_one_row_per_grasp_and_direction(tmp_path: Path) -> None:
    run = _run(tmp_path / "run")
    written = export_run(run, tmp_path / "tables")
    assert [p.name for p in written] == ["grasps.csv", "directions.csv", "columns.md"]
    grasps = _table(written[0])
    assert list(grasps[0]) == [c[0] for c in CELL_COLUMNS + GRASP_COLUMNS]
    # Sorted by object and label: the ES cell failed (one row, grasp columns empty), A* has two grasps.
    assert [(r["label"], r["status"], r["error"], r["grasp"]) for r in grasps] == [
        ("A*", "ok", "", "best"),
        ("A*", "ok", "", "hfts-run-1"),
        ("ES", "error", "OgcpError", ""),
    ]
    assert float(grasps[0]["q1"]) == 0.07 and grasps[0]["plan_cpu_seconds"] == "0.25"
    assert grasps[0]["valid"] == "true" and grasps[1]["valid"] == "false" and grasps[0]["grasp_contacts"] == "1 5 10"
    assert grasps[0]["measured_min"] == "" and grasps[0]["n_directions"] == "2"
    directions = _table(written[1])
    assert list(directions[0]) == [c[0] for c in CELL_COLUMNS + DIRECTION_COLUMNS]
    assert len(directions) == 4
    first, second = directions[:2]
    assert (first["direction"], first["u_fx"], first["measured"], first["censored"]) == ("+fx", "1.0", "19.0", "false")
    assert (second["u_fy"], second["measured"], second["censored"]) == ("0.0", "", "true")
    dictionary = written[2].read_text(encoding="utf-8")
    assert "| q1 | dimensionless |" in dictionary and "| measured | N |" in dictionary
    assert all(f"| {c[0]} |" in dictionary for c in CELL_COLUMNS + GRASP_COLUMNS + DIRECTION_COLUMNS)


def test_export_defaults_to_the_run_folder_and_rejects_what_it_cannot_write(tmp_path: Path) -> None:
    run = _run(tmp_path / "run")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        assert cli.main(["export", str(run)]) == 0
    assert out.getvalue().split() == [str(run / n) for n in ("grasps.csv", "directions.csv", "columns.md")]
    with pytest.raises(OgcpError, match="no results.jsonl"):
        export_run(tmp_path / "absent")
    with pytest.raises(OgcpError, match="format"):
        export_run(run, fmt="xlsx")


def test_parquet_without_pyarrow_says_what_to_install(tmp_path: Path) -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        with pytest.raises(OgcpError, match="pip install pyarrow"):
            export_run(_run(tmp_path / "run"), fmt="parquet")
    else:  # pragma: no cover - pyarrow is not a dependency
        assert export_run(_run(tmp_path / "run"), fmt="parquet")[0].suffix == ".parquet"
