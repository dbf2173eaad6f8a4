"""Shared references for the tests: independent Q1 and exhaustive grasp search."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, SupportBound, q1, sample_contacts
from ogcp.planner.infra import TOL


def q1_by_facet_enumeration(wrenches: np.ndarray, tol: float = 1e-10) -> float:
    """Q1 by enumerating every 6-subset as a candidate facet hyperplane (no qhull).

    Every facet of a 6-D polytope contains 6 affinely independent vertices, so the
    supporting hyperplanes through 6-subsets include all facet hyperplanes. Feasible up
    to ~24 wrenches (134,596 subsets).
    """
    combos = np.array(list(itertools.combinations(range(len(wrenches)), 6)))
    pts = wrenches[combos]
    _, singular, vt = np.linalg.svd(pts[:, 1:] - pts[:, :1])
    nondegenerate = singular[:, -1] > 1e-9 * singular[:, 0]
    normals = vt[:, -1, :]
    offsets = np.einsum("ij,ij->i", normals, pts[:, 0])
    side = wrenches @ normals.T - offsets
    below, above = (side <= tol).all(axis=0), (side >= -tol).all(axis=0)
    supporting = nondegenerate & (below | above)
    if not supporting.any():
        return 0.0
    value = float(np.where(below, offsets, -offsets)[supporting].min())
    return value if value > TOL.force_closure else 0.0


def exhaustive_best(contacts: ContactSet, m: int, prefilter: bool = True) -> float:
    """Best Q1 over all m-subsets of distinct contacts.

    With ``prefilter`` the grasps are visited in order of decreasing support-function
    upper bound and the loop stops once no remaining bound can beat the best exact
    value: the same maximum, found with far fewer hulls. Without it every grasp is
    evaluated.
    """
    grasps = np.array(list(itertools.combinations(range(len(contacts)), m)))
    if not prefilter:
        return max(q1(contacts.subset_wrenches(g)) for g in grasps)
    bounds = SupportBound(contacts.wrenches, seed=1, random_directions=500)
    support = bounds._support[:, : bounds.count]
    upper = support[grasps].max(axis=1).min(axis=1)
    best = 0.0
    for i in np.argsort(-upper):
        if upper[i] <= best:
            break
        best = max(best, q1(contacts.subset_wrenches(grasps[i])))
    return best


def winding_number(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """Generalised winding number (1 inside, 0 outside a watertight mesh), no spatial index.

    Sum of the triangles' signed solid angles (Van Oosterom-Strackee) over 4 pi.
    """
    tri = mesh.triangles[None, :, :, :] - points[:, None, None, :]  # (p, t, 3, 3)
    a, b, c = tri[..., 0, :], tri[..., 1, :], tri[..., 2, :]
    la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
    numerator = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
    denominator = (
        la * lb * lc
        + np.einsum("ptk,ptk->pt", a, b) * lc
        + np.einsum("ptk,ptk->pt", b, c) * la
        + np.einsum("ptk,ptk->pt", c, a) * lb
    )
    return 2.0 * np.arctan2(numerator, denominator).sum(axis=1) / (4.0 * np.pi)


@pytest.fixture(scope="session")
def object_contacts():
    """Factory of cached contact sets: (object, n, seed) -> ContactSet."""
    cache: dict[tuple[str, int, int], ContactSet] = {}

    def make(name: str, n: int, seed: int = 0) -> ContactSet:
        key = (name, n, seed)
        if key not in cache:
            cache[key] = sample_contacts(builtin_mesh(name), n, seed=seed, source={"kind": "builtin", "name": name})
        return cache[key]

    return make
