"""Disturbance directions (ogcp.sim_eval.protocols.directions) and agreement metrics (ogcp.sim_eval.protocols.metrics)."""

from __future__ import annotations

import itertools
import json
import math
import warnings

import numpy as np
import pytest
from scipy.optimize import linprog

from ogcp.planner.grasp import contact_wrenches, q1_certificate
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval.protocols.directions import (
    DirectionSet,
    axis_directions,
    axis_labels,
    direction_set,
    min_pairwise_angle,
    sphere_directions,
    weakest_q1_direction,
)
from ogcp.sim_eval.protocols.metrics import (
    below_floor,
    fidelity,
    kendall,
    median_fidelity,
    roc_auc,
    set_metrics,
    spearman,
)

# --- directions -------------------------------------------------------------------------


def test_axes_are_the_twelve_signed_unit_axes() -> None:
    axes = axis_directions()
    assert axes.shape == (12, 6)
    expected = {tuple(float(v) for v in sign * row) for row in np.eye(6) for sign in (1.0, -1.0)}
    assert {tuple(row) for row in axes} == expected
    labels = axis_labels()
    assert len(set(labels)) == 12
    for vector, label in zip(axes, labels, strict=True):
        index = ["fx", "fy", "fz", "tx", "ty", "tz"].index(label[1:])
        assert vector[index] == (1.0 if label[0] == "+" else -1.0)


def random_min_angle(n: int, seed: int) -> float:
    x = np.random.default_rng(seed).normal(size=(n, 6))
    return min_pairwise_angle(x / np.linalg.norm(x, axis=1, keepdims=True))


@pytest.mark.parametrize("n", [16, 64])
def test_sphere_directions_are_unit_deterministic_and_spread(n: int) -> None:
    x = sphere_directions(n, seed=3)
    assert x.shape == (n, 6)
    np.testing.assert_allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(x, sphere_directions(n, seed=3))
    assert not np.allclose(x, sphere_directions(n, seed=4))
    best_random = max(random_min_angle(n, seed) for seed in range(10))
    assert min_pairwise_angle(x) > 1.5 * best_random
    # Spread means no preferred direction: the mean is near 0 relative to 1/sqrt(n) noise.
    assert np.linalg.norm(x.mean(axis=0)) < 0.5 / math.sqrt(n)


def test_seven_directions_approach_the_regular_simplex() -> None:
    # The regular simplex minimises every Riesz energy for 7 points on the 5-sphere; all
    # its pairwise angles are arccos(-1/6).
    angle = min_pairwise_angle(sphere_directions(7, seed=0))
    assert math.degrees(angle) == pytest.approx(math.degrees(math.acos(-1.0 / 6.0)), abs=0.5)


def test_sphere_directions_edge_counts_and_errors() -> None:
    assert sphere_directions(0, seed=0).shape == (0, 6)
    assert np.linalg.norm(sphere_directions(1, seed=0)) == pytest.approx(1.0)
    for bad in (-1, 2.5, "3"):
        with pytest.raises(OgcpError, match="integer"):
            sphere_directions(bad, seed=0)  # type: ignore[arg-type]
    with pytest.raises(OgcpError, match="seed"):
        sphere_directions(4, seed=-2)


def test_direction_set_layout_and_labels() -> None:
    u = np.array([3.0, 0.0, -4.0, 0.0, 0.0, 0.0])
    ds = direction_set(n_sphere=5, seed=1, certificate_direction=u)
    assert isinstance(ds, DirectionSet)
    assert len(ds) == 12 + 5 + 1 and ds.vectors.shape == (18, 6)
    assert ds.labels[:2] == ("+fx", "-fx") and ds.labels[11] == "-tz"
    assert ds.labels[12:17] == ("s00", "s01", "s02", "s03", "s04")
    assert ds.labels[-1] == "q1-weakest"
    np.testing.assert_allclose(ds.vectors[-1], -u / 5.0)
    np.testing.assert_array_equal(ds.vectors[12:17], sphere_directions(5, seed=1))
    assert not ds.vectors.flags.writeable
    assert direction_set(n_sphere=0).labels == axis_labels()
    assert direction_set(n_sphere=120).labels[12] == "s000"


def test_weakest_direction_rejects_degenerate_certificates() -> None:
    with pytest.raises(OgcpError, match="degenerate"):
        weakest_q1_direction(np.full(6, np.nan))
    with pytest.raises(OgcpError, match="shape"):
        weakest_q1_direction(np.ones(5))
    with pytest.raises(OgcpError, match="zero length"):
        weakest_q1_direction(np.zeros(6))


def l1_resistance(wrenches: np.ndarray, d: np.ndarray) -> float:
    """Largest s with -s d in conv({0} U W): the disturbance resisted under sum(lambda) <= 1."""
    n = len(wrenches)
    a_eq = np.hstack([wrenches.T, d[:, None]])
    a_ub = np.concatenate([np.ones(n), [0.0]])[None]
    cost = np.concatenate([np.zeros(n), [-1.0]])
    res = linprog(cost, A_ub=a_ub, b_ub=[1.0], A_eq=a_eq, b_eq=np.zeros(6), bounds=(0, None), method="highs")
    assert res.status == 0
    return float(res.x[-1])


def test_weakest_direction_sign_matches_q1_under_the_l1_budget() -> None:
    # Four tips roughly tetrahedral on a sphere, off-centre COM: in force closure and not
    # centrally symmetric, so the sign of the direction matters.
    rng = np.random.default_rng(7)
    outward = np.array([[1.0, 0.2, -0.3], [-0.6, 0.9, -0.2], [-0.5, -0.8, -0.4], [0.1, 0.0, 1.0]])
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    positions, normals, com = 0.05 * outward, -outward, np.array([0.004, -0.003, 0.002])
    wrenches = contact_wrenches(positions, normals, com, 0.08, 0.5, 6).reshape(-1, 6)
    cert = q1_certificate(wrenches, kernel=False)
    assert cert.force_closure
    d = weakest_q1_direction(cert.direction)
    # Inside the hull, conv({0} U W) = conv(W), whose ray length is smallest (= Q1) along u.
    assert l1_resistance(wrenches, d) == pytest.approx(cert.q1, rel=1e-7)
    assert l1_resistance(wrenches, -d) > 1.05 * cert.q1
    others = rng.normal(size=(40, 6))
    for other in others / np.linalg.norm(others, axis=1, keepdims=True):
        assert l1_resistance(wrenches, other) >= cert.q1 * (1 - 1e-9)


# --- metrics ----------------------------------------------------------------------------


def brute_force_auc(scores: np.ndarray, labels: np.ndarray) -> float:
    wins = 0.0
    pos, neg = scores[labels], scores[~labels]
    for p, q in itertools.product(pos, neg):
        wins += 1.0 if p > q else 0.5 if p == q else 0.0
    return wins / (len(pos) * len(neg))


@pytest.mark.parametrize("seed", range(5))
def test_auc_matches_pair_count_with_ties(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 40))
    scores = rng.integers(0, 6, n).astype(float)  # few values: many ties
    labels = rng.random(n) < 0.4
    labels[:2] = [True, False]
    assert roc_auc(scores, labels) == pytest.approx(brute_force_auc(scores, labels), abs=1e-12)
    assert roc_auc(scores, labels.astype(int)) == pytest.approx(brute_force_auc(scores, labels), abs=1e-12)


def test_auc_extremes_and_empty_class() -> None:
    assert roc_auc([1.0, 2.0, 3.0, 4.0], [False, False, True, True]) == 1.0
    assert roc_auc([1.0, 2.0, 3.0, 4.0], [True, True, False, False]) == 0.0
    assert roc_auc([2.0, 2.0, 2.0], [True, False, True]) == 0.5
    assert math.isnan(roc_auc([1.0, 2.0], [True, True]))
    with pytest.raises(OgcpError, match="0/1"):
        roc_auc([1.0, 2.0], [0, 2])
    with pytest.raises(OgcpError, match="NaN"):
        roc_auc([1.0, np.nan], [0, 1])


def test_fidelity_values_and_floor() -> None:
    measured = np.array([2.0, 1.5, 0.3, np.nan, 4.0])
    predicted = np.array([2.5, 1.0, 0.001, 3.0, 0.0])
    values = fidelity(measured, predicted, floor=0.01)
    np.testing.assert_allclose(values[:2], [0.2, 0.5])
    assert np.isnan(values[2:]).all()
    np.testing.assert_array_equal(below_floor(predicted, 0.01), [False, False, True, False, True])
    assert median_fidelity(values) == pytest.approx(0.35)
    assert math.isnan(median_fidelity([np.nan, np.nan]))
    with pytest.raises(OgcpError, match="same length"):
        fidelity([1.0], [1.0, 2.0], 0.0)
    with pytest.raises(OgcpError, match="floor"):
        fidelity([1.0], [1.0], -1.0)


def brute_force_kendall(x: np.ndarray, y: np.ndarray) -> float:
    pairs = list(itertools.combinations(range(len(x)), 2))
    return sum(np.sign(x[i] - x[j]) * np.sign(y[i] - y[j]) for i, j in pairs) / len(pairs)


def test_rank_correlations_closed_forms() -> None:
    rng = np.random.default_rng(2)
    x = rng.permutation(12).astype(float)
    y = rng.permutation(12).astype(float)
    rank_diff = x - y  # already ranks 0..11, no ties
    n = len(x)
    assert spearman(x, y).value == pytest.approx(1 - 6 * np.sum(rank_diff**2) / (n * (n * n - 1)))
    assert kendall(x, y).value == pytest.approx(brute_force_kendall(x, y))
    monotone = np.exp(x)
    for corr in (spearman, kendall):
        assert corr(x, monotone).value == pytest.approx(1.0)
        assert corr(x, -monotone).value == pytest.approx(-1.0)
        assert corr(x, monotone).p_value < 1e-3


def test_rank_correlations_drop_nan_and_degenerate_inputs_quietly() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = spearman([1.0, 2.0, np.nan, 4.0, 5.0], [2.0, 3.0, 1.0, np.inf, 9.0])
        assert result.n == 3 and result.value == pytest.approx(1.0)
        for corr in (spearman, kendall):
            short = corr([1.0, 2.0], [1.0, 2.0])
            assert math.isnan(short.value) and math.isnan(short.p_value) and short.n == 2
            assert math.isnan(corr([1.0, 1.0, 1.0, 1.0], [1.0, 2.0, 3.0, 4.0]).value)
            assert math.isnan(corr([1.0, 2.0, 3.0], [5.0, 5.0, 5.0]).p_value)


def test_set_metrics_is_json_ready() -> None:
    q1 = np.array([0.01, 0.05, 0.02, 0.08, 0.0])
    measured = np.array([1.0, 3.0, 2.0, np.nan, 0.1])
    predicted = np.array([1.1, 2.9, 2.2, 4.0, 0.0])
    holds = np.array([False, True, True, True, False])
    out = set_metrics(q1, predicted, measured, holds)
    json.dumps(out, allow_nan=False)
    assert out["n_grasps"] == 5 and out["n_holds"] == 3 and out["n_fails"] == 2
    assert out["q1_vs_measured"]["n_pairs"] == 4
    assert out["q1_vs_measured"]["spearman"] == pytest.approx(1.0)
    assert out["predicted_vs_measured"]["kendall"] == pytest.approx(1.0)
    assert out["auc_q1_holds"] == pytest.approx(brute_force_auc(q1, holds))
    empty = set_metrics(q1[:2], predicted[:2], measured[:2], [True, True])
    assert empty["auc_q1_holds"] is None and empty["q1_vs_measured"]["spearman"] is None
    json.dumps(empty, allow_nan=False)
