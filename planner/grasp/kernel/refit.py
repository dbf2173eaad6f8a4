"""Canonical refit of a certified facet's hyperplane (numba), shared by every Q1 path.

Different hulls (the compiled kernel, qhull on the full set or on an active subset) find
the same nearest facet with hyperplanes that differ in the last bits. Every path hands
its facet to :func:`_canonical_plane`, which selects the wrenches within ``ON_FACET`` of
it and refits the hyperplane through them, in index order, by a Householder QR with
column pivoting of the centred points. The result is a function of the wrench set and
the on-facet index set alone, so the same grasp gets the bit-identical Q1 from A*, ES,
HFTS or a direct call. It is plain IEEE arithmetic in a fixed order (no BLAS, no LAPACK):
the bits do not depend on the machine's linear-algebra library either.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.geometry import DIM, RANK_TOL
from ogcp.planner.grasp.kernel.jit import cached_njit

#: Wrenches this close to a certified facet's hyperplane are taken to lie on it [N].
ON_FACET = 1e-11


@cached_njit()
def _canonical_plane(
    P: np.ndarray, n: int, u: np.ndarray, d: float, X: np.ndarray, out: np.ndarray
) -> tuple[float, bool]:
    """Hyperplane through the points of ``P[:n]`` that lie on the facet ``u.x = d``.

    The points with ``|P_i . u - d| <= ON_FACET`` are centred on their mean (summed in
    index order); a Householder QR with column pivoting of that (k, 6) matrix gives the
    null vector of its 5-dimensional row space. Accepted only when k >= 6 and the
    points span 5 dimensions (``|R_44| > RANK_TOL |R_00|``, the QR analogue of the
    singular-value test of the reference).

    Args:
        P: Points, shape (>= n, 6) [N].
        n: Number of points to consider.
        u: Unit normal of the facet, shape (6,).
        d: Its offset [N].
        X: Scratch, shape (>= n, 6).
        out: Receives the refitted unit normal, oriented like ``u``, shape (6,).

    Returns:
        ``(offset, ok)``: the refitted offset [N]; ``ok`` False (``out`` untouched) when
        the on-facet points do not determine a hyperplane.
    """
    centre = np.zeros(DIM)
    k = 0
    for i in range(n):
        t = -d
        for j in range(DIM):
            t += P[i, j] * u[j]
        if abs(t) <= ON_FACET:
            for j in range(DIM):
                X[k, j] = P[i, j]
                centre[j] += P[i, j]
            k += 1
    if k < DIM:
        return d, False
    for j in range(DIM):
        centre[j] /= k
    for i in range(k):
        for j in range(DIM):
            X[i, j] -= centre[j]
    perm = np.arange(DIM)
    diag = np.zeros(DIM)
    for r in range(DIM):
        # Pivot: the remaining column of largest norm (recomputed: k x 6 is tiny and
        # downdated norms lose accuracy exactly in the thin cases that matter).
        best = -1.0
        bc = r
        for c in range(r, DIM):
            s = 0.0
            for i in range(r, k):
                s += X[i, perm[c]] * X[i, perm[c]]
            if s > best:
                best = s
                bc = c
        t = perm[r]
        perm[r] = perm[bc]
        perm[bc] = t
        pc = perm[r]
        norm = np.sqrt(best)
        if norm == 0.0:
            diag[r] = 0.0
            continue
        alpha = -norm if X[r, pc] >= 0.0 else norm
        # Householder vector v = x - alpha e_r, stored in place below the diagonal.
        X[r, pc] -= alpha
        vnorm2 = 0.0
        for i in range(r, k):
            vnorm2 += X[i, pc] * X[i, pc]
        for c in range(r + 1, DIM):
            cc = perm[c]
            s = 0.0
            for i in range(r, k):
                s += X[i, pc] * X[i, cc]
            f = 2.0 * s / vnorm2
            for i in range(r, k):
                X[i, cc] -= f * X[i, pc]
        diag[r] = alpha
    if not abs(diag[DIM - 2]) > RANK_TOL * abs(diag[0]):
        return d, False  # fewer than 5 dimensions: not a facet
    # Null vector of R (upper triangle in rows 0..4 of X, diagonal in diag): z_5 = 1.
    z = np.zeros(DIM)
    z[perm[DIM - 1]] = 1.0
    for r in range(DIM - 2, -1, -1):
        s = 0.0
        for c in range(r + 1, DIM):
            s += X[r, perm[c]] * z[perm[c]]
        z[perm[r]] = -s / diag[r]
    nrm = 0.0
    dot = 0.0
    for j in range(DIM):
        nrm += z[j] * z[j]
        dot += z[j] * u[j]
    nrm = np.sqrt(nrm)
    if dot < 0.0:
        nrm = -nrm
    offset = 0.0
    for j in range(DIM):
        out[j] = z[j] / nrm
        offset += out[j] * centre[j]
    return offset, True
