"""The ``ogcp.plan/1`` record: what every planning method writes and the simulation reads.

This module owns the schema: it builds the record (:func:`plan_record` and its blocks)
and reads it back (:func:`load_plan`, :func:`contact_sampling`, :func:`plan_grasps`).
Later stages (simulation, suites) consume it: fields are only ever added.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from planner.grasp.contact_set import DEFAULT_CONE_EDGES, DEFAULT_MU, EVEN_SAMPLING, ContactSet
from planner.infra.errors import OgcpError
from planner.infra.provenance import provenance
from planner.infra.tolerance import TOL

if TYPE_CHECKING:
    from planner.hands.reachability import SDHReachability

PLAN_SCHEMA = "ogcp.plan/1"
#: Keys of a contact set's ``source`` that say how it was sampled (the rest describe the object).
SAMPLING_KEYS = ("sampling", "n", "seed")


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


# -- reading ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContactSampling:
    """How a plan's contact set was sampled: enough to sample it again.

    Attributes:
        object: The object's description (``kind``, ``name`` or ``path``, ``diagonal``, ``sha256``).
        n: Number of contacts.
        seed: Sampling seed.
        mu: Friction coefficient.
        cone_edges: Friction-cone edges k.
        com: Recorded centre of mass [m], None if the plan has none.
    """

    object: dict[str, Any]
    n: int
    seed: int
    mu: float
    cone_edges: int
    com: tuple[float, ...] | None


def load_plan(path: str | Path) -> dict[str, Any]:
    """Read and check a plan JSON file (schema ``ogcp.plan/1``).

    Raises:
        OgcpError: For a missing or unreadable file, invalid JSON or another schema.
    """
    path = Path(path)
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        raise OgcpError(f"{path}: no such plan file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise OgcpError(f"{path}: cannot read plan: {exc}") from exc
    except json.JSONDecodeError as exc:
        raise OgcpError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from exc
    if not isinstance(record, dict) or record.get("schema") != PLAN_SCHEMA:
        found = record.get("schema") if isinstance(record, dict) else type(record).__name__
        raise OgcpError(f"{path}: expected a plan with schema {PLAN_SCHEMA!r}, got {found!r}")
    return record


def contact_sampling(record: dict[str, Any]) -> ContactSampling:
    """How the plan's contact set was sampled, from its ``contact_set`` block.

    Raises:
        OgcpError: When the plan does not record it (e.g. it was planned on a contact file).
    """
    block = record.get("contact_set") or {}
    source = dict(block.get("source") or record.get("source") or {})
    if source.get("sampling") != EVEN_SAMPLING or "n" not in source or "seed" not in source:
        raise OgcpError("the plan does not record how its contacts were sampled (object, n, seed): cannot rebuild them")
    com = block.get("com")
    return ContactSampling(
        object={k: v for k, v in source.items() if k not in SAMPLING_KEYS},
        n=int(source["n"]),
        seed=int(source["seed"]),
        mu=float(block.get("mu", DEFAULT_MU)),
        cone_edges=int(block.get("cone_edges", DEFAULT_CONE_EDGES)),
        com=None if com is None else tuple(float(c) for c in com),
    )


def plan_grasps(record: dict[str, Any], n: int) -> tuple[tuple[tuple[int, ...], ...], tuple[str, ...]]:
    """The plan's distinct grasps, best first, and where each came from.

    The best grasp is labelled ``best``; a plan's ``top`` list gives ``top-<i>`` and
    HFTS's ``runs`` give ``hfts-run-<i>``. A grasp listed twice keeps its first label.

    Args:
        record: The plan.
        n: Size of the contact set the grasps index.

    Raises:
        OgcpError: For a grasp that is not a list of contact indices below ``n``.
    """
    found: dict[tuple[int, ...], str] = {}
    candidates = [("best", record.get("grasp"))]
    candidates += [
        (f"top-{i}", t.get("grasp") if isinstance(t, dict) else t) for i, t in enumerate(record.get("top") or [])
    ]
    candidates += [(f"hfts-run-{i}", r.get("grasp")) for i, r in enumerate(record.get("runs") or [])]
    for label, grasp in candidates:
        if not isinstance(grasp, list) or not all(isinstance(i, int) for i in grasp):
            raise OgcpError(f"plan grasp {label!r} must be a list of contact indices, got {grasp!r}")
        if any(i < 0 or i >= n for i in grasp):
            raise OgcpError(f"plan grasp {label!r} {grasp} indexes outside the {n}-contact set")
        found.setdefault(tuple(grasp), label)
    return tuple(found), tuple(found.values())


def recorded_positions(record: dict[str, Any]) -> NDArray[np.float64]:
    """Contact points of the plan's best grasp as recorded, shape (m, 3) [m] (empty if none)."""
    return np.asarray((record.get("contacts") or {}).get("positions", []), dtype=float)
