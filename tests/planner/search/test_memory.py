"""A search under a memory limit: recycled ids, counted waiting children, forgetting, and a sound certificate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.grasp.constraints import DistinctContacts
from ogcp.planner.infra import OgcpError, SearchTimeout
from ogcp.planner.search import GraspPlanner
from ogcp.planner.search.best_first import Search
from ogcp.planner.search.memory import PROCESS_BYTES, forget_threshold, states_budget
from ogcp.planner.search.open_list import OpenList
from ogcp.planner.search.parts import PartOutcome, merge, search_in_parts
from ogcp.planner.search.refine import BOUND, EXACT, EXACT_G, PARTIAL, pack_waiting
from ogcp.planner.search.storage import IdPool, WaitingStore, waiting_bytes
from tests.conftest import exhaustive_best


@pytest.fixture(scope="module")
def sphere40():
    """Forty contacts on the sphere and their best 4-contact Q1 (brute force, once: 6 s)."""
    contacts = sample_contacts(builtin_mesh("sphere"), 40, seed=0, source={"kind": "builtin", "name": "sphere"})
    return contacts, exhaustive_best(contacts, 4)


def _search(contacts, m: int, method: str = "astar", limit: float | None = None, seed: int = 0) -> Search:
    config = GraspPlanner(method=method, seed=seed).resolved_config() | {"m": m}
    return Search(contacts, m, config, [DistinctContacts()], memory_limit=limit)


def test_forget_threshold_frees_the_excess_from_the_largest_keys():
    edges = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    weights = np.array([10.0, 0.0, 10.0, 10.0])
    assert forget_threshold(edges, weights, 0) == math.inf
    assert forget_threshold(edges, weights, 5) == 0.3  # the top bin frees 10 bytes
    assert forget_threshold(edges, weights, 15) == 0.2
    assert forget_threshold(edges, weights, 25) == 0.0  # the empty bin frees nothing
    assert forget_threshold(edges, weights, 1e9) == 0.0  # everything


def test_open_list_weighs_its_entries_by_key():
    open_list = OpenList()
    for ident, (key, stage) in enumerate([(0.1, 0), (0.5, 2), (0.2, 2), (0.9, 1), (0.9, 3)]):
        open_list.push(key, 0, key, stage, 0.0, ident)
    edges, weights = open_list.key_weights(4, 10.0, 2, 100.0)
    assert edges.tolist() == pytest.approx([0.1, 0.3, 0.5, 0.7, 0.9])
    assert weights.tolist() == [120.0, 0.0, 110.0, 20.0]  # keys 0.1 and 0.2 (stage 2); 0.5 (stage 2); 0.9 twice
    flat = OpenList()
    flat.push(0.4, 0, 0.4, 0, 0.0, 0)
    edges, weights = flat.key_weights(3, 1.0, 2, 0.0)
    assert weights.tolist() == [0.0, 0.0, 1.0] and forget_threshold(edges, weights, 1.0) == 0.4


def test_id_pool_hands_out_dead_ids_first_only_when_recycling():
    pool = IdPool(recycle=True)
    assert [pool.take() for _ in range(3)] == [1, 2, 3]
    pool.give(2)
    pool.give_many(np.array([3, 1]))
    assert [pool.take() for _ in range(4)] == [1, 3, 2, 4] and pool.high == 5
    kept = IdPool(recycle=False)
    kept.take()
    kept.give(1)
    kept.give_many(np.array([1]))
    assert kept.take() == 2


def test_taking_many_ids_is_taking_each_in_turn():
    one, many = IdPool(recycle=True), IdPool(recycle=True)
    for pool in (one, many):
        pool.give_many(np.array([7, 3, 9]))
    assert [one.take() for _ in range(5)] == many.take_many(5).tolist() == [9, 3, 7, 1, 2]
    assert one.high == many.high == 3 and many.take_many(0).tolist() == []
    assert many.take_many(2).tolist() == [3, 4]


def test_waiting_store_counts_the_bytes_it_holds():
    store = WaitingStore()
    small = pack_waiting(np.arange(4), np.linspace(0, 1, 4), np.zeros(4, np.int8), np.full(4, -1, np.int32))
    large = pack_waiting(np.arange(64), np.linspace(0, 1, 64), np.zeros(64, np.int8), np.full(64, -1, np.int32))
    store.put(7, small)
    store.put(9, large)
    assert store.nbytes == waiting_bytes(small) + waiting_bytes(large) and len(store) == 2
    store.put(7, large)  # replaced, not added
    assert store.nbytes == 2 * waiting_bytes(large)
    assert store.take(7) is large and store.take(7) is None
    store.take(9)
    assert store.nbytes == 0 and not store


def test_open_list_forgets_the_largest_keys_but_the_kept_state():
    open_list = OpenList(capacity=2)
    keys = [0.3, 0.9, 0.1, 0.7, 0.5, 0.9, 0.2]
    for ident, key in enumerate(keys):
        open_list.push(key, 0, key - 0.05, ident % 4, 0.0, ident)
    idents, stages, key, lowest = open_list.forget(0.7, keep=5)
    assert sorted(idents.tolist()) == [1, 3] and stages.tolist() == [i % 4 for i in idents.tolist()]
    assert key == 0.7 and lowest == pytest.approx(0.65)
    nothing, _, key, lowest = open_list.forget(0.95)
    assert len(nothing) == 0 and key == lowest == math.inf
    popped = [open_list.pop()[0] for _ in range(len(open_list))]
    assert popped == sorted(popped) == [0.1, 0.2, 0.3, 0.5, 0.9]
    assert open_list.forget(0.0)[3] == math.inf  # empty: nothing to forget


@pytest.mark.parametrize("method", ["astar", "wastar", "dijkstra"])
def test_a_search_past_its_memory_limit_keeps_a_sound_certificate(method, sphere40):
    """Tight limits forget states: the search may stop with status memory, never with a wrong bound."""
    contacts, best = sphere40
    statuses = set()
    for kib in (8, 24, 96, 4096):
        search = _search(contacts, 4, method, kib * 1024)
        result = search.run()
        q0 = result.q_ows
        statuses.add(result.status)
        assert result.q1 <= best + 1e-12 and best <= result.bound + 1e-12 and result.bound <= q0
        assert result.stats.forgotten == search.forgotten
        if result.status == "memory":
            assert search.forgotten > 0 and result.q1 < result.bound
        else:  # finished: the method's own guarantee holds
            assert q0 - result.q1 <= (1.0 + result.eps) * (q0 - best) + 1e-12
            if method != "wastar":
                assert result.q1 == pytest.approx(best, abs=1e-9) and result.status == "optimal"
    assert "memory" in statuses and statuses - {"memory"}  # both ends of the range were reached


def test_the_same_limit_forgets_the_same_states(sphere40):
    """Memory is looked at by iteration count, not by the clock."""
    contacts, _ = sphere40
    runs = [_search(contacts, 4, limit=24 * 1024) for _ in range(2)]
    results = [search.run() for search in runs]
    assert runs[0].forgotten == runs[1].forgotten > 0
    assert results[0].grasp == results[1].grasp and results[0].stats.visited == results[1].stats.visited


def test_recycled_ids_change_no_result(object_contacts):
    contacts = object_contacts("amphora", 40, 2)
    recycled = _search(contacts, 4, seed=2)
    fresh = _search(contacts, 4, seed=2)
    fresh._ids = IdPool(recycle=False)
    a, b = recycled.run(), fresh.run()
    assert (a.grasp, a.q1, a.stats.visited, a.stats.created) == (b.grasp, b.q1, b.stats.visited, b.stats.created)
    assert recycled._ids.high < fresh._ids.high  # rows of dead states served new ones


def test_a_better_grasp_makes_forgotten_states_harmless(object_contacts):
    search = _search(object_contacts("box", 12, 0), 3)
    search.forgotten_key, search.forgotten_lower = 0.30, 0.25
    search.lower_cutoff(0.26)  # a forgotten state may still hold a better grasp
    assert (search.forgotten_key, search.forgotten_lower) == (0.30, 0.25)
    search.lower_cutoff(0.2)  # the best grasp beats every forgotten state
    assert search.forgotten_key == search.forgotten_lower == math.inf


def test_the_limit_is_shared_by_the_parts_and_validated(object_contacts):
    assert states_budget(None, 2) is None
    assert states_budget(4.0, 2) == 2 * 2**30 - PROCESS_BYTES
    with pytest.raises(OgcpError, match=r"memory_limit 0.5 GiB is too small for a search in 2 process\(es\)"):
        states_budget(0.5, 2)
    for bad in (0, -1.0, float("nan"), "4"):
        with pytest.raises(OgcpError, match="memory_limit"):
            GraspPlanner(memory_limit=bad).plan(object_contacts("box", 12, 0), 3)
    result = GraspPlanner(memory_limit=None).plan(object_contacts("box", 12, 0), 3)
    assert result.status == "optimal" and result.stats.forgotten == 0


def test_parts_past_their_limit_merge_to_status_memory(sphere40):
    contacts, best = sphere40
    config = GraspPlanner(seed=0).resolved_config() | {"m": 4}
    result = search_in_parts(contacts, 4, config, [DistinctContacts()], 2, memory_limit=8 * 1024)
    assert result.status == "memory" and result.stats.forgotten > 0
    assert result.q1 <= best <= result.bound + 1e-12


def _outcome(q: float | None, bound: float, status: str, object_contacts) -> PartOutcome:
    result = GraspPlanner(seed=1).plan(object_contacts("box", 12, 0), 3)
    if q is None:
        return PartOutcome(None, bound, status, result.stats)
    return PartOutcome(result.__class__(**{**result.__dict__, "q1": q, "bound": bound}), bound, status, result.stats)


def test_merge_says_memory_only_when_no_part_stopped_otherwise(object_contacts):
    config = GraspPlanner().resolved_config() | {"m": 3}
    done = _outcome(0.05, 0.05, "finished", object_contacts)
    forgot = _outcome(0.04, 0.07, "memory", object_contacts)
    timed = _outcome(0.03, 0.08, "stopped", object_contacts)
    assert merge([done, forgot], config, 1.0, 1.0, None).status == "memory"
    assert merge([done, forgot, timed], config, 1.0, 1.0, 5.0).status == "stopped"
    with pytest.raises(SearchTimeout, match="at its memory limit"):
        merge([_outcome(None, 0.2, "memory", object_contacts)] * 2, config, 1.0, 1.0, None)


@pytest.mark.parametrize("how", ["forget", "purge"])
def test_a_state_forgotten_or_purged_leaves_no_waiting_record(object_contacts, how):
    """A record held by a state in a branch and bound (PARTIAL) or about to be expanded
    (EXACT) goes with the state: its id serves a new state next, which must start afresh."""
    search = _search(object_contacts("box", 12, 0), 3, limit=1.0)
    open_list = OpenList()
    record = pack_waiting(np.arange(3), np.array([0.3, 0.2, 0.1]), np.zeros(3, np.int8), np.zeros(3, np.int32))
    for ident, stage in enumerate((PARTIAL, EXACT, BOUND, EXACT_G), start=1):
        if stage >= PARTIAL:
            search._pending.put(ident, record.copy())
        open_list.push(0.1 * ident, -1, 0.1 * ident, stage, 0.0, ident)
    if how == "forget":
        search.forget(open_list, -1)
    else:
        search.lower_cutoff(0.0)
        search.purge(open_list, 1e9)
    assert len(open_list) == 0 and len(search._pending) == 0 and search._pending.nbytes == 0


def test_a_memory_stop_climbs_as_far_on_a_slow_machine(sphere40, monkeypatch):
    """The local search a memory stop runs counts its work, not the clock: a machine ten times
    slower (its clock run ten times fast for the climb) returns the same grasp."""
    import time

    from ogcp.planner.search import polish

    contacts, _ = sphere40
    fast = _search(contacts, 4, limit=24 * 1024).run()
    real = time.perf_counter
    start = real()
    monkeypatch.setattr(polish.time, "perf_counter", lambda: start + 10.0 * (real() - start))
    slow = _search(contacts, 4, limit=24 * 1024).run()
    assert fast.status == slow.status == "memory"
    assert fast.grasp == slow.grasp and fast.q1 == slow.q1
