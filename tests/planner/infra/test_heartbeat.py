"""The progress heartbeat: lines while the work runs, none after, and never a traceback."""

from __future__ import annotations

import threading
import time

import pytest

from ogcp.planner.infra.heartbeat import Heartbeat


def test_lines_come_while_the_work_runs_and_stop_with_it() -> None:
    lines: list[str] = []
    count = iter(range(1000))
    with Heartbeat(lines.append, lambda: f"line {next(count)}", every=0.02):
        time.sleep(0.2)
    seen = len(lines)
    time.sleep(0.1)
    assert seen >= 2 and len(lines) == seen and lines[0] == "line 0"


def test_nothing_starts_without_a_place_for_lines() -> None:
    before = threading.active_count()
    with Heartbeat(None, lambda: "never", every=0.01) as beat:
        assert beat._thread is None and threading.active_count() == before


def test_a_failing_line_ends_the_heartbeat_quietly(capfd: pytest.CaptureFixture[str]) -> None:
    def broken() -> str:
        raise RuntimeError("dictionary changed size during iteration")

    lines: list[str] = []
    with Heartbeat(lines.append, broken, every=0.01):
        time.sleep(0.1)
    assert lines == [] and "Traceback" not in capfd.readouterr().err
