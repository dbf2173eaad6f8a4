"""Q1 of contact subsets of one contact set, memoised: the one interface the search calls.

Super-contact quality (paper Eq. 9) is Q1 of the union of the super-contacts, so the cache
is keyed by the union's packed membership bitmask: two states with the same union never
cost two Q1 evaluations.

The search mostly needs to know that a union is no better than a value it already holds,
which an upper bound proves: :meth:`GraspQuality.tighten` climbs from the support bound to
facet bounds (:mod:`ogcp.planner.grasp.kernel.ray_bound`, about 10 µs each) and only then to the
exact value (100-300 µs).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel.geometry import CUT_MARGIN
from ogcp.planner.grasp.quality import KERNEL_MAX, q1_certificate
from ogcp.planner.grasp.support_bound import SupportBound, Vector
from ogcp.planner.infra.tolerance import TOL

PackedMask = NDArray[np.uint8]
#: Directions of lowest support passed to the exact engine as a warm start.
HINT_DIRECTIONS = 12
#: Start directions of :meth:`GraspQuality.tighten`'s facet bounds (lowest support first).
FACET_STARTS = 4
#: The level of :meth:`GraspQuality.tighten` that is Q1 itself.
EXACT = 3
#: Budget of the support table: |C| x |D| entries (16 MB; the search's node vectors take
#: about twice that). Up to 1000 contacts D may hold 2000 directions (a search at m = 5 on
#: 1000 contacts then expands a third more states a minute than with 640: a tighter support
#: bound settles more children without facet bounds); beyond, |D| shrinks to stay in
#: budget, down to the 640 every size gets.
DIRECTION_BUDGET = 2_000_000
MIN_DIRECTIONS = 640
MAX_DIRECTIONS = 2000


def direction_capacity(n: int) -> int:
    """Directions the support bound of ``n`` contacts may learn (:data:`DIRECTION_BUDGET`)."""
    return min(MAX_DIRECTIONS, max(MIN_DIRECTIONS, DIRECTION_BUDGET // max(n, 1)))


#: Facet bounds kept at most (about 300 bytes each); beyond, the store starts afresh, which
#: costs recomputation only (a search at m >= 5 asks for millions).
UPPER_CAPACITY = 1_000_000


class GraspQuality:
    """Memoised Q1 over subsets of a :class:`ContactSet`.

    Exact values come from :func:`ogcp.planner.grasp.quality.q1_certificate`; each certificate's
    weakest direction also tightens the :class:`SupportBound` that gives cheap upper
    bounds, and a bound below the force-closure tolerance settles Q1 = 0 without a hull.

    Attributes:
        bounds: The support-function upper bounds.
        evaluations: Q1 computations performed (cache misses that needed a hull).
        bound_rejections: Cache misses settled as Q1 = 0 by the support bound.
        cache_hits: Lookups answered from the cache.
        hull_calls: qhull invocations spent by those computations.
        facet_bounds: Facet bounds computed by :meth:`tighten`.
    """

    def __init__(self, contacts: ContactSet, seed: int = 0) -> None:
        self.contacts = contacts
        self.bounds = SupportBound(contacts.wrenches, seed, max_directions=direction_capacity(len(contacts)))
        self.bound_rejections = 0
        self.n = len(contacts)
        self._cache: dict[bytes, float] = {}
        self.evaluations = 0
        self.cache_hits = 0
        self.hull_calls = 0
        self.facet_bounds = 0
        #: The unit normal of the facet bound the last :meth:`tighten` computed, shape (6,)
        #: (None when it computed none, or one that proves Q1 = 0).
        self.last_normal: NDArray[np.float64] | None = None
        #: (facet bound, level) per union key of the unions not evaluated exactly (:meth:`tighten`).
        self._upper: dict[bytes, tuple[float, int]] = {}

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
        return self._evaluate(union, key, vectors)

    def _evaluate(self, union: PackedMask, key: bytes, vectors: Sequence[Vector] | None) -> float:
        """Q1 of a union not in the cache, which then holds it [-]."""
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
        self._upper.pop(key, None)
        return cert.q1

    def tighten(
        self,
        masks: Sequence[PackedMask],
        vectors: Sequence[Vector] | None,
        level: int,
        bound: float,
        start: int | None = None,
    ) -> tuple[float, int]:
        """Tighten an upper bound of Q1 of the union by one level: (bound [-], level reached).

        Levels: 0, the support bound (the caller's); 1, the facet bound
        (:func:`ogcp.planner.grasp.kernel.ray_bound.facet_bound`) from the direction of lowest
        support, about 10 µs; 2, facet bounds from the next ``FACET_STARTS - 1`` directions;
        :data:`EXACT`, Q1 itself (:meth:`of_masks`, 100-300 µs). A cached value is returned
        at once, as exact; so is Q1 = 0 when a facet bound proves it. Facet bounds carry
        ``CUT_MARGIN``, so that they bound the computed (canonical) Q1, which may sit a
        rounding error above the true value, and a tie is always settled by exact values.

        Args:
            masks: Packed membership masks of the super-contacts.
            vectors: Their support vectors; None serves at level 0 only, where they rank
                nothing when ``start`` is given, and a bound below the force-closure
                tolerance then skips the support-bound rejection.
            level: The level of the bound the caller holds (0-2).
            bound: That bound [-].
            start: At level 0, a direction of D to start the first facet bound from: the
                one of lowest support when the caller computed its bound (directions
                learned since may rank lower; any direction gives a valid bound). None:
                rank D now.
        """
        self.last_normal = None
        union = functools.reduce(np.bitwise_or, masks)
        key = union.tobytes()
        cached = self._cache.get(key)
        if cached is not None:
            self.cache_hits += 1
            return cached, EXACT
        known = self._upper.get(key)
        if known is not None and known[1] > level:
            return known
        if level >= 2 or bound <= TOL.force_closure:
            return self._evaluate(union, key, vectors), EXACT
        first, last = (0, 1) if level == 0 else (1, FACET_STARTS)
        if level == 0 and start is not None:
            raw, normal = self.bounds.facet_bound_along(union, start)
        else:
            if vectors is None:
                raise ValueError("tighten needs the support vectors from level 1 on")
            raw, normal = self.bounds.facet_bound(union, vectors, first, last)
        if TOL.force_closure < raw < np.inf:
            self.last_normal = normal
        if known is not None:
            raw = min(raw, known[0] - CUT_MARGIN)
        self.facet_bounds += last - first
        if raw <= TOL.force_closure:
            self.bound_rejections += 1
            self._upper.pop(key, None)
            self._cache[key] = 0.0
            return 0.0, EXACT
        if len(self._upper) >= UPPER_CAPACITY:
            self._upper.clear()
        tightened = self._upper[key] = (raw + CUT_MARGIN, level + 1)
        return tightened

    def of_indices(self, indices: NDArray[np.intp]) -> float:
        """Q1 of a set of contacts [-]."""
        return self.of_masks([self.mask_of(indices)])
