"""Exhaustive search: exact against plain enumeration, deterministic chunks, resume, Dask."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner.baselines import ExhaustiveSearch
from ogcp.planner.baselines.combinations import combinations_range, count
from ogcp.planner.grasp import q1
from ogcp.planner.infra import OgcpError


@pytest.fixture(scope="module")
def amphora(object_contacts):
    return object_contacts("amphora", 22, 1)


@pytest.fixture(scope="module")
def reference(amphora):
    """Plain enumeration: every grasp's Q1, the argmax (first in lexicographic order)."""
    grasps = list(itertools.combinations(range(len(amphora)), 3))
    values = np.array([q1(amphora.subset_wrenches(np.array(g))) for g in grasps])
    return grasps, values


@pytest.mark.parametrize("n,m", [(10, 3), (9, 4), (12, 2), (7, 7), (6, 1)])
def test_combination_ranges_match_itertools(n, m):
    full = np.array(list(itertools.combinations(range(n), m)))
    assert count(n, m) == len(full)
    for start, stop in ((0, 5), (3, 40), (0, len(full)), (len(full) - 1, len(full) + 9), (7, 7)):
        assert np.array_equal(combinations_range(n, m, start, stop).reshape(-1, m), full[start:stop])


@pytest.mark.parametrize("kwargs", [{}, {"chunk": 97}, {"chunk": 97, "jobs": 2}, {"chunk": 1000, "bins": 7}])
def test_es_equals_plain_enumeration(amphora, reference, kwargs):
    grasps, values = reference
    result = ExhaustiveSearch(**kwargs).run(amphora, 3)
    best = values.max()
    assert result.q1 == best and result.grasp == grasps[int(np.flatnonzero(values == best)[0])]
    assert result.grasps == len(grasps)
    assert result.zero == int((values == 0).sum()) and 0 < result.force_closure_fraction < 1
    expected_counts, _ = np.histogram(values[values > 0], bins=result.bin_edges)
    assert np.array_equal(result.counts, expected_counts)
    assert result.bin_edges[-1] == pytest.approx(result.q_ows) and result.q_ows >= best
    assert result.exact_evaluations < len(grasps)  # bounds settled some grasps as Q1 = 0


def test_pruned_es_is_a_separate_method_with_the_same_argmax(amphora, reference):
    plain = ExhaustiveSearch().run(amphora, 3)
    pruned = ExhaustiveSearch(pruned=True, chunk=300).run(amphora, 3)
    assert (pruned.grasp, pruned.q1) == (plain.grasp, plain.q1)
    assert pruned.method == "es-pruned" and pruned.counts is None and pruned.zero is None
    assert pruned.exact_evaluations < plain.exact_evaluations


def test_ties_break_to_the_lexicographically_smallest_grasp(object_contacts):
    # Two point contacts are never in force closure: every grasp ties at Q1 = 0.
    result = ExhaustiveSearch(chunk=7).run(object_contacts("box", 12, 0), 2)
    assert result.grasp == (0, 1) and result.q1 == 0.0 and result.zero == count(12, 2)


def test_resume_after_interruption_gives_the_identical_answer(amphora, tmp_path):
    full = ExhaustiveSearch(chunk=150, checkpoint=tmp_path).run(amphora, 3)
    chunk_files = sorted(tmp_path.glob("chunk_*.json"))
    assert len(chunk_files) == full.chunks == -(-count(22, 3) // 150)
    for path in chunk_files[::3]:  # an interrupted run: some chunks never finished
        path.unlink()
    chunk_files[1].write_text('{"index": 1, "best_q1": ')  # and one torn write
    with pytest.warns(UserWarning, match="is unreadable"):  # the torn chunk is recomputed, said once
        resumed = ExhaustiveSearch(chunk=150, checkpoint=tmp_path, jobs=2).run(amphora, 3)
    assert resumed.resumed == full.chunks - len(chunk_files[::3]) - 1
    assert (resumed.grasp, resumed.q1, resumed.zero) == (full.grasp, full.q1, full.zero)
    assert np.array_equal(resumed.counts, full.counts)
    again = ExhaustiveSearch(chunk=150, checkpoint=tmp_path).run(amphora, 3)
    assert again.resumed == full.chunks and again.grasp == full.grasp


def test_checkpoint_of_another_run_is_refused(amphora, tmp_path):
    ExhaustiveSearch(chunk=500, checkpoint=tmp_path).run(amphora, 3)
    with pytest.raises(OgcpError, match="different run"):
        ExhaustiveSearch(chunk=400, checkpoint=tmp_path).run(amphora, 3)


def test_dask_local_cluster_matches_local_processes(amphora):
    distributed = pytest.importorskip("distributed")
    local = ExhaustiveSearch(chunk=200).run(amphora, 3)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        remote = ExhaustiveSearch(chunk=200, backend="dask", address=cluster.scheduler_address).run(amphora, 3)
    assert (remote.grasp, remote.q1, remote.zero) == (local.grasp, local.q1, local.zero)
    assert np.array_equal(remote.counts, local.counts)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"backend": "spark"}, "dask, loky"),
        ({"backend": "dask"}, "needs --address"),
        ({"address": "localhost:1"}, "applies to backend 'dask' only"),
        ({"jobs": 0}, "jobs must be"),
        ({"chunk": 0}, "chunk: expected an integer >= 1"),
    ],
)
def test_invalid_settings_are_rejected(amphora, kwargs, message):
    with pytest.raises(OgcpError, match=message):
        ExhaustiveSearch(**kwargs).run(amphora, 3)


def test_cli_es_json_and_resume(tmp_path, capsys):
    args = ["plan", "donut", "-n", "18", "-m", "3", "--method", "es", "--chunk", "200", "--checkpoint", str(tmp_path)]
    assert main([*args, "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert first["schema"] == "ogcp.plan/1" and first["method"] == "es"
    assert sum(first["histogram"]["counts"]) + first["histogram"]["zero"] == first["stats"]["grasps"] == count(18, 3)
    assert main([*args, "--json"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert second["stats"]["resumed_chunks"] == second["stats"]["chunks"]
    assert (second["grasp"], second["q1"]) == (first["grasp"], first["q1"])
    assert main(["plan", "donut", "-n", "18", "-m", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["q1"] == first["q1"]  # A* finds the ES optimum, bit for bit
