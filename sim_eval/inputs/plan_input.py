"""Turn an ``ogcp.plan/1`` record back into what the simulation needs: mesh, contact set, grasps.

A plan records its contact set in full (positions, inward normals, COM, rho, mu, k) and
how it was made (object, sampling seed, tip radius). The recorded set is the reference: it
is used as recorded, never re-sampled, so a plan evaluates the same contacts on any machine
(trimesh's sampling changes between versions). It is checked against the object instead:
the object's identity (kind, name, mesh file sha256, diagonal), the set's size, rho and COM
against the mesh's, every contact on the mesh surface with its face's normal, the best
grasp's contacts against the set, and the Q1 and Q_OWS recomputed from it (where mu and the
cone edges k show). On the very build the plan was made with (same ogcp commit and sampling
libraries), re-sampling must also reproduce the set, so an edited n, seed or tip radius shows.

Older plans, which record only how their set was sampled, are re-sampled as before and
checked the same way against the re-sampled set. A plan that disagrees anywhere is refused
with the field, its recorded and its rebuilt value (and the recorded vs running library
versions where they differ), never simulated as if it were the original. Reading the record
itself (file, schema, grasps, sampling) is :mod:`ogcp.planner.records.plan`'s job.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import (
    DEFAULT_CONE_EDGES,
    DEFAULT_MU,
    EVEN_SAMPLING,
    ContactSet,
    mass_properties,
    sample_contacts,
)
from ogcp.planner.grasp.quality import q1
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.tolerance import TOL
from ogcp.planner.objects import DEFAULT_DIAGONAL, file_sha256, resolve_object
from ogcp.planner.records.plan import (
    SAMPLING_KEYS,
    ContactSampling,
    contact_sampling,
    plan_grasps,
    recorded_contacts,
    recorded_positions,
)
from ogcp.sim_eval.inputs.plan_contacts import (
    FACE_NORMAL_TOLERANCE,
    SURFACE_TOLERANCE,
    mesh_candidates,
    same_sampling_build,
    surface_misfit,
    versions_note,
)
from ogcp.sim_eval.inputs.plan_fields import check_plan_fields

POSITION_TOLERANCE = 1e-9  # [m] recorded vs re-sampled contact positions, COM and rho
NORMAL_TOLERANCE = 1e-9  # recorded vs re-sampled unit normals (per component)
#: [-] recorded vs recomputed Q1 and Q_OWS. Each value is certified to TOL.q1_gap, and
#: contacts that agree to POSITION_TOLERANCE move Q1 by about that much over rho (~0.1 m).
Q1_TOLERANCE = 2 * TOL.q1_gap + 1e-8


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


def _show(value: Any) -> str:
    """A recorded or rebuilt value for a message: floats to 12 significant digits."""
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_show(v) for v in np.asarray(value).tolist()) + "]"
    if isinstance(value, float):
        return f"{value:.12g}"
    return repr(value)


_REFUSAL = "the plan does not match its problem: {}; refusing to simulate it as the original"


def _mismatch(field: str, recorded: Any, rebuilt: Any, why: str = "") -> OgcpError:
    """The one-line refusal of a plan whose ``field`` differs from the rebuilt problem."""
    hint = f" ({why})" if why else ""
    return OgcpError(_REFUSAL.format(f"{field} recorded {_show(recorded)}, rebuilt {_show(rebuilt)}{hint}"))


def _misfit(field: str, recorded: Any, fits: Any, evidence: str) -> OgcpError:
    """The refusal of a recorded input ``field`` that the plan's own results show was another value."""
    return OgcpError(_REFUSAL.format(f"{field} recorded {_show(recorded)}, but {evidence} fit {field} {_show(fits)}"))


def _check_copies(record: dict[str, Any]) -> None:
    """Search plans record their contact source twice; the copies must agree key by key."""
    inner = (record.get("contact_set") or {}).get("source")
    outer = record.get("source")
    if not isinstance(inner, dict) or not isinstance(outer, dict):
        return
    for key in sorted(set(inner) | set(outer)):
        if inner.get(key) != outer.get(key):
            raise OgcpError(
                f"the plan records its contact source twice, differently: {key} is {_show(inner.get(key))} in "
                f"contact_set.source and {_show(outer.get(key))} in source; refusing to guess which is right"
            )


def _mesh(source: dict[str, Any], candidates: Sequence[Path]) -> trimesh.Trimesh:
    """Rebuild the plan's object and check every recorded key of its description.

    Args:
        source: The object's description as recorded.
        candidates: Where a mesh file may be, tried in order (:func:`ogcp.sim_eval.inputs.plan_contacts.mesh_candidates`).
    """
    kind = source.get("kind")
    if kind in ("builtin", "fetched"):
        diagonal = source.get("diagonal", DEFAULT_DIAGONAL)
        if diagonal is None:  # only a mesh file keeps its own size
            raise OgcpError(f"plan field source.diagonal: a {kind} object is scaled to a diagonal, got null")
        mesh, rebuilt = resolve_object(str(source.get("name")), float(diagonal))
    elif kind == "mesh":
        found = [path for path in candidates if path.is_file()]
        if not found:
            tried = ", ".join(str(path) for path in candidates) or "no path recorded"
            raise OgcpError(
                f"the plan's mesh {source.get('path')} does not exist (tried {tried}); "
                "keep it where it was, or beside the plan as it was when planned"
            )
        path = found[0]
        # Checked before loading: a changed file may not load at all, and this says why.
        if source.get("sha256") and (digest := file_sha256(path)) != source["sha256"]:
            raise _mismatch("object sha256", source["sha256"], digest, f"the plan's mesh {path} changed since planning")
        # A mesh file planned with --diagonal was normalised to it; without, it keeps its size.
        diagonal = source.get("diagonal")
        mesh, rebuilt = resolve_object(str(path), None if diagonal is None else float(diagonal))
    else:
        raise OgcpError(
            f"cannot tell which object the plan was made on (contact-set source kind {kind!r}); "
            "valid kinds: builtin, fetched, mesh (plan from a built-in name, a fetched name or a mesh path)"
        )
    for key, value in rebuilt.items():
        # Keys an older plan lacks are not held against it; keys it has must agree. The path
        # may differ: the file is found wherever the plan and it moved (its sha256 is checked).
        if key in source and key != "path" and source[key] != value:
            raise _mismatch(f"object {key}", source[key], value)
    return mesh


def _close(recorded: NDArray[np.float64], rebuilt: NDArray[np.float64], tolerance: float) -> bool:
    return recorded.shape == rebuilt.shape and bool(np.allclose(recorded, rebuilt, atol=tolerance, rtol=0.0))


def _first_row(recorded: NDArray[np.float64], rebuilt: NDArray[np.float64]) -> int:
    """The row where two (m, 3) arrays differ most, for naming a contact."""
    return int(np.argmax(np.max(np.abs(recorded - rebuilt), axis=1)))


def _number(value: Any) -> float | None:
    """A recorded finite number, else None (absent, null for NaN, or not a number)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value):
        return float(value)
    return None


def _check_geometry(
    record: dict[str, Any], sampling: ContactSampling, contacts: ContactSet, best: Sequence[int]
) -> None:
    """Size, scale, COM, positions and normals: recorded vs rebuilt, in an order that names the cause."""
    block = record.get("contact_set") or {}
    size = block.get("size")
    if size is not None and size != len(contacts):
        raise _mismatch("contact set size", size, len(contacts), f"sampled with n = {sampling.n}")
    index = np.asarray(best, dtype=np.intp)
    recorded = recorded_positions(record)
    if recorded.shape != (len(index), 3):
        raise OgcpError(
            f"the plan's contacts are not on the object as re-sampled: it records {recorded.shape} positions "
            f"for its {len(index)}-contact best grasp"
        )
    positions = contacts.positions[index]
    moved = not _close(recorded, positions, POSITION_TOLERANCE)
    rho = _number(block.get("torque_scale"))
    if rho is not None and abs(rho - contacts.torque_scale) > POSITION_TOLERANCE:
        diagonal = _number(sampling.object.get("diagonal"))
        # Objects are scaled about their bounding-box centre (the origin) and sampling is
        # scale-equivariant, so contacts and COM of the same object at another diagonal are the
        # rebuilt ones times the ratio of the rhos: if they are, the diagonal was changed.
        ratio = rho / contacts.torque_scale
        com = np.asarray(sampling.com if sampling.com is not None else contacts.com * ratio)
        if (
            moved
            and diagonal is not None
            and _close(recorded, positions * ratio, POSITION_TOLERANCE)
            and _close(com, contacts.com * ratio, POSITION_TOLERANCE)
        ):
            evidence = f"its torque scale rho {_show(rho)} m (rebuilt {_show(contacts.torque_scale)} m) and contacts"
            raise _misfit("diagonal [m]", diagonal, diagonal * ratio, evidence)
        why = "the contacts differ too: another object, or the object at another diagonal" if moved else ""
        raise _mismatch("torque scale rho [m]", rho, contacts.torque_scale, why)
    if sampling.com is not None and not _close(np.asarray(sampling.com), contacts.com, POSITION_TOLERANCE):
        raise _mismatch("centre of mass [m]", sampling.com, contacts.com)
    if moved:
        row = _first_row(recorded, positions)
        raise _mismatch(
            f"position [m] of contact {int(index[row])}",
            recorded[row],
            positions[row],
            "the plan's contacts are not on the object as re-sampled: were n, seed or tip_radius changed?",
        )
    normals = np.asarray((record.get("contacts") or {}).get("normals", []), dtype=float)
    if normals.size and not _close(normals, contacts.normals[index], NORMAL_TOLERANCE):
        if normals.shape != positions.shape:
            raise _mismatch("normals' shape", list(normals.shape), list(positions.shape))
        row = _first_row(normals, contacts.normals[index])
        raise _mismatch(f"inward normal of contact {int(index[row])}", normals[row], contacts.normals[index][row])


def _qualities(
    contacts: ContactSet, best: Sequence[int], mu: float, k: int, torsion: float | None = None
) -> tuple[float, float]:
    """Q1 of the best grasp and of the whole set [-] under friction ``mu``, ``k`` cone edges and ``torsion`` [m]."""
    torsion = contacts.torsional_friction if torsion is None else torsion
    if (mu, k, torsion) != (contacts.mu, contacts.cone_edges, contacts.torsional_friction):
        contacts = ContactSet(
            contacts.positions,
            contacts.normals,
            contacts.com,
            contacts.torque_scale,
            mu,
            k,
            torsional_friction=torsion,
        )
    return q1(contacts.subset_wrenches(np.asarray(best, dtype=np.intp))), q1(contacts.wrenches.reshape(-1, 6))


def _check_quality(record: dict[str, Any], contacts: ContactSet, best: Sequence[int]) -> None:
    """Q1 and Q_OWS as recorded vs recomputed: mu and the cone edges k show only here."""
    recorded = (_number(record.get("q1")), _number(record.get("q_ows")))
    # A grasp that repeats a contact is scored 0 by convention (HFTS), not by its wrenches.
    if recorded == (None, None) or len(set(best)) != len(best) or not best:
        return
    rebuilt = _qualities(contacts, best, contacts.mu, contacts.cone_edges)
    wrong = [r is not None and abs(r - b) > Q1_TOLERANCE for r, b in zip(recorded, rebuilt)]
    if not any(wrong):
        return
    # A friction-model field set away from its default names itself when the default reproduces
    # the recorded values (torsion may move Q1 alone: Q_OWS can be limited where it does not help).
    for field, value, default, mu, k, torsion in (
        ("mu", contacts.mu, DEFAULT_MU, DEFAULT_MU, contacts.cone_edges, None),
        ("cone_edges", contacts.cone_edges, DEFAULT_CONE_EDGES, contacts.mu, DEFAULT_CONE_EDGES, None),
        ("torsional_friction", contacts.torsional_friction, 0.0, contacts.mu, contacts.cone_edges, 0.0),
    ):
        trial = _qualities(contacts, best, mu, k, torsion) if value != default else None
        if trial is not None and all(r is None or abs(r - t) <= Q1_TOLERANCE for r, t in zip(recorded, trial)):
            raise _misfit(field, value, default, "its q1 and q_ows")
    if all(wrong):
        raise _mismatch(
            "(q1, q_ows)",
            list(recorded),
            list(rebuilt),
            f"recomputed with the recorded mu {contacts.mu:g}, cone_edges {contacts.cone_edges} and "
            f"torsional_friction {contacts.torsional_friction:g}: was one of them changed?",
        )
    field = "q1 of the best grasp" if wrong[0] else "q_ows of the contact set"
    raise _mismatch(field, recorded[0 if wrong[0] else 1], rebuilt[0 if wrong[0] else 1])


def _refuse(what: str) -> OgcpError:
    return OgcpError(_REFUSAL.format(what))


def _check_recorded_set(record: dict[str, Any], mesh: trimesh.Trimesh, contacts: ContactSet) -> None:
    """The recorded set against the object: size and n, rho and COM, every contact on the surface."""
    block = record.get("contact_set") or {}
    n = contacts.source.get("n")
    if n is not None and n != len(contacts):
        raise _mismatch("contact set size", len(contacts), n, f"sampled with n = {n}")
    if block.get("size") is not None and block["size"] != len(contacts):
        raise _mismatch("contact set size", block["size"], len(contacts), "the recorded contacts")
    com, rho = mass_properties(mesh)
    if abs(contacts.torque_scale - rho) > POSITION_TOLERANCE:
        ratio = contacts.torque_scale / rho
        diagonal = _number(contacts.source.get("diagonal"))
        # Objects are scaled about their bounding-box centre (the origin): the same object at
        # another diagonal has its COM and contacts times the ratio of the rhos. If the recorded
        # ones are, the recorded diagonal is not the one planned at.
        if (
            diagonal is not None
            and _close(contacts.com, com * ratio, POSITION_TOLERANCE)
            and surface_misfit(mesh, contacts.positions / ratio, contacts.normals) is None
        ):
            evidence = f"its torque scale rho {_show(contacts.torque_scale)} m (rebuilt {_show(rho)} m) and contacts"
            raise _misfit("diagonal [m]", diagonal, diagonal * ratio, evidence)
        off = surface_misfit(mesh, contacts.positions, contacts.normals) is not None
        why = "the contacts are off the object too: another object, or the object at another diagonal" if off else ""
        raise _mismatch("torque scale rho [m]", contacts.torque_scale, rho, why)
    if not _close(contacts.com, np.asarray(com), POSITION_TOLERANCE):
        raise _mismatch("centre of mass [m]", contacts.com, com)
    misfit = surface_misfit(mesh, contacts.positions, contacts.normals)
    if misfit is not None:
        index, distance, normal_error = misfit
        if distance > SURFACE_TOLERANCE:
            raise _refuse(
                f"recorded contact {index} at {_show(contacts.positions[index])} m is {distance:.3g} m off the mesh "
                f"surface (tolerance {SURFACE_TOLERANCE:g} m)"
            )
        raise _refuse(
            f"recorded inward normal of contact {index} {_show(contacts.normals[index])} differs from its face's "
            f"by {normal_error:.3g} (tolerance {FACE_NORMAL_TOLERANCE:g})"
        )


def _check_best_block(record: dict[str, Any], contacts: ContactSet, best: Sequence[int]) -> None:
    """The best grasp's ``contacts`` block (positions, normals) against the recorded set's rows."""
    index = np.asarray(best, dtype=np.intp)
    positions = recorded_positions(record)
    if positions.shape != (len(index), 3):
        raise OgcpError(
            f"the plan records {positions.shape} positions for its {len(index)}-contact best grasp; "
            "refusing to simulate it as the original"
        )
    if not _close(positions, contacts.positions[index], POSITION_TOLERANCE):
        row = _first_row(positions, contacts.positions[index])
        raise _mismatch(
            f"position [m] of contact {int(index[row])}",
            positions[row],
            contacts.positions[index][row],
            "the best grasp's contacts are not the recorded contact set's",
        )
    normals = np.asarray((record.get("contacts") or {}).get("normals", []), dtype=float)
    if normals.size and not _close(normals, contacts.normals[index], NORMAL_TOLERANCE):
        if normals.shape != positions.shape:
            raise _mismatch("normals' shape", list(normals.shape), list(positions.shape))
        row = _first_row(normals, contacts.normals[index])
        raise _mismatch(f"inward normal of contact {int(index[row])}", normals[row], contacts.normals[index][row])


def _check_resampling(record: dict[str, Any], mesh: trimesh.Trimesh, contacts: ContactSet) -> None:
    """On the build the plan was made with, re-sampling must give the recorded set (n, seed, tip radius)."""
    if contacts.source.get("sampling") != EVEN_SAMPLING or not same_sampling_build(record):
        return
    sampling = contact_sampling(record)
    again = _resample(mesh, sampling)
    for key in SAMPLING_KEYS:
        if key in contacts.source and contacts.source[key] != again.source.get(key):
            raise _mismatch(key, contacts.source[key], again.source.get(key))
    if len(again) != len(contacts):
        raise _mismatch("contact set size", len(contacts), len(again), f"sampled with n = {sampling.n}")
    hint = "the plan's contacts are not on the object as re-sampled: were n, seed or tip_radius changed?"
    for name, recorded, rebuilt in (
        ("position [m]", contacts.positions, again.positions),
        ("inward normal", contacts.normals, again.normals),
    ):
        if not _close(recorded, rebuilt, POSITION_TOLERANCE):
            row = _first_row(recorded, rebuilt)
            raise _mismatch(f"{name} of contact {row}", recorded[row], rebuilt[row], hint)


def _resample(mesh: trimesh.Trimesh, sampling: ContactSampling) -> ContactSet:
    return sample_contacts(
        mesh,
        sampling.n,
        sampling.seed,
        sampling.mu,
        sampling.cone_edges,
        sampling.object,
        tip_radius=sampling.tip_radius,
        reach_tolerance=sampling.reach_tolerance,
        torsional_friction=sampling.torsional_friction,
    )


def _from_recorded(record: dict[str, Any], contacts: ContactSet, plan_file: Path | None) -> PlanInput:
    """Check a plan that carries its contacts: the recorded set is the reference."""
    mesh_block = (record.get("contact_set") or {}).get("mesh") or {}
    source = contacts.source
    mesh = _mesh(source, mesh_candidates(source, mesh_block, plan_file))
    _check_recorded_set(record, mesh, contacts)
    grasps, labels = plan_grasps(record, len(contacts))
    _check_best_block(record, contacts, grasps[0])
    _check_resampling(record, mesh, contacts)
    _check_quality(record, contacts, grasps[0])
    return PlanInput(mesh, contacts, grasps, labels, record)


def _from_sampling(record: dict[str, Any], plan_file: Path | None) -> PlanInput:
    """Re-sample the set of an older plan that records only how it was sampled, and check it."""
    sampling = contact_sampling(record)
    mesh = _mesh(sampling.object, mesh_candidates(sampling.object, {}, plan_file))
    contacts = _resample(mesh, sampling)
    # The source contact_sampling read: the contact set's own, else the plan's top-level copy.
    recorded_source = dict((record.get("contact_set") or {}).get("source") or record.get("source") or {})
    for key in SAMPLING_KEYS:
        # The rebuilt set records its own sampling; a recorded key it does not reproduce is an edit.
        if key in recorded_source and recorded_source[key] != contacts.source.get(key):
            raise _mismatch(key, recorded_source[key], contacts.source.get(key))
    grasps, labels = plan_grasps(record, len(contacts))
    _check_geometry(record, sampling, contacts, grasps[0])
    _check_quality(record, contacts, grasps[0])
    return PlanInput(mesh, contacts, grasps, labels, record)


def plan_input(record: dict[str, Any], plan_file: str | Path | None = None) -> PlanInput:
    """Rebuild the mesh and contact set of a plan, check them against it, and collect its grasps.

    Checks, in order: field types and ranges (:func:`check_plan_fields`), the two copies of
    the contact source, then with recorded contacts: the mesh (found by :func:`mesh_candidates`,
    its sha256, name and diagonal), the set's size and n, rho and COM against the mesh's
    (naming an edited diagonal), every contact on the mesh surface with its face's normal,
    the best grasp's contacts against the set, re-sampling on the very same build, and Q1 and
    Q_OWS recomputed from the set. Older plans without contacts are re-sampled and checked
    against the re-sampled set instead.

    Args:
        record: The plan record.
        plan_file: The file the plan was read from, to find its mesh file relative to it;
            None: only the recorded absolute and as-given paths are tried.

    Raises:
        OgcpError: A field of the wrong type or out of range, an unknown object, a mesh file
            not found or changed, a contact set that cannot be reproduced, or any recorded
            field of the problem (object, size, rho, COM, contact positions and normals,
            Q1, Q_OWS) that differs from the rebuilt one: the one-line message names the field
            and gives its recorded and rebuilt values, and the recorded and running library
            versions where they differ.
    """
    check_plan_fields(record)
    folder = None if plan_file is None else Path(plan_file)
    try:
        _check_copies(record)
        contacts = recorded_contacts(record)
        if contacts is None:
            return _from_sampling(record, folder)
        return _from_recorded(record, contacts, folder)
    except OgcpError as exc:
        note = versions_note(record)
        if not note:
            raise
        raise OgcpError(f"{exc}; {note}") from exc
