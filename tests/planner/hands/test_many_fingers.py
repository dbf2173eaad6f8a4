"""Grasps of four fingers: judged by every three of them, pruned soundly, planned optimally under that test."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ogcp.planner.grasp import q1
from ogcp.planner.hands import HandReachability
from ogcp.planner.hands.many_fingers import TRIPLE_SLACK
from ogcp.planner.search import GraspPlanner

from .hand_files import write_four_finger_hand


@pytest.fixture(scope="module")
def four(tmp_path_factory):
    folder = tmp_path_factory.mktemp("four")
    return HandReachability(write_four_finger_hand(folder), samples=8000, seed=0, cache_dir=folder / "cache")


@pytest.fixture(scope="module")
def contacts(object_contacts):
    return object_contacts("box", 18, 2)


def _accepted(hand, contacts):
    grasps = np.array(list(itertools.combinations(range(len(contacts)), 4)), dtype=np.intp)
    return grasps, np.array([hand.accepts(g, contacts) for g in grasps])


def test_a_four_finger_grasp_is_accepted_where_every_three_fingers_accept_their_contacts(four, contacts):
    grasps, accepted = _accepted(four, contacts)
    assert 0 < accepted.sum() < len(grasps)  # the test decides something here
    residuals = four.residuals(contacts.positions[grasps], contacts.normals[grasps])
    assert np.array_equal(accepted, residuals <= four.threshold)
    assert np.array_equal(four.accepts_many(grasps, contacts), accepted)
    # By hand for one accepted grasp: some assignment under which each three's own model accepts.
    grasp = grasps[np.argmax(accepted)]
    models = {three: four._model_of(three) for three in itertools.combinations(range(4), 3)}
    from ogcp.planner.hands.sampled_model import residuals as code_residuals

    def three_ok(order):
        for three, model in models.items():
            slots = [order[k] for k in three]
            pads = grasp[slots]
            # the model's residual over its own assignments is at most the one of this assignment
            if code_residuals(model, contacts.positions[pads][None], contacts.normals[pads][None])[0] > TRIPLE_SLACK:
                return False
        return True

    assert any(three_ok(order) for order in itertools.permutations(range(4)))


def test_pruning_never_drops_a_state_holding_an_accepted_grasp(four, contacts):
    """Super-contacts of two or three contacts each: a state is admitted wherever one of its grasps is accepted."""
    grasps, accepted = _accepted(four, contacts)
    good = {tuple(g) for g in grasps[accepted]}
    rng = np.random.default_rng(0)
    pruned = 0
    for _ in range(150):
        picked = rng.choice(len(contacts), size=rng.integers(5, 9), replace=False)
        cuts = np.sort(rng.choice(np.arange(1, len(picked)), size=3, replace=False))
        groups = [np.sort(part) for part in np.split(picked, cuts)]
        members = [tuple(sorted(c)) for c in itertools.product(*groups)]
        holds = any(tuple(sorted(m)) in good for m in members)
        admitted = four.admits(groups, contacts)
        assert admitted or not holds
        pruned += not admitted
    assert pruned > 0  # the pruning prunes something


def test_a_star_finds_the_best_grasp_the_test_accepts(four, contacts):
    grasps, accepted = _accepted(four, contacts)
    best = max(q1(contacts.subset_wrenches(g)) for g in grasps[accepted])
    result = GraspPlanner(constraints=[four]).plan(contacts, 4)
    assert four.accepts(result.grasp, contacts)
    assert result.q1 == pytest.approx(best, abs=1e-9)


def test_a_fit_of_four_fingers_starts_from_each_threes_nearest_samples(four, contacts):
    grasps, accepted = _accepted(four, contacts)
    grasp = tuple(int(i) for i in grasps[np.argmax(accepted)])
    starts = four.starts(grasp, contacts, 6)
    assert len(starts) == 6 and all(len(s.joint_angles) == len(four.joint_names) for s in starts)
    assert all(sorted(s.fingers) == [0, 1, 2, 3] for s in starts)
    assert [s.residual for s in starts] == sorted(s.residual for s in starts)
    assert four.reach(grasp, contacts).residual == pytest.approx(starts[0].residual)
    assert four.reach(grasp, contacts).residual <= four.threshold
    assert "every 3 of them accept their contacts within 1.25 thresholds" in four.why_none(4)
