"""The 3D scenes of the report: object meshes, contact sets and grasps as compact JSON-ready data.

A scene is what the viewer draws for one grasp: the object mesh (shared by every grasp on that
object, so a report holds each mesh once), the contact set's points (shared per contact set),
the grasp's contacts and inward normals, and the simulated outcome. Meshes are rebuilt from the
records (:func:`ogcp.sim_eval.inputs.plan_input.plan_input` for plans, which shows the contacts a plan
records, on its mesh found as ``ogcp evaluate`` finds it; the recorded object description,
re-sampled, for simulation records on their own), never stored in them, and coarsened by vertex
clustering to at most :data:`MAX_FACES` faces so that a report stays small.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.benchmarks.report.hand_mesh import HAND_FACES, settled_hand
from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import DEFAULT_DIAGONAL, resolve_object
from ogcp.planner.records.plan import PlanView
from ogcp.sim_eval.inputs.plan_input import plan_input
from ogcp.sim_eval.result import SimGraspRecord, SimRecord

#: Most faces kept per object mesh; a finer mesh is coarsened by vertex clustering.
MAX_FACES = 20_000
#: Coordinates are written to this many digits after the point [m]: 10 um, far below a pixel.
DIGITS = 5
#: Longest triangle edge the viewer gets, as a fraction of the object's size (see :func:`display_mesh`).
EDGE_FRACTION = 0.08


def _key(value: Any) -> str:
    """A stable text key of a JSON value (to share meshes and contact sets)."""
    return json.dumps(value, sort_keys=True, default=str)


def _flat(values: NDArray[np.float64]) -> list[float | None]:
    # JSON has no NaN: a missing coordinate is null (the viewer reads it as 0).
    return [round(float(v), DIGITS) if math.isfinite(v) else None for v in np.asarray(values, dtype=float).ravel()]


def _finite(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def coarsen(mesh: trimesh.Trimesh, max_faces: int = MAX_FACES) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Vertices and faces of ``mesh`` with at most ``max_faces`` faces.

    Vertex clustering: vertices are snapped to a grid and merged per cell (at the cluster's
    mean), and faces that collapse or repeat are dropped. The grid starts near the budget's
    resolution and coarsens until the mesh fits; it keeps the silhouette, which is what the
    viewer needs, not the topology.

    Args:
        mesh: The object mesh.
        max_faces: The face budget.

    Returns:
        Vertices (V, 3) and faces (F, 3).
    """
    vertices = np.asarray(mesh.vertices, dtype=float)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if len(faces) <= max_faces:
        return vertices, faces
    extent = float(np.ptp(vertices, axis=0).max()) or 1.0
    # Faces scale with the square of the cells per side: start near the budget's resolution.
    cells = max(4, int(math.sqrt(max_faces) * 1.5))
    while True:
        size = extent / cells
        cell = np.floor((vertices - vertices.min(axis=0)) / size).astype(np.int64)
        _, first, inverse = np.unique(cell, axis=0, return_index=True, return_inverse=True)
        merged = inverse.reshape(-1)[faces]
        keep = (merged[:, 0] != merged[:, 1]) & (merged[:, 1] != merged[:, 2]) & (merged[:, 0] != merged[:, 2])
        kept = np.unique(np.sort(merged[keep], axis=1), axis=0, return_index=True)[1]
        reduced = merged[keep][np.sort(kept)]
        if len(reduced) <= max_faces or cells <= 4:
            # Each merged vertex sits at the cluster's mean: smoother than the cell corner.
            counts = np.bincount(inverse.reshape(-1), minlength=len(first)).astype(float)
            means = np.stack([np.bincount(inverse.reshape(-1), vertices[:, i]) for i in range(3)], axis=1)
            return means / counts[:, None], reduced
        cells = int(cells * 0.7)


def display_mesh(
    mesh: trimesh.Trimesh, max_faces: int = MAX_FACES
) -> tuple[NDArray[np.float64], NDArray[np.int64], float]:
    """The mesh as the viewer draws it: coarsened to ``max_faces``, large faces split.

    The viewer sorts whole triangles by their centre's depth (painter's algorithm), which
    misorders a point against a triangle much larger than the point's distance to it: a box's
    two triangles per side would hide the contacts on that side. Splitting every edge longer
    than :data:`EDGE_FRACTION` of the object's size bounds that error; the viewer biases the
    points by about this edge length towards the eye.

    Returns:
        Vertices (V, 3), faces (F, 3) and the longest edge kept [m].
    """
    vertices, faces = coarsen(mesh, max_faces)
    extent = float(np.ptp(vertices, axis=0).max()) or 1.0
    split_vertices, split_faces = trimesh.remesh.subdivide_to_size(vertices, faces, max_edge=extent * EDGE_FRACTION)
    if len(split_faces) <= max_faces:
        vertices, faces = np.asarray(split_vertices, dtype=float), np.asarray(split_faces, dtype=np.int64)
    edges = vertices[faces] - vertices[np.roll(faces, 1, axis=1)]
    return vertices, faces, float(np.linalg.norm(edges, axis=2).max()) if len(faces) else 0.0


@dataclass
class Scenes:
    """The viewer's data for a set of grasps, with meshes and contact sets stored once.

    Attributes:
        meshes: Per mesh: ``name``, flat ``vertices`` and ``faces``.
        sets: Per contact set: ``mesh`` (its index) and flat ``points``.
        grasps: Per grasp: title, mesh and set index, contacts, normals, outcome.
        notes: One line per grasp or record that could not be shown in full.
    """

    meshes: list[dict[str, Any]] = field(default_factory=list)
    sets: list[dict[str, Any]] = field(default_factory=list)
    grasps: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    _mesh_index: dict[str, int] = field(default_factory=dict)
    _set_index: dict[str, tuple[int, ContactSet | None]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON form, embedded in the page."""
        return {"meshes": self.meshes, "sets": self.sets, "grasps": self.grasps}

    def _add_mesh(self, name: str, key: str, mesh: trimesh.Trimesh) -> int:
        if key not in self._mesh_index:
            vertices, faces, edge = display_mesh(mesh)
            self._mesh_index[key] = len(self.meshes)
            self.meshes.append(
                {
                    "name": name,
                    "vertices": _flat(vertices),
                    "faces": faces.ravel().tolist(),
                    "edge": round(edge, DIGITS),
                }
            )
        return self._mesh_index[key]

    def _contact_set(
        self, source: dict[str, Any], plan: dict[str, Any] | None, plan_file: Path | None = None
    ) -> tuple[int, ContactSet | None]:
        """The index and rebuilt contact set of a contact-set source (-1, None when it cannot be rebuilt).

        A plan's set is the one it records, checked against its mesh as ``ogcp evaluate`` does
        (:func:`ogcp.sim_eval.inputs.plan_input.plan_input`; the mesh file is looked for next to ``plan_file``
        first); only a record without a plan is re-sampled from its description.
        """
        key = _key(source)
        if key in self._set_index:
            return self._set_index[key]
        try:
            if plan is not None:
                rebuilt = plan_input(plan, plan_file)
                mesh, contacts = rebuilt.mesh, rebuilt.contacts
            else:
                mesh, contacts = _rebuild(source)
        except OgcpError as exc:
            self.notes.append(f"{source.get('name', source.get('path', '?'))}: no mesh or contact set shown ({exc})")
            self._set_index[key] = (-1, None)
            return self._set_index[key]
        name = str(source.get("name") or source.get("path") or "object")
        mesh_key = _key({k: source.get(k) for k in ("kind", "name", "path", "diagonal", "sha256")})
        index = len(self.sets)
        self.sets.append({"mesh": self._add_mesh(name, mesh_key, mesh), "points": _flat(contacts.positions)})
        self._set_index[key] = (index, contacts)
        return self._set_index[key]

    def add_plan(
        self, title: str, plan: dict[str, Any], sim: dict[str, Any] | None = None, plan_file: str | Path | None = None
    ) -> None:
        """Add the grasps of a plan: every simulated grasp, else the plan's best grasp.

        Args:
            title: What the grasps are (object, method), shown above the view.
            plan: The ``ogcp.plan/1`` record.
            sim: Its ``ogcp.sim/1`` or ``/2`` record, if it was simulated.
            plan_file: The file the record was read from: a mesh file is looked for relative to
                it first, as ``ogcp evaluate`` does (None: only the recorded paths).
        """
        source = (plan.get("contact_set") or {}).get("source") or plan.get("source") or {}
        index, contacts = self._contact_set(dict(source), plan, None if plan_file is None else Path(plan_file))
        if sim is not None:
            self._add_sim(title, SimRecord.from_dict(sim), index, contacts)
            return
        view = PlanView(plan)
        recorded = plan.get("contacts") or {}
        self.grasps.append(
            {
                "title": f"{title} / best",
                "set": index,
                "grasp": list(view.grasp or ()),
                "points": _flat(np.asarray(recorded.get("positions", []), dtype=float)),
                "normals": _flat(np.asarray(recorded.get("normals", []), dtype=float)),
                "q1": _finite(view.q1),
                "simulated": False,
            }
        )

    def add_sim(self, title: str, sim: dict[str, Any]) -> None:
        """Add the grasps of a simulation record on its own (the object is rebuilt from its description)."""
        record = SimRecord.from_dict(sim)
        index, contacts = self._contact_set(dict(record.object), None)
        self._add_sim(title, record, index, contacts)

    def _add_sim(self, title: str, record: SimRecord, index: int, contacts: ContactSet | None) -> None:
        for grasp in record.grasps:
            shown = {"title": f"{title} / {grasp.label}", "set": index, **_sim_grasp(grasp, contacts)}
            if grasp.hand:
                shown.update(self._hand(shown["title"], grasp.hand))
            self.grasps.append(shown)

    def _hand(self, title: str, block: dict[str, Any]) -> dict[str, Any]:
        """The viewer's ``hand`` of a grasp tested with one: its settled surface, coarsened; {} without."""
        try:
            found = settled_hand(block)
        except OgcpError as exc:
            self.notes.append(f"{title}: hand not shown ({exc})")
            return {}
        if found is None or not len(found[1]):
            return {}
        vertices, faces = coarsen(trimesh.Trimesh(*found, process=False), HAND_FACES)
        return {"hand": {"vertices": _flat(vertices), "faces": faces.ravel().tolist()}}


def _rebuild(source: dict[str, Any]) -> tuple[trimesh.Trimesh, ContactSet]:
    """The mesh and contact set a contact-set source describes (no checks: for display only)."""
    kind = source.get("kind")
    if kind in ("builtin", "fetched"):
        mesh, _ = resolve_object(str(source.get("name")), float(source.get("diagonal") or DEFAULT_DIAGONAL))
    elif kind == "mesh":
        diagonal = source.get("diagonal")
        mesh, _ = resolve_object(str(source.get("path")), None if diagonal is None else float(diagonal))
    else:
        raise OgcpError(f"unknown object kind {kind!r}")
    n, seed = source.get("n"), source.get("seed", 0)
    if not isinstance(n, int) or not isinstance(seed, int):
        raise OgcpError("the record does not say how its contact set was sampled")
    tip, tolerance = source.get("tip_radius"), source.get("reach_tolerance")
    contacts = sample_contacts(
        mesh,
        n,
        seed,
        source=dict(source),
        tip_radius=None if tip is None else float(tip),
        reach_tolerance=None if tolerance is None else float(tolerance),
    )
    return mesh, contacts


def _sim_grasp(grasp: SimGraspRecord, contacts: ContactSet | None) -> dict[str, Any]:
    """The viewer's data of one simulated grasp: contacts (realized if recorded), outcome, weakest direction."""
    indices = list(grasp.grasp or ())
    points: Sequence[Any] = grasp.realized.get("points") or []
    normals: Sequence[Any] = grasp.realized.get("normals") or []
    if not points and contacts is not None and indices:
        points, normals = contacts.positions[indices].tolist(), contacts.normals[indices].tolist()
    weakest = None
    finite = np.isfinite(grasp.measured)
    if finite.any() and len(grasp.directions) == len(grasp.measured):
        # The disturbance the grasp resists least: its force part as an arrow through the centre.
        worst = int(np.flatnonzero(finite)[np.argmin(grasp.measured[finite])])
        force = grasp.directions[worst, :3]
        label = grasp.direction_labels[worst] if worst < len(grasp.direction_labels) else str(worst)
        if np.linalg.norm(force) > 0:
            weakest = {"force": _flat(force / np.linalg.norm(force)), "label": label}
    center = contacts.com if contacts is not None else np.zeros(3)
    return {
        "grasp": indices,
        "points": _flat(np.asarray(points, dtype=float)),
        "normals": _flat(np.asarray(normals, dtype=float)),
        "q1": _finite(grasp.q1),
        "simulated": True,
        "valid": grasp.valid,
        "error": grasp.error,
        "measured_min": _finite(grasp.measured_min),
        "reasons": list(grasp.invalid_reasons),
        "weakest": weakest,
        "center": _flat(center),
    }
