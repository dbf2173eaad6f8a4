"""The expanding-polytope kernel: exact Q1 of one wrench set, in numba.

See :mod:`ogcp.planner.grasp.kernel` for the design and the tolerances.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.certify import _certify
from ogcp.planner.grasp.kernel.geometry import (
    BOUND,
    CUT_MARGIN,
    DIM,
    FALLBACK,
    FC_TOL,
    MAX_FACETS,
    OK,
    REL_EPS,
    _facet_plane,
    _hash_insert,
    _mask_for,
    _reference_rank_ok,
    _ridge_key,
    _support,
)
from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.grasp.kernel.refit import _canonical_plane

# --------------------------------------------------------------------------------------
# Workspace
# --------------------------------------------------------------------------------------


class Workspace:
    """Preallocated scratch arrays for :func:`_q1_kernel` (reuse across grasps).

    Facets live in slots ``0 .. hw-1`` of the arrays; freed slots go on a stack and are
    reused, so facet indices stay valid while they are alive (adjacency needs that).

    Args:
        max_points: Largest wrench set the workspace will serve.
        max_facets: Facet capacity; overflow returns the fallback status.
    """

    def __init__(self, max_points: int = 64, max_facets: int = MAX_FACETS) -> None:
        self.FV = np.zeros((max_facets, DIM), dtype=np.int32)  # sorted vertex indices
        self.FU = np.zeros((max_facets, DIM))  # outward unit normals
        self.FD = np.zeros(max_facets)  # offsets u.x = d
        self.FN = np.zeros((max_facets, DIM), dtype=np.int32)  # neighbour opposite vertex j
        self.alive = np.zeros(max_facets, dtype=np.bool_)
        self.vis = np.zeros(max_facets, dtype=np.bool_)
        self.free = np.zeros(max_facets, dtype=np.int32)
        self.horizon = np.zeros((max_facets * DIM, 3), dtype=np.int32)  # (visible f, j, g)
        size = 1 << 16  # per-iteration horizon pairing only; overflow -> fallback
        self.hkey = np.zeros(size, dtype=np.int64)
        self.hcnt = np.zeros(size, dtype=np.int32)
        self.hown = np.zeros(size, dtype=np.int64)
        self.hstamp = np.zeros(size, dtype=np.int64)
        self.used = np.zeros(size, dtype=np.int64)
        self.gen = np.zeros(1, dtype=np.int64)
        self.active = np.zeros(max_points, dtype=np.bool_)
        self.M = np.zeros((5, DIM))
        self.perm = np.zeros(DIM, dtype=np.int64)
        self.R = np.zeros((max_points, DIM))  # residuals for the initial simplex
        self._tuple: tuple[np.ndarray, ...] | None = None

    def as_tuple(self) -> tuple[np.ndarray, ...]:
        """The arrays in the order the kernel expects (built once: cheaper to pass)."""
        if self._tuple is None:
            self._tuple = self._build_tuple()
        return self._tuple

    def _build_tuple(self) -> tuple[np.ndarray, ...]:
        return (
            self.FV,
            self.FU,
            self.FD,
            self.FN,
            self.alive,
            self.vis,
            self.free,
            self.horizon,
            self.hkey,
            self.hcnt,
            self.hown,
            self.hstamp,
            self.used,
            self.gen,
            self.active,
            self.M,
            self.perm,
            self.R,
        )


@cached_njit(inline="always")
def _alloc(alive: np.ndarray, free: np.ndarray, nfree: int, hw: int) -> tuple[int, int, int]:
    """A facet slot: reuse a freed one or extend the high-water mark. Returns (slot, nfree, hw)."""
    if nfree > 0:
        nfree -= 1
        s = free[nfree]
    else:
        s = hw
        hw += 1
    alive[s] = True
    return s, nfree, hw


# nogil: the search evaluates several sets at once in threads (ogcp.planner.grasp.subset_quality).
@cached_njit(nogil=True)
def _q1_kernel(
    P: np.ndarray, n: int, ws: tuple, certify: bool, stats: np.ndarray, threshold: float, direction: np.ndarray
) -> tuple[int, float]:
    """Q1 of the first ``n`` rows of ``P`` (status, value); see :mod:`ogcp.planner.grasp.kernel`.

    ``direction`` (6,) receives the unit normal of the facet that settled the answer: the
    certified nearest facet, or a direction whose support proves Q1 = 0; when only the
    certificate failed, the nearest facet found (a hint, not a proof). It is left
    untouched when no facet was involved (degenerate input, other fallbacks).

    With ``threshold`` > 0 the loop stops as soon as a support value
    s < threshold - CUT_MARGIN proves Q1 < threshold and returns ``(BOUND, s)``: callers
    that only need grasps at least as good as a threshold (branch and bound) save most of
    the hull work, and a grasp whose Q1 ties the threshold still gets its exact value.

    An exact answer is canonical: the certified facet's hyperplane is refitted through
    the points on it (:func:`ogcp.planner.grasp.kernel.refit._canonical_plane`), so every path
    reports the bit-identical Q1 for the same wrench set.

    Returns:
        ``(OK, q1)``, ``(BOUND, s)`` (threshold mode) or ``(FALLBACK, nan)`` when the
        result could not be certified.
    """
    FV, FU, FD, FN, alive, vis, free, horizon, hkey, hcnt, hown, hstamp, used, gen, active, M, perm, R = ws
    if n <= DIM:
        return OK, 0.0
    if n >= 4096:
        return FALLBACK, np.nan  # ridge keys hold 12-bit vertex indices
    scale = 0.0
    for i in range(n):
        for j in range(DIM):
            a = abs(P[i, j])
            if not np.isfinite(a):
                return OK, 0.0
            scale = max(scale, a)
    if scale == 0.0:
        return OK, 0.0
    eps = REL_EPS * scale
    res_tol = 1e-13 * scale
    cap = FV.shape[0]

    # ---- initial simplex: greedy farthest point from the current affine hull --------
    # Residuals of every point against the growing orthonormal basis are updated in
    # place (one projection per new basis vector), so this costs O(6 n DIM).
    for i in range(n):
        active[i] = False
    sel = np.empty(DIM + 1, dtype=np.int64)
    best = -1.0
    for i in range(n):
        s = 0.0
        for j in range(DIM):
            s += P[i, j] * P[i, j]
        if s > best:
            best = s
            sel[0] = i
    for i in range(n):
        for j in range(DIM):
            R[i, j] = P[i, j] - P[sel[0], j]
    bvec = np.empty(DIM)
    for k in range(1, DIM + 1):
        bestd = -1.0
        bi = 0
        for i in range(n):
            dd = 0.0
            for j in range(DIM):
                dd += R[i, j] * R[i, j]
            if dd > bestd:
                bestd = dd
                bi = i
        if np.sqrt(bestd) <= 1e-7 * scale:
            # Nearly flat set: decide exactly as the reference does.
            if not _reference_rank_ok(P, n):
                return OK, 0.0
            return FALLBACK, np.nan
        sel[k] = bi
        nr = np.sqrt(bestd)
        for j in range(DIM):
            bvec[j] = R[bi, j] / nr
        for i in range(n):
            dot = 0.0
            for j in range(DIM):
                dot += R[i, j] * bvec[j]
            for j in range(DIM):
                R[i, j] -= dot * bvec[j]
    c = np.zeros(DIM)  # interior reference point: stays strictly inside conv(active)
    for k in range(DIM + 1):
        active[sel[k]] = True
        for j in range(DIM):
            c[j] += P[sel[k], j] / (DIM + 1)
    srt = np.sort(sel)
    u = np.empty(DIM)
    for a in range(DIM + 1):  # facet a omits vertex srt[a]
        q = 0
        for k in range(DIM + 1):
            if k != a:
                FV[a, q] = srt[k]
                FN[a, q] = k  # the facet omitting srt[k] shares the ridge without srt[k]
                q += 1
        d, ok = _facet_plane(P, FV[a], c, M, perm, u)
        if not ok:
            return FALLBACK, np.nan
        FU[a] = u
        FD[a] = d
        alive[a] = True
    hw = DIM + 1
    nfree = 0

    newv = np.empty(DIM, dtype=np.int32)
    nn = np.empty(DIM)
    B7 = np.empty((7, DIM))
    for _it in range(n + 1):
        stats[0] += 1
        # Facet nearest the origin (smallest signed offset).
        f = -1
        for g in range(hw):
            if alive[g] and (f < 0 or FD[g] < FD[f]):
                f = g
        s, idx = _support(P, n, FU[f])
        if s <= FC_TOL:
            direction[:] = FU[f]
            return OK, 0.0  # h(u) <= 1e-9 for a unit u proves Q1 <= 1e-9
        if s < threshold - CUT_MARGIN:
            direction[:] = FU[f]
            return BOUND, s  # proven Q1 <= s < threshold: an upper bound, not Q1
        dmin = FD[f]
        if s - dmin <= eps:
            # Converged: Q1 <= s (support) and, once certified, Q1 >= dmin.
            if dmin <= FC_TOL:
                return OK, 0.0
            if certify and not _certify(P, FV, FU, FD, FN, alive, hw, eps, scale, B7, stats):
                direction[:] = FU[f]  # uncertified, but a good seed for the caller's fallback
                return FALLBACK, np.nan
            # The reference calls the set rank-deficient only if sigma_min <= 1e-9 sigma_max,
            # and Q1 <= sigma_min, so its SVD test can only matter for tiny Q1.
            if dmin <= 1e-8 * scale * n and not _reference_rank_ok(P, n):
                return OK, 0.0
            value, refitted = _canonical_plane(P, n, FU[f], dmin, R, direction)
            if not refitted:
                direction[:] = FU[f]
                value = dmin
            return OK, value if value > FC_TOL else 0.0
        if active[idx]:
            return FALLBACK, np.nan  # an active point beyond the complex: rounding trouble
        active[idx] = True
        pv = P[idx]
        # Visible facets (strictly beyond by eps; coplanar points count as not visible).
        for g in range(hw):
            if alive[g]:
                t = -FD[g]
                for j in range(DIM):
                    t += FU[g, j] * pv[j]
                vis[g] = t > eps
            else:
                vis[g] = False
        # Horizon ridges: a visible facet next to a non-visible one.
        nh = 0
        for g in range(hw):
            if vis[g]:
                for j in range(DIM):
                    nb = FN[g, j]
                    if not vis[nb]:
                        horizon[nh, 0] = g
                        horizon[nh, 1] = j
                        horizon[nh, 2] = nb
                        nh += 1
        gen[0] += 1
        hg = gen[0]
        nused = 0
        if 2 * nh * 5 > hkey.shape[0]:
            return FALLBACK, np.nan
        mask = _mask_for(nh * 5)
        for e in range(nh):
            fv = horizon[e, 0]
            jv = horizon[e, 1]
            gn = horizon[e, 2]
            if nfree == 0 and hw >= cap:
                return FALLBACK, np.nan
            h, nfree, hw = _alloc(alive, free, nfree, hw)
            stats[2] += 1
            vis[h] = False
            # Vertices: the ridge (fv without position jv) plus the new point, kept sorted.
            q = 0
            pos_p = -1
            for k in range(DIM):
                if k == jv:
                    continue
                vk = FV[fv, k]
                if pos_p < 0 and idx < vk:
                    newv[q] = idx
                    pos_p = q
                    q += 1
                newv[q] = vk
                q += 1
            if pos_p < 0:
                newv[q] = idx
                pos_p = q
            for k in range(DIM):
                FV[h, k] = newv[k]
                FN[h, k] = -1
            # Hyperplane through the ridge and p: in the pencil of the two facets at the
            # ridge, n = alpha u_f + beta u_g with p on it (30 flops instead of an
            # elimination); verified by its residual at all 6 vertices.
            alpha = FD[gn]
            beta = -FD[fv]
            for j in range(DIM):
                alpha -= FU[gn, j] * pv[j]
                beta += FU[fv, j] * pv[j]
            nrm = 0.0
            for j in range(DIM):
                nn[j] = alpha * FU[fv, j] + beta * FU[gn, j]
                nrm += nn[j] * nn[j]
            nrm = np.sqrt(nrm)
            good = nrm > 1e-3 * (abs(alpha) + abs(beta))
            if good:
                dd = (alpha * FD[fv] + beta * FD[gn]) / nrm
                dc = 0.0
                for j in range(DIM):
                    nn[j] /= nrm
                    dc += nn[j] * c[j]
                good = dc < dd
                if good:
                    for k in range(DIM):
                        t = -dd
                        for j in range(DIM):
                            t += nn[j] * P[newv[k], j]
                        if abs(t) > res_tol:
                            good = False
                            break
            if good:
                for j in range(DIM):
                    FU[h, j] = nn[j]
                FD[h] = dd
            else:
                stats[4] += 1
                d, ok = _facet_plane(P, FV[h], c, M, perm, u)
                if not ok:
                    return FALLBACK, np.nan
                FU[h] = u
                FD[h] = d
            # Adjacency across the old ridge: the non-visible neighbour now sees h.
            FN[h, pos_p] = gn
            for k in range(DIM):
                if FN[gn, k] == fv:
                    FN[gn, k] = h
            # Ridges through p are shared by two new facets: pair them by hashing.
            for k in range(DIM):
                if k == pos_p:
                    continue
                sl, nused = _hash_insert(
                    _ridge_key(FV[h], k), h * 8 + k, hkey, hcnt, hown, hstamp, hg, used, nused, mask
                )
                if hcnt[sl] == 2:
                    o = hown[sl]
                    FN[h, k] = o // 8
                    FN[o // 8, o % 8] = h
                elif hcnt[sl] > 2:
                    return FALLBACK, np.nan  # non-manifold horizon
        for i in range(nused):
            if hcnt[used[i]] != 2:
                return FALLBACK, np.nan  # a ridge through p without a partner: broken horizon
        # Retire the visible facets.
        for g in range(hw):
            if vis[g]:
                alive[g] = False
                vis[g] = False
                free[nfree] = g
                nfree += 1
    return FALLBACK, np.nan
