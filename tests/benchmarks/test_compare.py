"""``ogcp compare``: identical runs pass, injected regressions fail naming the row, bad input exits 2."""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from ogcp.benchmarks import cli
from ogcp.benchmarks.compare import Tolerances, compare_dirs
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.planner.infra import OgcpError

SUITE = """
schema_version = 1
name = "compare-test"
objects = ["box"]
contacts = 16
m = [3]

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "wastar"
eps = 0.5
label = "WA*"

[[methods]]
method = "es"
label = "ES"

[[methods]]
method = "hfts"
runs = 3
iterations = 5
label = "HFTS"
"""


def _ogcp(argv: list[str], monkeypatch: pytest.MonkeyPatch) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(argv)
    return status, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def baseline(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("baseline") / "out"
    SuiteRunner(parse_suite(SUITE), out).run()
    return out


@pytest.fixture
def run(baseline, tmp_path) -> Path:
    """A copy of the baseline to edit."""
    return Path(shutil.copytree(baseline, tmp_path / "run"))


def _edit(directory: Path, label: str, change: Callable[[dict], dict | None]) -> None:
    """Rewrite the record(s) with this label through ``change`` (None drops the line)."""
    path = directory / "results.jsonl"
    lines = []
    for line in path.read_text().splitlines():
        record = json.loads(line)
        if record["params"]["label"] == label:
            record = change(record)
        if record is not None:
            lines.append(json.dumps(record))
    path.write_text("".join(line + "\n" for line in lines))


def _simulated(valid: bool, resistance: float) -> Callable[[dict], dict]:
    def change(record: dict) -> dict:
        record["simulation"] = {
            "schema": "ogcp.sim/1",
            "grasps": [{"label": "best", "grasp": record["plan"]["grasp"], "valid": valid, "measured_min": resistance}],
        }
        return record

    return change


def _regressions(text: str) -> list[str]:
    return [line.strip() for line in text.splitlines() if line.startswith("  ")]


def _verdicts(text: str) -> dict[str, str]:
    rows = [line.split() for line in text.splitlines() if line.startswith("box ")]
    return {" ".join(row[1:-6]): row[-1] for row in rows}


def test_identical_runs_pass(baseline, run, monkeypatch):
    status, text, _ = _ogcp(["compare", str(run), str(baseline)], monkeypatch)
    assert status == 0 and "no regressions" in text
    assert _verdicts(text) == {"A*": "ok", "WA*": "ok", "ES": "ok", "HFTS": "ok"}


def test_a_fresh_run_of_the_same_suite_passes(baseline, tmp_path):
    SuiteRunner(parse_suite(SUITE), tmp_path / "again").run()
    text, status = compare_dirs(tmp_path / "again", baseline)
    assert status == 0, text


def test_lowered_optimal_q1_is_an_optimality_and_a_q1_regression(baseline, run, monkeypatch):
    def lower(record: dict) -> dict:
        record["plan"]["q1"] -= 1e-3
        return record

    _edit(run, "A*", lower)
    status, text, _ = _ogcp(["compare", str(run), str(baseline)], monkeypatch)
    assert status == 1
    found = _regressions(text)
    assert {line.split(":")[0] for line in found} == {"optimality", "q1"}
    assert all(line.split(": ")[1].startswith("box / A* [n=16 seed=0 m=3") for line in found)
    assert _verdicts(text) == {"A*": "REGRESSED", "WA*": "ok", "ES": "ok", "HFTS": "ok"}
    assert (
        _ogcp(
            ["compare", str(run), str(baseline), "--q1-tolerance", "0.01", "--optimality-tolerance", "0.01"],
            monkeypatch,
        )[0]
        == 0
    )


def test_lowered_hfts_q1_and_broken_wastar_bound(baseline, run):
    def lower(record: dict) -> dict:
        record["plan"]["q1"] *= 0.5
        return record

    _edit(run, "HFTS", lower)
    records = [json.loads(line) for line in (run / "results.jsonl").read_text().splitlines()]
    optimum = next(r["plan"]["q1"] for r in records if r["params"]["label"] == "ES")
    # With Q_OWS just above the optimum, eps = 0.5 guarantees Q1 >= 0.95 of the optimum.
    _edit(run, "WA*", lambda r: {**r, "plan": {**r["plan"], "q_ows": 1.1 * optimum, "q1": 0.5 * optimum}})
    text, status = compare_dirs(run, baseline)
    kinds = sorted((line.split(":")[0], line.split(" / ")[1].split(" [")[0]) for line in _regressions(text))
    assert status == 1 and kinds == [("bound", "WA*"), ("q1", "HFTS"), ("q1", "WA*")]


def test_slower_cell_fails_beyond_the_time_ratio(baseline, run, monkeypatch):
    def slower(record: dict) -> dict:
        record["plan"]["stats"]["cpu_seconds"] = 10 * max(record["plan"]["stats"]["cpu_seconds"], 1.0) + 5
        return record

    _edit(run, "ES", slower)
    status, text, _ = _ogcp(["compare", str(run), str(baseline)], monkeypatch)
    assert status == 1 and _regressions(text)[0].startswith("time: box / ES")
    assert _verdicts(text)["ES"] == "REGRESSED" and _verdicts(text)["A*"] == "ok"
    assert _ogcp(["compare", str(run), str(baseline), "--time-ratio", "100"], monkeypatch)[0] == 0
    # The cells' own times were not touched.
    assert _ogcp(["compare", str(run), str(baseline), "--time-key", "wall"], monkeypatch)[0] == 0
    _edit(run, "ES", lambda r: {**r, "cpu_seconds": 10 * max(r["cpu_seconds"], 1.0) + 5})
    assert _ogcp(["compare", str(run), str(baseline), "--time-key", "cpu"], monkeypatch)[0] == 1


def test_failed_gate_and_lower_resistance(baseline, run, tmp_path, monkeypatch):
    reference = Path(shutil.copytree(baseline, tmp_path / "reference"))
    _edit(reference, "A*", _simulated(True, 4.0))
    _edit(run, "A*", _simulated(False, 3.0))
    status, text, _ = _ogcp(["compare", str(run), str(reference)], monkeypatch)
    found = _regressions(text)
    assert status == 1 and [line.split(":")[0] for line in found] == ["gates", "resistance"]
    assert all(line.split(": ")[1].startswith("box / A*") for line in found) and "grasp best" in found[1]
    _edit(run, "A*", _simulated(True, 3.0))
    status, text, _ = _ogcp(["compare", str(run), str(reference), "--resistance-tolerance", "0.3"], monkeypatch)
    assert status == 0, text


def test_missing_and_failed_cells(baseline, run, monkeypatch):
    _edit(run, "HFTS", lambda r: None)
    _edit(
        run,
        "ES",
        lambda r: {
            **r,
            "status": "error",
            "plan": None,
            "error": {"type": "OgcpError", "message": "boom", "traceback": ""},
        },
    )
    status, text, _ = _ogcp(["compare", str(run), str(baseline)], monkeypatch)
    assert status == 1
    assert sorted(line.split(" [")[0] for line in _regressions(text)) == ["error: box / ES", "missing: box / HFTS"]
    status, text, _ = _ogcp(["compare", str(run), str(baseline), "--allow-missing"], monkeypatch)
    assert status == 1 and "1 cells of BASELINE missing from RUN (allowed)" in text
    assert [line.split(" [")[0] for line in _regressions(text)] == ["error: box / ES"]


def test_torn_tail_is_noted_not_fatal(baseline, run):
    with open(run / "results.jsonl", "ab") as handle:
        handle.write(b'{"id": "abc", "par')
    text, status = compare_dirs(run, baseline)
    assert status == 0 and "note: RUN: results.jsonl: last line is incomplete" in text


@pytest.mark.parametrize(
    "argv,message",
    [
        (["compare", "{tmp}/nothing", "{base}"], "no such folder"),
        (["compare", "{tmp}", "{base}"], "no results.jsonl"),
        (["compare", "{base}", "{base}", "--q1-tolerance", "-1"], "q1 tolerance must be a number >= 0"),
        (["compare", "{base}", "{base}", "--time-ratio", "0.5"], "time ratio must be a number >= 1"),
        (
            ["compare", "{base}", "{base}", "--time-key", "gpu"],
            "unknown time key 'gpu'; valid choices: cpu, plan, wall",
        ),
    ],
)
def test_bad_input_exits_2(baseline, tmp_path, monkeypatch, argv, message):
    argv = [a.format(tmp=tmp_path, base=baseline) for a in argv]
    status, _, err = _ogcp(argv, monkeypatch)
    assert status == 2 and message in err


def test_records_that_are_not_cells_are_refused(tmp_path):
    (tmp_path / "results.jsonl").write_text('{"id": "x"}\n')
    with pytest.raises(OgcpError, match="not a cell record"):
        compare_dirs(tmp_path, tmp_path)
    with pytest.raises(OgcpError, match="time ratio"):
        compare_dirs(tmp_path, tmp_path, Tolerances(time_ratio=0.1))
