"""SDH reachability: the kinematic chain, the sampled model, sound pruning, constrained search."""

from __future__ import annotations

import itertools
import json
import re

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner.grasp import q1
from ogcp.planner.hands import forward_kinematics, random_configurations
from ogcp.planner.hands.reachability import SDHReachability, finger_chain, pad_normals, self_collision_free
from ogcp.planner.infra.cache import CacheEntryWarning
from ogcp.planner.search import GraspPlanner


@pytest.fixture(scope="module")
def hand(tmp_path_factory):
    return SDHReachability(samples=4000, seed=1, threshold=0.35, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def donut(object_contacts):
    return object_contacts("donut", 18, 4)


def test_chain_ends_at_the_forward_kinematics_tips():
    q = random_configurations(300, 5)
    tips, normals = forward_kinematics(q)
    np.testing.assert_allclose(finger_chain(q)[:, :, 2], tips, atol=1e-12)
    np.testing.assert_allclose(pad_normals(q), normals, atol=1e-12)


def test_self_collision_rejects_crossed_fingers():
    assert self_collision_free(np.zeros(7))[0]
    crossed = np.array([0.0, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5])  # every finger curled into the centre
    assert not self_collision_free(crossed)[0]


def test_model_is_cached_and_survives_a_corrupt_entry(tmp_path):
    first = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
    files = list(tmp_path.glob("sdh_reach_*/model.npz"))
    assert len(files) == 1 and [p.name for p in tmp_path.iterdir()] == [files[0].parent.name]
    again = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
    assert np.array_equal(first.q, again.q)
    for damage in (b"not an npz", files[0].read_bytes()[:-10]):
        files[0].write_bytes(damage)
        with pytest.warns(CacheEntryWarning, match="is damaged"):
            rebuilt = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
        assert np.array_equal(first.q, rebuilt.q)
        assert SDHReachability(samples=500, seed=2, cache_dir=tmp_path).q.shape == first.q.shape  # repaired


def test_residual_ignores_contact_order_and_reports_a_configuration(hand, donut):
    reach = hand.reach((2, 7, 11), donut)
    for order in itertools.permutations((2, 7, 11)):
        assert hand.reach(order, donut).residual == pytest.approx(reach.residual, abs=1e-12)
    assert len(reach.joint_angles) == 7 and sorted(reach.fingers) == [0, 1, 2]
    assert hand.accepts((2, 7, 11), donut) == (reach.residual <= hand.threshold)


def test_pruning_is_sound_against_brute_force(hand, donut):
    rng = np.random.default_rng(0)
    pruned = 0
    for _ in range(150):
        sets = [np.sort(rng.choice(18, int(rng.integers(1, 3)), replace=False)) for _ in range(3)]
        reachable = any(len({a, b, c}) == 3 and hand.accepts((a, b, c), donut) for a, b, c in itertools.product(*sets))
        admitted = hand.admits(sets, donut)
        assert admitted or not reachable  # never prunes a state that holds a reachable grasp
        pruned += not admitted
    assert pruned > 0  # and it does prune


def test_constrained_astar_equals_constrained_enumeration(hand, donut):
    valid = [g for g in itertools.combinations(range(18), 3) if hand.accepts(g, donut)]
    assert 0 < len(valid) < 816
    best = max(q1(donut.subset_wrenches(np.array(g))) for g in valid)
    result = GraspPlanner(constraints=[hand]).plan(donut, 3)
    assert result.q1 == best and hand.accepts(result.grasp, donut)


def test_cli_reports_the_hand_configuration(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    assert main(["plan", "donut", "-n", "30", "-m", "3", "--hand", "sdh", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["hand"]["name"] == "sdh" and len(record["hand"]["joint_angles"]) == 7
    assert record["hand"]["residual"] <= 0.3
    assert sorted(record["hand"]["finger_contacts"]) == record["grasp"]
    assert main(["plan", "donut", "-n", "30", "-m", "4", "--hand", "sdh"]) == 2
    assert "3 fingers" in capsys.readouterr().err


def test_es_filtered_by_the_same_predicate(hand, donut):
    from ogcp.planner.baselines.es import ExhaustiveSearch

    grasps = list(itertools.combinations(range(18), 3))
    valid = [g for g in grasps if hand.accepts(g, donut)]
    values = {g: q1(donut.subset_wrenches(np.array(g))) for g in valid}
    best = max(values.values())
    result = ExhaustiveSearch(chunk=100, constraints=[hand]).run(donut, 3)
    assert result.q1 == best and result.grasp == min(g for g in valid if values[g] == best)
    assert result.excluded == len(grasps) - len(valid)
    assert result.zero == sum(v == 0 for v in values.values())
    assert result.q1 == GraspPlanner(constraints=[hand]).plan(donut, 3).q1


def test_hfts_penalises_the_residual(hand, object_contacts):
    from ogcp.planner.baselines.hfts import HFTS

    contacts = object_contacts("donut", 100, 0)
    free = HFTS(runs=12, seed=0).run(contacts, 3)
    with_hand = HFTS(runs=12, seed=0, hand=hand).run(contacts, 3)
    assert all(r.residual is None for r in free.runs) and all(r.residual is not None for r in with_hand.runs)
    free_residuals = hand.residuals(
        contacts.positions[[list(r.grasp) for r in free.runs]], contacts.normals[[list(r.grasp) for r in free.runs]]
    )
    assert np.mean([r.residual for r in with_hand.runs]) < np.mean(free_residuals)
    assert with_hand.config["hand"]["name"] == "sdh"


def test_cli_es_summary_counts_admissible_grasps(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    assert main(["plan", "donut", "-n", "16", "-m", "3", "--method", "es", "--hand", "sdh"]) == 0
    out = capsys.readouterr().out
    excluded, admissible = map(int, re.search(r"constraints: (\d+) grasps excluded, (\d+) admissible", out).groups())
    assert excluded + admissible == 560  # C(16, 3)
    fc, of = map(int, re.search(r"force closure: (\d+) of (\d+)", out).groups())
    assert of == admissible and fc <= admissible
