"""The paper-scale timing study (ogcp.benchmarks.studies.paper_scale): rows, resumption, stopped searches."""

from __future__ import annotations

import csv
import itertools
import types

import pytest

from ogcp.benchmarks.studies import paper_scale
from ogcp.planner.search import best_first as search_run


def _rows(out):
    with open(out / "runs.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def test_finished_runs_record_status_bound_and_memory_and_resume(tmp_path):
    argv = ["--out", str(tmp_path), "-n", "30", "--objects", "box", "--eps", "0.4"]
    argv += ["--more-fingers", "4", "--more-fingers-objects", "box"]
    assert paper_scale.main(argv) == 0
    rows = _rows(tmp_path)
    assert [(r["method"], r["m"]) for r in rows] == [("astar", "3"), ("wastar", "3"), ("astar", "4")]
    for row in rows:
        assert row["status"] in ("optimal", "bounded") and int(row["peak_mib"]) > 0 and row["forgotten"] == "0"
        assert float(row["bound"]) >= float(row["q1"]) > 0
    assert rows[0]["status"] == "optimal" and float(rows[0]["bound"]) == float(rows[0]["q1"])
    assert paper_scale.main(argv) == 0  # everything recorded: nothing runs again
    assert len(_rows(tmp_path)) == 3
    assert "| A*, m = 4 |" in (tmp_path / "table.md").read_text()


def test_a_stopped_search_is_a_row_with_its_gap(tmp_path, monkeypatch):
    # The search's clock ticks 1 s a reading: the 30 s limit stops it long before it ends.
    ticks = itertools.count()
    clock = types.SimpleNamespace(perf_counter=lambda: float(next(ticks)), process_time=lambda: 0.0)
    monkeypatch.setattr(search_run, "time", clock)
    argv = ["--out", str(tmp_path), "-n", "40", "--objects", "", "--more-fingers", "5"]
    argv += ["--more-fingers-objects", "sphere", "--time-limit", "30"]
    assert paper_scale.main(argv) == 0
    (row,) = _rows(tmp_path)
    assert row["status"] == "stopped" and float(row["bound"]) > float(row["q1"])
    assert "stopped, gap" in (tmp_path / "table.md").read_text()
    assert paper_scale.main(argv) == 0 and len(_rows(tmp_path)) == 1  # recorded: skipped
    monkeypatch.undo()  # a real clock: the search now ends well inside the limit
    assert paper_scale.main([*argv, "--retry-stopped"]) == 0
    stopped, finished = _rows(tmp_path)
    assert stopped == row and finished["status"] == "optimal" and float(finished["bound"]) == float(finished["q1"])
    assert "stopped, gap" not in (tmp_path / "table.md").read_text()  # the newer row counts


def test_a_search_past_its_memory_limit_is_a_row_with_its_gap(tmp_path, monkeypatch):
    """The process allowance shrunk so that a few kilobytes of open states reach the limit."""
    from ogcp.planner.search import memory

    monkeypatch.setattr(memory, "PROCESS_BYTES", 2**30 - 8 * 1024)
    monkeypatch.setattr(memory, "MIN_STATES_BYTES", 1024)
    argv = ["--out", str(tmp_path), "-n", "40", "--objects", "", "--more-fingers", "4"]
    argv += ["--more-fingers-objects", "sphere", "--memory-limit", "1"]
    assert paper_scale.main(argv) == 0
    (row,) = _rows(tmp_path)
    assert row["status"] == "memory" and int(row["forgotten"]) > 0 and float(row["bound"]) > float(row["q1"])
    assert "memory, gap" in (tmp_path / "table.md").read_text()
    monkeypatch.undo()  # the real allowance: the search ends within it
    assert paper_scale.main([*argv, "--retry-stopped"]) == 0
    assert _rows(tmp_path)[1]["status"] == "optimal"


def test_a_runs_file_of_older_columns_is_rewritten_with_the_new_ones(tmp_path):
    old = ("object", "n", "m", "method", "eps", "q1", "grasp", "created", "visited", "b_star", "wall_s", "cpu_s")
    with open(tmp_path / "runs.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(old)
        writer.writerow(["box", "30", "3", "astar", "0.0", "0.1", "1 2 3", "10", "5", "1.5", "0.1", "0.1"])
    assert paper_scale.main(["--out", str(tmp_path), "-n", "30", "--objects", "box", "--eps", ""]) == 0
    (row,) = _rows(tmp_path)  # kept, not run again
    assert tuple(row) == paper_scale.FIELDS and row["q1"] == "0.1" and row["status"] == ""


def test_a_time_limit_out_of_range_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit):
        paper_scale.main(["--out", str(tmp_path), "--time-limit", "0"])
    assert "--time-limit must be in (0," in capsys.readouterr().err
    with pytest.raises(SystemExit):
        paper_scale.main(["--out", str(tmp_path), "--memory-limit", "0"])
    assert "--memory-limit must be > 0 GiB" in capsys.readouterr().err
