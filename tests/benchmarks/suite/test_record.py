"""The ``ogcp.cell/1`` record: built by run_cell through CellRecord, read back by CellRecord."""

from __future__ import annotations

import json

import pytest

from ogcp.benchmarks.suite.cells import run_cell
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.record import CELL_SCHEMA, PROBLEM_FIELDS, TRACEBACK_LINES, CellError, CellParams, CellRecord
from ogcp.planner.infra import OgcpError

SUITE = "schema_version = 1\nobjects = ['box']\ncontacts = 12\n[[methods]]\nmethod = 'astar'\nlabel = 'A*'\n"


def _line(record: dict) -> dict:
    """The record as results.jsonl holds it."""
    return json.loads(json.dumps(record, allow_nan=False))


def test_a_cell_record_round_trips_through_its_parser() -> None:
    (cell,) = parse_suite(SUITE).cells
    line = _line(run_cell(cell))
    assert line["schema"] == CELL_SCHEMA and list(line) == [
        "schema",
        "id",
        "params",
        "groups",
        "status",
        "error",
        "plan",
        "simulation",
        "simulation_seconds",
        "wall_seconds",
        "cpu_seconds",
        "finished_at",
    ]
    record = CellRecord.from_dict(line)
    assert record.to_dict() == line and json.dumps(record.to_dict()) == json.dumps(line)  # same keys, same order
    assert record.ok and record.id == cell.id and record.params == cell.params() and record.error is None
    assert (record.method, record.object, record.label) == ("astar", "box", "A*")
    assert record.problem == tuple(cell.params().get(k) for k in PROBLEM_FIELDS)
    assert record.plan["schema"] == "ogcp.plan/1" and record.simulation is None
    assert record.plan_view is not None and record.plan_view.q1 == record.plan["q1"]


def test_the_params_block_is_written_by_cell_params_and_read_by_the_record() -> None:
    (cell,) = parse_suite(SUITE).cells
    params = cell.params()
    assert params == CellParams(**{**params, "variant": dict(cell.variant)}).to_dict()
    assert list(params) == [
        "object",
        "contacts",
        "contact_seed",
        "m",
        "mu",
        "cone_edges",
        "diagonal",
        "tip_radius",
        "method",
        "variant",
        "label",
    ]
    assert params["tip_radius"] == "default"
    present = [k for k in PROBLEM_FIELDS if k in params]  # a hard cell leaves torsional_friction out
    assert list(params)[: len(present)] == present and present == list(PROBLEM_FIELDS[:-1])
    record = CellRecord(cell.id, params)
    assert (record.contacts, record.contact_seed, record.m, record.variant) == (12, 0, 3, dict(cell.variant))
    empty = CellRecord("x", {"m": True})
    assert (empty.contacts, empty.contact_seed, empty.m, empty.method, empty.label, empty.plan_view) == (None,) * 6


def test_a_failing_cell_records_its_error(monkeypatch: pytest.MonkeyPatch) -> None:
    (cell,) = parse_suite(SUITE).cells

    def fail(*args: object) -> None:
        raise OgcpError("no contacts today\nsecond line")

    monkeypatch.setattr("ogcp.benchmarks.suite.cells.contact_set", fail)
    line = _line(run_cell(cell))
    record = CellRecord.from_dict(line)
    assert record.status == "error" and record.plan is None and record.to_dict() == line
    assert (record.error.type, record.error.message) == ("OgcpError", "no contacts today")
    assert "in fail" in record.error.traceback and len(record.error.traceback.splitlines()) <= TRACEBACK_LINES
    assert record.describe() == "box n=12 seed=0 m=3 A*"


def test_error_of_an_exception_keeps_the_tail_of_its_traceback() -> None:
    def ping(n: int) -> None:
        if n == 0:
            raise ValueError("")
        pong(n - 1)

    def pong(n: int) -> None:
        ping(n)  # two alternating frames: Python folds only repeats of one line

    try:
        ping(30)
    except ValueError as exc:
        error = CellError.from_exception(exc)
    assert error.type == "ValueError" and error.message == ""
    lines = error.traceback.splitlines()
    assert len(lines) == TRACEBACK_LINES and lines[-1] == "ValueError"
    assert CellError.from_dict(error.to_dict()) == error and CellError.from_dict({}).type == "error"


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ([1, 2], "not a cell record with an id"),
        ({"status": "ok", "params": {}}, "not a cell record with an id"),
        ({"id": "x", "status": "ok"}, "record x has no params/status"),
        ({"id": "x", "params": {}}, "record x has no params/status"),
    ],
)
def test_what_is_not_a_cell_record_is_refused(data: object, message: str) -> None:
    with pytest.raises(OgcpError, match=message):
        CellRecord.from_dict(data)


def test_other_keys_read_leniently() -> None:
    record = CellRecord.from_dict({"id": "x", "params": {}, "status": "ok", "plan": [], "wall_seconds": True})
    assert record.plan is None and record.wall_seconds is None and record.groups == () and record.variant == {}
    assert record.method is None and record.label is None and record.object == "None"
