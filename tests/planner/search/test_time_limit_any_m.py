"""A time limit holds for any m: Γ lists up to b^m children per state, so the search must not start
an expansion that cannot end in time, and what it does after the limit (dive, local search) is
bounded too. Before, m = 20 of 60 contacts answered after 52 s for a 5 s limit, m = 30 never."""

from __future__ import annotations

import time

import pytest

from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts
from ogcp.planner.grasp.quality import q1
from ogcp.planner.infra.errors import SearchTimeout

LIMIT = 2.0
#: [s] The issue's grace, max(1 s, 10 %), plus room for a loaded machine: the failure this catches
#: took minutes, not seconds.
SLACK = 3.0


@pytest.fixture(scope="module")
def contacts():
    return sample_contacts(builtin_mesh("box"), n=60, seed=0)


@pytest.mark.parametrize("m", [20, 30, 50])
@pytest.mark.parametrize("method", ["astar", "wastar", "dijkstra"])
def test_a_time_limit_ends_the_search_in_time_with_a_certified_answer(contacts, method: str, m: int) -> None:
    planner = GraspPlanner(method=method, time_limit=LIMIT)
    start = time.perf_counter()
    try:
        result = planner.plan(contacts, m)
    except SearchTimeout as stopped:  # no grasp found in time: the bound is still certified
        assert time.perf_counter() - start < LIMIT + SLACK
        assert stopped.best_q1 is None and 0 < stopped.upper_bound
        return
    assert time.perf_counter() - start < LIMIT + SLACK
    assert result.status == "stopped" and len(set(result.grasp)) == m
    recomputed = q1(contacts.wrenches[list(result.grasp)].reshape(-1, 6))
    assert recomputed == pytest.approx(result.q1, abs=1e-12)
    assert result.q1 <= result.bound <= result.q_ows + 1e-12


def test_an_m_with_hardly_any_valid_child_still_ends_in_time() -> None:
    # 59 of 60: nearly every combination of children repeats a contact, so the dive after the
    # limit lists children against its own clock, each multiset once.
    planner = GraspPlanner(method="astar", time_limit=LIMIT)
    start = time.perf_counter()
    try:
        result = planner.plan(sample_contacts(builtin_mesh("box"), n=60, seed=1), 59)
    except SearchTimeout as stopped:
        assert stopped.upper_bound > 0
    else:
        assert result.status == "stopped" and result.q1 <= result.bound
    assert time.perf_counter() - start < LIMIT + SLACK


def test_a_long_search_off_a_terminal_prints_progress_lines(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("ogcp.planner.search.grasp_planner.PROGRESS_LINE_SECONDS", 0.0)
    lines: list[str] = []
    # m = 5 of 100 contacts: a search of many short expansions, which reports twice a second.
    box = sample_contacts(builtin_mesh("box"), n=100, seed=0)
    GraspPlanner(method="astar", time_limit=LIMIT).plan(box, 5, lines=lines.append)
    assert lines and all(line.startswith("astar: ") and " expansions, " in line for line in lines)
    assert "bound 0." in lines[-1] and lines[-1].endswith(" s elapsed")
