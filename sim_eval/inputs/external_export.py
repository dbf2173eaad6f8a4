"""Write an ogcp plan's grasps as ``ogcp.grasps/1``: the form any planner's grasps take.

An exported plan evaluated with :func:`~ogcp.sim_eval.external.evaluate_grasps` reproduces the
plan's own evaluation (``ogcp.sim_eval.evaluate_plan``) exactly: the same contacts bit for bit
(floats are written in full), the same COM and rho (the same mesh), the same mu and k. This is
the check that the external path adds nothing of its own (benchmarks/studies/external_roundtrip.py),
and a ready example of the format for other planners.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.quality import q1_certificate
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.grasps import ExternalGrasp, ExternalGrasps, load_grasps, save_grasps
from ogcp.planner.records.plan import PlanView, contact_set_record, plan_grasps


class PlanResult(Protocol):
    """A planning result that writes its ``ogcp.plan/1`` record (SearchResult, ESResult, HFTSResult)."""

    def to_dict(self, contact_set: dict[str, Any] | None = None) -> dict[str, Any]: ...


def _object_fields(source: Mapping[str, Any]) -> dict[str, Any]:
    """``mesh``, ``diagonal`` and ``sha256`` of the record, from a contact set's source."""
    kind = source.get("kind")
    diagonal = source.get("diagonal")
    if kind in ("builtin", "fetched"):
        return {"mesh": str(source.get("name")), "diagonal": diagonal}
    if kind == "mesh":
        # Absolute here: save_grasps writes it relative to the file, so the folder moves as one.
        mesh = str(Path(str(source.get("path"))).resolve())
        return {"mesh": mesh, "diagonal": diagonal, "sha256": source.get("sha256")}
    raise OgcpError(
        f"cannot tell which object the plan was made on (contact-set source kind {kind!r}); "
        "valid kinds: builtin, fetched, mesh"
    )


def export_grasps(
    plan: Mapping[str, Any] | PlanResult,
    path: str | Path,
    *,
    contacts: ContactSet | None = None,
    max_grasps: int | None = None,
) -> ExternalGrasps:
    """Write a plan's distinct grasps (best first) as an ``ogcp.grasps/1`` file.

    Each grasp keeps the plan's label (``best``, ``top-<i>``, ``hfts-run-<i>``) and method, and
    its ogcp Q1 [-] as its score. A grasp that repeats a contact (HFTS scores those 0 by
    convention) has no fingertip placement and is left out with a warning.

    Args:
        plan: An ``ogcp.plan/1`` record, or a planning result (``SearchResult``, ``ESResult``,
            ``HFTSResult``) together with ``contacts``.
        path: The file to write; a mesh path is written relative to its folder.
        contacts: The contact set the plan indexes. None for a record: it is re-sampled and
            checked against the record (:func:`ogcp.sim_eval.inputs.plan_input.plan_input`).
        max_grasps: Export at most this many grasps, best first.

    Returns:
        The grasps as written and read back.

    Raises:
        OgcpError: For a plan whose contact set cannot be rebuilt or is not given, an object
            that cannot be named, or a file that cannot be written.
    """
    if max_grasps is not None and (isinstance(max_grasps, bool) or not isinstance(max_grasps, int) or max_grasps < 1):
        raise OgcpError(f"max_grasps must be a positive integer, got {max_grasps!r}")
    if isinstance(plan, Mapping):
        record = dict(plan)
        if contacts is None:
            from ogcp.sim_eval.inputs.plan_input import plan_input

            rebuilt = plan_input(record)
            contacts, grasps, labels = rebuilt.contacts, rebuilt.grasps, rebuilt.labels
        else:
            grasps, labels = plan_grasps(record, len(contacts))
    else:
        if contacts is None:
            raise OgcpError("a planning result records no friction model: pass the contact set it was planned on")
        record = plan.to_dict(contact_set_record(contacts))
        grasps, labels = plan_grasps(record, len(contacts))
    repeated = [label for grasp, label in zip(grasps, labels, strict=True) if len(set(grasp)) != len(grasp)]
    if repeated:
        warnings.warn(
            f"left out {len(repeated)} grasp(s) that repeat a contact ({', '.join(repeated[:5])}): "
            "two fingertips cannot touch one point",
            UserWarning,
            stacklevel=2,
        )
    kept = [(g, label) for g, label in zip(grasps, labels, strict=True) if len(set(g)) == len(g)][:max_grasps]
    if not kept:
        raise OgcpError("the plan has no grasp of distinct contacts to export")
    entries = []
    for grasp, label in kept:
        idx = np.asarray(grasp, dtype=np.intp)
        score = q1_certificate(contacts.subset_wrenches(idx)).q1
        entries.append(ExternalGrasp(contacts.positions[idx], contacts.normals[idx], label, score=score))
    path = Path(path)
    fields = _object_fields(contacts.source)
    external = ExternalGrasps(
        tuple(entries),
        contacts.mu,
        contacts.cone_edges,
        mesh=fields["mesh"],
        diagonal=fields.get("diagonal"),
        sha256=fields.get("sha256"),
        method=PlanView(record).method,
        torsional_friction=contacts.torsional_friction,
    )
    save_grasps(external, path)
    return load_grasps(path)
