"""Local search for good grasps while a search runs (ogcp.planner.search.polish)."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest

from ogcp.planner.grasp.constraints import DistinctContacts, MaxFingerSpread
from ogcp.planner.grasp.quality import q1
from ogcp.planner.search import GraspPlanner
from ogcp.planner.search import best_first as search_run
from ogcp.planner.search.polish import Polisher
from tests.conftest import exhaustive_best


def _q1(contacts, grasp):
    return q1(contacts.subset_wrenches(np.array(grasp)))


def test_the_climb_reaches_a_local_optimum_with_exact_values(object_contacts):
    """The best grasp is valid, sorted, scored with the value every method reports, and no
    move of one finger (to any contact) or of two (to nearby contacts) improves it."""
    contacts = object_contacts("amphora", 20, 1)
    polisher = Polisher(contacts, 3, [DistinctContacts()], seed=0)
    grasp, q, done = polisher.climb(None, time.perf_counter() + 1.0)
    assert not done and q > 0 and polisher.evaluations > 0
    assert len(set(grasp)) == 3 and list(grasp) == sorted(grasp)
    assert q == _q1(contacts, grasp)  # bit-identical to the search's Q1 of that grasp
    for finger, contact in itertools.product(range(3), range(len(contacts))):
        moved = list(grasp)
        moved[finger] = contact
        if len(set(moved)) == 3:
            assert _q1(contacts, moved) <= q + 1e-12, moved


def test_the_climb_never_returns_a_worse_grasp_than_its_start(object_contacts):
    contacts = object_contacts("box", 40, 0)
    start = (0, 13, 27)
    q_start = _q1(contacts, start)
    polisher = Polisher(contacts, 3, [DistinctContacts()], seed=3)
    grasp, q, _ = polisher.climb((start, q_start), time.perf_counter() + 0.3)
    assert q >= q_start and q == _q1(contacts, grasp)
    # A start no better than the best reached changes nothing.
    _, q_again, _ = polisher.climb((start, q_start), time.perf_counter() + 0.01)
    assert q_again >= q


def test_the_climb_keeps_the_constraints(object_contacts):
    contacts = object_contacts("amphora", 60, 2)
    spread = 0.5 * float(np.ptp(contacts.positions, axis=0).max())
    constraint = MaxFingerSpread(spread)
    polisher = Polisher(contacts, 4, [DistinctContacts(), constraint], seed=1)
    grasp, q, _ = polisher.climb(None, time.perf_counter() + 0.5)
    assert q > 0 and constraint.accepts(grasp, contacts) and len(set(grasp)) == 4


def test_the_climb_gives_up_where_no_grasp_is_valid(object_contacts):
    contacts = object_contacts("box", 30, 0)
    polisher = Polisher(contacts, 3, [DistinctContacts(), MaxFingerSpread(1e-9)], seed=0)
    grasp, q, done = polisher.climb(None, time.perf_counter() + 60.0)
    assert (grasp, q, done) == ((), 0.0, True)


@pytest.fixture
def climbs(monkeypatch):
    """The best grasps' Q1 [-] that each call of local search reported."""
    found = []
    climb = Polisher.climb

    def spying(self, start, deadline, chunks=None):
        answer = climb(self, start, deadline, chunks)
        found.append(answer[1])
        return answer

    monkeypatch.setattr(Polisher, "climb", spying)
    return found


@pytest.fixture
def eager_polish(monkeypatch, climbs):
    """Local search at every iteration of the search, a few milliseconds each."""
    monkeypatch.setattr(search_run, "PROGRESS_SECONDS", 0.0)
    monkeypatch.setattr(search_run, "POLISH_AFTER", 0.0)
    monkeypatch.setattr(search_run, "POLISH_SHARE", math.inf)
    monkeypatch.setattr(search_run, "POLISH_SECONDS", math.inf)
    monkeypatch.setattr(search_run, "POLISH_SLICE", 0.003)
    return climbs


@pytest.mark.parametrize(("name", "method"), [("amphora", "astar"), ("sphere", "astar"), ("box", "dijkstra")])
def test_local_search_changes_nothing_of_a_finished_search_but_memory(
    name, method, object_contacts, eager_polish, monkeypatch
):
    """A* and Dijkstra pop no state past the best grasp, whoever found it: the expansions, the
    grasp and its certificate are those of a search without local search."""
    contacts = object_contacts(name, 26, 2)
    polished = GraspPlanner(method=method, seed=2).plan(contacts, 3)
    assert eager_polish and max(eager_polish) > 0  # it ran and found grasps
    monkeypatch.setattr(search_run, "POLISH_SHARE", 0.0)
    plain = GraspPlanner(method=method, seed=2).plan(contacts, 3)
    assert polished.stats.trace == plain.stats.trace and polished.stats.visited == plain.stats.visited
    assert polished.grasp == plain.grasp and polished.q1 == plain.q1 == pytest.approx(
        exhaustive_best(contacts, 3), abs=1e-9
    )
    assert polished.bound == plain.bound and polished.status == plain.status == "optimal"
    assert polished.stats.dropped >= plain.stats.dropped


def test_wastar_runs_no_local_search_before_it_stops(object_contacts, eager_polish):
    """WA* may pop states A* never would, so a cutoff moved by the clock would change its path."""
    result = GraspPlanner(method="wastar", eps=0.5, seed=2).plan(object_contacts("amphora", 26, 2), 3)
    assert result.status in ("bounded", "optimal") and not eager_polish


@pytest.mark.parametrize("setting", [{"record_tree": True}, {"symmetry": True}, {"ordered": True}])
def test_no_local_search_where_its_grasps_could_not_stand(setting, object_contacts, eager_polish):
    """A recorded tree's path ends at a state, a symmetry-reduced optimum may lie below a grasp of
    the full space, and constraints may read the finger order, which local search sorts."""
    GraspPlanner(seed=2, **setting).plan(object_contacts("amphora", 26, 2), 3)
    assert not eager_polish


def test_a_stopped_search_returns_local_search_grasps(object_contacts, climbs):
    """Stopped long before its proof (and before local search would start while it runs), the
    search climbs once and returns a grasp at least as good as the best local search reached,
    with its exact Q1 and a sound bound."""
    contacts = object_contacts("amphora", 300, 0)
    result = GraspPlanner(seed=0, time_limit=3.0).plan(contacts, 5)
    assert result.status == "stopped" and climbs and max(climbs) > 0
    assert result.q1 >= max(climbs) and result.q1 == _q1(contacts, result.grasp)
    assert len(set(result.grasp)) == 5 and result.q1 <= result.bound <= result.q_ows
    stats = result.stats
    assert stats.local_search_evaluations > 0 and 0 < stats.local_search_seconds < 0.2 * stats.wall_seconds
    record = result.to_dict()["stats"]
    assert record["local_search_evaluations"] == stats.local_search_evaluations
