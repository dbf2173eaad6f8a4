"""Approximate symmetry removal (paper Sec. IV-D).

Each state is embedded in a feature space that is invariant to rotating or translating
the object and to reordering the fingers: the sorted list of pairwise (distance,
normal difference) between the fingers' mean contacts, plus the distance between the
centre of mass and the grasp centre. Features are discretised into cells; states whose
features fall into the same cell at the same depth are treated as equivalent and only
the first one generated (the class representative) is kept.

This is an *approximation*: two states in one cell need not have equal quality, so the
search may miss the optimum. Results report that symmetry removal was on. Removing
finger-order permutations (the default in :mod:`ogcp.planner.search.grasp_planner`) is exact and separate.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet

Indices = NDArray[np.intp]


class SymmetryFilter:
    """Keeps one representative per discretised feature cell and depth.

    Args:
        contacts: The contact set.
        position_cell: Cell size for distances, as a fraction of rho.
        normal_cell: Cell size for normal differences (unit-vector distance).
    """

    def __init__(self, contacts: ContactSet, position_cell: float = 0.05, normal_cell: float = 0.1) -> None:
        self.contacts = contacts
        self.position_cell = position_cell * contacts.torque_scale
        self.normal_cell = normal_cell
        self._seen: set[tuple[int, tuple[int, ...]]] = set()
        self.removed = 0

    def features(self, super_contacts: Sequence[Indices]) -> NDArray[np.float64]:
        """Invariant features of a state, shape (m(m-1) + 1,)."""
        pos = np.array([self.contacts.positions[s].mean(axis=0) for s in super_contacts])
        nrm = np.array([self.contacts.normals[s].mean(axis=0) for s in super_contacts])
        norms = np.linalg.norm(nrm, axis=1, keepdims=True)
        nrm = np.divide(nrm, norms, out=np.zeros_like(nrm), where=norms > 0)
        pairs = sorted(
            (float(np.linalg.norm(pos[i] - pos[j])), float(np.linalg.norm(nrm[i] - nrm[j])))
            for i, j in itertools.combinations(range(len(super_contacts)), 2)
        )
        centre = float(np.linalg.norm(pos.mean(axis=0) - self.contacts.com))
        flat = [value for pair in pairs for value in pair]
        return np.array([*flat, centre])

    def is_new(self, depth: int, super_contacts: Sequence[Indices]) -> bool:
        """Record the state's cell; False if a state in the same cell was seen before."""
        f = self.features(super_contacts)
        scale = np.full_like(f, self.position_cell)
        scale[1:-1:2] = self.normal_cell
        key = (depth, tuple(np.floor(f / scale).astype(int).tolist()))
        if key in self._seen:
            self.removed += 1
            return False
        self._seen.add(key)
        return True
