"""The ``ogcp.plan/1`` record: what every planning method writes and the simulation reads.

Later stages (simulation, suites) consume this schema: fields are only ever added.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from planner.infra.provenance import provenance
from planner.infra.tolerance import TOL

if TYPE_CHECKING:
    from planner.grasp.contact_set import ContactSet
    from planner.hands.reachability import SDHReachability

PLAN_SCHEMA = "ogcp.plan/1"


def plan_record(
    method: str,
    grasp: tuple[int, ...],
    q1: float,
    q_ows: float,
    bound: float,
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    stats: dict[str, Any],
    config: dict[str, Any],
    contact_set: dict[str, Any] | None = None,
    **extra: Any,
) -> dict[str, Any]:
    """The ``ogcp.plan/1`` record shared by every planning method.

    Args:
        method: Method name.
        grasp: Sorted contact indices.
        q1: Q1 of the grasp [N].
        q_ows: Q1 of the whole contact set [N].
        bound: Certified upper bound on the optimum [N].
        positions: Contact points of the grasp, shape (m, 3) [m].
        normals: Inward normals of the grasp, shape (m, 3).
        stats: Method-specific statistics.
        config: Method parameters.
        contact_set: Description of the contact set (COM, rho, mu, k, source).
        **extra: Further method-specific top-level fields.
    """
    return {
        "schema": PLAN_SCHEMA,
        "method": method,
        "grasp": list(grasp),
        "q1": q1,
        "q_ows": q_ows,
        "bound": bound,
        "force_closure": q1 > 0,
        "contacts": {"positions": positions.tolist(), "normals": normals.tolist()},
        "contact_set": contact_set or {},
        **extra,
        "stats": stats,
        "config": config,
        "tolerances": TOL.as_dict(),
        "provenance": provenance(),
    }


def contact_set_record(contacts: ContactSet) -> dict[str, Any]:
    """What a plan records about its contact set (enough to rebuild or evaluate it)."""
    return {
        "size": len(contacts),
        "com": contacts.com.tolist(),
        "torque_scale": contacts.torque_scale,
        "mu": contacts.mu,
        "cone_edges": contacts.cone_edges,
        "source": contacts.source,
    }


def hand_record(hand: SDHReachability, grasp: Sequence[int], contacts: ContactSet) -> dict[str, Any]:
    """The ``"hand"`` block of a result: joint angles, residual, which finger takes which contact."""
    reach = hand.reach(grasp, contacts)
    return {
        "name": hand.name,
        "joint_angles": list(reach.joint_angles),
        "residual": reach.residual,
        "reachable": reach.residual <= hand.threshold,
        "finger_contacts": [grasp[i] for i in reach.fingers],
    }
