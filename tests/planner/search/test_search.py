"""Search: optimality against exhaustive enumeration, the WA* bound, statistics, modes."""

from __future__ import annotations

import itertools
import math
import threading
import types

import numpy as np
import pytest

from ogcp.planner.grasp import q1
from ogcp.planner.infra import OgcpError, SearchTimeout
from ogcp.planner.search import GraspPlanner, effective_branching_factor, memory
from ogcp.planner.search import best_first as search_run
from tests.conftest import exhaustive_best

OBJECTS = ("box", "sphere", "donut", "amphora")


class _Nothing:
    """A constraint that admits every super-contact and accepts no grasp."""

    name = "nothing"

    def accepts(self, grasp, contacts):
        return False

    def admits(self, super_contacts, contacts):
        return True

    def describe(self):
        return {"name": self.name}


# (n, m, seed) instances per object: 4 objects x 3 = 12 contact sets.
INSTANCES = ((20, 3, 1), (26, 3, 2), (13, 4, 3))
VARIANTS = (  # (successor, heuristic, branching)
    ("fc", "fc", 2),
    ("ru", "ru", 2),
    ("fc", "none", 2),
    ("fc", "ru", 2),
    ("ru", "fc", 3),
)


@pytest.fixture(scope="module")
def optimum(object_contacts):
    cache: dict[tuple, float] = {}

    def best(name: str, n: int, m: int, seed: int) -> float:
        if (name, n, m, seed) not in cache:
            cache[(name, n, m, seed)] = exhaustive_best(object_contacts(name, n, seed), m)
        return cache[(name, n, m, seed)]

    return best


@pytest.mark.parametrize("name", OBJECTS)
@pytest.mark.parametrize("n,m,seed", INSTANCES)
def test_astar_finds_the_brute_force_optimum(name, n, m, seed, object_contacts, optimum):
    contacts = object_contacts(name, n, seed)
    expected = optimum(name, n, m, seed)
    for successor, heuristic, branching in VARIANTS:
        result = GraspPlanner(successor=successor, heuristic=heuristic, branching=branching, seed=seed).plan(
            contacts, m
        )
        assert result.q1 == pytest.approx(expected, abs=1e-9), (successor, heuristic, branching)
        assert result.bound == pytest.approx(result.q1, abs=1e-12)
        assert len(set(result.grasp)) == m and list(result.grasp) == sorted(result.grasp)
        assert np.array_equal(result.positions, contacts.positions[list(result.grasp)])
        # Bit for bit: the reported value is the grasp's Q1, not q0 - (q0 - q).
        assert result.q1 == q1(contacts.subset_wrenches(np.array(result.grasp)))


def test_prefiltered_reference_equals_plain_enumeration(object_contacts):
    contacts = object_contacts("donut", 16, seed=4)
    assert exhaustive_best(contacts, 3, prefilter=True) == exhaustive_best(contacts, 3, prefilter=False)


@pytest.mark.parametrize("name", OBJECTS)
def test_dijkstra_and_ordered_tree_find_the_optimum(name, object_contacts, optimum):
    contacts = object_contacts(name, 20, 1)
    expected = optimum(name, 20, 3, 1)
    dijkstra = GraspPlanner(method="dijkstra").plan(contacts, 3)
    ordered = GraspPlanner(ordered=True).plan(contacts, 3)
    sorted_states = GraspPlanner().plan(contacts, 3)
    assert dijkstra.q1 == pytest.approx(expected, abs=1e-9)
    assert ordered.q1 == pytest.approx(expected, abs=1e-9)
    assert ordered.stats.created > sorted_states.stats.created


@pytest.mark.parametrize("weight", [0.25, 1.0, 2.0, 16.0])
@pytest.mark.parametrize("name", ["box", "amphora"])
def test_astar_is_optimal_whatever_the_position_weight(name, weight, object_contacts, optimum):
    """The weight shapes Γ^fc's tree (how many states A* expands), never the optimum it returns."""
    contacts = object_contacts(name, 26, 2)
    result = GraspPlanner(position_weight=weight).plan(contacts, 3)
    assert result.status == "optimal" and result.bound == result.q1
    assert result.q1 == pytest.approx(optimum(name, 26, 3, 2), abs=1e-9)


def test_m2_optimum_is_zero_and_search_still_returns_a_grasp(object_contacts):
    result = GraspPlanner().plan(object_contacts("box", 12, 0), 2)
    assert result.q1 == 0.0 and len(set(result.grasp)) == 2


@pytest.mark.parametrize("eps", [0.2, 0.5, 1.0, 3.0])
@pytest.mark.parametrize("name", OBJECTS)
def test_wastar_respects_its_bound(name, eps, object_contacts, optimum):
    for n, m, seed in INSTANCES[:2]:
        contacts = object_contacts(name, n, seed)
        best = optimum(name, n, m, seed)
        result = GraspPlanner(method="wastar", eps=eps, seed=seed).plan(contacts, m)
        assert result.q_ows - result.q1 <= (1 + eps) * (result.q_ows - best) + 1e-9
        assert result.q1 <= best + 1e-12
        assert result.bound >= best - 1e-12 and result.eps_bound >= best - 1e-12
        assert result.eps == eps


def test_wastar_with_zero_eps_is_astar(object_contacts):
    contacts = object_contacts("amphora", 26, 2)
    a = GraspPlanner().plan(contacts, 3)
    w = GraspPlanner(method="wastar", eps=0.0).plan(contacts, 3)
    assert (w.grasp, w.q1, w.stats.visited) == (a.grasp, a.q1, a.stats.visited)


@pytest.mark.parametrize("name", OBJECTS)
def test_consistent_heuristic_expands_in_nondecreasing_f(name, object_contacts):
    # Γ = Γh makes h consistent (Thm. III.2b): A* expands states in nondecreasing f.
    result = GraspPlanner().plan(object_contacts(name, 26, 2), 3)
    f = [value for _, value in result.stats.trace]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(f))
    assert f[-1] == pytest.approx(result.q_ows - result.q1, abs=1e-12)


def test_statistics_are_consistent(object_contacts):
    result = GraspPlanner().plan(object_contacts("box", 40, 0), 3)
    s = result.stats
    assert sum(s.created_per_level) == s.created and sum(s.visited_per_level) == s.visited
    assert len(s.trace) == s.visited <= s.created
    assert [i for i, _ in s.trace] == list(range(s.visited))
    assert s.created_per_level[0] == s.visited_per_level[0] == 1
    assert s.visited_per_level[s.solution_depth] >= 1
    b = s.effective_branching_factor
    assert sum(b**i for i in range(s.solution_depth + 1)) == pytest.approx(s.created, rel=1e-9)
    assert s.q1_evaluations > 0 and s.wall_seconds > 0 and s.cpu_seconds > 0


def test_effective_branching_factor_of_a_full_binary_tree():
    assert effective_branching_factor(2 + 4 + 8, 3) == pytest.approx(2.0, abs=1e-9)
    assert math.isnan(effective_branching_factor(5, 0))


def test_search_is_deterministic(object_contacts):
    contacts = object_contacts("sphere", 22, 3)
    for successor in ("fc", "ru"):
        a = GraspPlanner(successor=successor, heuristic=successor, seed=7).plan(contacts, 3)
        b = GraspPlanner(successor=successor, heuristic=successor, seed=7).plan(contacts, 3)
        assert (a.grasp, a.q1, a.stats.created, a.stats.visited, a.stats.trace) == (
            b.grasp,
            b.q1,
            b.stats.created,
            b.stats.visited,
            b.stats.trace,
        )
    assert a.config["seed"] == 7


def test_symmetry_removal_is_approximate_but_sound(object_contacts, optimum):
    contacts = object_contacts("sphere", 26, 2)
    full = GraspPlanner().plan(contacts, 3)
    reduced = GraspPlanner(symmetry=True).plan(contacts, 3)
    assert reduced.q1 <= optimum("sphere", 26, 3, 2) + 1e-12
    assert reduced.stats.symmetric_removed > 0
    assert reduced.stats.created < full.stats.created
    assert reduced.config["symmetry"] is True


@pytest.mark.parametrize(
    "kwargs, m, message",
    [
        ({"method": "greedy"}, 3, "astar, dijkstra, wastar"),
        ({"eps": -0.1, "method": "wastar"}, 3, "eps: expected a number >= 0"),
        ({"eps": 0.3}, 3, "wastar"),
        ({"branching": 1}, 3, "branching"),
        ({"successor": "xx"}, 3, "fc, ru"),
        ({"heuristic": "xx"}, 3, "fc, none, ru"),
        ({"method": "dijkstra", "heuristic": "fc"}, 3, "no heuristic"),
        ({"seed": -1}, 3, "seed"),
        ({}, 1, "m must be"),
        ({}, 99, "exceeds"),
        ({"time_limit": 0}, 3, "time_limit must be"),
        ({"time_limit": float("nan")}, 3, "time_limit must be"),
    ],
)
def test_invalid_parameters_are_rejected(kwargs, m, message, object_contacts):
    with pytest.raises(OgcpError, match=message):
        GraspPlanner(**kwargs).plan(object_contacts("box", 12, 0), m)


@pytest.mark.parametrize("method, eps", [("astar", None), ("wastar", 0.5), ("dijkstra", None)])
def test_time_limit_stops_with_a_sound_bound(method, eps, object_contacts, optimum, monkeypatch):
    """A fake clock ticks 1 s per reading, so the limit cuts the search at every depth in turn.

    A stopped search returns a valid grasp (found by the search or by the dive below its best
    open states) with a bound that the brute-force optimum never exceeds.
    """
    contacts = object_contacts("amphora", 26, 2)
    best = optimum("amphora", 26, 3, 2)
    full = GraspPlanner(method=method, eps=eps, seed=2).plan(contacts, 3)
    statuses = []
    for limit in (1, 2, 5, 10, 20, 40, 80, 10_000):
        ticks = itertools.count()
        monkeypatch.setattr(
            search_run,
            "time",
            types.SimpleNamespace(perf_counter=lambda clock=ticks: float(next(clock)), process_time=lambda: 0.0),
        )
        result = GraspPlanner(method=method, eps=eps, seed=2, time_limit=limit).plan(contacts, 3)
        statuses.append(result.status)
        assert len(set(result.grasp)) == 3 and result.q1 == pytest.approx(
            q1(contacts.subset_wrenches(np.array(result.grasp)))
        )
        assert result.q1 <= best + 1e-12 <= result.bound + 2e-12 and result.bound <= result.q_ows
        assert result.gap == pytest.approx(result.bound - result.q1)
        if result.status == "stopped":
            assert result.stats.visited <= full.stats.visited
        else:
            assert result.status == full.status and result.grasp == full.grasp and result.q1 == full.q1
    assert statuses[0] == "stopped" and statuses[-1] != "stopped"  # the smallest limit stops it, the largest not


def test_a_stop_request_returns_the_best_grasp_so_far(object_contacts, optimum):
    """A stop event set before the search starts: the dive's grasp, status interrupted, a sound bound."""
    contacts = object_contacts("amphora", 26, 2)
    best = optimum("amphora", 26, 3, 2)
    stop = threading.Event()
    stop.set()
    result = GraspPlanner(seed=2).plan(contacts, 3, stop=stop)
    assert result.status == "interrupted" and result.stats.visited == 0
    assert result.q1 <= best <= result.bound and result.gap > 0
    record = result.to_dict()
    assert record["status"] == "interrupted" and record["gap"] == result.gap and record["bound"] == result.bound


def test_a_search_stopped_before_any_valid_grasp_raises(object_contacts):
    """No valid grasp within reach of the dive: the stop is an error naming the bound."""
    contacts = object_contacts("box", 12, 0)
    stop = threading.Event()
    stop.set()
    with pytest.raises(SearchTimeout, match="stopped by request after 0 expansions"):
        GraspPlanner(constraints=[_Nothing()]).plan(contacts, 3, stop=stop)


@pytest.mark.parametrize("name", ["amphora", "sphere"])
def test_dropping_states_past_the_best_grasp_changes_nothing_but_memory(name, object_contacts, optimum, monkeypatch):
    """A* pops no state whose lower bound of f exceeds its goal's: dropping them keeps every expansion."""
    contacts = object_contacts(name, 26, 2)
    dropping = GraspPlanner(seed=2).plan(contacts, 3)
    monkeypatch.setattr(search_run, "DROP_MARGIN", math.inf)  # the cutoff never falls: nothing dropped
    keeping = GraspPlanner(seed=2).plan(contacts, 3)
    assert dropping.stats.dropped > 0 and keeping.stats.dropped == 0
    assert dropping.q1 == keeping.q1 == pytest.approx(optimum(name, 26, 3, 2), abs=1e-9)
    assert dropping.grasp == keeping.grasp and dropping.status == "optimal"
    assert dropping.stats.visited == keeping.stats.visited and dropping.stats.trace == keeping.stats.trace
    # Purged at every iteration once the cutoff falls: still the same expansions.
    monkeypatch.setattr(search_run, "DROP_MARGIN", 1e-9)
    monkeypatch.setattr(search_run, "PROGRESS_SECONDS", 0.0)
    monkeypatch.setattr(memory, "PURGE_SECONDS", 0.0)
    purging = GraspPlanner(seed=2).plan(contacts, 3)
    assert purging.stats.trace == keeping.stats.trace and purging.grasp == keeping.grasp
    assert purging.stats.dropped > dropping.stats.dropped  # entries made before the best grasp was found
