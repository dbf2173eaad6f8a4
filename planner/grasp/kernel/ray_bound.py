"""An upper bound of Q1 from the facet that a ray from the origin leaves the hull through.

For any unit u, Q1(W) <= h(u) = max_i w_i.u. The support bound of the search evaluates h
on a fixed set of directions; this finds a better direction for one wrench set: the normal
of the facet of conv(W) that the ray along a given direction c crosses. That facet is the
optimum of the linear programme

    maximise c.y  subject to  w_i.y <= 1 for every wrench i,

whose feasible set is the polar of conv(W) (bounded when the origin is strictly inside):
the optimal vertex y* is the facet's normal divided by its offset, so h(y*/|y*|) = 1/|y*|.
The facet it finds lies nearer the origin than h(c) whenever the ray does not cross the
hull where c's supporting hyperplane touches it, which is what a direction chosen from a
finite set usually misses by.

The programme is solved by an active-set walk from the interior point y = 0: move along
the part of c orthogonal to the constraints already tight until another becomes tight
(six steps reach a vertex), then pivot (Dantzig's rule: drop the tight constraint of most
negative multiplier) until every multiplier is >= 0. Six variables and tens to hundreds of
constraints: each step is one pass over the wrenches plus a 6x6 solve.

Validity does not rest on the programme being solved well: the bound returned is h(u)
evaluated directly at the unit direction u = y/|y| reached, which bounds Q1 for any u. A
step limit, a degenerate pivot or rounding can only make the bound looser, never wrong.
"""

from __future__ import annotations

import numpy as np

from ogcp.planner.grasp.kernel.geometry import DIM
from ogcp.planner.grasp.kernel.jit import cached_njit

#: Pivots after the first vertex before the walk settles for the best direction so far.
MAX_PIVOTS = 40
#: |pivot| / scale below which a 6x6 system counts as singular (the walk stops there).
SINGULAR = 1e-12


@cached_njit()
def _solve6(A: np.ndarray, b: np.ndarray, x: np.ndarray) -> bool:
    """Solve the 6x6 system A x = b by Gaussian elimination with partial pivoting.

    A and b are overwritten. Returns False (x undefined) when a pivot is below
    :data:`SINGULAR` times the largest entry of A.
    """
    scale = 0.0
    for i in range(DIM):
        for j in range(DIM):
            scale = max(scale, abs(A[i, j]))
    if scale == 0.0:
        return False
    for k in range(DIM):
        p = k
        for i in range(k + 1, DIM):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if abs(A[p, k]) <= SINGULAR * scale:
            return False
        if p != k:
            for j in range(DIM):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            b[k], b[p] = b[p], b[k]
        for i in range(k + 1, DIM):
            f = A[i, k] / A[k, k]
            for j in range(k, DIM):
                A[i, j] -= f * A[k, j]
            b[i] -= f * b[k]
    for k in range(DIM - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, DIM):
            s -= A[k, j] * x[j]
        x[k] = s / A[k, k]
    return True


@cached_njit()
def _reject(v: np.ndarray, ortho: np.ndarray, k: int) -> None:
    """Remove from v (in place) its components along the first k rows of ``ortho`` (orthonormal)."""
    for r in range(k):
        dot = 0.0
        for j in range(DIM):
            dot += v[j] * ortho[r, j]
        for j in range(DIM):
            v[j] -= dot * ortho[r, j]


@cached_njit()
def _ratio_step(P: np.ndarray, y: np.ndarray, d: np.ndarray, tight: np.ndarray) -> tuple[float, int]:
    """Longest step t >= 0 along d that keeps every P[i].(y + t d) <= 1; (inf, -1) if unbounded."""
    best_t = np.inf
    arg = -1
    for i in range(P.shape[0]):
        if tight[i]:
            continue
        rate = 0.0
        slack = 1.0
        for j in range(DIM):
            rate += P[i, j] * d[j]
            slack -= P[i, j] * y[j]
        if rate > 1e-300:
            t = max(slack, 0.0) / rate
            if t < best_t:
                best_t = t
                arg = i
    return best_t, arg


@cached_njit()
def facet_bound(P: np.ndarray, c: np.ndarray) -> tuple[float, np.ndarray]:
    """Upper bound of Q1(P) [-] from the facet that the ray along c leaves conv(P) through.

    Args:
        P: Wrenches, shape (N, 6).
        c: Start direction (unit), shape (6,).

    Returns:
        (h(u), u): the support of P along the unit direction u reached, an upper bound of
        Q1(P); a value <= 0 proves Q1 = 0. u has shape (6,).
    """
    n = P.shape[0]
    y = np.zeros(DIM)
    d = c.copy()
    tight = np.zeros(n, dtype=np.bool_)
    basis = np.empty(DIM, dtype=np.int64)
    ortho = np.zeros((DIM, DIM))  # orthonormal basis of the tight rows (the walk to a vertex)
    A = np.empty((DIM, DIM))
    rhs = np.empty(DIM)
    lam = np.empty(DIM)
    best_u = c.copy()
    unbounded = False
    # Walk to a vertex: each step makes one more constraint tight.
    k = 0
    while k < DIM:
        t, i = _ratio_step(P, y, d, tight)
        if i < 0:
            unbounded = True  # the polar is unbounded along d: the origin is not inside
            best_u = d.copy()
            break
        for j in range(DIM):
            y[j] += t * d[j]
        tight[i] = True
        basis[k] = i
        # Gram-Schmidt: extend the orthonormal basis of the tight rows by row i.
        v = P[i].copy()
        _reject(v, ortho, k)
        nv = np.sqrt(np.sum(v * v))
        if nv <= SINGULAR * np.sqrt(np.sum(P[i] * P[i])):
            break  # a dependent row: stop at the best point so far
        ortho[k] = v / nv
        k += 1
        # The part of c orthogonal to every tight row; zero at a vertex.
        for j in range(DIM):
            d[j] = c[j]
        _reject(d, ortho, k)
        if np.sqrt(np.sum(d * d)) <= 1e-12:
            break  # c lies in the span of the tight rows: y is optimal on this face
    if not unbounded and k == DIM:
        # Simplex pivots at the vertex: drop the tight row of most negative multiplier.
        for _ in range(MAX_PIVOTS):
            for r in range(DIM):
                for j in range(DIM):
                    A[j, r] = P[basis[r], j]  # B^T: columns are the tight rows
                rhs[r] = c[r]
            if not _solve6(A, rhs, lam):
                break
            leave = -1
            most = -1e-12
            for r in range(DIM):
                if lam[r] < most:
                    most = lam[r]
                    leave = r
            if leave < 0:
                break  # every multiplier >= 0: y is optimal
            # Direction keeping the other tight rows tight and loosening the leaving one.
            for r in range(DIM):
                for j in range(DIM):
                    A[r, j] = P[basis[r], j]
                rhs[r] = -1.0 if r == leave else 0.0
            if not _solve6(A, rhs, d):
                break
            t, i = _ratio_step(P, y, d, tight)
            if i < 0:
                unbounded = True
                best_u = d.copy()
                break
            for j in range(DIM):
                y[j] += t * d[j]
            tight[basis[leave]] = False
            tight[i] = True
            basis[leave] = i
    if not unbounded:
        norm = np.sqrt(np.sum(y * y))
        if norm > 0.0:
            best_u = y / norm
    norm = np.sqrt(np.sum(best_u * best_u))
    best_u = best_u / norm
    h = -np.inf
    for i in range(n):
        s = 0.0
        for j in range(DIM):
            s += P[i, j] * best_u[j]
        h = max(h, s)
    return h, best_u


@cached_njit()
def _union_points(wrenches: np.ndarray, union: np.ndarray) -> np.ndarray:
    """The wrenches of the members of a packed union (big-endian bits), shape (s k, 6)."""
    members = np.empty(wrenches.shape[0], dtype=np.int64)
    size = 0
    for byte in range(union.shape[0]):
        bits = union[byte]
        if bits == 0:
            continue
        for bit in range(8):
            if bits & (128 >> bit):
                members[size] = 8 * byte + bit
                size += 1
    k = wrenches.shape[1]
    P = np.empty((size * k, DIM))
    for a in range(size):
        for e in range(k):
            for j in range(DIM):
                P[a * k + e, j] = wrenches[members[a], e, j]
    return P


@cached_njit()
def union_facet_bound_along(wrenches: np.ndarray, union: np.ndarray, direction: np.ndarray) -> tuple[float, np.ndarray]:
    """:func:`facet_bound` of a union of contacts from one start direction: ([-], u).

    :func:`union_facet_bound` with ``first, last = 0, 1`` when ``direction`` is the one of
    lowest support, for callers that know it already (members x |D| work saved).

    Args:
        wrenches: Cone-edge wrenches of every contact, shape (n, k, 6).
        union: The union's membership flags, packed (``numpy.packbits``), shape (ceil(n / 8),).
        direction: Unit start direction, shape (6,).

    Returns:
        The bound and the unit direction whose support it is, shape (6,).
    """
    return facet_bound(_union_points(wrenches, union), direction)


@cached_njit()
def union_facet_bound(
    wrenches: np.ndarray,
    union: np.ndarray,
    rows: np.ndarray,
    directions: np.ndarray,
    count: int,
    first: int,
    last: int,
) -> tuple[float, np.ndarray]:
    """The best :func:`facet_bound` of a union of contacts from its directions of lowest support [-].

    The directions of D are ranked by the union's support along them (lowest first; ties
    by index) and those of rank ``first`` to ``last - 1`` start one facet bound each.

    Args:
        wrenches: Cone-edge wrenches of every contact, shape (n, k, 6).
        union: The union's membership flags packed as ``numpy.packbits`` packs them
            (big-endian bits), shape (ceil(n / 8),).
        rows: Support vectors of sets whose union it is (the super-contacts, or the
            contacts themselves), shape (r, >= count): the union's support is their
            maximum, m x |D| work where the contacts' would be members x |D|.
        directions: Unit directions, shape (>= count, 6); D is the first ``count``.
        count: |D|.
        first: Rank of the first start direction (0: the lowest support).
        last: One past the rank of the last.

    Returns:
        (bound, u): the smallest bound found (inf when no direction is ranked there) and
        the unit direction whose support it is, shape (6,) (zero when none is ranked).
    """
    P = _union_points(wrenches, union)
    joint = np.full(count, -np.inf)
    for r in range(rows.shape[0]):
        for j in range(count):
            joint[j] = max(joint[j], rows[r, j])
    taken = np.zeros(count, dtype=np.bool_)
    best = np.inf
    best_u = np.zeros(DIM)
    for rank in range(min(last, count)):
        arg = -1
        for j in range(count):
            if not taken[j] and (arg < 0 or joint[j] < joint[arg]):
                arg = j
        taken[arg] = True
        if rank >= first:
            value, u = facet_bound(P, directions[arg])
            if value < best:
                best = value
                best_u = u
    return best, best_u
