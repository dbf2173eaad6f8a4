"""Compiled exact Ferrari-Canny Q1 for small and medium 6-D wrench sets (numba).

Q1(W) is the distance from the origin to the boundary of conv(W) when the origin is
strictly inside (Q1 > 1e-9), else 0; degenerate sets (affine rank < 6) give 0. This module
is the fast path of :func:`ogcp.planner.grasp.quality.q1_certificate`: same definition, no qhull on
the common path; anything it cannot certify goes back to the qhull paths there.

Design (three stages, every early answer is a proof, not a heuristic):

1. **Support-table rejection** (batch API only). For a fixed set D of unit directions the
   support of every contact, ``max_j w_cj . u``, is tabulated once. For a grasp the
   support of the union is the max over its contacts. Any u with support <= 1e-9 proves
   Q1 <= 1e-9, i.e. reported Q1 = 0 (Q1 <= h(u) for every unit u). This rejects most
   non-force-closure grasps in well under a microsecond (and, in threshold mode, any
   grasp whose support falls below the threshold by ``CUT_MARGIN``).

2. **Expanding polytope (EPA / lazy beneath-beyond).** Start from a full-dimensional
   simplex of W (greedy farthest points), keep a closed simplicial complex of facets
   (6 sorted vertex indices, outward unit normal u, offset d, and the neighbour across
   each ridge). Repeatedly take the facet with the smallest offset d (signed distance of
   the origin to its hyperplane) and evaluate the support of the *whole* set along its
   normal, s = h(u):
     * s <= 1e-9: u separates (or nearly touches) the origin: Q1 = 0, proven.
     * s - d <= eps: converged; Q1 is in [d, s] once the certificate below holds.
     * else the support point p is beyond that facet: remove every facet p sees (by more
       than eps; coplanar counts as not visible), and cone p over the horizon ridges
       (visible facet next to a non-visible one). The new facet through ridge R and p
       gets its normal from the pencil of the two facets at R,
       ``n = (d_g - u_g.p) u_f + (u_f.p - d_f) u_g`` (30 flops, instead of a 5x6
       elimination), accepted only if its residual at all 6 vertices is < 1e-13 max|w|;
       otherwise a full-pivoting elimination is used. New-new adjacencies are paired by
       hashing the ridges through p.
   Only the part of the hull near the origin is ever built, so it also works for large
   sets (800 wrenches) where the full hull has 10^5+ facets.

3. **Certificate of the lower bound** (``certify=True``, the default). The upper bound
   Q1 <= s is automatic (Q1 <= h(u) for any unit u). The lower bound Q1 >= min_f d_f
   needs the facet list to be complete. We check on the final complex that (a) every
   facet's neighbour across each ridge is alive, points back, and shares exactly that
   ridge (so the ridges pair up: a closed chain), (b) each such pair induces opposite
   orientations on its ridge: both apexes strictly beneath the other facet's hyperplane
   (for d_f, d_g > 0 this is *equivalent* to opposite orientation: the hyperplane through
   the origin and the ridge has normal z = d_g u_f - d_f u_g, and z.a_f, z.a_g have
   opposite signs iff (d_g - u_g.a_f)(d_f - u_f.a_g) > 0), or, for (nearly) coplanar pairs,
   apexes on opposite sides of the ridge inside the common hyperplane (Gram-Schmidt test
   with 1e-9 margins), and (c) every offset is > 1e-9 (min d_f is the answer). Then the
   positively oriented facet simplices form an integer cycle about the origin whose
   radial projection has degree = number of preimages >= 1, so every ray from the origin
   meets a facet simplex (a subset of conv(W)) at distance d_f / (u_f.v) >= d_f: the ball
   of radius min d_f lies in conv(W). If any check fails, or anything else looks wrong
   (overflow, a degenerate simplex, a broken horizon), the kernel returns a FALLBACK
   status and :mod:`ogcp.planner.grasp.quality` answers with its qhull paths instead.

4. **Canonical refit** (:mod:`ogcp.planner.grasp.kernel.refit`). The certified facet's hyperplane is
   refitted through the wrenches within 1e-11 of it, in index order (Householder QR with
   column pivoting, plain IEEE arithmetic in a fixed order). The qhull paths of
   :mod:`ogcp.planner.grasp.quality` hand their facets to the same compiled routine, so the reported
   Q1 depends on the wrench set alone and is bit-identical across every method.

Statuses: ``OK`` (exact, canonical), ``FALLBACK`` (not certified: use qhull), ``BOUND``
(threshold mode: an upper bound at least ``CUT_MARGIN`` below the threshold), ``ZERO``
(batch: Q1 = 0 proven by the support table).

Compiled code is cached on disk as numba caches it, with every file checked on load
(:mod:`ogcp.planner.grasp.kernel.jit`): a damaged cache costs one compilation, never a failed run.

Numerical tolerances: eps = 1e-11 * max|w| for visibility / convergence (points within
eps of a facet hyperplane are treated as on it, which moves Q1 by at most eps), 1e-9 for
force closure and rank (identical to ``ogcp.planner.infra.tolerance.TOL``).
"""

from ogcp.planner.grasp.kernel.batch import (
    canonical_plane,
    default_directions,
    evaluate_batch,
    kernel_q1,
    last_active,
    q1_batch,
    support_table,
)
from ogcp.planner.grasp.kernel.geometry import BOUND, FALLBACK, OK, ZERO


def warm_up() -> float:
    """Compile, or load from numba's disk cache, the kernels the planners call; idempotent.

    A process pays numba's compilation (seconds on a cold cache, ~0.1 s to load a warm one) at
    the first call of each kernel. Calling this first keeps that cost out of whatever is timed
    next (a benchmark cell's CPU seconds). It runs one certified Q1 (with the canonical refit)
    and one batch evaluation, exact and with a cut, on a tiny fixed wrench set: the same
    argument types as the planners' calls, so the same compiled signatures. The parallel batch
    (``evaluate_batch(parallel=True)``) is left out: no planner calls it.

    Returns:
        Wall time of the warm-up [s].
    """
    import time

    import numpy as np

    start = time.perf_counter()
    # The cross-polytope +-e_i: in force closure, Q1 = 1/sqrt(6), every facet a clean simplex.
    cross = np.vstack([np.eye(6), -np.eye(6)])
    ok, value, normal = kernel_q1(cross)
    if ok:
        canonical_plane(cross, normal, value)
    # Four contacts of three wrenches each: the 12 points above perturbed, grouped by contact.
    contacts = (cross + 0.01 * default_directions(12, seed=1)).reshape(4, 3, 6)
    grasps = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], dtype=np.int64)
    table = support_table(contacts, default_directions())
    evaluate_batch(contacts, grasps, table=table)
    evaluate_batch(contacts, grasps, table=table, threshold=1.0)
    return time.perf_counter() - start


__all__ = [
    "BOUND",
    "FALLBACK",
    "OK",
    "ZERO",
    "canonical_plane",
    "default_directions",
    "evaluate_batch",
    "kernel_q1",
    "last_active",
    "q1_batch",
    "support_table",
    "warm_up",
]
