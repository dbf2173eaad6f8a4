"""Certificate of the kernel's lower bound: the facet complex is closed and encloses the origin.

See :mod:`ogcp.planner.grasp.kernel` for why these checks prove that no facet is missing.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.geometry import (
    DIM,
)
from ogcp.planner.grasp.kernel.jit import cached_njit

# --------------------------------------------------------------------------------------
# The kernel
# --------------------------------------------------------------------------------------


@cached_njit()
def _flat_pair_ok(
    P: np.ndarray, FV: np.ndarray, FU: np.ndarray, f: int, j: int, g: int, jg: int, scale: float, B: np.ndarray
) -> bool:
    """Orientation test for two (nearly) coplanar facets f, g sharing a ridge.

    Both simplices lie in (almost) one hyperplane; they form a cycle locally only if their
    apexes lie on opposite sides of the ridge inside that hyperplane. Project the apex
    offsets onto the 1-D complement of span(ridge directions, u_f) and compare signs.
    """
    for q in range(DIM):
        B[0, q] = FU[f, q]
    r0 = -1
    nb = 1
    for k in range(DIM):
        if k == j:
            continue
        if r0 < 0:
            r0 = FV[f, k]
            continue
        v = FV[f, k]
        for q in range(DIM):
            B[nb, q] = P[v, q] - P[r0, q]
        for b in range(nb):
            dot = 0.0
            for q in range(DIM):
                dot += B[nb, q] * B[b, q]
            for q in range(DIM):
                B[nb, q] -= dot * B[b, q]
        nr = 0.0
        for q in range(DIM):
            nr += B[nb, q] * B[nb, q]
        nr = np.sqrt(nr)
        if nr <= 1e-9 * scale:
            return False
        for q in range(DIM):
            B[nb, q] /= nr
        nb += 1
    tf = B[5]
    tg = B[6]
    af = FV[f, j]
    ag = FV[g, jg]
    for q in range(DIM):
        tf[q] = P[af, q] - P[r0, q]
        tg[q] = P[ag, q] - P[r0, q]
    for b in range(5):
        df = 0.0
        dg = 0.0
        for q in range(DIM):
            df += tf[q] * B[b, q]
            dg += tg[q] * B[b, q]
        for q in range(DIM):
            tf[q] -= df * B[b, q]
            tg[q] -= dg * B[b, q]
    nf = 0.0
    ng = 0.0
    dd = 0.0
    for q in range(DIM):
        nf += tf[q] * tf[q]
        ng += tg[q] * tg[q]
        dd += tf[q] * tg[q]
    nf = np.sqrt(nf)
    ng = np.sqrt(ng)
    return nf > 1e-9 * scale and ng > 1e-9 * scale and dd < -0.5 * nf * ng


@cached_njit()
def _certify(
    P: np.ndarray,
    FV: np.ndarray,
    FU: np.ndarray,
    FD: np.ndarray,
    FN: np.ndarray,
    alive: np.ndarray,
    hw: int,
    eps: float,
    scale: float,
    B: np.ndarray,
    stats: np.ndarray,
) -> bool:
    """Check that the facet complex covers every direction from the origin.

    For every facet f and every ridge (the 5 vertices other than FV[f, j]) the neighbour
    g = FN[f, j] must be alive, point back to f, share exactly that ridge, and the two
    simplices must induce opposite orientations on it: both apexes beneath the other's
    hyperplane (convex dihedral), or, for (nearly) coplanar pairs, apexes on opposite sides
    of the ridge inside the hyperplane. With every offset positive (checked by the caller)
    the facets then form an integer cycle of positively oriented simplices about the
    origin, whose radial projection has degree >= 1 and so covers every direction: the
    lower bound Q1 >= min d_f holds.
    """
    strict = 1e-12 * scale
    stats[3] += 1
    for f in range(hw):
        if not alive[f]:
            continue
        for j in range(DIM):
            g = FN[f, j]
            if g < 0 or not alive[g] or g == f:
                return False
            jg = -1
            for q in range(DIM):
                if FN[g, q] == f:
                    jg = q
            if jg < 0:
                return False
            if g < f:
                continue  # each pair once
            # Same ridge: the two sorted 5-lists must coincide.
            a = 0
            b = 0
            for _ in range(5):
                if a == j:
                    a += 1
                if b == jg:
                    b += 1
                if FV[f, a] != FV[g, b]:
                    return False
                a += 1
                b += 1
            pa = FV[f, j]
            pb = FV[g, jg]
            sa = FD[g]
            sb = FD[f]
            for q in range(DIM):
                sa -= FU[g, q] * P[pa, q]
                sb -= FU[f, q] * P[pb, q]
            if sa > strict and sb > strict:
                continue  # strictly convex dihedral
            if sa < -eps or sb < -eps:
                return False
            stats[1] += 1
            if not _flat_pair_ok(P, FV, FU, f, j, g, jg, scale, B):
                return False
    return True
