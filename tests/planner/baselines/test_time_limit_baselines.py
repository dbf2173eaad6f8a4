"""Exhaustive search and HFTS keep a time limit for any m: ES lists C(n, m) grasps (4e15 for m = 20 of
60, killed for memory before it started), and HFTS's A* optimum never finished at m = 20. Each now
stops within S + max(1 s, 10 %) with the best grasp it has and a certified bound."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.baselines.es import ExhaustiveSearch
from ogcp.planner.baselines.hfts import HFTS
from ogcp.planner.config.methods import HFTSConfig
from ogcp.planner.grasp.quality import q1
from ogcp.planner.infra import heartbeat
from ogcp.planner.methods.runners import RunOptions, run_hfts

LIMIT = 2.0
#: [s] The issue's grace, max(1 s, 10 %), plus room for a loaded machine: the failures this
#: catches took minutes or never ended.
SLACK = 3.0


@pytest.fixture(scope="module")
def contacts():
    return sample_contacts(builtin_mesh("box"), n=60, seed=0)


def _exact(contacts, grasp) -> float:
    return q1(contacts.wrenches[list(grasp)].reshape(-1, 6))


@pytest.mark.parametrize("m", [20, 30, 50])
@pytest.mark.parametrize("pruned", [False, True])
def test_exhaustive_search_stops_at_its_time_limit_with_the_best_grasp_it_covered(contacts, m: int, pruned) -> None:
    start = time.perf_counter()
    result = ExhaustiveSearch(pruned=pruned, time_limit=LIMIT).run(contacts, m)
    assert time.perf_counter() - start < LIMIT + SLACK
    assert result.status == "stopped" and 0 < result.evaluated < result.grasps
    assert len(set(result.grasp)) == m and list(result.grasp) == sorted(result.grasp)
    assert _exact(contacts, result.grasp) == pytest.approx(result.q1, abs=1e-9)
    assert result.q1 <= result.bound == result.q_ows
    record = result.to_dict()
    assert record["status"] == "stopped" and record["bound"] == result.q_ows
    assert record["gap"] == pytest.approx(result.q_ows - result.q1)
    assert record["stats"]["evaluated_grasps"] == result.evaluated
    if not pruned:  # the histogram counts exactly the grasps covered
        assert int(result.counts.sum()) + result.zero == result.evaluated


def test_a_time_limit_that_is_not_reached_changes_nothing() -> None:
    small = sample_contacts(builtin_mesh("box"), n=16, seed=3)
    plain = ExhaustiveSearch().run(small, 3)
    timed = ExhaustiveSearch(time_limit=600.0).run(small, 3)
    assert timed.status == plain.status == "optimal" and timed.evaluated == plain.grasps
    assert timed.grasp == plain.grasp and timed.q1 == plain.q1
    assert np.array_equal(timed.counts, plain.counts) and timed.zero == plain.zero


def test_a_stopped_run_checkpoints_only_whole_chunks_and_a_rerun_finishes_it(tmp_path: Path) -> None:
    small = sample_contacts(builtin_mesh("box"), n=30, seed=1)
    reference = ExhaustiveSearch(chunk=2000).run(small, 4)
    stopped = ExhaustiveSearch(chunk=2000, checkpoint=tmp_path, time_limit=0.3).run(small, 4)
    assert stopped.status == "stopped" and stopped.evaluated < reference.grasps
    saved = len(list(tmp_path.glob("chunk_*.json")))
    assert saved == stopped.chunks  # the chunk cut short is not among them
    resumed = ExhaustiveSearch(chunk=2000, checkpoint=tmp_path).run(small, 4)
    assert resumed.status == "optimal" and resumed.resumed == saved
    assert resumed.grasp == reference.grasp and resumed.q1 == reference.q1
    assert np.array_equal(resumed.counts, reference.counts) and resumed.zero == reference.zero


@pytest.mark.parametrize("m", [20, 50])
def test_hfts_stops_at_its_time_limit_and_every_run_ends_on_distinct_contacts(contacts, m: int) -> None:
    start = time.perf_counter()
    result = HFTS(time_limit=0.05, runs=4).run(contacts, m)
    assert time.perf_counter() - start < 0.05 + SLACK
    for run in result.runs:
        assert len(set(run.grasp)) == m  # before: fingers shared contacts once m exceeded the clusters
        assert _exact(contacts, run.grasp) == pytest.approx(run.q1, abs=1e-9)
    assert result.to_dict()["status"] == ("stopped" if any(r.stopped for r in result.runs) else "heuristic")


def test_an_hfts_run_past_its_deadline_makes_no_moves(contacts) -> None:
    result = HFTS(time_limit=1e-9, runs=3).run(contacts, 3)
    assert result.status == "stopped" and all(r.stopped for r in result.runs)
    assert all(r.evaluations == 0 and r.objective_per_level == () for r in result.runs)
    assert all(len(set(r.grasp)) == 3 for r in result.runs)


def test_hfts_with_its_optimum_keeps_the_time_limit_and_says_the_optimum_is_unproven(contacts) -> None:
    start = time.perf_counter()
    run = run_hfts(HFTSConfig(runs=2), contacts, 20, RunOptions(time_limit=LIMIT, optimum=True))
    assert time.perf_counter() - start < LIMIT + SLACK  # before: A* at m = 20 never finished
    optimum = run.record.get("optimum")
    if optimum is not None:  # none when A* found no grasp in the time left
        assert optimum["status"] == "stopped" and optimum["q1"] <= optimum["bound"]


def test_long_work_off_a_terminal_prints_progress_lines(contacts, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(heartbeat, "LINE_SECONDS", 0.2)
    lines: list[str] = []
    ExhaustiveSearch(time_limit=1.0, lines=lines.append).run(contacts, 20)
    assert lines and all(line.startswith("es: ") and " grasps (" in line for line in lines)
    assert lines[-1].endswith(" s elapsed")
