"""The one set of numerical tolerances used across ogcp.

Every comparison against a tolerance in the planner reads it from :data:`TOL`, so a
user who needs different numerics changes them in one place (and results record them).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class Tolerances:
    """Numerical tolerances.

    Attributes:
        q1_gap: Certification gap for exact Q1 [wrench units]. The engine stops when the
            support of the full wrench set along the nearest facet normal exceeds that
            facet's offset by at most this much, so the reported Q1 is within
            ``q1_gap`` of the true value.
        force_closure: A grasp is in force closure only if its Q1 exceeds this; smaller
            values (the origin on or numerically at the hull boundary) report Q1 = 0.
        rank: Relative singular-value threshold below which a wrench set is treated as
            spanning fewer than 6 dimensions (then Q1 = 0).
        normal_norm: Minimum norm of a contact normal before normalisation.
    """

    q1_gap: float = 1e-12
    force_closure: float = 1e-9
    rank: float = 1e-9
    normal_norm: float = 1e-9

    def as_dict(self) -> dict[str, float]:
        """Return the tolerances as a JSON-ready dict."""
        return asdict(self)


TOL = Tolerances()
