"""Q1 of contact subsets of one contact set, memoised: the one interface the search calls.

Super-contact quality (paper Eq. 9) is Q1 of the union of the super-contacts, so the cache
is keyed by the union's packed membership bitmask: two states with the same union never
cost two Q1 evaluations.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from planner.grasp.contact_set import ContactSet
from planner.grasp.quality import KERNEL_MAX, q1_certificate
from planner.grasp.support_bound import SupportBound, Vector
from planner.infra.tolerance import TOL

PackedMask = NDArray[np.uint8]
#: Directions of lowest support passed to the exact engine as a warm start.
HINT_DIRECTIONS = 12


class GraspQuality:
    """Memoised Q1 over subsets of a :class:`ContactSet`.

    Exact values come from :func:`planner.grasp.quality.q1_certificate`; each certificate's
    weakest direction also tightens the :class:`SupportBound` that gives cheap upper
    bounds, and a bound below the force-closure tolerance settles Q1 = 0 without a hull.

    Attributes:
        bounds: The support-function upper bounds.
        evaluations: Q1 computations performed (cache misses that needed a hull).
        bound_rejections: Cache misses settled as Q1 = 0 by the support bound.
        cache_hits: Lookups answered from the cache.
        hull_calls: qhull invocations spent by those computations.
    """

    def __init__(self, contacts: ContactSet, seed: int = 0) -> None:
        self.contacts = contacts
        self.bounds = SupportBound(contacts.wrenches, seed)
        self.bound_rejections = 0
        self.n = len(contacts)
        self._cache: dict[bytes, float] = {}
        self.evaluations = 0
        self.cache_hits = 0
        self.hull_calls = 0

    def mask_of(self, indices: NDArray[np.intp]) -> PackedMask:
        """Packed membership mask of contact indices."""
        flags = np.zeros(self.n, dtype=bool)
        flags[np.asarray(indices, dtype=np.intp)] = True
        return np.packbits(flags)

    def of_masks(self, masks: Sequence[PackedMask], vectors: Sequence[Vector] | None = None) -> float:
        """Q1 of the union of the contacts in the given packed masks [-].

        Args:
            masks: Packed membership masks of the super-contacts.
            vectors: Their support vectors, if known (enables the cheap rejection).
        """
        union = functools.reduce(np.bitwise_or, masks)
        key = union.tobytes()
        cached = self._cache.get(key)
        if cached is not None:
            self.cache_hits += 1
            return cached
        if vectors is not None and self.bounds.bound(vectors) <= TOL.force_closure:
            self.bound_rejections += 1
            self._cache[key] = 0.0
            return 0.0
        indices = np.flatnonzero(np.unpackbits(union, count=self.n))
        hints = None
        if vectors is not None and len(indices) * self.contacts.wrenches.shape[1] > KERNEL_MAX:
            # Hints only steer the qhull loop, which sets the kernel takes never reach.
            hints = self.bounds.lowest_directions(vectors, HINT_DIRECTIONS)
        cert = q1_certificate(self.contacts.subset_wrenches(indices), hints)
        self.evaluations += 1
        self.hull_calls += cert.hull_calls
        self.bounds.add(cert.direction)
        self._cache[key] = cert.q1
        return cert.q1

    def of_indices(self, indices: NDArray[np.intp]) -> float:
        """Q1 of a set of contacts [-]."""
        return self.of_masks([self.mask_of(indices)])
