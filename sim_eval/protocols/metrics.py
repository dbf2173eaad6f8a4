"""Agreement between measured and predicted grasp resistance, and between Q1 and physics.

Per grasp: :func:`fidelity` compares the measured breaking magnitude with the analytic
prediction of the same model per direction. Over a set of grasps: rank correlations of Q1
(and of the predicted minimum resistance) with the measured minimum resistance, and the
ROC-AUC of Q1 as a predictor of holding a fixed load: exact (:func:`roc_auc`, Mann-Whitney)
or binned as DexGraspBench computes it (:func:`binned_roc`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from ogcp.planner.infra.errors import OgcpError

#: Fewer finite pairs than this make a rank correlation meaningless (NaN).
MIN_PAIRS = 3
#: Most groups of sorted grasps (ROC points - 1) in DexGraspBench's ROC curve.
ROC_BINS = 100


@dataclass(frozen=True)
class Correlation:
    """A rank correlation with its two-sided p-value.

    Attributes:
        value: The coefficient in [-1, 1]; NaN with fewer than 3 finite pairs or constant input.
        p_value: Two-sided p-value of no association; NaN whenever ``value`` is.
        n: Number of finite pairs used.
    """

    value: float
    p_value: float
    n: int


def _vector(values: object, name: str) -> NDArray[np.float64]:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"{name} must be numbers: {exc}") from None
    if array.ndim != 1:
        raise OgcpError(f"{name} must be one-dimensional, got shape {array.shape}")
    return array


def _pair(x: object, y: object, names: tuple[str, str]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    a, b = _vector(x, names[0]), _vector(y, names[1])
    if a.shape != b.shape:
        raise OgcpError(f"{names[0]} and {names[1]} must have the same length, got {len(a)} and {len(b)}")
    return a, b


def below_floor(predicted: object, floor: float) -> NDArray[np.bool_]:
    """Directions whose prediction is too small to divide by.

    Args:
        predicted: Predicted resistance per direction, shape (D,) [N].
        floor: Predictions at or below this are excluded from fidelity [N].

    Returns:
        Boolean mask, shape (D,): True where ``predicted <= floor`` or predicted is NaN.
    """
    p = _vector(predicted, "predicted")
    return ~(p > _floor(floor))


def _floor(floor: float) -> float:
    value = float(floor)
    if not (math.isfinite(value) and value >= 0):
        raise OgcpError(f"fidelity floor must be finite and >= 0 N, got {floor!r}")
    return value


def fidelity(measured: object, predicted: object, floor: float) -> NDArray[np.float64]:
    """Relative error ``|measured / predicted - 1|`` per direction.

    Args:
        measured: Measured breaking magnitude per direction, shape (D,) [N]; NaN allowed
            (a failed measurement gives NaN).
        predicted: Predicted resistance per direction, shape (D,) [N].
        floor: Directions with ``predicted <= floor`` get NaN instead of a ratio that
            would divide by almost nothing; :func:`below_floor` lists them [N].

    Returns:
        Relative errors, shape (D,) (dimensionless); NaN where excluded.

    Raises:
        OgcpError: Mismatched shapes or an invalid floor.
    """
    m, p = _pair(measured, predicted, ("measured", "predicted"))
    excluded = below_floor(p, floor)
    out = np.full(m.shape, np.nan)
    keep = ~excluded
    out[keep] = np.abs(m[keep] / p[keep] - 1.0)
    return out


def median_fidelity(values: object) -> float:
    """Median of the finite fidelity values (NaN when there are none).

    Args:
        values: Fidelity values, shape (D,), NaN for excluded directions.

    Returns:
        The median relative error, or NaN.
    """
    v = _vector(values, "fidelity values")
    finite = v[np.isfinite(v)]
    return float(np.median(finite)) if finite.size else float("nan")


def _correlation(x: object, y: object, which: str) -> Correlation:
    a, b = _pair(x, y, ("x", "y"))
    keep = np.isfinite(a) & np.isfinite(b)
    a, b = a[keep], b[keep]
    n = int(a.size)
    if n < MIN_PAIRS or np.all(a == a[0]) or np.all(b == b[0]):
        return Correlation(float("nan"), float("nan"), n)
    # Near-constant input can still trip scipy's warnings (e.g. on exact ties in p-value
    # computations); the result is well defined, so keep them out of the caller's log.
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        result = stats.spearmanr(a, b) if which == "spearman" else stats.kendalltau(a, b)
    return Correlation(float(result.statistic), float(result.pvalue), n)


def spearman(x: object, y: object) -> Correlation:
    """Spearman rank correlation over the pairs where both values are finite.

    Args:
        x: First variable, shape (n,).
        y: Second variable, shape (n,).

    Returns:
        The :class:`Correlation` (NaN with fewer than 3 finite pairs or constant input).
    """
    return _correlation(x, y, "spearman")


def kendall(x: object, y: object) -> Correlation:
    """Kendall tau-b over the pairs where both values are finite.

    Args:
        x: First variable, shape (n,).
        y: Second variable, shape (n,).

    Returns:
        The :class:`Correlation` (NaN with fewer than 3 finite pairs or constant input).
    """
    return _correlation(x, y, "kendall")


def _labels(labels: object, n: int) -> NDArray[np.bool_]:
    raw = np.asarray(labels)
    if raw.shape != (n,):
        raise OgcpError(f"labels must have shape ({n},), got {raw.shape}")
    if raw.dtype != bool and not np.all(np.isin(raw, (0, 1))):
        raise OgcpError("labels must be booleans or 0/1")
    return raw.astype(bool)


def roc_auc(scores: object, labels: object) -> float:
    """ROC-AUC of scores for binary labels, ties counted as 1/2 (Mann-Whitney U / (n1 n0)).

    It is the probability that a random positive scores higher than a random negative.

    Args:
        scores: Finite scores, shape (n,); higher should mean positive.
        labels: True / 1 for positives, shape (n,).

    Returns:
        The AUC in [0, 1]; NaN when either class is empty.

    Raises:
        OgcpError: Non-finite scores, mismatched shapes or labels that are not 0/1.
    """
    s = _vector(scores, "scores")
    if not np.all(np.isfinite(s)):
        raise OgcpError("scores contain NaN or infinite values")
    positive = _labels(labels, len(s))
    n_pos, n_neg = int(positive.sum()), int((~positive).sum())
    if n_pos == 0 or n_neg == 0:
        return float("nan")
    # Average ranks give tied pairs half a win, which is the Mann-Whitney convention.
    ranks = stats.rankdata(s)
    u = float(ranks[positive].sum()) - n_pos * (n_pos + 1) / 2.0
    return u / (n_pos * n_neg)


@dataclass(frozen=True)
class BinnedRoc:
    """DexGraspBench's ROC curve: points at the boundaries of groups of grasps sorted by energy.

    Attributes:
        tpr: True-positive rates, shape (bins + 1,).
        fpr: False-positive rates, shape (bins + 1,).
        thresholds: The energy at each boundary, shape (bins + 1,).
        auc: Area under (fpr, tpr) by the trapezoid rule; NaN when a class is empty.
    """

    tpr: NDArray[np.float64]
    fpr: NDArray[np.float64]
    thresholds: NDArray[np.float64]
    auc: float


def binned_roc(energy: object, success: object, max_bins: int = ROC_BINS) -> BinnedRoc:
    """DexGraspBench's ROC of an energy (lower predicts success) against simulated success.

    As ``compute_ROC_data`` and ``sklearn.metrics.auc`` in their ``src/task/statistic.py``
    (JYChen18/DexGraspBench@1e7a5a6, read, not copied).

    Grasps are sorted by energy with numpy's default sort (as theirs: the order of ties
    depends on it), split into ``min(max_bins, n)`` consecutive groups whose sizes differ by
    at most one (the larger first), and the rates are taken at the group boundaries. With
    at most ``max_bins`` grasps and no ties it equals the Mann-Whitney AUC; tied energies and
    larger sets can differ from it.

    Args:
        energy: Energy per grasp, shape (n,); for Q1 pass -Q1 (their Q1 metric is 2 - Q1).
        success: Simulated success per grasp, shape (n,).
        max_bins: Most groups, >= 1.

    Returns:
        The curve and its area (NaN when either class is empty).

    Raises:
        OgcpError: No grasps, non-finite energies, labels that are not 0/1 or of another
            length, or fewer than one group.
    """
    e = _vector(energy, "energy")
    if not len(e) or not np.all(np.isfinite(e)):
        raise OgcpError(f"binned ROC needs at least one grasp and finite energies, got {e.tolist()[:5]}")
    if isinstance(max_bins, bool) or not isinstance(max_bins, int) or max_bins < 1:
        raise OgcpError(f"binned ROC needs max_bins >= 1 groups, got {max_bins!r}")
    hits = _labels(success, len(e))
    order = np.argsort(e)
    hits, e = hits[order], e[order]
    bins = min(max_bins, len(e))
    size, left = divmod(len(e), bins)
    edges = np.concatenate([[0], np.cumsum([size + 1] * left + [size] * (bins - left))])
    tp = np.concatenate([[0], np.cumsum(hits)])[edges].astype(float)
    fp = edges - tp
    with np.errstate(invalid="ignore", divide="ignore"):
        tpr, fpr = tp / hits.sum(), fp / (~hits).sum()
    area = float(np.sum(np.diff(fpr) * (tpr[1:] + tpr[:-1]) / 2.0))
    last = edges.copy()
    last[-1] -= 1
    return BinnedRoc(tpr, fpr, e[last], area)


def _json_float(value: float) -> float | None:
    return None if not math.isfinite(value) else float(value)


def _correlation_entry(x: NDArray[np.float64], y: NDArray[np.float64]) -> dict[str, float | int | None]:
    rs, kt = spearman(x, y), kendall(x, y)
    return {
        "spearman": _json_float(rs.value),
        "spearman_p": _json_float(rs.p_value),
        "kendall": _json_float(kt.value),
        "kendall_p": _json_float(kt.p_value),
        "n_pairs": rs.n,
    }


def set_metrics(q1: object, predicted_min: object, measured_min: object, holds: object) -> dict[str, Any]:
    """Set-level agreement of Q1 and of the analytic prediction with the simulation.

    Args:
        q1: Q1 of each grasp, shape (n,) [-].
        predicted_min: Minimum predicted resistance over the directions, shape (n,) [N].
        measured_min: Minimum measured resistance over the directions, shape (n,) [N];
            NaN for grasps whose simulation failed (left out of the correlations).
        holds: Whether each grasp held the fixed test load, shape (n,) (bool or 0/1).

    Returns:
        JSON-ready dict (NaN written as None): ``n_grasps``, ``q1_vs_measured`` and
        ``predicted_vs_measured`` (each ``spearman``, ``spearman_p``, ``kendall``,
        ``kendall_p``, ``n_pairs``), ``auc_q1_holds``, ``n_holds``, ``n_fails``.

    Raises:
        OgcpError: Mismatched shapes, non-finite Q1 or labels that are not 0/1.
    """
    q, measured = _pair(q1, measured_min, ("q1", "measured_min"))
    predicted, _ = _pair(predicted_min, measured, ("predicted_min", "measured_min"))
    held = _labels(holds, len(q))
    return {
        "n_grasps": len(q),
        "q1_vs_measured": _correlation_entry(q, measured),
        "predicted_vs_measured": _correlation_entry(predicted, measured),
        "auc_q1_holds": _json_float(roc_auc(q, held)),
        "n_holds": int(held.sum()),
        "n_fails": int((~held).sum()),
    }
