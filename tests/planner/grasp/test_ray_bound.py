"""Facet bounds of Q1 (ogcp.planner.grasp.kernel.ray_bound) and the tightening ladder that uses them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from ogcp.planner.grasp.kernel.ray_bound import facet_bound, union_facet_bound, union_facet_bound_along
from ogcp.planner.grasp.quality import q1_certificate
from ogcp.planner.grasp.subset_quality import EXACT, GraspQuality
from ogcp.planner.infra.tolerance import TOL


def _support(points: np.ndarray, u: np.ndarray) -> float:
    return float(np.max(points @ u))


def _unit(rng: np.random.Generator) -> np.ndarray:
    u = rng.normal(size=6)
    return u / np.linalg.norm(u)


def _sets(count: int, seed: int = 0):
    """Wrench sets around the origin (mostly force closure), 12-200 points."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.integers(12, 200))
        yield rng.normal(size=(n, 6)) * rng.uniform(0.2, 3.0, size=6) + rng.normal(scale=0.3, size=6)


def test_facet_bound_is_an_upper_bound_never_worse_than_its_start():
    rng = np.random.default_rng(1)
    checked = 0
    for points in _sets(200):
        exact = q1_certificate(points).q1
        start = _unit(rng)
        bound, u = facet_bound(points, start)
        assert np.isclose(np.linalg.norm(u), 1.0)
        assert bound == pytest.approx(_support(points, u), abs=1e-12)  # the support it reports
        assert bound >= exact - 1e-12  # Q1 <= h(u) for every unit u
        assert bound <= _support(points, start) + 1e-9  # the walk only improves on the start
        checked += exact > 0
    assert checked > 100


def test_facet_bound_finds_the_facet_the_ray_crosses():
    """Against a reference LP: max c.y subject to W y <= 1 gives the crossed facet's offset 1 / |y|."""
    rng = np.random.default_rng(2)
    compared = 0
    for points in _sets(60, seed=3):
        if q1_certificate(points).q1 <= 0:
            continue
        start = _unit(rng)
        reference = linprog(-start, A_ub=points, b_ub=np.ones(len(points)), bounds=[(None, None)] * 6, method="highs")
        assert reference.status == 0
        bound, _ = facet_bound(points, start)
        assert bound == pytest.approx(1.0 / np.linalg.norm(reference.x), rel=1e-6)
        compared += 1
    assert compared > 30


def test_facet_bound_from_the_weakest_direction_is_q1():
    for points in _sets(40, seed=4):
        cert = q1_certificate(points)
        if cert.q1 <= 0:
            continue
        bound, _ = facet_bound(points, np.asarray(cert.direction))
        assert bound == pytest.approx(cert.q1, abs=1e-9)


def test_facet_bound_proves_q1_zero_when_the_origin_is_outside():
    rng = np.random.default_rng(5)
    points = rng.normal(size=(40, 6)) + np.array([3.0, 0, 0, 0, 0, 0])  # all on one side
    assert q1_certificate(points).q1 == 0.0
    bound, u = facet_bound(points, _unit(rng))
    assert bound <= TOL.force_closure and np.all(points @ u <= TOL.force_closure)


def test_union_facet_bound_starts_from_the_lowest_support_directions():
    rng = np.random.default_rng(6)
    wrenches = rng.normal(size=(30, 4, 6))
    directions = np.array([_unit(rng) for _ in range(50)])
    support = np.max(wrenches @ directions.T, axis=1)  # (30, 50)
    members = np.array([2, 5, 11, 17, 23, 29], dtype=np.intp)
    flags = np.zeros(30, dtype=bool)
    flags[members] = True
    union = np.packbits(flags)
    points = wrenches[members].reshape(-1, 6)
    order = np.argsort(np.max(support[members], axis=0), kind="stable")
    for first, last in ((0, 1), (1, 4), (0, 8)):
        expected = min(facet_bound(points, directions[j])[0] for j in order[first:last])
        bound, normal = union_facet_bound(wrenches, union, support[members], directions, 50, first, last)
        assert bound == pytest.approx(expected)
        # The direction returned is the one whose support the bound is.
        assert np.linalg.norm(normal) == pytest.approx(1.0)
        assert np.max(points @ normal) == pytest.approx(bound, abs=1e-12)
        # Super-contacts' vectors (maxima over their members) rank the same directions.
        rows = np.stack([support[members[:2]].max(axis=0), support[members[2:]].max(axis=0)])
        assert union_facet_bound(wrenches, union, rows, directions, 50, first, last)[0] == pytest.approx(expected)
    along, normal = union_facet_bound_along(wrenches, union, directions[order[0]])
    assert along == pytest.approx(union_facet_bound(wrenches, union, support[members], directions, 50, 0, 1)[0])
    assert np.max(points @ normal) == pytest.approx(along, abs=1e-12)
    assert union_facet_bound(wrenches, union, support[members], directions, 50, 60, 70)[0] == np.inf


def test_tighten_climbs_to_the_exact_value(object_contacts):
    contacts = object_contacts("sphere", 120, 0)
    oracle = GraspQuality(contacts, seed=0)
    rng = np.random.default_rng(7)
    climbed = 0
    for _ in range(40):
        members = [np.sort(rng.choice(len(contacts), size=4, replace=False)) for _ in range(3)]
        masks = [oracle.mask_of(m) for m in members]
        vectors = [oracle.bounds.vector(m) for m in members]
        union = np.unique(np.concatenate(members))
        exact = GraspQuality(contacts, seed=0).of_indices(union)
        value, level = oracle.bounds.bound(vectors), 0
        while level != EXACT:
            value, level = oracle.tighten(masks, vectors, level, value)
            assert value >= exact  # every rung bounds the computed Q1
        assert value == exact
        climbed += exact > 0
    assert climbed > 10
    assert oracle.facet_bounds > 0


def test_tighten_settles_zero_without_an_exact_value(object_contacts):
    contacts = object_contacts("box", 200, 0)
    oracle = GraspQuality(contacts, seed=0)
    # Three contacts on the same face: no force closure.
    face = np.flatnonzero(contacts.normals[:, 2] > 0.99)[:3]
    masks = [oracle.mask_of(face[i : i + 1]) for i in range(3)]
    vectors = [oracle.bounds.vector(face[i : i + 1]) for i in range(3)]
    value, level = 1.0, 0  # pretend the support bound said nothing
    while level != EXACT:
        value, level = oracle.tighten(masks, vectors, level, value)
    assert value == 0.0 and oracle.evaluations == 0


def test_the_facet_bound_store_is_capped(object_contacts, monkeypatch):
    from ogcp.planner.grasp import subset_quality

    monkeypatch.setattr(subset_quality, "UPPER_CAPACITY", 5)
    contacts = object_contacts("sphere", 120, 0)
    oracle = GraspQuality(contacts, seed=0)
    rng = np.random.default_rng(8)
    for _ in range(30):
        members = [np.sort(rng.choice(len(contacts), size=4, replace=False)) for _ in range(3)]
        masks = [oracle.mask_of(m) for m in members]
        vectors = [oracle.bounds.vector(m) for m in members]
        value, level = oracle.tighten(masks, vectors, 0, oracle.bounds.bound(vectors))
        assert level == EXACT or value >= GraspQuality(contacts, seed=0).of_masks(masks)
        assert len(oracle._upper) <= 5


def test_facet_bound_along_the_lowest_direction_is_the_first_facet_bound(object_contacts):
    contacts = object_contacts("donut", 80, 1)
    oracle = GraspQuality(contacts, 0)
    rng = np.random.default_rng(9)
    for _ in range(30):
        members = [rng.choice(80, size=int(rng.integers(1, 9)), replace=False) for _ in range(3)]
        vectors = [oracle.bounds.vector(m) for m in members]
        union = oracle.mask_of(np.concatenate(members))
        bound, start = oracle.bounds.lowest(vectors)
        assert bound == oracle.bounds.bound(vectors)
        assert oracle.bounds.facet_bound_along(union, start)[0] == oracle.bounds.facet_bound(union, vectors, 0, 1)[0]
