"""A suite's time limit holds for a search or exhaustive-search cell whose m is too large to finish."""

from __future__ import annotations

import time
from pathlib import Path

from ogcp.benchmarks.suite.parse import load_suite
from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import ResultStore

SUITE = """schema_version = 1
name = "large-m"
objects = ["box"]
contacts = 60
m = [30]

[[methods]]
method = "wastar"
label = "WA*"

[[methods]]
method = "es"
label = "ES"
"""


def test_a_large_m_cell_stops_at_its_time_limit_with_a_certified_grasp(tmp_path: Path) -> None:
    suite = tmp_path / "large.toml"
    suite.write_text(SUITE, encoding="utf-8")
    start = time.perf_counter()
    summary = SuiteRunner(load_suite(suite), tmp_path / "run", time_limit=2.0).run()
    assert time.perf_counter() - start < 30.0  # before: no answer in minutes
    assert summary.ran == 2
    lines = ResultStore(tmp_path / "run").read().records
    assert sorted(line["params"]["method"] for line in lines) == ["es", "wastar"]
    for line in lines:  # exhaustive search too: before, listing its 1e17 grasps' chunks never ended
        record = CellRecord.from_dict(line)
        view = record.plan_view
        assert record.status == "stopped" and view is not None and view.q1 is not None and view.bound is not None
        assert 0 < view.q1 <= view.bound <= view.q_ows
