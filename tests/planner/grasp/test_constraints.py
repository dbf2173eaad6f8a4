"""Grasp constraints: exact predicates, sound state tests, and constrained search."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, DistinctContacts, MaxFingerSpread, q1, sample_contacts
from ogcp.planner.grasp.constraints import ExcludedGrasps
from ogcp.planner.infra import OgcpError
from ogcp.planner.search import GraspPlanner


def _random_contacts(rng: np.random.Generator, n: int) -> ContactSet:
    normals = rng.normal(size=(n, 3))
    return ContactSet(rng.uniform(0.0, 1.0, (n, 3)), normals, np.full(3, 0.5), 1.0)


def _random_family(rng: np.random.Generator, universe: int, max_size: int) -> list[np.ndarray]:
    m = int(rng.integers(2, 5))
    family = []
    for _ in range(m):
        if family and rng.random() < 0.2:  # repeat an earlier set verbatim
            family.append(family[int(rng.integers(len(family)))].copy())
            continue
        size = int(rng.integers(1, max_size + 1))
        family.append(np.sort(rng.choice(universe, size, replace=False)).astype(np.intp))
    return family


def _distinct_exists(family) -> bool:
    return any(len(set(g)) == len(g) for g in itertools.product(*[s.tolist() for s in family]))


def test_distinct_admits_equals_brute_force():
    rng = np.random.default_rng(0)
    contacts = _random_contacts(rng, 8)
    constraint = DistinctContacts()
    outcomes = set()
    for _ in range(600):
        family = _random_family(rng, 8, int(rng.integers(1, 5)))
        expected = _distinct_exists(family)
        assert constraint.admits(family, contacts) == expected, [s.tolist() for s in family]
        outcomes.add(expected)
    assert outcomes == {True, False}


@pytest.mark.parametrize(
    "family, expected",
    [
        ([[3], [3]], False),
        ([[1, 2], [1, 2], [1, 2]], False),
        ([[1, 2], [1, 2], [0, 1, 2]], True),
        ([[5], [0, 5], [0, 5, 7]], True),
        ([[0, 1, 2, 3], [0], [1], [2]], True),
        ([[0, 1, 2], [0], [1], [2]], False),
    ],
)
def test_distinct_admits_hand_cases(family, expected):
    contacts = _random_contacts(np.random.default_rng(1), 8)
    assert DistinctContacts().admits([np.array(s, dtype=np.intp) for s in family], contacts) is expected


def test_distinct_accepts():
    contacts = _random_contacts(np.random.default_rng(1), 8)
    constraint = DistinctContacts()
    assert constraint.accepts([0, 1, 2], contacts)
    assert not constraint.accepts([0, 1, 0], contacts)
    assert not constraint.accepts([4, 4], contacts)
    assert constraint.describe() == {"name": "distinct"}


def _within(positions, grasp, spread) -> bool:
    return all(np.linalg.norm(positions[i] - positions[j]) <= spread for i, j in itertools.combinations(grasp, 2))


def test_max_spread_accepts_equals_pairwise_check():
    rng = np.random.default_rng(2)
    contacts = _random_contacts(rng, 12)
    outcomes = set()
    for _ in range(300):
        spread = float(rng.uniform(0.2, 1.2))
        grasp = rng.choice(12, int(rng.integers(2, 5)), replace=False).tolist()
        expected = _within(contacts.positions, grasp, spread)
        assert MaxFingerSpread(spread).accepts(grasp, contacts) == expected
        outcomes.add(expected)
    assert outcomes == {True, False}


def test_max_spread_accepts_boundary_distance():
    contacts = ContactSet(np.array([[0.0, 0, 0], [0.25, 0, 0]]), np.tile([0.0, 0, 1], (2, 1)), np.zeros(3), 1.0)
    assert MaxFingerSpread(0.25).accepts([0, 1], contacts)
    assert MaxFingerSpread(0.25).admits([np.array([0]), np.array([1])], contacts)
    assert not MaxFingerSpread(0.2499).accepts([0, 1], contacts)
    assert not MaxFingerSpread(0.2499).admits([np.array([0]), np.array([1])], contacts)


def test_max_spread_admits_is_sound():
    rng = np.random.default_rng(3)
    n = 10
    contacts = _random_contacts(rng, n)
    rejected = feasible = 0
    for _ in range(400):
        spread = float(rng.uniform(0.15, 0.9))
        constraint = MaxFingerSpread(spread)
        family = _random_family(rng, n, 4)
        exists = any(
            len(set(g)) == len(g) and _within(contacts.positions, g, spread)
            for g in itertools.product(*[s.tolist() for s in family])
        )
        admitted = constraint.admits(family, contacts)
        if exists:
            feasible += 1
            assert admitted, ([s.tolist() for s in family], spread)
        if not admitted:
            rejected += 1
            assert not exists
    # The test must exercise both branches.
    assert feasible > 20 and rejected > 20


@pytest.mark.parametrize("spread", [0, -1, float("nan"), float("inf")])
def test_max_spread_invalid(spread):
    with pytest.raises(OgcpError, match="maximum finger spread must be a positive number"):
        MaxFingerSpread(spread)


@pytest.fixture(scope="module")
def box16() -> ContactSet:
    return sample_contacts(builtin_mesh("box"), 16, seed=0)


@pytest.fixture(scope="module")
def box16_q1(box16) -> dict[tuple[int, ...], float]:
    """Brute-force Q1 of every 3-contact grasp of ``box16``."""
    return {g: q1(box16.subset_wrenches(np.array(g))) for g in itertools.combinations(range(16), 3)}


@pytest.mark.parametrize("spread", [0.1, 0.12])
def test_constrained_plan_matches_brute_force(box16, box16_q1, spread):
    positions = box16.positions
    feasible = [g for g in box16_q1 if _within(positions, g, spread)]
    assert feasible
    best = max(box16_q1[g] for g in feasible)
    unconstrained = max(box16_q1.values())
    assert best > 0 and best < unconstrained - 1e-6  # the constraint really binds
    result = GraspPlanner(constraints=[MaxFingerSpread(spread)]).plan(box16, 3)
    assert abs(result.q1 - best) < 1e-9
    assert len(set(result.grasp)) == 3
    assert _within(positions, result.grasp, spread)
    assert abs(q1(box16.subset_wrenches(np.array(result.grasp))) - result.q1) < 1e-9
    assert {"name": "max_spread", "spread": spread} in result.config["constraints"]


def test_constrained_plan_without_feasible_grasp(box16):
    with pytest.raises(OgcpError, match="no grasp satisfies the constraints"):
        GraspPlanner(constraints=[MaxFingerSpread(1e-6)]).plan(box16, 3)


def test_excluded_grasps_are_sets_of_contacts_in_any_order(box16):
    excluded = ExcludedGrasps([(3, 1, 2), [7, 5, 6]])
    assert not excluded.accepts((2, 3, 1), box16) and excluded.accepts((1, 2, 4), box16)
    many = excluded.accepts_many(np.array([[1, 2, 3], [6, 7, 5], [1, 2, 4]]), box16)
    assert many.tolist() == [False, False, True]
    assert excluded.admits([np.arange(16)] * 3, box16)  # never prunes a state
    assert excluded.describe() == {"name": "excluded", "grasps": [[1, 2, 3], [5, 6, 7]]}


def test_a_plan_without_its_best_grasps_returns_the_next_best(box16, box16_q1):
    """What ``ogcp plan --realise`` does when the hand cannot realise a grasp: A* excludes it and
    proves the best of the others, as brute force finds it."""
    ranked = sorted(box16_q1, key=lambda g: -box16_q1[g])
    first = GraspPlanner().plan(box16, 3)
    assert tuple(sorted(first.grasp)) == ranked[0] or abs(first.q1 - box16_q1[ranked[0]]) < 1e-9
    excluded = [tuple(sorted(first.grasp))]
    for _ in range(3):
        result = GraspPlanner(constraints=[ExcludedGrasps(excluded)]).plan(box16, 3)
        best_left = max(q for g, q in box16_q1.items() if g not in excluded)
        assert abs(result.q1 - best_left) < 1e-9 and tuple(sorted(result.grasp)) not in excluded
        excluded.append(tuple(sorted(result.grasp)))
