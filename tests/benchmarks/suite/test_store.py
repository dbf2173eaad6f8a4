"""The results store: whole lines only, torn tails ignored and cut, strict JSON, one writer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ogcp.benchmarks.suite.store import ResultStore, jsonable, read_results
from ogcp.planner.infra import OgcpError


def _records(k: int) -> list[dict]:
    return [{"id": f"cell{i}", "status": "ok", "value": i * 0.5} for i in range(k)]


def test_appended_records_read_back_in_order(tmp_path):
    store = ResultStore(tmp_path / "out")
    for record in _records(4):
        store.append(record)
    report = store.read()
    assert list(report.records) == _records(4)
    assert report.problems == () and report.partial_tail == 0
    text = store.results_path.read_text()
    assert text.count("\n") == 4 and text.endswith("\n")


def test_torn_last_line_is_reported_ignored_and_cut(tmp_path):
    store = ResultStore(tmp_path)
    for record in _records(3):
        store.append(record)
    whole = store.results_path.stat().st_size
    with open(store.results_path, "ab") as handle:  # a crash in the middle of a write
        handle.write(b'{"id": "cell3", "status": "o')
    report = store.read()
    assert [r["id"] for r in report.records] == ["cell0", "cell1", "cell2"]
    assert report.partial_tail == store.results_path.stat().st_size - whole > 0
    assert any("incomplete" in p for p in report.problems)
    assert store.cut_partial_tail() == report.partial_tail
    assert store.results_path.stat().st_size == whole
    store.append({"id": "cell3", "status": "ok"})
    assert [r["id"] for r in store.read().records] == ["cell0", "cell1", "cell2", "cell3"]


def test_invalid_complete_lines_are_reported_not_read(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(b'{"id": "a", "status": "ok"}\nnot json\n[1, 2]\n{"status": "ok"}\n{"id": "b"}\n')
    report = read_results(path)
    assert [r["id"] for r in report.records] == ["a", "b"]
    assert len(report.problems) == 3
    assert "line 2" in report.problems[0] and "line 4" in report.problems[2]


def test_latest_record_of_a_cell_wins(tmp_path):
    store = ResultStore(tmp_path)
    store.append({"id": "x", "status": "error"})
    store.append({"id": "y", "status": "ok"})
    store.append({"id": "x", "status": "ok"})
    latest = store.read().latest()
    assert set(latest) == {"x", "y"} and latest["x"]["status"] == "ok"


def test_missing_file_reads_as_empty(tmp_path):
    report = read_results(tmp_path / "none.jsonl")
    assert report.records == () and report.size == 0


def test_records_are_strict_json_with_numpy_values(tmp_path):
    store = ResultStore(tmp_path)
    store.append(
        {
            "id": "n",
            "nan": math.nan,
            "inf": -math.inf,
            "np": np.int64(7),
            "arr": np.arange(3),
            "f": np.float64(0.25),
            "nested": [{"v": np.float32(np.nan)}],
        }
    )
    line = store.results_path.read_text()
    assert "NaN" not in line and "Infinity" not in line
    record = json.loads(line)
    assert record == {
        "id": "n",
        "nan": None,
        "inf": None,
        "np": 7,
        "arr": [0, 1, 2],
        "f": 0.25,
        "nested": [{"v": None}],
    }
    assert jsonable((1, np.bool_(True))) == [1, True]


def test_manifest_round_trip_and_garbage(tmp_path):
    store = ResultStore(tmp_path)
    assert store.read_manifest() is None
    store.write_manifest({"suite": {"hash": "abc"}, "count": np.int64(2)})
    assert store.read_manifest() == {"suite": {"hash": "abc"}, "count": 2}
    store.manifest_path.write_text("[1,")
    with pytest.raises(OgcpError, match="manifest.json"):
        store.read_manifest()


def test_lock_is_exclusive_and_released(tmp_path):
    store = ResultStore(tmp_path / "out")
    with store.lock(), pytest.raises(OgcpError, match="in use by another"), ResultStore(tmp_path / "out").lock():
        pass
    with store.lock():  # released on exit
        pass
