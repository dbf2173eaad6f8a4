"""Turn an ``ogcp.plan/1`` record back into what the simulation needs: mesh, contact set, grasps.

A plan records how its contact set was made (object and sampling seed), not the set itself,
so the set is sampled again and checked against the contacts the plan recorded: a plan whose
contacts are not reproduced exactly (another mesh, another ogcp version) is refused.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from planner.grasp.contact_set import ContactSet, sample_contacts
from planner.infra.errors import OgcpError
from planner.objects import DEFAULT_DIAGONAL, file_sha256, resolve_object
from planner.records.plan import PLAN_SCHEMA

POSITION_TOLERANCE = 1e-9  # [m] recorded vs re-sampled contact positions


@dataclass(frozen=True, eq=False)
class PlanInput:
    """The grasps of a plan, ready to simulate.

    Attributes:
        mesh: The object mesh.
        contacts: The contact set the grasps index.
        grasps: Distinct grasps of the plan, best first.
        labels: Where each grasp came from (``best``, ``hfts-run-<i>``, ``top-<i>``).
        record: The plan record.
    """

    mesh: trimesh.Trimesh
    contacts: ContactSet
    grasps: tuple[tuple[int, ...], ...]
    labels: tuple[str, ...]
    record: dict[str, Any]


def load_plan(path: str | Path) -> dict[str, Any]:
    """Read and check a plan JSON file (schema ``ogcp.plan/1``)."""
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


def _mesh(source: dict[str, Any]) -> trimesh.Trimesh:
    kind = source.get("kind")
    if kind in ("builtin", "fetched"):
        mesh, _ = resolve_object(str(source.get("name")), float(source.get("diagonal", DEFAULT_DIAGONAL)))
        return mesh
    if kind == "mesh":
        path = Path(str(source.get("path")))
        if not path.exists():
            raise OgcpError(f"the plan's mesh {path} does not exist (run from the folder the plan was made in)")
        if source.get("sha256") and file_sha256(path) != source["sha256"]:
            raise OgcpError(f"the plan's mesh {path} has changed since planning (sha256 differs)")
        mesh, _ = resolve_object(str(path))
        return mesh
    raise OgcpError(
        f"cannot tell which object the plan was made on (contact-set source kind {kind!r}); "
        "plan from a built-in name or a mesh path"
    )


def _grasps(record: dict[str, Any], n: int) -> tuple[tuple[tuple[int, ...], ...], tuple[str, ...]]:
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


def plan_input(record: dict[str, Any]) -> PlanInput:
    """Rebuild the mesh and contact set of a plan and collect its grasps.

    Raises:
        OgcpError: Unknown object, a contact set that cannot be reproduced, or contacts that
            are not where the plan says.
    """
    cs = record.get("contact_set") or {}
    source = dict(cs.get("source") or record.get("source") or {})
    if source.get("sampling") != "even" or "n" not in source or "seed" not in source:
        raise OgcpError("the plan does not record how its contacts were sampled (object, n, seed): cannot rebuild them")
    mesh = _mesh(source)
    contacts = sample_contacts(
        mesh,
        int(source["n"]),
        int(source["seed"]),
        float(cs.get("mu", 0.5)),
        int(cs.get("cone_edges", 8)),
        {k: v for k, v in source.items() if k not in ("sampling", "n", "seed")},
    )
    grasps, labels = _grasps(record, len(contacts))
    recorded = np.asarray(record.get("contacts", {}).get("positions", []), dtype=float)
    best = np.asarray(grasps[0], dtype=np.intp)
    if recorded.shape != (len(best), 3) or not np.allclose(
        contacts.positions[best], recorded, atol=POSITION_TOLERANCE, rtol=0.0
    ):
        raise OgcpError("the plan's contacts are not on the object as re-sampled (different mesh or ogcp version?)")
    if "com" in cs and not np.allclose(contacts.com, cs["com"], atol=POSITION_TOLERANCE, rtol=0.0):
        raise OgcpError("the plan's centre of mass differs from the object's: refusing to mix them")
    return PlanInput(mesh, contacts, grasps, labels, record)
