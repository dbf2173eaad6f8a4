"""One search dealt to parts: completeness against brute force, node-id independence, merging, processes."""

from __future__ import annotations

import dataclasses
import os
import threading
from pathlib import Path

import pytest

from ogcp.planner.grasp.constraints import DistinctContacts
from ogcp.planner.infra import OgcpError, SearchTimeout
from ogcp.planner.search import GraspPlanner
from ogcp.planner.search.best_first import Search
from ogcp.planner.search.deal import Board, Part, owner
from ogcp.planner.search.parts import PartOutcome, merge, run_part
from tests.conftest import exhaustive_best


def _config(method: str = "astar", eps: float | None = None, seed: int = 1) -> dict:
    return GraspPlanner(method=method, eps=eps, seed=seed).resolved_config()


def _parts_in_turn(contacts, m, config, board_path: Path, parts: int, depth: int, order=None) -> list[PartOutcome]:
    """Every part's search in this process, one after the other, on one board."""
    board = Board.create(board_path, parts)
    outcomes = []
    for rank in order or range(parts):
        search = Search(contacts, m, config, [DistinctContacts()], part=Part(rank, board, depth))
        outcome = run_part(search)
        board.bounds[rank] = outcome.bound
        outcomes.append(outcome)
    return outcomes


@pytest.mark.parametrize("name,n,m,seed", [("box", 20, 3, 1), ("amphora", 26, 3, 2), ("sphere", 14, 4, 3)])
@pytest.mark.parametrize("parts,depth", [(2, 1), (3, 2), (2, 4)])
def test_parts_together_find_the_brute_force_optimum(name, n, m, seed, parts, depth, object_contacts, tmp_path):
    """The dealt parts cover every grasp: the best part is the optimum, and the merged bound proves it."""
    contacts = object_contacts(name, n, seed)
    config = _config(seed=seed) | {"m": m}
    outcomes = _parts_in_turn(contacts, m, config, tmp_path / "board", parts, depth)
    q0 = max(o.result.q_ows for o in outcomes if o.result is not None)
    result = merge(outcomes, config, q0, 1.0, None)
    assert result.q1 == pytest.approx(exhaustive_best(contacts, m), abs=1e-9)
    assert result.status == "optimal" and result.bound == result.q1
    assert result.stats.visited == sum(o.stats.visited for o in outcomes)


@pytest.mark.parametrize("method,eps", [("wastar", 0.5), ("dijkstra", None)])
def test_parts_keep_the_guarantee_of_wastar_and_dijkstra(method, eps, object_contacts, tmp_path):
    contacts = object_contacts("amphora", 26, 2)
    config = _config(method, eps, seed=2) | {"m": 3}
    outcomes = _parts_in_turn(contacts, 3, config, tmp_path / "board", 2, 2)
    q0 = max(o.result.q_ows for o in outcomes if o.result is not None)
    result = merge(outcomes, config, q0, 1.0, None)
    best = exhaustive_best(contacts, 3)
    assert result.q1 <= best <= result.bound + 1e-12
    assert q0 - result.q1 <= (1.0 + (eps or 0.0)) * (q0 - best) + 1e-12
    if method == "dijkstra":
        assert result.q1 == pytest.approx(best, abs=1e-9) and result.status == "optimal"


def test_a_part_beaten_by_another_stops_early(object_contacts, tmp_path):
    """The part searched second knows the first's grasp: it expands less than it would alone."""
    contacts = object_contacts("amphora", 26, 2)
    config = _config(seed=2) | {"m": 3}
    together = _parts_in_turn(contacts, 3, config, tmp_path / "a", 2, 2)
    alone = _parts_in_turn(contacts, 3, config, tmp_path / "b", 2, 2, order=[1])
    assert together[1].stats.visited <= alone[0].stats.visited
    assert together[1].bound <= max(o.result.q1 for o in together if o.result is not None)


def test_the_deal_depends_on_contacts_not_node_ids(object_contacts):
    """Two trees split in different orders number their nodes differently, yet deal alike."""
    contacts = object_contacts("box", 20, 1)
    config = _config() | {"m": 3}
    natural = Search(contacts, 3, config, [DistinctContacts()])
    reversed_ = Search(contacts, 3, config, [DistinctContacts()])
    frontier = [0]
    while frontier:  # split the second tree right child first
        node = frontier.pop()
        kids = [k for k in reversed_.tree.children(node) if k != node]
        frontier.extend(kids)

    def dealt(search: Search, depth: int = 2) -> dict[frozenset, int]:
        states, found = [(0, 0, 0)], {}
        for _ in range(depth):
            states = [child for state in states for child in search.successors(state)]
        for state in states:
            key = frozenset(tuple(search.tree.members[node].tolist()) for node in state)
            found[key] = owner(search.first_contacts(state), 3)
        return found

    deal = dealt(natural)
    assert deal == dealt(reversed_) and len(set(deal.values())) == 3
    pairs = zip(natural.tree.members, reversed_.tree.members, strict=False)
    assert any(a.tolist() != b.tolist() for a, b in pairs)  # the same node id, other contacts


def _outcome(q: float | None, bound: float, status: str, object_contacts) -> PartOutcome:
    result = GraspPlanner(seed=1).plan(object_contacts("box", 12, 0), 3)
    stats = result.stats
    if q is None:
        return PartOutcome(None, bound, status, stats)
    return PartOutcome(dataclasses.replace(result, q1=q, bound=bound), bound, status, stats)


def test_merge_takes_the_best_grasp_and_the_largest_bound(object_contacts):
    config = _config() | {"m": 3}
    a = _outcome(0.05, 0.05, "finished", object_contacts)
    b = _outcome(0.04, 0.07, "stopped", object_contacts)
    merged = merge([a, b], config, 1.0, 2.0, 10.0)
    assert (merged.q1, merged.bound, merged.status) == (0.05, 0.07, "stopped")
    assert merged.stats.visited == 2 * a.stats.visited and merged.stats.wall_seconds == 2.0
    done = merge([a, _outcome(None, 0.03, "finished", object_contacts)], config, 1.0, 2.0, None)
    assert (done.q1, done.bound, done.status) == (0.05, 0.05, "optimal")
    with pytest.raises(SearchTimeout, match="time limit of 10 s"):
        merge([_outcome(None, 0.2, "stopped", object_contacts)] * 2, config, 1.0, 2.0, 10.0)
    with pytest.raises(OgcpError, match="no grasp satisfies"):
        merge([_outcome(None, 0.0, "finished", object_contacts)] * 2, config, 1.0, 2.0, None)


def _part_children() -> list[int]:
    """Pids of this process's live ``ogcp.planner.search.part_child`` children (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                command = (entry / "cmdline").read_bytes()
                parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue  # ended meanwhile
            if b"ogcp.planner.search.part_child" in command and parent == os.getpid():
                found.append(int(entry.name))
    return found


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="counts child processes through /proc")
def test_jobs_run_the_parts_in_processes_that_end_with_the_search(object_contacts):
    """Through the planner: the same optimum with two processes; a stop request ends both."""
    contacts = object_contacts("amphora", 26, 2)
    serial = GraspPlanner(seed=2).plan(contacts, 3)
    parallel = GraspPlanner(seed=2, jobs=2).plan(contacts, 3)
    assert parallel.q1 == serial.q1 and parallel.status == "optimal" and parallel.bound == parallel.q1
    assert parallel.stats.peak_rss_bytes > serial.stats.peak_rss_bytes  # two processes counted
    stop = threading.Event()
    stop.set()
    stopped = GraspPlanner(seed=2, jobs=2).plan(object_contacts("sphere", 300, 0), 4, stop=stop)
    assert stopped.status == "interrupted" and stopped.q1 <= stopped.bound
    assert not _part_children()


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="counts child processes through /proc")
def test_a_time_limit_stops_every_part_with_status_stopped(object_contacts):
    """Each part keeps the deadline itself: the merged status is stopped (exit 3), not interrupted."""
    contacts = object_contacts("sphere", 400, 0)
    result = GraspPlanner(seed=0, jobs=2, time_limit=2.0).plan(contacts, 5)
    assert result.status == "stopped" and result.q1 < result.bound <= result.q_ows
    assert result.stats.wall_seconds < 2.0 + 10.0
    assert not _part_children()


def test_jobs_reject_a_recorded_tree(object_contacts):
    with pytest.raises(OgcpError, match="record_tree needs jobs = 1"):
        GraspPlanner(record_tree=True, jobs=2).plan(object_contacts("box", 12, 0), 3)
    with pytest.raises(OgcpError, match="jobs"):
        GraspPlanner(jobs=0).plan(object_contacts("box", 12, 0), 3)
