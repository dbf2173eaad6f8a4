"""Suite progress off a terminal (-q, -v, periodic lines) and the per-process kernel warm-up.

The cells are stubbed (no planning): these tests check the runner's reporting and timing
bookkeeping, serially, in this process.
"""

from __future__ import annotations

import contextlib
import io
import json
import time
from pathlib import Path
from typing import Any

import pytest

from ogcp.benchmarks import cli
from ogcp.benchmarks.compare import compare_dirs
from ogcp.benchmarks.suite import runner
from ogcp.benchmarks.suite.manifest import kernel_warmups
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import ResultStore

SUITE = """
schema_version = 1
name = "stub"
objects = ["box"]
contacts = 12
contact_seeds = [0, 1, 2]
m = [3]

[[methods]]
method = "astar"
label = "A*"
"""


@pytest.fixture
def stub(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """Cells that only record their parameters; a kernel warm-up that counts its calls."""
    calls: list[float] = []

    def run_cell(cell: Any, settings: Any, time_limit: Any, memory_limit: Any) -> dict[str, Any]:
        plan = {"method": "astar", "q1": 0.07, "q_ows": 0.1, "bound": 0.07, "stats": {"cpu_seconds": 0.1}}
        return CellRecord(cell.id, cell.params(), plan=plan, wall_seconds=0.5).to_dict()

    def warm_up(methods: Any = (), announce: Any = None) -> float:
        calls.append(3.5)
        return 3.5

    monkeypatch.setattr(runner, "run_cell", run_cell)
    monkeypatch.setattr("ogcp.planner.methods.warm_up.warm_up", warm_up)
    monkeypatch.setattr(runner, "_WARMED", set())
    return calls


def _run(folder: Path, **options: Any) -> list[str]:
    lines: list[str] = []
    SuiteRunner(parse_suite(SUITE), folder, log=lines.append, **options).run()
    return lines


def test_warm_up_runs_once_per_process_and_is_recorded(tmp_path: Path, stub: list[float]) -> None:
    _run(tmp_path / "a")
    _run(tmp_path / "b")
    assert stub == [3.5]  # the second run's process was already warm
    first = json.loads((tmp_path / "a" / "manifest.json").read_text())
    second = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert first["sessions"][-1]["kernel_warmup_seconds"] == [3.5]
    assert second["sessions"][-1]["kernel_warmup_seconds"] == [0.0]
    assert kernel_warmups(first) == [3.5] and kernel_warmups({"sessions": [{}]}) is None


def test_periodic_lines_are_throttled_and_end_with_the_last_cell(tmp_path: Path, stub: list[float]) -> None:
    every = _run(tmp_path / "a", lines="periodic", interval=0.0)
    assert every[0] == "ogcp: stub: 3 cells to run, 0 of 3 done before"  # at once, before any cell
    assert len(every) == 4 and every[-1].startswith("ogcp: stub: 3/3 cells, 0 errors, ")
    assert "elapsed, ETA" in every[1]
    throttled = _run(tmp_path / "b", lines="periodic", interval=1e9)
    assert [line.split(" cells")[0] for line in throttled[1:]] == ["ogcp: stub: 1/3", "ogcp: stub: 3/3"]
    assert _run(tmp_path / "c") == []


def test_verbose_lines_name_each_cell(tmp_path: Path, stub: list[float]) -> None:
    lines = _run(tmp_path / "a", lines="each")[1:]
    assert len(lines) == 3 and lines[0].startswith("ogcp: [1/3] box n=12 seed=")
    assert lines[0].endswith("m=3 A* ok: Q1 0.070000, 0.50 s")


def test_a_silent_stretch_gets_a_line_at_least_every_heartbeat(
    tmp_path: Path, stub: list[float], monkeypatch: pytest.MonkeyPatch
) -> None:
    def slow_cell(cell: Any, settings: Any, time_limit: Any, memory_limit: Any) -> dict[str, Any]:
        time.sleep(1.6)  # a long cell: no cell line for a while
        plan = {"method": "astar", "q1": 0.07, "q_ows": 0.1, "bound": 0.07, "stats": {"cpu_seconds": 0.1}}
        return CellRecord(cell.id, cell.params(), plan=plan, wall_seconds=1.6).to_dict()

    monkeypatch.setattr(runner, "run_cell", slow_cell)
    monkeypatch.setattr("ogcp.benchmarks.suite.progress.HEARTBEAT_S", 0.5)
    lines = _run(tmp_path / "a", lines="periodic", interval=1e9, max_cells=1)
    assert lines[0].startswith("ogcp: stub: 1 cells to run")
    beats = [line for line in lines if line.endswith("elapsed, running")]
    assert beats and beats[0].startswith("ogcp: stub: 0/3 cells, 0 errors, ")
    assert lines[-1].startswith("ogcp: stub: 1/3 cells")


def test_cli_quiet_and_off_terminal_progress(tmp_path: Path, stub: list[float]) -> None:
    suite = tmp_path / "stub.toml"
    suite.write_text(SUITE, encoding="utf-8")

    def ogcp(*argv: str) -> str:
        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            assert cli.main(["suite", str(suite), *argv]) == 0
        return err.getvalue()

    assert "3/3 cells" in ogcp("--out", str(tmp_path / "a"))  # stderr is no terminal here
    assert ogcp("--out", str(tmp_path / "b"), "-q") == ""
    assert ogcp("--out", str(tmp_path / "c"), "-v").count("ogcp: [") == 3


def test_compare_notes_compiled_and_unwarmed_runs(tmp_path: Path, stub: list[float]) -> None:
    _run(tmp_path / "run")  # warm-up 3.5 s: compiled
    _run(tmp_path / "base")  # already warm: 0 s
    text, status = compare_dirs(tmp_path / "run", tmp_path / "base")
    assert status == 0 and "note: RUN: compiled the kernels (warm-up up to 3.5 s per process" in text
    assert "BASELINE: compiled" not in text and "no kernel warm-up recorded" not in text
    store = ResultStore(tmp_path / "base")
    manifest = store.read_manifest()
    assert manifest is not None
    for session in manifest["sessions"]:
        del session["kernel_warmup_seconds"]  # as a run made before the warm-up
    store.write_manifest(manifest)
    text, _ = compare_dirs(tmp_path / "run", tmp_path / "base")
    assert "note: BASELINE: no kernel warm-up recorded" in text
