"""Turn an ``ogcp.plan/1`` record back into what the simulation needs: mesh, contact set, grasps.

A plan records how its contact set was made (object, sampling seed and, for reach-aware
sampling, the fingertip radius and tolerance), not the set itself, so the set is sampled
again. Everything the plan records about the problem is then checked against the rebuilt
one: the object's identity (kind, name, file sha256, diagonal), the set's size, torque scale
rho and centre of mass, the best grasp's contact positions and normals, and its Q1 and the
set's Q_OWS (which are where mu and the cone edges k show). A plan that disagrees anywhere
(an edited field, another mesh, another ogcp version) is refused with the field, its recorded
and its rebuilt value, never simulated as if it were the original. Reading the record itself
(file, schema, grasps, sampling) is :mod:`planner.records.plan`'s job.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from planner.config.options import Option
from planner.grasp.contact_set import DEFAULT_CONE_EDGES, DEFAULT_MU, ContactSet, sample_contacts
from planner.grasp.defaults import CONE_EDGES, CONTACT_SEED, CONTACTS, DIAGONAL, MU, TIP_RADIUS
from planner.grasp.quality import q1
from planner.infra.errors import OgcpError
from planner.infra.tolerance import TOL
from planner.objects import DEFAULT_DIAGONAL, file_sha256, resolve_object
from planner.records.plan import SAMPLING_KEYS, ContactSampling, contact_sampling, plan_grasps, recorded_positions

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


#: The plan's fields that the simulation reads, by key path, with their valid values (a
#: missing or null field is allowed where older plans or other methods lack it).
_NUMBERS: dict[str, Option] = {
    "q1": Option("float", None, minimum=0),
    "q_ows": Option("float", None, minimum=0),
    "contact_set.size": CONTACTS,
    "contact_set.torque_scale": Option("float", None, minimum=0, exclusive=True),
    "contact_set.mu": MU,
    "contact_set.cone_edges": CONE_EDGES,
}
#: Keys of a contact source (either copy) and their valid values.
_SOURCE: dict[str, Option | type] = {
    "n": CONTACTS,
    "seed": CONTACT_SEED,
    "tip_radius": TIP_RADIUS,
    "reach_tolerance": Option("float", None, minimum=0),
    "diagonal": DIAGONAL,
    "sampling": str,
    "kind": str,
    "name": str,
    "path": str,
    "sha256": str,
}


def _field(record: dict[str, Any], path: str) -> Any:
    node: Any = record
    for key in path.split("."):
        node = node.get(key) if isinstance(node, dict) else None
    return node


def _present(record: dict[str, Any], path: str) -> bool:
    *parents, last = path.split(".")
    node = _field(record, ".".join(parents)) if parents else record
    return isinstance(node, dict) and last in node


def _block(record: dict[str, Any], path: str, kind: type) -> None:
    value = _field(record, path)
    if value is not None and not isinstance(value, kind):
        what = "an object" if kind is dict else "a list"
        raise OgcpError(f"plan field {path}: expected {what}, got {type(value).__name__} {_show_short(value)}")


def _show_short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _point(value: Any) -> bool:
    """Whether ``value`` is [x, y, z] of finite numbers."""
    numbers = isinstance(value, list) and len(value) == 3
    return numbers and all(isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in value)


def _rows(record: dict[str, Any], path: str) -> None:
    """A list of [x, y, z] rows of finite numbers (positions or normals), if present."""
    value = _field(record, path)
    if value is None:
        return
    if not (isinstance(value, list) and all(_point(row) for row in value)):
        raise OgcpError(
            f"plan field {path}: expected a list of [x, y, z] rows of finite numbers, got {_show_short(value)}"
        )


def check_plan_fields(record: dict[str, Any]) -> None:
    """Check the type and range of every field of an ``ogcp.plan/1`` record that the simulation reads.

    Fields it does not read (``method``, ``bound``, ``status``, ``stats``, ``config``,
    ``provenance``, ...) are left to their readers, which are lenient by design.

    Raises:
        OgcpError: ``plan field <key path>: expected ..., got ...`` for the first bad field.
    """
    for path in ("contact_set", "contact_set.source", "source", "contacts"):
        _block(record, path, dict)
    for path in ("grasp", "top", "runs"):
        _block(record, path, list)
    for i, run in enumerate(_field(record, "runs") or []):
        if not isinstance(run, dict):
            raise OgcpError(f"plan field runs[{i}]: expected an object with a grasp, got {_show_short(run)}")
    for path, declared in _NUMBERS.items():
        value = _field(record, path)
        # NaN is written as null, so a quality may be null; mu, k and the size never are.
        if value is not None or (path.startswith("contact_set.") and _present(record, path)):
            declared.check(f"plan field {path}", value)
    com = _field(record, "contact_set.com")
    if com is not None and not _point(com):
        raise OgcpError(f"plan field contact_set.com: expected [x, y, z] of finite numbers, got {_show_short(com)}")
    for path in ("contacts.positions", "contacts.normals"):
        _rows(record, path)
    for where in ("contact_set.source", "source"):
        source = _field(record, where) or {}
        for key, expected in _SOURCE.items():
            value = source.get(key)
            if value is None and (key not in source or key not in ("n", "seed", "sampling")):
                continue  # absent, or null where null means none (no tip, a mesh at its own size)
            if isinstance(expected, Option):
                expected.check(f"plan field {where}.{key}", value)
            elif not isinstance(value, expected):
                raise OgcpError(f"plan field {where}.{key}: expected a string, got {_show_short(value)}")


def _mesh(source: dict[str, Any]) -> trimesh.Trimesh:
    """Rebuild the plan's object and check every recorded key of its description."""
    kind = source.get("kind")
    if kind in ("builtin", "fetched"):
        diagonal = source.get("diagonal", DEFAULT_DIAGONAL)
        if diagonal is None:  # only a mesh file keeps its own size
            raise OgcpError(f"plan field source.diagonal: a {kind} object is scaled to a diagonal, got null")
        mesh, rebuilt = resolve_object(str(source.get("name")), float(diagonal))
    elif kind == "mesh":
        path = Path(str(source.get("path")))
        if not path.exists():
            raise OgcpError(f"the plan's mesh {path} does not exist (run from the folder the plan was made in)")
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
        # Keys an older plan lacks are not held against it; keys it has must agree.
        if key in source and source[key] != value:
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


def _qualities(contacts: ContactSet, best: Sequence[int], mu: float, k: int) -> tuple[float, float]:
    """Q1 of the best grasp and of the whole set [-] under friction ``mu`` with ``k`` cone edges."""
    if (mu, k) != (contacts.mu, contacts.cone_edges):
        contacts = ContactSet(contacts.positions, contacts.normals, contacts.com, contacts.torque_scale, mu, k)
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
    if all(wrong):
        # Both moved: the friction model. A field set away from its default names itself when
        # the default reproduces both recorded values.
        for field, value, default, mu, k in (
            ("mu", contacts.mu, DEFAULT_MU, DEFAULT_MU, contacts.cone_edges),
            ("cone_edges", contacts.cone_edges, DEFAULT_CONE_EDGES, contacts.mu, DEFAULT_CONE_EDGES),
        ):
            trial = _qualities(contacts, best, mu, k) if value != default else None
            if trial is not None and all(r is None or abs(r - t) <= Q1_TOLERANCE for r, t in zip(recorded, trial)):
                raise _misfit(field, value, default, "its q1 and q_ows")
        raise _mismatch(
            "(q1, q_ows)",
            list(recorded),
            list(rebuilt),
            f"recomputed with the recorded mu {contacts.mu:g} and cone_edges {contacts.cone_edges}: "
            "was mu or cone_edges changed?",
        )
    field = "q1 of the best grasp" if wrong[0] else "q_ows of the contact set"
    raise _mismatch(field, recorded[0 if wrong[0] else 1], rebuilt[0 if wrong[0] else 1])


def plan_input(record: dict[str, Any]) -> PlanInput:
    """Rebuild the mesh and contact set of a plan, check them against it, and collect its grasps.

    Raises:
        OgcpError: A field of the wrong type or out of range (:func:`check_plan_fields`),
            an unknown object, a contact set that cannot be reproduced, or any recorded
            field of the problem (object, size, rho, COM, contact positions and normals,
            Q1, Q_OWS) that differs from the rebuilt one: the message names the field and
            gives its recorded and rebuilt values.
    """
    check_plan_fields(record)
    sampling = contact_sampling(record)
    _check_copies(record)
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
