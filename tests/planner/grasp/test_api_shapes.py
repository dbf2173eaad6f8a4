"""The public array functions of ogcp.planner.grasp: a wrongly shaped or non-finite array is an error.

A mistake such as ``q1(contact_set.wrenches)`` (shape (n, k, 6), not stacked) used to give Q1 = 0,
indistinguishable from a grasp that is not in force closure. Degenerate but well-formed input
(too few wrenches, none, all zero) still gives 0.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import (
    ContactSet,
    cone_edges,
    contact_wrenches,
    exact_q1_batch,
    q1,
    q1_certificate,
    sample_contacts,
    signed_q1,
    tangent_basis,
)
from ogcp.planner.grasp.kernel import support_table
from ogcp.planner.grasp.kernel.batch import default_directions
from ogcp.planner.grasp.quality import q1_certificate_direct
from ogcp.planner.infra import OgcpError

Q1_FUNCTIONS = [q1, signed_q1, q1_certificate, q1_certificate_direct]


@pytest.fixture(scope="module")
def contacts() -> ContactSet:
    return sample_contacts(builtin_mesh("box"), 40, seed=2)


@pytest.mark.parametrize("function", Q1_FUNCTIONS)
def test_unstacked_contact_wrenches_name_both_shapes(function, contacts):
    with pytest.raises(OgcpError, match=r"wrenches must have shape \(N, 6\), got \(40, 8, 6\); stack"):
        function(contacts.wrenches)


@pytest.mark.parametrize("function", Q1_FUNCTIONS)
@pytest.mark.parametrize("shape", [(6,), (0,), (10, 5), (10, 7), (2, 10, 6), ()])
def test_any_other_shape_is_an_error(function, shape):
    with pytest.raises(OgcpError, match=re.escape(f"wrenches must have shape (N, 6), got {shape}")):
        function(np.ones(shape))


@pytest.mark.parametrize("function", Q1_FUNCTIONS)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_wrenches_are_an_error(function, bad, contacts):
    w = np.array(contacts.subset_wrenches(np.arange(6)))
    w[5, 2] = bad
    with pytest.raises(OgcpError, match=r"wrenches must be finite, got .* at index \(5, 2\)"):
        function(w)


@pytest.mark.parametrize("function", Q1_FUNCTIONS)
def test_non_numeric_wrenches_are_an_error(function):
    with pytest.raises(OgcpError, match=r"wrenches must be a numeric array of shape \(N, 6\)"):
        function([["a"] * 6] * 8)
    with pytest.raises(OgcpError, match=r"wrenches must be a numeric array"):
        function([[1.0] * 6, [1.0] * 5])  # ragged


def test_degenerate_but_well_formed_input_still_gives_zero():
    for w in (np.zeros((0, 6)), np.zeros((6, 6)), np.zeros((50, 6)), np.ones((3, 6)), [[0.0] * 6] * 7):
        assert q1(w) == 0.0
        assert q1_certificate(w).q1 == 0.0
        assert q1_certificate_direct(w).q1 == 0.0
        assert signed_q1(w) == -np.inf


def test_lists_and_integer_arrays_are_accepted(contacts):
    w = contacts.subset_wrenches(np.array([0, 9, 17, 30]))
    assert q1(w.tolist()) == q1(w)
    assert q1(np.rint(w * 1000).astype(np.int64)) == q1(np.rint(w * 1000))


def test_hints_are_checked(contacts):
    w = contacts.subset_wrenches(np.arange(20))
    reference = q1_certificate(w).q1
    assert q1_certificate(w, hints=np.eye(6)[:2]).q1 == reference
    assert q1_certificate(w, hints=np.eye(6)[0]).q1 == reference  # one direction
    with pytest.raises(OgcpError, match=r"hints must have shape \(j, 6\), got \(2, 5\)"):
        q1_certificate(w, hints=np.ones((2, 5)))
    with pytest.raises(OgcpError, match="hints must be finite"):
        q1_certificate(w, hints=np.full((1, 6), np.nan))


def _with_nan(array, index):
    array = np.array(array)
    array[index] = np.nan
    return array


def test_exact_q1_batch_checks_every_argument(contacts):
    wrenches = np.asarray(contacts.wrenches)
    table = support_table(wrenches, default_directions())
    grasps = np.array([[0, 5, 9], [1, 2, 3]], dtype=np.int64)
    values, _ = exact_q1_batch(wrenches, grasps, table)
    assert values.tolist() == [q1(contacts.subset_wrenches(g)) for g in grasps]
    cases = [
        ((wrenches.reshape(-1, 6), grasps, table), r"contact wrenches must have shape \(n, k, 6\), got \(320, 6\)"),
        (
            (_with_nan(wrenches, (5, 2, 3)), grasps, table),
            r"contact wrenches must be finite, got nan at index \(5, 2, 3\)",
        ),
        ((wrenches, grasps[0], table), r"grasps must be integer contact indices of shape \(B, m\), got int64 of shape"),
        ((wrenches, grasps.astype(float), table), r"grasps must be integer contact indices .*got float64"),
        ((wrenches, grasps + 38, table), "grasps must index the 40 contacts, got indices from 38 to 47"),
        ((wrenches, -grasps, table), "grasps must index the 40 contacts, got indices from -9 to 0"),
        ((wrenches, grasps, table[:10]), r"table must have shape \(40, D\), one row per contact, got \(10, 128\)"),
    ]
    for args, match in cases:
        with pytest.raises(OgcpError, match=match):
            exact_q1_batch(*args)
    with pytest.raises(OgcpError, match="cut must be a finite number"):
        exact_q1_batch(wrenches, grasps, table, cut=float("nan"))
    # A bad contact no grasp uses changes no value, so a small batch need not look at it.
    values_with_unused_nan, _ = exact_q1_batch(_with_nan(wrenches, (39, 0, 0)), grasps, table)
    assert values_with_unused_nan.tolist() == values.tolist()


def test_subset_wrenches_checks_the_indices(contacts):
    assert contacts.subset_wrenches([0, 3]).shape == (16, 6)
    assert contacts.subset_wrenches(np.array([], dtype=np.intp)).shape == (0, 6)
    for indices, match in [
        (np.array([0, -1]), r"contact indices must be in \[0, 40\), got -1"),
        (np.array([0, 40]), r"contact indices must be in \[0, 40\), got 40"),
        (np.array([0.0, 1.7]), r"contact indices must be integers of shape \(m,\), got float64"),
        (np.array([[0, 1], [2, 3]]), r"contact indices must be integers of shape \(m,\), got int64 of shape \(2, 2\)"),
        (np.array([True, False]), "contact indices must be integers"),
    ]:
        with pytest.raises(OgcpError, match=match):
            contacts.subset_wrenches(indices)


def test_wrench_functions_check_their_arrays():
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    positions = np.zeros((2, 3))
    assert contact_wrenches(positions, normals, np.zeros(3), 0.1, 0.5, 4).shape == (2, 4, 6)
    assert cone_edges(normals, 0.0, 1).shape == (2, 1, 3)  # frictionless, one edge: still well formed
    cases = [
        (lambda: tangent_basis(np.ones(3)), r"normals must have shape \(n, 3\), got \(3,\)"),
        (lambda: tangent_basis([[0.0, 0.0, 0.0]]), "normals must be nonzero, normal 0 is zero"),
        (lambda: tangent_basis([[np.nan, 0.0, 1.0]]), r"normals must be finite, got nan at index \(0, 0\)"),
        (lambda: cone_edges(normals, -0.1, 8), "friction coefficient mu must be a finite number >= 0"),
        (lambda: cone_edges(normals, float("inf"), 8), "friction coefficient mu"),
        (lambda: cone_edges(normals, 0.5, 0), "the number of cone edges k must be an integer >= 1, got 0"),
        (lambda: cone_edges(normals, 0.5, 4.0), "the number of cone edges k must be an integer"),
        (lambda: contact_wrenches(positions[:1], normals, np.zeros(3), 0.1, 0.5, 4), r"normals must have the shape"),
        (lambda: contact_wrenches(positions, normals, np.zeros(2), 0.1, 0.5, 4), r"com must have shape \(3,\)"),
        (lambda: contact_wrenches(positions, normals, np.zeros(3), 0.0, 0.5, 4), "torque scale rho must be"),
        (lambda: contact_wrenches(positions, normals, np.zeros(3), "1", 0.5, 4), "torque scale rho must be"),
        (
            lambda: contact_wrenches(positions.T, normals, np.zeros(3), 0.1, 0.5, 4),
            r"positions must have shape \(n, 3\)",
        ),
    ]
    for call, match in cases:
        with pytest.raises(OgcpError, match=match):
            call()


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"positions": [["a", "b", "c"]]}, "must be numeric arrays"),
        ({"torque_scale": "0.1"}, "torque_scale must be a number, got '0.1'"),
        ({"mu": None}, "mu must be a number, got None"),
        ({"cone_edges": "8"}, "cone_edges must be an integer >= 3, got '8'"),
    ],
)
def test_contact_set_rejects_non_numeric_input_with_an_ogcp_error(changes, match):
    args = {"positions": np.zeros((1, 3)), "normals": [[0.0, 0.0, 1.0]], "com": np.zeros(3), "torque_scale": 0.1}
    args.update(changes)
    with pytest.raises(OgcpError, match=match):
        ContactSet(**args)


def test_valid_results_are_unchanged_by_the_checks(contacts):
    # The checked wrappers and the contact set's own wrenches agree bit for bit.
    w = contact_wrenches(contacts.positions, contacts.normals, contacts.com, contacts.torque_scale, contacts.mu, 8)
    assert np.array_equal(w, contacts.wrenches)
    grasp = contacts.subset_wrenches(np.array([1, 7, 22, 35]))
    assert q1(grasp) == q1_certificate(grasp).q1 == q1_certificate(grasp, kernel=False).q1
