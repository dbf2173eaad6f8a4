"""Exact Ferrari-Canny Q1 (L1 grasp-wrench-space radius), one definition for all of ogcp.

Q1 of a wrench set W (N, 6) is the distance from the origin to the boundary of conv(W)
when the origin lies strictly inside, else 0. "Strictly" means Q1 > ``TOL.force_closure``
(1e-9): smaller values report 0. Degenerate but well-formed sets (fewer than 7 wrenches, none
at all, wrenches spanning an affine subspace of fewer than 6 dimensions) give 0. An array of
another shape (such as a contact set's (n, k, 6) wrenches, not stacked) or with NaN or infinite
entries raises :class:`~ogcp.planner.infra.errors.OgcpError`: it is a mistake, not a grasp of Q1 0.
The public functions check their input (one pass over the array, as :func:`q1_certificate` always
made to find NaNs) and from there run on unchecked internals.

The fast path is the compiled expanding-polytope kernel of :mod:`ogcp.planner.grasp.kernel`, whose
answers carry a certificate (the facet complex it built provably encloses the ball of
radius Q1). Whatever it cannot certify comes here, to two qhull paths. The full hull of
a large wrench set is very expensive (800 wrenches: seconds and 100k+ facets), so
:func:`q1_certificate` never builds it for large sets. The qhull path grows a small active subset
A of W (an expanding-polytope scheme): qhull on A gives the facet of conv(A) nearest the
origin with offset d and unit normal u; the support of the *full* set along u,
``h(u) = max_w u.w``, is an upper bound on Q1 and d (when positive) is a lower bound,
because conv(A) is inside conv(W). If ``h(u) - d`` exceeds ``TOL.q1_gap`` the support
points of the nearest facets are added to A and the loop repeats; otherwise Q1 is
certified to within ``TOL.q1_gap``. A certified nearest facet with d <= 0 proves that the
origin is not strictly inside conv(W).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel import FALLBACK, canonical_plane, evaluate_batch, kernel_q1, last_active
from ogcp.planner.grasp.wrench import check_finite, finite_array, shaped_array
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.tolerance import TOL

if TYPE_CHECKING:
    from scipy.spatial import ConvexHull

DIM = 6
#: The compiled kernel takes sets below 4096 wrenches (its ridge keys hold 12-bit indices).
KERNEL_MAX = 4095
#: Sets above KERNEL_MAX: seeded directions whose support points start the active set, and
#: how many support points beyond the facet join it per round.
ACTIVE_DIRECTIONS, ACTIVE_SEED, ACTIVE_ADD = 116, 0, 64
#: Wrench sets up to this size are hulled directly: one qhull call beats the loop.
DIRECT_HULL_MAX = 96
#: With direction hints the active-set loop starts close to the answer and wins earlier.
HINTED_DIRECT_HULL_MAX = 24
#: Nearest facets whose support points may join the active set per iteration.
FACETS_PER_ROUND = 24


@dataclass(frozen=True)
class Q1Certificate:
    """Exact Q1 with the facet that certifies it.

    Attributes:
        q1: Ferrari-Canny Q1 [-]; 0 when not in force closure or degenerate.
        offset: For force closure, the offset of the certified nearest facet (= Q1) [-].
            Otherwise the offset of a supporting hyperplane proving it (<= 1e-9;
            negative when the origin is strictly outside), not necessarily the most
            negative facet offset (use :func:`signed_q1` for that). NaN if degenerate.
        direction: Unit outward normal of that facet or hyperplane, shape (6,): for force
            closure, the wrench direction the grasp resists least. NaN if degenerate.
        hull_calls: Number of qhull invocations spent.
    """

    q1: float
    offset: float
    direction: NDArray[np.float64]
    hull_calls: int

    @property
    def force_closure(self) -> bool:
        """Whether the origin lies strictly inside the hull (Q1 > tolerance)."""
        return self.q1 > 0.0


def _checked_wrenches(wrenches: object) -> NDArray[np.float64]:
    """The wrench set as a float array of shape (N, 6), or an :class:`OgcpError` saying why not."""
    # The commonest slip is a contact set's (n, k, 6) wrenches passed whole: say how to stack them.
    return finite_array(wrenches, "wrenches", "(N, 6)", 2, DIM, hint="stack (n, k, 6) wrenches with .reshape(-1, 6)")


def _degenerate() -> Q1Certificate:
    return Q1Certificate(0.0, float("nan"), np.full(DIM, np.nan), 0)


def _clip(offset: float) -> float:
    return offset if offset > TOL.force_closure else 0.0


def _affine_rank_ok(points: NDArray[np.float64]) -> bool:
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    return bool(singular.size == DIM and singular[-1] > TOL.rank * max(singular[0], 1e-300))


def _hull(points: NDArray[np.float64]) -> ConvexHull | None:
    from scipy.spatial import ConvexHull, QhullError  # the fallback paths only: scipy.spatial costs 0.2 s to import

    try:
        return ConvexHull(points)
    except (QhullError, ValueError):
        return None


def _complete_to_full_dimension(wrenches: NDArray[np.float64], active: list[int]) -> list[int]:
    """Add support points until the active set spans 6 affine dimensions."""
    active = list(dict.fromkeys(active))
    for _ in range(DIM + 1):
        pts = wrenches[active]
        centred = pts - pts.mean(axis=0)
        _, singular, vt = np.linalg.svd(centred, full_matrices=True)
        rank = int(np.sum(singular > TOL.rank * max(singular[0] if singular.size else 1.0, 1e-300)))
        if rank >= DIM:
            return active
        # Directions orthogonal to the current affine hull: W is full-dimensional, so the
        # extreme wrenches along each of them leave that hull.
        for direction in vt[rank:]:
            proj = wrenches @ direction
            for idx in (int(np.argmax(proj)), int(np.argmin(proj))):
                if idx not in active:
                    active.append(idx)
    return active


def q1_certificate(
    wrenches: NDArray[np.float64], hints: NDArray[np.float64] | None = None, kernel: bool = True
) -> Q1Certificate:
    """Exact Q1 of a wrench set, with the certifying facet.

    Args:
        wrenches: Wrenches, shape (N, 6) [N] (torques already divided by rho).
        hints: Optional unit directions, shape (j, 6), along which the hull is expected
            to be closest to the origin; their support points seed the active set. They
            only affect speed, never the value.
        kernel: Try the compiled kernel first (False forces the qhull paths; the value
            is the same, bit for bit).

    Returns:
        The :class:`Q1Certificate` (Q1 = 0 for a degenerate set).

    Raises:
        OgcpError: For wrenches of another shape than (N, 6) or with NaN or infinite
            entries, or hints of another shape than (j, 6) or not finite.
    """
    w = _checked_wrenches(wrenches)
    if hints is not None:
        one = np.ndim(hints) == 1  # a single direction, which the active-set loop also takes
        hints = finite_array(hints, "hints", "(j, 6)", 1 if one else 2, DIM)
    return _q1_certificate(w, hints, kernel)


def _q1_certificate(w: NDArray[np.float64], hints: NDArray[np.float64] | None, kernel: bool) -> Q1Certificate:
    """:func:`q1_certificate` of a checked (N, 6) float array of finite wrenches."""
    if w.shape[0] <= DIM:
        return _degenerate()
    seed = None
    if kernel and w.shape[0] <= KERNEL_MAX:
        # The kernel applies the rank test itself wherever it could change the answer
        # (Q1 <= sigma_min), so the SVD below is only paid on the qhull paths.
        ok, value, direction = kernel_q1(w)
        if ok and value > 0:
            return Q1Certificate(value, value, direction, 0)  # already canonical
        if ok and np.all(np.isfinite(direction)):
            return Q1Certificate(0.0, float(np.max(w @ direction)), direction, 0)
        if not ok:
            # The points the kernel put in its hull span the hull near the origin: seeded
            # with them, the qhull loop usually ends after one call (speed only).
            seed = last_active(len(w))
    if not _affine_rank_ok(w):
        return _degenerate()
    if kernel and w.shape[0] > KERNEL_MAX:
        cert = _kernel_active_set_q1(w)
        if cert is not None:
            return cert
    if w.shape[0] <= (DIRECT_HULL_MAX if hints is None and seed is None else HINTED_DIRECT_HULL_MAX):
        return _full_hull_certificate(w)
    return _active_set_q1(w, hints, seed)


def _kernel_active_set_q1(w: NDArray[np.float64]) -> Q1Certificate | None:
    """The active-set certificate with the compiled kernel on the subset (sets too large for it).

    The kernel gives the nearest facet of conv(A) for a subset A; the support of the full
    set along its normal bounds Q1 from above, the kernel's certified value from below,
    and support points beyond the facet join A until the two agree. None when the kernel
    cannot certify or A outgrows it (the caller then uses qhull).
    """
    rng = np.random.default_rng(ACTIVE_SEED)
    directions = rng.normal(size=(ACTIVE_DIRECTIONS, DIM))
    directions = np.vstack([np.eye(DIM), -np.eye(DIM), directions / np.linalg.norm(directions, axis=1, keepdims=True)])
    active = np.zeros(len(w), dtype=bool)
    active[np.argmax(w @ directions.T, axis=0)] = True
    while active.sum() <= KERNEL_MAX:
        ok, value, direction = kernel_q1(w[active])
        if not ok or not np.all(np.isfinite(direction)):
            return None  # a degenerate subset says nothing about the full set
        support = w @ direction
        top = float(support.max())
        if value <= 0 and top <= TOL.force_closure:
            return Q1Certificate(0.0, top, direction, 0)
        if value > 0 and top - value <= TOL.q1_gap:
            return _certificate(w, direction, value, 0)
        beyond = np.flatnonzero((support > max(value, 0.0) + TOL.q1_gap) & ~active)
        if beyond.size == 0:
            return None
        active[beyond[np.argsort(-support[beyond])[:ACTIVE_ADD]]] = True
    return None


def _active_set_q1(
    w: NDArray[np.float64], hints: NDArray[np.float64] | None, seed: NDArray[np.intp] | None = None
) -> Q1Certificate:
    """The qhull active-set loop; ``seed`` (indices) joins the initial active set."""
    seeds = np.vstack([np.eye(DIM), -np.eye(DIM)] + ([] if hints is None else [np.atleast_2d(hints)]))
    active = [int(i) for i in np.argmax(w @ seeds.T, axis=0)]
    if seed is not None:
        active += [int(i) for i in seed]
    active = _complete_to_full_dimension(w, active)
    in_active = np.zeros(len(w), dtype=bool)
    in_active[active] = True
    for hull_calls in range(1, len(w) + 1):
        hull = _hull(w[in_active])
        if hull is None:
            # A numerically flat active set: fall back to hulling everything.
            cert = _direct_certificate(w)
            return Q1Certificate(cert.q1, cert.offset, cert.direction, hull_calls + cert.hull_calls)
        offsets = -hull.equations[:, DIM]
        nearest = np.argsort(offsets)[:FACETS_PER_ROUND]
        normals = hull.equations[nearest, :DIM]
        support = w @ normals.T
        gaps = support.max(axis=0) - offsets[nearest]
        if gaps[0] <= TOL.q1_gap:
            return _certificate(w, normals[0], float(offsets[nearest[0]]), hull_calls)
        beyond = gaps > TOL.q1_gap
        new = np.unique(np.argmax(support[:, beyond], axis=0))
        new = new[~in_active[new]]
        if new.size == 0:  # cannot happen in exact arithmetic; guard against round-off loops
            return _certificate(w, normals[0], float(offsets[nearest[0]]), hull_calls)
        in_active[new] = True
    raise AssertionError("active-set Q1 did not terminate")  # pragma: no cover


def q1_certificate_direct(wrenches: NDArray[np.float64]) -> Q1Certificate:
    """Q1 from the full convex hull of all wrenches (reference path; slow for large sets).

    Args:
        wrenches: Wrenches, shape (N, 6).

    Returns:
        The :class:`Q1Certificate` computed from one full qhull call.

    Raises:
        OgcpError: For wrenches of another shape than (N, 6) or with NaN or infinite entries.
    """
    return _direct_certificate(_checked_wrenches(wrenches))


def _direct_certificate(w: NDArray[np.float64]) -> Q1Certificate:
    """:func:`q1_certificate_direct` of checked wrenches."""
    return _degenerate() if w.shape[0] <= DIM else _full_hull_certificate(w)


def _full_hull_certificate(w: NDArray[np.float64]) -> Q1Certificate:
    hull = _hull(w)
    if hull is None:
        return _degenerate()
    offsets = -hull.equations[:, DIM]
    best = int(np.argmin(offsets))
    return _certificate(w, hull.equations[best, :DIM], float(offsets[best]), 1)


def _certificate(w: NDArray[np.float64], normal: NDArray[np.float64], offset: float, hull_calls: int) -> Q1Certificate:
    """Certificate of a facet, with its hyperplane refitted canonically.

    Different hulls (full or active-set, other seeds) find the same facet with
    hyperplanes that differ in the last bits. The compiled refit through the wrenches on
    it (:func:`ogcp.planner.grasp.kernel.canonical_plane`, the same code the kernel runs on its own
    answers) makes the reported value a function of the wrench set alone, so every
    method reports bit-identical Q1 for the same grasp.
    """
    normal, offset, _ = canonical_plane(w, normal, offset)
    return Q1Certificate(_clip(offset), offset, normal, hull_calls)


def exact_q1_batch(
    contact_wrenches: NDArray[np.float64], grasps: NDArray[np.int64], table: NDArray[np.float64], cut: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Exact Q1 of many grasps of one contact set: the compiled batch, qhull for the rest.

    This is what exhaustive search does per grasp. The kernel's exact answers are already
    canonical (refitted in compiled code), so only the grasps it could not certify go
    through :func:`q1`.

    Args:
        contact_wrenches: Wrenches of every contact, shape (n, k, 6) [N].
        grasps: Contact indices, shape (B, m).
        table: :func:`ogcp.planner.grasp.kernel.support_table` of ``contact_wrenches``.
        cut: Values below ``cut - CUT_MARGIN`` may be upper bounds (branch and bound) [-].

    Returns:
        ``(q1, status)`` per grasp, shape (B,) each: the canonical Q1 (bit-identical to
        every other method) or a bound below the cut, and the kernel's status
        (``FALLBACK`` marks the grasps recomputed here).

    Raises:
        OgcpError: For wrenches of another shape than (n, k, 6), grasps that are not
            integer indices of shape (B, m) below n, NaN or infinite wrenches of a contact
            they use, a table without one row per contact, or a cut that is not finite. The compiled kernel does not check its
            indices, so these checks are what keeps a bad grasp from reading stray memory.
    """
    w = shaped_array(contact_wrenches, "contact wrenches", "(n, k, 6)", 3, DIM)
    g = np.asarray(grasps)
    if g.ndim != 2 or not (g.dtype.kind in "iu" or g.size == 0):
        raise OgcpError(f"grasps must be integer contact indices of shape (B, m), got {g.dtype} of shape {g.shape}")
    if g.size and (int(g.min()) < 0 or int(g.max()) >= len(w)):
        raise OgcpError(f"grasps must index the {len(w)} contacts, got indices from {int(g.min())} to {int(g.max())}")
    # es-pruned calls this 32 grasps at a time: check the wrenches those grasps use, not all n.
    if not np.isfinite(w if g.size >= len(w) else w[g.ravel()]).all():
        check_finite(w, "contact wrenches")  # names the first bad entry
    t = np.asarray(table)
    if t.ndim != 2 or t.shape[0] != len(w) or t.shape[1] == 0:
        raise OgcpError(f"table must have shape ({len(w)}, D), one row per contact, got {t.shape}")
    if not math.isfinite(cut):
        raise OgcpError(f"cut must be a finite number, got {cut!r}")
    values, status = evaluate_batch(w, g, table=t, threshold=cut)
    for i in np.flatnonzero(status == FALLBACK):
        values[i] = _q1_certificate(w[g[i]].reshape(-1, DIM), None, True).q1
    return values, status


def signed_q1(wrenches: NDArray[np.float64]) -> float:
    """Q1 when in force closure, else the most negative facet offset (full hull; small sets).

    The signed form gives randomised optimisers (HFTS) a slope outside force closure.

    Args:
        wrenches: Wrenches, shape (N, 6).

    Returns:
        Q1 > 0, or the smallest facet offset (<= 1e-9) [-]; -inf for degenerate sets.

    Raises:
        OgcpError: For wrenches of another shape than (N, 6) or with NaN or infinite entries.
    """
    w = _checked_wrenches(wrenches)
    cert = _q1_certificate(w, None, True)
    if cert.q1 > 0:
        return cert.q1
    full = _direct_certificate(w)
    return full.offset if np.isfinite(full.offset) else -np.inf


def q1(wrenches: NDArray[np.float64]) -> float:
    """Exact Ferrari-Canny Q1 of a wrench set.

    Args:
        wrenches: Wrenches, shape (N, 6).

    Returns:
        Q1 [-]; 0 when the origin is not strictly inside the hull or the set is degenerate
        (fewer than 7 wrenches, none, or all in a lower-dimensional affine subspace).

    Raises:
        OgcpError: For wrenches of another shape than (N, 6), e.g. a contact set's
            (n, k, 6) wrenches not stacked, or with NaN or infinite entries.
    """
    return _q1_certificate(_checked_wrenches(wrenches), None, True).q1
