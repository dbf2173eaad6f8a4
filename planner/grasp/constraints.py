"""Grasp constraints P(g) and their sound tests on super-contact states (paper Eq. 15).

A constraint answers two questions. ``accepts(grasp)`` is the exact predicate P on an
m-contact grasp. ``admits(super_contacts)`` is a *sound* test on a state: it returns False
only when no grasp drawn from the super-contacts satisfies P, so pruning on it never loses
a valid grasp (it may keep states that turn out to hold none; leaves are then rejected by
``accepts``).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import OgcpError

Indices = NDArray[np.intp]


class Constraint(Protocol):
    """A grasp predicate with a sound state-level test."""

    name: str

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """Exact predicate on one grasp (contact indices)."""
        ...

    def admits(self, super_contacts: Sequence[Indices], contacts: ContactSet) -> bool:
        """False only if no grasp drawn from ``super_contacts`` is accepted."""
        ...

    def describe(self) -> dict[str, object]:
        """JSON-ready description for result records."""
        ...


def accepts_many(constraint: Constraint, grasps: NDArray[np.intp], contacts: ContactSet) -> NDArray[np.bool_]:
    """P(g) for many grasps (B, m): the constraint's vectorised form when it has one."""
    vectorised = getattr(constraint, "accepts_many", None)
    if vectorised is not None:
        return np.asarray(vectorised(grasps, contacts), dtype=bool)
    return np.array([constraint.accepts(tuple(g), contacts) for g in grasps], dtype=bool)


def _has_distinct_representatives(sets: Sequence[Indices]) -> bool:
    """Hall's condition via augmenting paths over the sets with fewer than m elements.

    A set with at least m elements can always be served last (the others take at most
    m - 1 of its elements), so only the smaller sets need a matching. Near the root every
    set is that large, which makes this check free for most states of a search.
    """
    m = len(sets)
    candidates = [list(map(int, s)) for s in sets if len(s) < m]
    if len(candidates) < 2:
        return all(len(s) for s in sets)
    owner: dict[int, int] = {}

    def augment(i: int, seen: set[int]) -> bool:
        for c in candidates[i]:
            if c in seen:
                continue
            seen.add(c)
            if c not in owner or augment(owner[c], seen):
                owner[c] = i
                return True
        return False

    return all(augment(i, set()) for i in range(len(candidates)))


class DistinctContacts:
    """Every finger on a different contact (always active in ogcp)."""

    name = "distinct"

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """True if the grasp's contacts are pairwise different."""
        return len(set(grasp)) == len(grasp)

    def admits(self, super_contacts: Sequence[Indices], contacts: ContactSet) -> bool:
        """True iff the super-contacts have a system of distinct representatives (exact)."""
        return _has_distinct_representatives(super_contacts)

    def describe(self) -> dict[str, object]:
        """JSON-ready description."""
        return {"name": self.name}


class MaxFingerSpread:
    """All pairwise fingertip distances at most ``spread`` [m] (hand aperture)."""

    name = "max_spread"

    def __init__(self, spread: float) -> None:
        if not (np.isfinite(spread) and spread > 0):
            raise OgcpError(f"maximum finger spread must be a positive number of metres, got {spread!r}")
        self.spread = float(spread)

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """True if every pair of grasp contacts is within the spread."""
        p = contacts.positions[list(grasp)]
        d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
        return bool(d.max() <= self.spread)

    def accepts_many(self, grasps: NDArray[np.intp], contacts: ContactSet) -> NDArray[np.bool_]:
        """P(g) for many grasps (B, m) at once."""
        p = contacts.positions[grasps]
        return np.linalg.norm(p[:, :, None, :] - p[:, None, :, :], axis=-1).max(axis=(1, 2)) <= self.spread

    def admits(self, super_contacts: Sequence[Indices], contacts: ContactSet) -> bool:
        """Necessary condition: every pair of super-contacts has two points within reach."""
        from scipy.spatial import cKDTree  # only here: an import of 0.2 s that most runs never need

        for a, b in itertools.combinations(range(len(super_contacts)), 2):
            pa = contacts.positions[super_contacts[a]]
            pb = contacts.positions[super_contacts[b]]
            nearest, _ = cKDTree(pb).query(pa, k=1, distance_upper_bound=self.spread * (1 + 1e-12))
            if not np.any(np.isfinite(nearest)):
                return False
        return True

    def describe(self) -> dict[str, object]:
        """JSON-ready description."""
        return {"name": self.name, "spread": self.spread}


class ExcludedGrasps:
    """Every grasp but the listed ones (as sets of contacts): a plan made again without the grasps a
    hand could not realise (``ogcp plan --realise``)."""

    name = "excluded"

    def __init__(self, grasps: Sequence[Sequence[int]]) -> None:
        self.grasps = tuple(tuple(sorted(int(i) for i in grasp)) for grasp in grasps)
        self._excluded = frozenset(self.grasps)

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """True unless the grasp's contacts are one of the excluded sets."""
        return tuple(sorted(int(i) for i in grasp)) not in self._excluded

    def accepts_many(self, grasps: NDArray[np.intp], contacts: ContactSet) -> NDArray[np.bool_]:
        """P(g) for many grasps (B, m) at once."""
        ordered = np.sort(np.asarray(grasps, dtype=np.intp), axis=1)
        return np.array([tuple(row) not in self._excluded for row in ordered.tolist()], dtype=bool)

    def admits(self, super_contacts: Sequence[Indices], contacts: ContactSet) -> bool:
        """Always: a state holds other grasps than the few excluded (sound, never prunes)."""
        return True

    def describe(self) -> dict[str, object]:
        """JSON-ready description."""
        return {"name": self.name, "grasps": [list(g) for g in self.grasps]}
