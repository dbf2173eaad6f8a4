"""The ``ogcp.grasps/1`` record: grasps from any planner, as fingertip contacts on one object.

A planner outside ogcp writes its grasps in this form, and ogcp gives them the same Q1, the
same physics and the same metrics as its own methods (``ogcp.sim_eval.evaluate_grasps``,
``ogcp evaluate GRASPS.json``). The minimal record::

    {"schema": "ogcp.grasps/1", "object": {"mesh": "box"}, "mu": 0.5,
     "grasps": [{"label": "mine", "contacts": [{"position": [x, y, z], "normal": [nx, ny, nz]}, ...]}]}

Positions are in the object's frame [m]; normals are unit vectors pointing *into* the object
(ogcp's convention). Every field is checked here, and a bad one is refused in one line that
names its JSON path (``grasps[3].contacts[1].normal: expected 3 finite numbers, got ...``).
Keys this reader does not know are ignored, so a planner may add its own. A record that names a
``hand`` may give each grasp a palm pose and joint angles instead of, or with, its contacts
(:mod:`ogcp.planner.records.hand_poses`). docs/external_grasps.md describes every field.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.grasp.contact_model import torsion_of
from ogcp.planner.grasp.defaults import CONE_EDGES, DEFAULT_CONE_EDGES, DIAGONAL, MU
from ogcp.planner.hands.registry import is_descriptor_path
from ogcp.planner.infra.atomic import read_json, write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import BUILTIN_OBJECTS, FETCHABLE_OBJECTS, file_sha256, resolve_object
from ogcp.planner.records.hand_poses import HandPose, parse_hand_name, parse_hand_pose

GRASPS_SCHEMA = "ogcp.grasps/1"
#: A normal's length may differ from 1 by this much; it is then normalised. Farther off, it is
#: refused: a length of 2 or 1000 is a force, a position or a unit error, not a rounded normal.
NORMAL_LENGTH_TOLERANCE = 1e-3
#: Two contacts of one grasp closer than this [m] are one contact given twice.
SAME_POSITION = 1e-9


def _short(value: Any) -> str:
    text = json.dumps(value) if _jsonable(value) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _jsonable(value: Any) -> bool:
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        return False
    return True


def is_object_name(mesh: str) -> bool:
    """Whether ``object.mesh`` names a built-in or fetched object rather than a mesh file."""
    return mesh in BUILTIN_OBJECTS or mesh in FETCHABLE_OBJECTS


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _vector(where: str, path: str, value: Any) -> NDArray[np.float64]:
    """Three finite numbers, else the one-line error naming ``path``."""
    if not (isinstance(value, (list, tuple)) and len(value) == 3 and all(_is_number(v) for v in value)):
        raise OgcpError(f"{where}: {path}: expected 3 finite numbers, got {_short(value)}")
    return np.array(value, dtype=float)


def _text(where: str, path: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip():
        raise OgcpError(f"{where}: {path}: expected a non-empty string, got {_short(value)}")
    return value


@dataclass(frozen=True, eq=False)
class ExternalGrasp:
    """One grasp of an ``ogcp.grasps/1`` record.

    Attributes:
        positions: Fingertip contact points in the object frame, shape (m, 3) [m], m >= 2.
        normals: Inward unit surface normals there, shape (m, 3).
        label: Name of the grasp (need not be unique; default ``grasp-<i>``).
        method: The planner that made it; None: the record's top-level ``method``.
        score: The planner's own score of it (any scale), None when not given.
        hand: The hand's palm pose and joint angles (a record that names a hand); its contacts
            may then be absent (``positions`` of shape (0, 3)): the pads' are used.
    """

    positions: NDArray[np.float64]
    normals: NDArray[np.float64]
    label: str
    method: str | None = None
    score: float | None = None
    hand: HandPose | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form of the grasp (absent method and score left out)."""
        entry: dict[str, Any] = {"label": self.label}
        if self.method is not None:
            entry["method"] = self.method
        if self.score is not None:
            entry["score"] = self.score
        if len(self.positions):
            entry["contacts"] = [
                {"position": p.tolist(), "normal": n.tolist()}
                for p, n in zip(self.positions, self.normals, strict=True)
            ]
        if self.hand is not None:
            entry["hand"] = self.hand.to_dict()
        return entry


@dataclass(frozen=True, eq=False)
class ExternalGrasps:
    """An ``ogcp.grasps/1`` record, checked: the object, the friction model and the grasps.

    Attributes:
        grasps: The grasps, in the record's order.
        mu: Coulomb friction coefficient of every contact.
        cone_edges: Friction-cone edges k of Q1's linearised cones.
        mesh: The object as written: a built-in or fetched name, or a mesh path (relative
            paths are relative to :attr:`base`); None for grasps given as arrays.
        diagonal: Bounding-box diagonal to scale the object to [m]; None: a built-in's default
            (0.2 m), a mesh file's own size.
        sha256: The mesh file's SHA-256, checked when the object is loaded; None: unchecked.
        method: The planner of every grasp that names none itself.
        base: Folder a relative mesh path is relative to (the record file's); None: the
            current folder.
        path: The file the record was read from, None when not read from a file.
        torsional_friction: Torsional friction coefficient of soft fingers [m] (the record's
            ``contact_model = "soft"`` and ``torsional_friction``); 0 = hard fingers.
        hand: The hand of the grasps' ``hand`` blocks: a built-in name or a descriptor path
            (relative to :attr:`base`); None: fingertip grasps.
    """

    grasps: tuple[ExternalGrasp, ...]
    mu: float
    cone_edges: int = DEFAULT_CONE_EDGES
    mesh: str | None = None
    diagonal: float | None = None
    sha256: str | None = None
    method: str | None = None
    base: Path | None = None
    path: Path | None = None
    torsional_friction: float = 0.0
    hand: str | None = None

    def method_of(self, grasp: ExternalGrasp) -> str | None:
        """The planner of a grasp: its own ``method``, else the record's."""
        return grasp.method if grasp.method is not None else self.method

    @property
    def object_spec(self) -> str | None:
        """The object as :func:`ogcp.planner.objects.resolve_object` takes it: a name, or a path resolved against ``base``."""
        if self.mesh is None or is_object_name(self.mesh):
            return self.mesh
        path = Path(self.mesh)
        return str(path if path.is_absolute() or self.base is None else self.base / path)

    @property
    def hand_spec(self) -> str | None:
        """The hand as ``--hand`` takes it: a built-in name, or a descriptor path resolved against ``base``."""
        if self.hand is None or not is_descriptor_path(self.hand):
            return self.hand
        path = Path(self.hand)
        return str(path if path.is_absolute() or self.base is None else self.base / path)

    def load_object(self) -> tuple[trimesh.Trimesh, dict[str, object]]:
        """The object's mesh (scaled to ``diagonal`` if given) and its source description.

        Raises:
            OgcpError: For a record without an object, an unknown name, a mesh that does not
                load, or a file whose SHA-256 differs from the recorded one.
        """
        spec = self.object_spec
        if spec is None:
            raise OgcpError("the grasps name no object: give object.mesh, or pass the mesh")
        if self.sha256 is not None and Path(spec).is_file() and (digest := file_sha256(Path(spec))) != self.sha256:
            raise OgcpError(
                f"object.sha256: the mesh {spec} has SHA-256 {digest}, the grasps were made on {self.sha256}"
            )
        return resolve_object(spec, self.diagonal)

    def to_dict(self) -> dict[str, Any]:
        """JSON form, schema ``ogcp.grasps/1`` (optional fields only where set).

        Raises:
            OgcpError: For grasps that name no object (given as arrays without a mesh).
        """
        if self.mesh is None:
            raise OgcpError("cannot write grasps that name no object: set its mesh (a name or a path)")
        obj: dict[str, Any] = {"mesh": self.mesh}
        if self.diagonal is not None:
            obj["diagonal"] = self.diagonal
        if self.sha256 is not None:
            obj["sha256"] = self.sha256
        record: dict[str, Any] = {"schema": GRASPS_SCHEMA, "object": obj, "mu": self.mu, "cone_edges": self.cone_edges}
        if self.torsional_friction > 0:
            record.update(contact_model="soft", torsional_friction=self.torsional_friction)
        if self.method is not None:
            record["method"] = self.method
        if self.hand is not None:
            record["hand"] = self.hand
        record["grasps"] = [g.to_dict() for g in self.grasps]
        return record

    @classmethod
    def from_dict(cls, data: Any, where: str = "grasps", base: Path | None = None) -> ExternalGrasps:
        """Read and check a parsed ``ogcp.grasps/1`` record.

        Args:
            data: The parsed JSON.
            where: Name of the record in error messages (the file path).
            base: Folder a relative mesh path is relative to.

        Raises:
            OgcpError: ``<where>: <JSON path>: expected ..., got ...`` for the first bad field.
        """
        if not isinstance(data, dict):
            raise OgcpError(f"{where}: expected a JSON object with schema {GRASPS_SCHEMA!r}, got {_short(data)}")
        if data.get("schema") != GRASPS_SCHEMA:
            raise OgcpError(f"{where}: schema: expected {GRASPS_SCHEMA!r}, got {_short(data.get('schema'))}")
        obj = data.get("object")
        if not isinstance(obj, dict):
            raise OgcpError(f"{where}: object: expected an object with a mesh name or path, got {_short(obj)}")
        mesh = _text(where, "object.mesh", obj.get("mesh"))
        diagonal = _optional(where, obj, "diagonal", "object.diagonal")
        if diagonal is not None:
            diagonal = DIAGONAL.check(f"{where}: object.diagonal [m]", diagonal)
        sha256 = obj.get("sha256")
        if sha256 is not None:
            sha256 = _text(where, "object.sha256", sha256)
        if "mu" not in data:
            raise OgcpError(f"{where}: mu: missing (the friction coefficient of the contacts, e.g. 0.5)")
        mu = MU.check(f"{where}: mu", data["mu"])
        cone_edges = CONE_EDGES.check(f"{where}: cone_edges", data.get("cone_edges", DEFAULT_CONE_EDGES))
        torsion = torsion_of(
            data.get("contact_model"),
            data.get("torsional_friction"),
            f"{where}: contact_model",
            f"{where}: torsional_friction",
        )
        method = data.get("method")
        method = None if method is None else _text(where, "method", method)
        hand = None if data.get("hand") is None else parse_hand_name(where, data["hand"])
        grasps = data.get("grasps")
        if not isinstance(grasps, list) or not grasps:
            raise OgcpError(f"{where}: grasps: expected a non-empty list of grasps, got {_short(grasps)}")
        return cls(
            grasps=tuple(_grasp(where, i, g, hand is not None) for i, g in enumerate(grasps)),
            mu=mu,
            cone_edges=cone_edges,
            mesh=mesh,
            diagonal=diagonal,
            sha256=sha256,
            method=method,
            base=base,
            torsional_friction=torsion,
            hand=hand,
        )

    @classmethod
    def from_arrays(
        cls,
        grasps: Sequence[tuple[ArrayLike, ArrayLike]],
        mu: float,
        cone_edges: int = DEFAULT_CONE_EDGES,
        labels: Sequence[str] | None = None,
        method: str | None = None,
        scores: Sequence[float | None] | None = None,
        torsional_friction: float = 0.0,
    ) -> ExternalGrasps:
        """Grasps given as arrays, checked as a record's are (the messages name the same paths).

        Args:
            grasps: Per grasp ``(positions (m, 3) [m], inward normals (m, 3))``.
            mu: Friction coefficient.
            cone_edges: Friction-cone edges k.
            labels: A label per grasp (default ``grasp-<i>``).
            method: The planner of every grasp.
            scores: The planner's score per grasp (None where it has none).
            torsional_friction: Torsional friction coefficient of soft fingers [m]; 0 = hard.

        Raises:
            OgcpError: For a bad array, count of labels or scores, mu or k.
        """
        for name, values in (("labels", labels), ("scores", scores)):
            if values is not None and len(values) != len(grasps):
                raise OgcpError(f"got {len(values)} {name} for {len(grasps)} grasps")
        entries = []
        for i, (positions, normals) in enumerate(grasps):
            p, n = np.asarray(positions, dtype=float), np.asarray(normals, dtype=float)
            if p.ndim != 2 or p.shape[1] != 3 or n.shape != p.shape:
                raise OgcpError(
                    f"grasps[{i}]: expected positions and normals of one shape (m, 3), got {p.shape} and {n.shape}"
                )
            entry: dict[str, Any] = {"contacts": [{"position": a, "normal": b} for a, b in zip(p.tolist(), n.tolist())]}
            if labels is not None:
                entry["label"] = labels[i]
            if scores is not None:
                entry["score"] = scores[i]
            entries.append(entry)
        # Checked as a record with a stand-in object, which the result then drops: the caller has the mesh.
        record = {"schema": GRASPS_SCHEMA, "object": {"mesh": "-"}, "mu": mu, "cone_edges": cone_edges}
        if torsional_friction:
            record["torsional_friction"] = torsional_friction
        if method is not None:
            record["method"] = method
        return replace(cls.from_dict({**record, "grasps": entries}, where="given grasps"), mesh=None)


def _optional(where: str, block: dict[str, Any], key: str, path: str) -> float | None:
    """An optional finite number (absent or null: None)."""
    value = block.get(key)
    if value is None:
        return None
    if not _is_number(value):
        raise OgcpError(f"{where}: {path}: expected a finite number or null, got {_short(value)}")
    return float(value)


def _grasp(where: str, index: int, data: Any, with_hand: bool = False) -> ExternalGrasp:
    """One entry of ``grasps``, checked (``with_hand``: the record names a hand)."""
    path = f"grasps[{index}]"
    if not isinstance(data, dict):
        raise OgcpError(f"{where}: {path}: expected an object with contacts, got {_short(data)}")
    label = data.get("label", f"grasp-{index}")
    label = _text(where, f"{path}.label", label)
    method = data.get("method")
    method = None if method is None else _text(where, f"{path}.method", method)
    score = _optional(where, data, "score", f"{path}.score")
    hand = None
    if data.get("hand") is not None:
        if not with_hand:
            raise OgcpError(f'{where}: {path}.hand: the record names no hand; add a top-level "hand"')
        hand = parse_hand_pose(where, f"{path}.hand", data["hand"])
    contacts = data.get("contacts")
    if hand is not None and contacts is None:
        empty = np.empty((0, 3))
        empty.setflags(write=False)
        return ExternalGrasp(empty, empty, label, method, score, hand)
    if not isinstance(contacts, list) or len(contacts) < 2:
        count = f"{len(contacts)} contact(s)" if isinstance(contacts, list) else _short(contacts)
        raise OgcpError(f"{where}: {path}.contacts: expected a list of at least 2 contacts, got {count}")
    positions, normals = np.empty((len(contacts), 3)), np.empty((len(contacts), 3))
    for j, contact in enumerate(contacts):
        at = f"{path}.contacts[{j}]"
        if not isinstance(contact, dict):
            raise OgcpError(f"{where}: {at}: expected an object with position and normal, got {_short(contact)}")
        for key in ("position", "normal"):
            if key not in contact:
                raise OgcpError(f"{where}: {at}.{key}: missing")
        positions[j] = _vector(where, f"{at}.position", contact["position"])
        normals[j] = _unit(where, f"{at}.normal", contact["normal"])
        same = np.flatnonzero(np.linalg.norm(positions[:j] - positions[j], axis=1) <= SAME_POSITION)
        if len(same):
            raise OgcpError(
                f"{where}: {at}.position: the same point as {path}.contacts[{int(same[0])}]; "
                "two fingertips cannot touch one point"
            )
    positions.setflags(write=False)
    normals.setflags(write=False)
    return ExternalGrasp(positions, normals, label, method, score, hand)


def _unit(where: str, path: str, value: Any) -> NDArray[np.float64]:
    """A normal: three finite numbers of length 1 +- :data:`NORMAL_LENGTH_TOLERANCE`, normalised."""
    normal = _vector(where, path, value)
    length = float(np.linalg.norm(normal))
    if abs(length - 1.0) > NORMAL_LENGTH_TOLERANCE:
        why = "zero" if length == 0 else f"{length:.6g}"
        raise OgcpError(
            f"{where}: {path}: expected a unit vector (length 1 +- {NORMAL_LENGTH_TOLERANCE:g}), got length {why}: "
            f"{_short(value)}"
        )
    # Rows already unit to rounding are kept bit for bit (as ContactSet keeps them), so that a
    # written and re-read record gives exactly the same wrenches.
    return normal if abs(length - 1.0) <= 1e-12 else normal / length


def load_grasps(path: str | Path) -> ExternalGrasps:
    """Read and check an ``ogcp.grasps/1`` file; a relative mesh path is relative to the file's folder.

    Raises:
        OgcpError: For a missing or unreadable file, invalid JSON, another schema, or a bad field
            (one line naming its JSON path).
    """
    path = Path(path)
    data = read_json(path, "grasps", "ogcp.grasps/1")
    return replace(ExternalGrasps.from_dict(data, where=str(path), base=path.parent), path=path)


def mesh_reference(mesh: str | Path, folder: str | Path) -> str:
    """How a record in ``folder`` names a mesh file: its path relative to that folder.

    Relative, so that the record and its mesh move together; absolute only where no relative
    path reaches it (another drive on Windows).
    """
    target = Path(mesh).resolve()
    try:
        return Path(os.path.relpath(target, Path(folder).resolve())).as_posix()
    except ValueError:
        return str(target)


def save_grasps(grasps: ExternalGrasps, path: str | Path) -> None:
    """Write grasps as an ``ogcp.grasps/1`` file, atomically.

    Floats are written in full (``repr``), so reading the file back gives the same contacts bit
    for bit. A mesh path is rewritten relative to the new file's folder.

    Raises:
        OgcpError: For grasps that name no object, or a file that cannot be written.
    """
    if grasps.mesh is not None and not is_object_name(grasps.mesh):
        grasps = replace(grasps, mesh=mesh_reference(str(grasps.object_spec), Path(path).parent))
    write_json_atomic(path, grasps.to_dict())


def is_grasps_file(path: str | Path) -> bool:
    """Whether ``path`` holds a JSON object whose schema is ``ogcp.grasps/1`` (False if unreadable)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return isinstance(data, dict) and data.get("schema") == GRASPS_SCHEMA
