"""Turn an ``ogcp.plan/1`` record back into what the simulation needs: mesh, contact set, grasps.

A plan records how its contact set was made (object, sampling seed and, for reach-aware
sampling, the fingertip radius and tolerance), not the set itself,
so the set is sampled again and checked against the contacts the plan recorded: a plan whose
contacts are not reproduced exactly (another mesh, another ogcp version) is refused. Reading
the record itself (file, schema, grasps, sampling) is :mod:`planner.records.plan`'s job.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from planner.grasp.contact_set import ContactSet, sample_contacts
from planner.infra.errors import OgcpError
from planner.objects import DEFAULT_DIAGONAL, file_sha256, resolve_object
from planner.records.plan import contact_sampling, plan_grasps, recorded_positions

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
        # A mesh file planned with --diagonal was normalised to it; without, it keeps its size.
        diagonal = source.get("diagonal")
        mesh, _ = resolve_object(str(path), None if diagonal is None else float(diagonal))
        return mesh
    raise OgcpError(
        f"cannot tell which object the plan was made on (contact-set source kind {kind!r}); "
        "plan from a built-in name or a mesh path"
    )


def plan_input(record: dict[str, Any]) -> PlanInput:
    """Rebuild the mesh and contact set of a plan and collect its grasps.

    Raises:
        OgcpError: Unknown object, a contact set that cannot be reproduced, or contacts that
            are not where the plan says.
    """
    sampling = contact_sampling(record)
    mesh = _mesh(sampling.object)
    contacts = sample_contacts(
        mesh,
        sampling.n,
        sampling.seed,
        sampling.mu,
        sampling.cone_edges,
        sampling.object,
        tip_radius=sampling.tip_radius,
        reach_tolerance=sampling.reach_tolerance,
    )
    grasps, labels = plan_grasps(record, len(contacts))
    recorded = recorded_positions(record)
    best = np.asarray(grasps[0], dtype=np.intp)
    if recorded.shape != (len(best), 3) or not np.allclose(
        contacts.positions[best], recorded, atol=POSITION_TOLERANCE, rtol=0.0
    ):
        raise OgcpError("the plan's contacts are not on the object as re-sampled (different mesh or ogcp version?)")
    if sampling.com is not None and not np.allclose(contacts.com, sampling.com, atol=POSITION_TOLERANCE, rtol=0.0):
        raise OgcpError("the plan's centre of mass differs from the object's: refusing to mix them")
    return PlanInput(mesh, contacts, grasps, labels, record)
