"""Exact Q1: against facet enumeration, scipy's hull, closed forms; bounds and monotonicity."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull, QhullError

from ogcp.planner.grasp import ContactSet, GraspQuality, SupportBound, contact_wrenches
from ogcp.planner.grasp.quality import q1, q1_certificate, q1_certificate_direct
from tests.conftest import q1_by_facet_enumeration

OBJECTS = ("box", "sphere", "donut", "amphora")


def scipy_q1(w: np.ndarray) -> float:
    """Q1 straight from scipy's ConvexHull with its default options (the usual reference)."""
    try:
        hull = ConvexHull(w)
    except QhullError:
        return 0.0
    value = float((-hull.equations[:, -1]).min())
    return value if value > 1e-9 else 0.0


def random_grasps(contacts: ContactSet, m: int, count: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.choice(len(contacts), m, replace=False) for _ in range(count)]


@pytest.mark.parametrize("name", OBJECTS)
def test_matches_facet_enumeration_on_small_grasps(name, object_contacts):
    contacts = object_contacts(name, 40, seed=5)
    four_edges = ContactSet(contacts.positions, contacts.normals, contacts.com, contacts.torque_scale, 0.5, 4)
    checked = fc = 0
    for cs, m, count in ((contacts, 3, 6), (four_edges, 3, 12), (four_edges, 4, 12)):
        for g in random_grasps(cs, m, count, seed=m):
            w = cs.subset_wrenches(g)
            expected = q1_by_facet_enumeration(w)
            assert q1(w) == pytest.approx(expected, abs=1e-9)
            checked += 1
            fc += expected > 0
    assert checked == 30 and fc > 0  # both outcomes must be exercised


@pytest.mark.parametrize("name", OBJECTS)
def test_agrees_with_scipy_hull(name, object_contacts):
    contacts = object_contacts(name, 60, seed=2)
    values = []
    for m, count in ((3, 15), (5, 6), (8, 4), (14, 3)):
        for g in random_grasps(contacts, m, count, seed=10 + m):
            w = contacts.subset_wrenches(g)
            reference = scipy_q1(w)
            assert q1(w) == pytest.approx(reference, abs=1e-9)
            values.append(reference)
    assert max(values) > 0 and min(values) == 0


@pytest.mark.parametrize("name", OBJECTS)
def test_kernel_active_set_and_full_hull_agree_bit_for_bit(name, object_contacts):
    # 30 contacts = 240 wrenches: kernel, active-set qhull (with and without hints), full hull.
    contacts = object_contacts(name, 30, seed=4)
    w = contacts.subset_wrenches(np.arange(30))
    reference = q1_certificate_direct(w)
    hints = np.random.default_rng(0).normal(size=(12, 6))
    hints /= np.linalg.norm(hints, axis=1, keepdims=True)
    paths = (q1_certificate(w), q1_certificate(w, kernel=False), q1_certificate(w, hints, kernel=False))
    for cert in paths:
        assert cert.q1 == reference.q1 > 0  # the facet plane is refitted canonically
    assert paths[0].hull_calls == 0 and paths[1].hull_calls > 1  # kernel, then the qhull loop


@pytest.mark.parametrize("name", OBJECTS)
def test_kernel_equals_qhull_on_random_grasps(name, object_contacts):
    contacts = object_contacts(name, 200, seed=9)
    rng = np.random.default_rng(2)
    fc = 0
    for m in (3, 3, 3, 4, 5, 6) * 30:
        w = contacts.subset_wrenches(rng.choice(200, m, replace=False))
        fast, slow = q1_certificate(w), q1_certificate(w, kernel=False)
        assert fast.q1 == slow.q1
        fc += fast.q1 > 0
        if fast.q1 == 0 and np.isfinite(fast.offset):  # a supporting hyperplane proves it
            assert np.max(w @ fast.direction) <= 1e-9
    assert fc > 10


@pytest.mark.parametrize("mu", [0.1, 0.5, 1.0, 1.7])
def test_closed_form_octahedral_sphere(mu):
    """Six contacts at ±x, ±y, ±z of a sphere around the COM, k = 4, rho = r.

    Every edge is f = n + mu s e_c (c a tangent axis), and its torque (p x f)/r = -mu s
    (n x e_c) is one of the six vertices ±mu e_b of an octahedron. The hyperplane
    T . (1,1,1)/sqrt(3) = mu/sqrt(3) passes through the 12 edges whose torques are
    +mu e_x, +mu e_y, +mu e_z and has all other edges below it: the nearest facet, so
    Q1 = mu / sqrt(3), along a pure-torque diagonal.
    """
    r = 0.05
    positions = np.vstack([np.eye(3), -np.eye(3)]) * r
    w = contact_wrenches(positions, -positions / r, np.zeros(3), r, mu, 4).reshape(-1, 6)
    cert = q1_certificate(w)
    assert cert.q1 == pytest.approx(mu / np.sqrt(3), abs=1e-12)
    assert np.allclose(np.abs(cert.direction[3:]), 1 / np.sqrt(3)) and np.allclose(cert.direction[:3], 0, atol=1e-12)


def test_two_contacts_never_force_closure(object_contacts):
    # Two point contacts cannot resist torque about the line through them.
    contacts = object_contacts("sphere", 30, seed=1)
    for g in random_grasps(contacts, 2, 20, seed=3):
        assert q1(contacts.subset_wrenches(g)) == 0.0


def test_degenerate_inputs_give_zero():
    rng = np.random.default_rng(0)
    assert q1(np.zeros((0, 6))) == 0.0
    assert q1(rng.normal(size=(6, 6))) == 0.0  # fewer than 7 points
    flat = rng.normal(size=(40, 6))
    flat[:, 5] = 0.3  # all wrenches on an affine hyperplane
    assert q1(flat) == 0.0
    # NaN or infinite wrenches are an error, not a degenerate set: tests/planner/grasp/test_api_shapes.py.
    positions = np.tile([[0.05, 0.0, 0.0]], (3, 1))  # one contact repeated
    normals = np.tile([[-1.0, 0.0, 0.0]], (3, 1))
    assert q1(contact_wrenches(positions, normals, np.zeros(3), 0.05, 0.5, 8).reshape(-1, 6)) == 0.0
    at_com = contact_wrenches(np.zeros((4, 3)), np.vstack([np.eye(3), [[0.6, 0.8, 0.0]]]), np.zeros(3), 0.05, 0.5, 8)
    at_com = at_com.reshape(-1, 6)
    assert q1(at_com) == 0.0  # no torque at all


def test_input_is_not_modified(object_contacts):
    # scipy's "Qbb" option rescales its input in place; the engine must never do that.
    w = np.array(object_contacts("box", 30, seed=4).subset_wrenches(np.arange(30)))
    before = w.copy()
    q1_certificate(w)
    assert np.array_equal(w, before)


@pytest.mark.parametrize("name", OBJECTS)
def test_monotone_when_contacts_are_added(name, object_contacts):
    contacts = object_contacts(name, 40, seed=8)
    order = np.random.default_rng(1).permutation(len(contacts))
    values = [q1(contacts.subset_wrenches(order[:size])) for size in range(3, 16)]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(values))
    assert values[-1] > 0


def test_certificate_direction_attains_q1(object_contacts):
    contacts = object_contacts("donut", 40, seed=3)
    for g in random_grasps(contacts, 6, 10, seed=4):
        w = contacts.subset_wrenches(g)
        cert = q1_certificate(w)
        assert np.linalg.norm(cert.direction) == pytest.approx(1.0, abs=1e-9)
        assert float(np.max(w @ cert.direction)) == pytest.approx(cert.offset, abs=1e-9)
        assert cert.force_closure == (cert.q1 > 0)


def test_support_bound_is_a_valid_monotone_upper_bound(object_contacts):
    contacts = object_contacts("amphora", 40, seed=2)
    bounds = SupportBound(contacts.wrenches, seed=0)
    rng = np.random.default_rng(5)
    negative_seen = 0
    for _ in range(40):
        g = rng.choice(len(contacts), int(rng.integers(3, 9)), replace=False)
        exact = q1(contacts.subset_wrenches(g))
        upper = bounds.bound([bounds.vector(g)])
        assert max(upper, 0.0) >= exact - 1e-12  # the bound is on the signed offset
        if upper < 0:
            negative_seen += 1
            assert exact == 0.0
        assert bounds.bound([bounds.vector(g[:-1])]) <= upper + 1e-15
    assert negative_seen > 0


def test_support_vectors_extend_when_directions_are_added(object_contacts):
    contacts = object_contacts("box", 30, seed=1)
    bounds = SupportBound(contacts.wrenches, seed=0)
    members = np.arange(0, 30, 3)
    before = bounds.vector(members)
    u = np.random.default_rng(2).normal(size=(5, 6))
    bounds.add(u / np.linalg.norm(u, axis=1, keepdims=True))
    extended = bounds.vector(members, before)
    assert len(extended) == bounds.count == len(before) + 5
    assert np.array_equal(extended, bounds.vector(members))


def test_oracle_never_evaluates_a_union_twice(object_contacts):
    contacts = object_contacts("box", 30, seed=1)
    oracle = GraspQuality(contacts)
    a, b = oracle.mask_of(np.arange(0, 10)), oracle.mask_of(np.arange(10, 20))
    first = oracle.of_masks([a, b])
    again = oracle.of_masks([oracle.mask_of(np.arange(20)), a])  # same union, other parts
    assert first == again == oracle.of_indices(np.arange(20))
    assert oracle.evaluations == 1 and oracle.cache_hits == 2


def test_kernel_adversarial_sets(object_contacts):
    box = object_contacts("box", 200, seed=3)
    top = np.flatnonzero(np.isclose(box.normals[:, 2], -1.0))  # inward normal -z: the top face
    assert len(top) >= 6
    for g in (top[:3], top[:6], np.array([top[0], top[0], top[1]]), np.array([top[0]] * 3)):
        w = box.subset_wrenches(g)
        assert q1_certificate(w).q1 == q1_certificate(w, kernel=False).q1 == 0.0  # one face cannot hold
    rng = np.random.default_rng(4)
    for _ in range(40):  # duplicated contacts inside otherwise random grasps
        g = rng.choice(200, 4, replace=False)
        g[3] = g[0]
        w = box.subset_wrenches(g)
        assert q1_certificate(w).q1 == q1_certificate(w, kernel=False).q1


def test_q1_is_invariant_to_translating_and_scaling_the_object(object_contacts):
    # Only p - com enters the wrenches and torques are divided by rho, so moving the object
    # or scaling it (rho scaled alike) leaves Q1 unchanged. (Rotation does not: the fixed
    # tangent basis turns the linearised cone about the normal with the world axes.)
    contacts = object_contacts("amphora", 100, seed=6)
    shift, scale = np.array([0.3, -1.2, 2.5]), 3.7
    moved = ContactSet(
        contacts.positions + shift,
        contacts.normals,
        contacts.com + shift,
        contacts.torque_scale,
        contacts.mu,
        contacts.cone_edges,
    )
    scaled = ContactSet(
        contacts.positions * scale,
        contacts.normals,
        contacts.com * scale,
        contacts.torque_scale * scale,
        contacts.mu,
        contacts.cone_edges,
    )
    rng = np.random.default_rng(8)
    fc = 0
    for _ in range(60):
        g = rng.choice(100, int(rng.integers(3, 7)), replace=False)
        a = q1(contacts.subset_wrenches(g))
        assert q1(moved.subset_wrenches(g)) == pytest.approx(a, abs=1e-12)
        assert q1(scaled.subset_wrenches(g)) == pytest.approx(a, abs=1e-12)
        fc += a > 0
    assert fc > 5


@pytest.mark.parametrize("name", ["donut", "amphora"])
def test_sets_beyond_the_kernel_size_use_the_kernel_active_set(name, object_contacts):
    w = object_contacts(name, 600, seed=0).wrenches.reshape(-1, 6)  # 4800 wrenches > 4095
    fast, slow = q1_certificate(w), q1_certificate(w, kernel=False)
    assert fast.q1 == slow.q1 > 0 and fast.hull_calls == 0 < slow.hull_calls


def test_kernel_is_safe_under_threads(object_contacts):
    from concurrent.futures import ThreadPoolExecutor

    contacts = object_contacts("sphere", 200, seed=1)
    rng = np.random.default_rng(3)
    sets = [contacts.subset_wrenches(rng.choice(200, int(rng.integers(3, 12)), replace=False)) for _ in range(200)]
    serial = [q1(w) for w in sets]
    with ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(q1, sets))
    assert threaded == serial and any(v > 0 for v in serial)


@pytest.mark.parametrize("name", OBJECTS)
def test_batched_es_path_is_bit_identical_to_single_calls_and_qhull(name, object_contacts):
    from ogcp.planner.grasp.kernel import BOUND, FALLBACK, default_directions, support_table
    from ogcp.planner.grasp.quality import exact_q1_batch

    contacts = object_contacts(name, 300, seed=3)
    rng = np.random.default_rng(6)
    grasps = np.array([rng.choice(300, 3, replace=False) for _ in range(300)])
    table = support_table(contacts.wrenches, default_directions())
    values, status = exact_q1_batch(contacts.wrenches, grasps, table)
    assert not np.any(status == BOUND)
    fc = 0
    for g, value in zip(grasps, values):
        w = contacts.subset_wrenches(g)
        assert value == q1(w) == q1_certificate(w, kernel=False).q1  # bit for bit
        fc += value > 0
    assert fc > 10
    # Branch-and-bound mode: exact at or above the cut, bounds strictly below it.
    cut = float(np.median(values[values > 0]))
    cut_values, cut_status = exact_q1_batch(contacts.wrenches, grasps, table, cut)
    exact = (cut_status != BOUND) & (cut_status != FALLBACK)
    assert np.all(cut_values[exact] == values[exact])
    assert np.all(cut_values[cut_status == BOUND] < cut - 1e-9)
    assert np.all(cut_values[cut_status == BOUND] >= values[cut_status == BOUND] - 1e-12)  # rounding
    assert np.all(cut_status[values >= cut] != BOUND)


def test_canonical_plane_refits_through_the_points_on_the_facet():
    from ogcp.planner.grasp.kernel import canonical_plane

    rng = np.random.default_rng(2)
    normal = rng.normal(size=6)
    normal /= np.linalg.norm(normal)
    basis = np.linalg.svd(normal[None, :])[2][1:]  # 5 directions inside the hyperplane
    on = 0.3 * normal + rng.normal(size=(9, 5)) @ basis
    below = 0.3 * normal - rng.uniform(0.1, 1.0, size=(20, 1)) * normal + rng.normal(size=(20, 5)) @ basis
    w = np.vstack([below[:10], on, below[10:]])
    tilted = normal + 1e-14 * rng.normal(size=6)
    refit, offset, ok = canonical_plane(w, tilted / np.linalg.norm(tilted), 0.3)
    assert ok and offset == pytest.approx(0.3, abs=1e-14) and np.allclose(refit, normal, atol=1e-13)
    again = canonical_plane(w, normal, 0.3)
    assert np.array_equal(again[0], refit) and again[1] == offset  # depends on the on-facet set only
    flat = np.vstack([below, 0.3 * normal + rng.normal(size=(9, 3)) @ basis[:3]])  # on-facet rank 3
    assert not canonical_plane(flat, normal, 0.3)[2]


def test_fallback_seeded_by_the_kernel_hull_gives_the_same_bits(object_contacts, monkeypatch):
    from ogcp.planner.grasp import quality

    real = quality.kernel_q1

    def uncertified(w, certify=True):  # as if every certificate failed
        real(w, certify)
        return False, float("nan"), np.full(6, np.nan)

    contacts = object_contacts("box", 200, seed=3)
    rng = np.random.default_rng(1)
    sets = [contacts.subset_wrenches(rng.choice(200, int(rng.integers(4, 12)), replace=False)) for _ in range(20)]
    expected = [q1_certificate(w).q1 for w in sets]
    monkeypatch.setattr(quality, "kernel_q1", uncertified)
    seeded = [q1_certificate(w) for w in sets]
    assert [c.q1 for c in seeded] == expected and any(v > 0 for v in expected)
    assert all(c.hull_calls >= 1 for c in seeded if c.q1 > 0)


def test_direction_capacity_keeps_the_support_table_in_budget(object_contacts):
    from ogcp.planner.grasp.subset_quality import DIRECTION_BUDGET, MAX_DIRECTIONS, MIN_DIRECTIONS, direction_capacity

    assert direction_capacity(1) == direction_capacity(1000) == MAX_DIRECTIONS
    assert direction_capacity(10**6) == MIN_DIRECTIONS
    sizes = [1, 500, 1000, 1500, 2500, 3125, 5000, 10**5]
    capacities = [direction_capacity(n) for n in sizes]
    assert capacities == sorted(capacities, reverse=True)  # never more directions for more contacts
    assert all(n * c <= DIRECTION_BUDGET or c == MIN_DIRECTIONS for n, c in zip(sizes, capacities, strict=True))
    oracle = GraspQuality(object_contacts("box", 30, 0), 0)
    assert oracle.bounds.capacity == MAX_DIRECTIONS and oracle.bounds.directions.shape == (MAX_DIRECTIONS, 6)
