"""HFTS baseline: determinism, the per-level procedure, exact final quality, never above ES."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner.baselines.hfts import HFTS, Hierarchy
from ogcp.planner.grasp import q1
from ogcp.planner.infra import OgcpError
from tests.conftest import exhaustive_best


@pytest.fixture(scope="module")
def donut(object_contacts):
    return object_contacts("donut", 60, 2)


@pytest.fixture(scope="module")
def twenty_runs(donut):
    return HFTS(runs=20, seed=0).run(donut, 3)


def test_hierarchy_levels_and_clusters(object_contacts):
    for n, depth in ((60, 1), (200, 2), (1000, 3)):
        contacts = object_contacts("box", n, 0)
        tree = Hierarchy(contacts, 1.0, 0)
        assert tree.depth == depth  # int(log4(N / 3)) - 1, at least 1
        assert len(tree.levels[0]) == 12
        for level in range(1, depth):
            assert all(len(tree.children[p]) == 4 for p in tree.levels[level - 1] if len(tree.members[p]) >= 4)
        leaves = np.sort(np.concatenate([tree.members[node] for node in tree.levels[-1]]))
        assert np.array_equal(leaves, np.arange(n))  # the deepest level partitions C


def test_runs_are_deterministic_per_seed(donut, twenty_runs):
    again = HFTS(runs=20, seed=0, jobs=2).run(donut, 3)
    assert [(r.grasp, r.q1) for r in again.runs] == [(r.grasp, r.q1) for r in twenty_runs.runs]
    alone = HFTS(runs=1, seed=7).run(donut, 3).runs[0]
    assert (alone.grasp, alone.q1, alone.objective_per_level) == (
        twenty_runs.runs[7].grasp,
        twenty_runs.runs[7].q1,
        twenty_runs.runs[7].objective_per_level,
    )
    assert [r.seed for r in twenty_runs.runs] == list(range(20))


def test_final_quality_is_the_exact_q1_of_real_distinct_contacts(donut, twenty_runs):
    for run in twenty_runs.runs:
        assert len(set(run.grasp)) == 3 and list(run.grasp) == sorted(run.grasp)
        assert run.q1 == q1(donut.subset_wrenches(np.array(run.grasp)))
    best = max(twenty_runs.runs, key=lambda r: r.q1)
    assert (twenty_runs.grasp, twenty_runs.q1) == (best.grasp, best.q1)


def test_never_above_the_exhaustive_optimum(donut, twenty_runs):
    optimum = exhaustive_best(donut, 3)
    assert twenty_runs.summary()["max"] <= optimum
    assert twenty_runs.summary()["mean"] < optimum  # randomised: a spread below the optimum


def test_per_level_procedure(donut, twenty_runs):
    levels = HFTS().run(donut, 3).config["levels"]
    for run in twenty_runs.runs:
        # one objective per cluster level plus the level of real contacts
        assert len(run.objective_per_level) == len(run.accepted_per_level) == levels + 1
        # at most `iterations` moves per level are accepted; every evaluation is counted
        assert all(0 <= a <= 40 for a in run.accepted_per_level)
        assert run.evaluations <= (levels + 1) * 41
    limited = HFTS(runs=5, iterations=1).run(donut, 3)
    assert all(sum(r.accepted_per_level) <= levels + 1 for r in limited.runs)


def test_greedy_acceptance_and_descent(donut, twenty_runs):
    worse_descents = 0
    for run in twenty_runs.runs:
        for start, end, accepted in zip(run.start_per_level, run.objective_per_level, run.accepted_per_level):
            assert end >= start and (end > start) == (accepted > 0)  # only improvements are accepted
        # a descent is taken even when the child is worse than the parent level's incumbent
        worse_descents += sum(s < e for s, e in zip(run.start_per_level[1:], run.objective_per_level[:-1]))
    assert worse_descents > 0


def test_more_runs_do_better_on_average(donut):
    values = HFTS(runs=40, seed=100).run(donut, 3).values
    best_of_2 = np.mean([values[i : i + 2].max() for i in range(0, 40, 2)])
    best_of_10 = np.mean([values[i : i + 10].max() for i in range(0, 40, 10)])
    assert best_of_10 >= best_of_2 >= values.mean()


def test_invalid_settings(donut):
    for kwargs, message in (({"runs": 0}, "runs"), ({"iterations": 0}, "iterations"), ({"seed": -2}, "seed")):
        with pytest.raises(OgcpError, match=message):
            HFTS(**kwargs).run(donut, 3)


def test_cli_json_lists_every_run(capsys):
    assert main(["plan", "box", "-n", "40", "--method", "hfts", "--runs", "4", "--seed", "5", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["schema"] == "ogcp.plan/1" and record["method"] == "hfts"
    assert [r["seed"] for r in record["runs"]] == [5, 6, 7, 8]
    assert record["q1"] == max(r["q1"] for r in record["runs"]) == record["stats"]["max"]
