"""The position-weight study (ogcp.benchmarks.studies.position_weight): its inputs and one small case."""

from __future__ import annotations

import pytest

from ogcp.benchmarks.studies import position_weight
from ogcp.planner.infra import OgcpError


def test_cases_and_settings_are_parsed_and_checked():
    assert position_weight.parse_cases("bunny:4, plane:5") == [("bunny", 4), ("plane", 5)]
    assert position_weight.parse_weights("1,2.5") == [1.0, 2.5]
    assert position_weight.parse_settings("1,2", "10,100") == [(1.0, 10), (2.0, 100)]
    assert position_weight.parse_settings("1,2,4", "30") == [(1.0, 30), (2.0, 30), (4.0, 30)]
    assert position_weight.parse_settings("2", "10,100") == [(2.0, 10), (2.0, 100)]
    with pytest.raises(OgcpError, match="give as many, or one"):
        position_weight.parse_settings("1,2", "10,30,100")
    with pytest.raises(OgcpError, match="must be >= 1"):
        position_weight.parse_settings("1", "0")
    with pytest.raises(OgcpError, match="list of integers"):
        position_weight.parse_settings("1", "ten")
    for bad in ("bunny", "bunny:x", ":3", "box:1"):
        with pytest.raises(OgcpError, match="is not OBJECT:M"):
            position_weight.parse_cases(bad)
    with pytest.raises(OgcpError, match="comma-separated list of numbers"):
        position_weight.parse_weights("1,two")
    with pytest.raises(OgcpError, match="must be > 0"):
        position_weight.parse_weights("1,0")


def test_every_setting_reaches_the_same_optimum():
    settings = [(1.0, 10), (2.0, 100), (4.0, 1)]
    rows = position_weight.run_case("donut", 3, settings, contacts=40, time_limit=None, repeats=2)
    assert [s for s, _, _ in rows] == settings
    assert all(len(times) == 2 and min(times) > 0 for _, times, _ in rows)
    results = [r for _, _, r in rows]
    assert all(r.status == "optimal" for r in results)
    assert len({r.q1 for r in results}) == 1
    # Different trees: the setting is really passed on (the same tree would expand the same states).
    assert len({(r.stats.visited, r.stats.created) for r in results}) > 1


@pytest.mark.parametrize(
    "argv,message",
    [
        (["--cases", "nosuch:3"], "position_weight: nosuch m=3: unknown object 'nosuch'"),
        (["--cases", "box:3", "--contacts", "2"], "position_weight: box m=3: m = 3 exceeds the number of contacts"),
    ],
)
def test_a_failing_case_is_one_line(monkeypatch, argv, message):
    monkeypatch.setattr("sys.argv", ["position_weight", *argv])
    with pytest.raises(SystemExit) as stop:
        position_weight.main()
    assert str(stop.value).startswith(message) and "\n" not in str(stop.value)


@pytest.mark.parametrize(
    "argv,message",
    [(["--repeats", "0"], "--repeats: expected an integer >= 1"), (["--time-limit", "-1"], "--time-limit: expected")],
)
def test_bad_counts_are_refused(monkeypatch, capsys, argv, message):
    monkeypatch.setattr("sys.argv", ["position_weight", *argv])
    with pytest.raises(SystemExit):
        position_weight.main()
    assert message in capsys.readouterr().err
