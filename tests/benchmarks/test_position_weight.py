"""The position-weight study (benchmarks.studies.position_weight): its inputs and one small case."""

from __future__ import annotations

import pytest

from benchmarks.studies import position_weight
from planner.infra import OgcpError


def test_cases_and_weights_are_parsed_and_checked():
    assert position_weight.parse_cases("bunny:4, plane:5") == [("bunny", 4), ("plane", 5)]
    assert position_weight.parse_weights("1,2.5") == [1.0, 2.5]
    for bad in ("bunny", "bunny:x", ":3", "box:1"):
        with pytest.raises(OgcpError, match="is not OBJECT:M"):
            position_weight.parse_cases(bad)
    with pytest.raises(OgcpError, match="comma-separated list of numbers"):
        position_weight.parse_weights("1,two")
    with pytest.raises(OgcpError, match="must be > 0"):
        position_weight.parse_weights("1,0")


def test_every_weight_reaches_the_same_optimum():
    rows = position_weight.run_case("donut", 3, [1.0, 2.0, 4.0], contacts=40, time_limit=None, repeats=2)
    assert [w for w, _, _ in rows] == [1.0, 2.0, 4.0]
    assert all(len(times) == 2 and min(times) > 0 for _, times, _ in rows)
    results = [r for _, _, r in rows]
    assert all(r.status == "optimal" for r in results)
    assert len({r.q1 for r in results}) == 1
    # Different trees: the weight is really passed on (the same tree would expand the same states).
    assert len({(r.stats.visited, r.stats.created) for r in results}) > 1
