"""Batched kernel calls and the public API of the exact Q1 kernel."""

from __future__ import annotations

import functools
import threading
from typing import TypeVar

import numpy as np
from numba import prange
from numpy.typing import NDArray

from ogcp.planner.grasp.kernel.epa import Workspace, _q1_kernel
from ogcp.planner.grasp.kernel.geometry import BOUND, CUT_MARGIN, DIM, FALLBACK, FC_TOL, MAX_FACETS, OK, ZERO
from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.grasp.kernel.refit import _canonical_plane

# --------------------------------------------------------------------------------------
# Batch kernel
# --------------------------------------------------------------------------------------


@cached_njit()
def _batch_kernel(
    wc: np.ndarray,
    grasps: np.ndarray,
    table: np.ndarray,
    ws: tuple,
    certify: bool,
    out: np.ndarray,
    status: np.ndarray,
    stats: np.ndarray,
    threshold: float,
) -> None:
    """Q1 of many grasps of one contact set; see :func:`evaluate_batch`."""
    B, m = grasps.shape
    k = wc.shape[1]
    D = table.shape[1]
    P = np.empty((m * k, DIM))
    direction = np.empty(DIM)
    for g in range(B):
        # Stage 1: support-table rejection (a proof of Q1 = 0, or of Q1 < threshold).
        code = -1
        h = 0.0
        for t in range(D):
            h = table[grasps[g, 0], t]
            for a in range(1, m):
                v = table[grasps[g, a], t]
                h = max(h, v)
            if h <= FC_TOL:
                code = ZERO
                break
            if h < threshold - CUT_MARGIN:
                code = BOUND
                break
        if code >= 0:
            out[g] = 0.0 if code == ZERO else h
            status[g] = code
            continue
        for a in range(m):
            for e in range(k):
                for j in range(DIM):
                    P[a * k + e, j] = wc[grasps[g, a], e, j]
        st, val = _q1_kernel(P, m * k, ws, certify, stats, threshold, direction)
        out[g] = val
        status[g] = st


@cached_njit()
def _new_workspace(max_points: int, max_facets: int) -> tuple:
    """The :class:`Workspace` arrays, allocated inside compiled code (one per thread)."""
    size = 1 << 16
    return (
        np.zeros((max_facets, DIM), dtype=np.int32),
        np.zeros((max_facets, DIM)),
        np.zeros(max_facets),
        np.zeros((max_facets, DIM), dtype=np.int32),
        np.zeros(max_facets, dtype=np.bool_),
        np.zeros(max_facets, dtype=np.bool_),
        np.zeros(max_facets, dtype=np.int32),
        np.zeros((max_facets * DIM, 3), dtype=np.int32),
        np.zeros(size, dtype=np.int64),
        np.zeros(size, dtype=np.int32),
        np.zeros(size, dtype=np.int64),
        np.zeros(size, dtype=np.int64),
        np.zeros(size, dtype=np.int64),
        np.zeros(1, dtype=np.int64),
        np.zeros(max_points, dtype=np.bool_),
        np.zeros((5, DIM)),
        np.zeros(DIM, dtype=np.int64),
        np.zeros((max_points, DIM)),
    )


@cached_njit(parallel=True)
def _batch_parallel(
    wc: np.ndarray,
    grasps: np.ndarray,
    table: np.ndarray,
    certify: bool,
    out: np.ndarray,
    status: np.ndarray,
    threshold: float,
    nchunks: int,
    max_facets: int,
) -> None:
    """:func:`_batch_kernel` over ``nchunks`` contiguous chunks in parallel (own workspace each)."""
    B = grasps.shape[0]
    npts = grasps.shape[1] * wc.shape[1]
    for c in prange(nchunks):
        lo = c * B // nchunks
        hi = (c + 1) * B // nchunks
        ws = _new_workspace(max(64, npts), max_facets)
        stats = np.zeros(6, dtype=np.int64)
        _batch_kernel(wc, grasps[lo:hi], table, ws, certify, out[lo:hi], status[lo:hi], stats, threshold)


# --------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------

_Scalar = TypeVar("_Scalar", bound=np.generic)

#: One workspace per thread: Dask workers run several tasks in one process at once.
_LOCAL = threading.local()
#: Diagnostic counters: [EPA iterations, flat ridge pairs certified, facets created, certificates,
#: pencil normals recomputed by elimination, unused]. Shared; only indicative under threads.
_STATS = np.zeros(6, dtype=np.int64)


# numba compiles a kernel once per signature, and an array's signature includes whether it is
# writeable: the contact sets' arrays are read-only, arrays built on the way are not. Each entry
# point below hands its kernel one kind only (one compilation per kernel, never two): the
# single-set kernels get writeable arrays, as the batch kernel's own calls of them do, and the
# batch kernel read-only ones.


def _readonly(array: NDArray[_Scalar]) -> NDArray[_Scalar]:
    """A read-only view (no copy) of an input array."""
    view = array.view()
    view.flags.writeable = False
    return view


def _writeable(array: NDArray[np.float64]) -> NDArray[np.float64]:
    """A C-contiguous float64 array that is writeable (a copy only when the input is not)."""
    out = np.ascontiguousarray(array, dtype=np.float64)
    return out if out.flags.writeable else out.copy()


def _workspace(n: int) -> Workspace:
    workspace = getattr(_LOCAL, "workspace", None)
    if workspace is None or workspace.active.shape[0] < n:
        # Hull size grows quickly with N in 6-D: give large sets room (alive facets).
        workspace = Workspace(max(64, n), MAX_FACETS if n <= 64 else 1 << 17)
        _LOCAL.workspace = workspace
    return workspace


def kernel_q1(wrenches: NDArray[np.float64], certify: bool = True) -> tuple[bool, float, NDArray[np.float64]]:
    """Exact Q1 of one wrench set by the compiled kernel.

    Args:
        wrenches: Wrenches, shape (N, 6), N < 4096, finite.
        certify: Verify the lower bound combinatorially (see :mod:`ogcp.planner.grasp.kernel`).

    Returns:
        ``(ok, q1, direction)``: ``ok`` False means the kernel could not certify an answer
        and the caller must use another method; ``direction`` is the unit normal of the
        settling facet (NaN when none; with ``ok`` False, when finite, the nearest facet
        whose certificate failed: a seed for the other method).
    """
    w = _writeable(wrenches)
    direction = np.full(DIM, np.nan)
    ws = _workspace(len(w))
    status, value = _q1_kernel(w, len(w), ws.as_tuple(), certify, _STATS, 0.0, direction)
    return status == OK, float(value), direction


def last_active(n: int) -> NDArray[np.intp]:
    """Indices of the points the last :func:`kernel_q1` call of this thread put in its hull.

    After a failed certificate these span the part of the hull near the origin, so they
    seed another method well (see :func:`ogcp.planner.grasp.quality.q1_certificate`).

    Args:
        n: Size of the wrench set of that call.
    """
    return np.flatnonzero(_LOCAL.workspace.active[:n])


@functools.lru_cache(maxsize=8)
def default_directions(count: int = 128, seed: int = 0) -> NDArray[np.float64]:
    """The 12 signed axes plus seeded random unit directions, shape (count, 6), read-only."""
    rng = np.random.default_rng([seed, 6])
    rnd = rng.normal(size=(max(count - 12, 0), DIM))
    rnd /= np.linalg.norm(rnd, axis=1, keepdims=True)
    out = np.vstack([np.eye(DIM), -np.eye(DIM), rnd])[:count]
    out.setflags(write=False)
    return out


def support_table(contact_wrenches: NDArray[np.float64], directions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per-contact support values ``max_e w_ce . u``, shape (n, len(directions))."""
    return np.ascontiguousarray(np.max(contact_wrenches @ directions.T, axis=1))


def evaluate_batch(
    contact_wrenches: NDArray[np.float64],
    grasps: NDArray[np.integer],
    certify: bool = True,
    table: NDArray[np.float64] | None = None,
    threshold: float = 0.0,
    parallel: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Q1 of many grasps of one contact set in one compiled call, with a status per grasp.

    Args:
        contact_wrenches: Wrenches of every contact, shape (n, k, 6) [N].
        grasps: Contact indices of each grasp, shape (B, m).
        certify: See :func:`kernel_q1`.
        table: Optional precomputed :func:`support_table` (reuse it across calls).
        threshold: Branch-and-bound cut-off [-]. 0 (default): every settled value is the
            exact Q1. If > 0, every grasp with Q1 >= threshold still gets its exact Q1,
            but a grasp proven to have Q1 < threshold may get an *upper bound* of its Q1
            below ``threshold - CUT_MARGIN`` instead, found without finishing its hull.
        parallel: Spread the grasps over all numba threads (same results).

    Returns:
        ``(q1, status)``, shape (B,) each: per grasp the value [-] and how it was settled:
        ``OK`` exact canonical Q1 from the expanding polytope, ``ZERO`` Q1 = 0 proven by
        the support table, ``BOUND`` an upper bound below the threshold, ``FALLBACK``
        not settled (NaN; the caller computes it by another method).
    """
    wc = _readonly(np.ascontiguousarray(contact_wrenches, dtype=np.float64))
    g = _readonly(np.ascontiguousarray(grasps, dtype=np.int64))
    table = _readonly(
        np.ascontiguousarray(support_table(wc, default_directions()) if table is None else table, dtype=np.float64)
    )
    out = np.empty(len(g))
    status = np.zeros(len(g), dtype=np.int64)
    if parallel and len(g) >= 1024:
        import numba

        nchunks = 4 * numba.get_num_threads()
        _batch_parallel(
            wc,
            g,
            table,
            certify,
            out,
            status,
            float(threshold),
            nchunks,
            MAX_FACETS if g.shape[1] * wc.shape[1] <= 64 else 1 << 17,
        )
    else:
        ws = _workspace(g.shape[1] * wc.shape[1])
        _batch_kernel(wc, g, table, ws.as_tuple(), certify, out, status, _STATS, float(threshold))
    return out, status


def q1_batch(
    contact_wrenches: NDArray[np.float64],
    grasps: NDArray[np.integer],
    certify: bool = True,
    table: NDArray[np.float64] | None = None,
    threshold: float = 0.0,
    parallel: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """:func:`evaluate_batch` with the status reduced to settled or not.

    Returns:
        ``(q1, ok)``: Q1 per grasp, shape (B,) [-] (an upper bound below
        ``threshold - CUT_MARGIN`` where the threshold settled it), and whether the kernel
        settled it; the caller computes the grasps with ``ok`` False by another method.
    """
    values, status = evaluate_batch(contact_wrenches, grasps, certify, table, threshold, parallel)
    return values, status != FALLBACK


def canonical_plane(
    wrenches: NDArray[np.float64], normal: NDArray[np.float64], offset: float
) -> tuple[NDArray[np.float64], float, bool]:
    """The canonical hyperplane of a facet: refitted through the wrenches on it.

    Args:
        wrenches: Wrenches, shape (N, 6) [N].
        normal: Unit normal of a facet of their hull, shape (6,).
        offset: Its offset [N].

    Returns:
        ``(normal, offset, ok)``: the refitted plane; the input plane with ``ok`` False
        when the wrenches on it do not determine one (see
        :func:`ogcp.planner.grasp.kernel.refit._canonical_plane`).
    """
    w = _writeable(wrenches)
    u = _writeable(normal)
    out = u.copy()
    value, ok = _canonical_plane(w, len(w), u, float(offset), np.empty_like(w), out)
    return out, float(value), bool(ok)
