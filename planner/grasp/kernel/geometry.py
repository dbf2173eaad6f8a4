"""Numba helpers of the exact Q1 kernel: constants, facet planes, supports, ridge hashing.

Shared by :mod:`ogcp.planner.grasp.kernel.epa` (the expanding polytope and its certificate) and
:mod:`ogcp.planner.grasp.kernel.batch`. See :mod:`ogcp.planner.grasp.kernel` for the design.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.jit import cached_njit

DIM = 6
#: Same as ogcp.planner.infra.tolerance.TOL.force_closure: Q1 at or below this reports 0.
FC_TOL = 1e-9
#: Same as ogcp.planner.infra.tolerance.TOL.rank.
RANK_TOL = 1e-9
#: Visibility / convergence tolerance relative to the largest wrench coordinate.
REL_EPS = 1e-11
#: Minimum |last pivot| / |largest pivot| of a facet simplex before we distrust it.
COND_TOL = 1e-10
#: Facet slots of the workspace for small sets (alive facets at any time); large sets
#: (N > 64) get 2**17. Overflow returns the fallback status, never a wrong value.
MAX_FACETS = 8192

# Kernel status codes: exact (canonical) Q1, no certified answer, an upper bound below the
# caller's threshold (threshold mode only), Q1 = 0 proven by the support table (batch only).
OK = 0
FALLBACK = 1
BOUND = 2
ZERO = 3
#: Threshold mode returns a bound only this far below the threshold [-]: canonical Q1 can
#: sit a rounding error above the true value, and a tie with the threshold must be exact.
CUT_MARGIN = 1e-9


# --------------------------------------------------------------------------------------
# Small dense helpers (no allocation: all scratch arrays come from the caller).
# --------------------------------------------------------------------------------------


@cached_njit(inline="always")
def _ridge_key(v: np.ndarray, skip: int) -> np.int64:
    """Pack the 5 sorted vertex indices of facet ``v`` other than position ``skip``.

    12 bits per index (N < 4096, enforced by the kernel), so a ridge is one int64 key for
    the hash that pairs up the new facets' ridges.
    """
    key = np.int64(0)
    for j in range(DIM):
        if j != skip:
            key = (key << np.int64(12)) | np.int64(v[j])
    return key


@cached_njit()
def _facet_plane(
    P: np.ndarray, v: np.ndarray, c: np.ndarray, M: np.ndarray, perm: np.ndarray, u: np.ndarray
) -> tuple[float, bool]:
    """Unit normal and offset of the hyperplane through the 6 points ``P[v]``.

    Gaussian elimination with full pivoting on the 5x6 difference matrix gives its
    null vector; full pivoting keeps the result accurate for the thin simplices that
    degenerate (coplanar, cocircular) wrench sets produce. The normal is oriented so that
    the interior reference point ``c`` lies beneath the hyperplane.

    Args:
        P: Points, shape (N, 6).
        v: 6 vertex indices.
        c: Interior reference point, shape (6,).
        M: Scratch (5, 6).
        perm: Scratch int (6,).
        u: Output unit normal, shape (6,).

    Returns:
        ``(offset, ok)``; ``ok`` is False for a numerically degenerate simplex.
    """
    for k in range(5):
        for j in range(DIM):
            M[k, j] = P[v[k + 1], j] - P[v[0], j]
    for j in range(DIM):
        perm[j] = j
    first = 0.0
    for r in range(5):
        best = -1.0
        br = r
        bc = r
        for i in range(r, 5):
            for j in range(r, DIM):
                a = abs(M[i, perm[j]])
                if a > best:
                    best = a
                    br = i
                    bc = j
        if r == 0:
            first = best
        # A tiny last pivot means the 6 points are (nearly) affinely dependent: the
        # normal would be noise, so the caller must not trust this facet.
        if best <= COND_TOL * first or best == 0.0:
            return 0.0, False
        if br != r:
            for j in range(DIM):
                t = M[r, j]
                M[r, j] = M[br, j]
                M[br, j] = t
        t2 = perm[r]
        perm[r] = perm[bc]
        perm[bc] = t2
        piv = M[r, perm[r]]
        for i in range(r + 1, 5):
            f = M[i, perm[r]] / piv
            if f != 0.0:
                for j in range(r, DIM):
                    M[i, perm[j]] -= f * M[r, perm[j]]
    for j in range(DIM):
        u[j] = 0.0
    u[perm[5]] = 1.0
    for r in range(4, -1, -1):
        s = 0.0
        for j in range(r + 1, DIM):
            s += M[r, perm[j]] * u[perm[j]]
        u[perm[r]] = -s / M[r, perm[r]]
    nrm = 0.0
    for j in range(DIM):
        nrm += u[j] * u[j]
    nrm = np.sqrt(nrm)
    d = 0.0
    dc = 0.0
    for j in range(DIM):
        u[j] /= nrm
        d += u[j] * P[v[0], j]
        dc += u[j] * c[j]
    if dc > d:
        for j in range(DIM):
            u[j] = -u[j]
        d = -d
    return d, True


@cached_njit()
def _support(P: np.ndarray, n: int, u: np.ndarray) -> tuple[float, int]:
    """Support value ``max_i P[i].u`` and its argmax over the first ``n`` points."""
    best = -np.inf
    arg = 0
    for i in range(n):
        s = 0.0
        for j in range(DIM):
            s += P[i, j] * u[j]
        if s > best:
            best = s
            arg = i
    return best, arg


@cached_njit()
def _reference_rank_ok(P: np.ndarray, n: int) -> bool:
    """ogcp.planner.grasp.quality._affine_rank_ok verbatim: SVD of the centred points."""
    X = P[:n].copy()
    mean = np.zeros(DIM)
    for i in range(n):
        for j in range(DIM):
            mean[j] += X[i, j]
    for j in range(DIM):
        mean[j] /= n
    for i in range(n):
        for j in range(DIM):
            X[i, j] -= mean[j]
    _, sv, _ = np.linalg.svd(X, full_matrices=False)
    return sv.size == DIM and sv[-1] > RANK_TOL * max(sv[0], 1e-300)


@cached_njit(inline="always")
def _slot(key: np.int64, mask: np.int64) -> np.int64:
    """Fibonacci hash of a ridge key into an open-addressing table of size mask + 1."""
    h = np.uint64(key) * np.uint64(0x9E3779B97F4A7C15)
    return np.int64(h >> np.uint64(40)) & mask


@cached_njit(inline="always")
def _mask_for(count: int) -> np.int64:
    """Smallest power-of-two-minus-one mask with at least 2 * count slots."""
    size = 16
    while size < 2 * count:
        size *= 2
    return np.int64(size - 1)


@cached_njit()
def _hash_insert(
    key: np.int64,
    owner: int,
    hkey: np.ndarray,
    hcnt: np.ndarray,
    hown: np.ndarray,
    hstamp: np.ndarray,
    gen: np.int64,
    used: np.ndarray,
    nused: int,
    mask: np.int64,
) -> tuple[np.int64, int]:
    """Insert or find ``key``; returns (slot, new nused). Slots are valid iff stamp == gen,
    so clearing the table between uses costs nothing (the generation is bumped). Only the
    first ``mask + 1`` slots are used, sized to the job, so the table stays in cache."""
    s = _slot(key, mask)
    while hstamp[s] == gen:
        if hkey[s] == key:
            hcnt[s] += 1
            return s, nused
        s = (s + 1) & mask
    hstamp[s] = gen
    hkey[s] = key
    hcnt[s] = 1
    hown[s] = owner
    used[nused] = s
    return s, nused + 1
