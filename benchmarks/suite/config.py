"""Benchmark suites as values: objects, cells (with their ids) and the suite (read by :mod:`ogcp.benchmarks.suite.parse`).

A suite names objects, contact counts, contact seeds, m values, friction coefficients and
method variants, either at the top level or in ``[[group]]`` tables that inherit unset keys
from the top level. Cells are the cartesian product object x contacts x contact seed x m x
mu x tip radius x variant of every group, plus one cell per external grasps file
(``method = "external"``), which brings its own contacts, m and mu; a cell's id is a hash of its canonical parameters (defaults filled in), so
it does not depend on the order of anything in the file, and a cell listed by two groups
runs once. Everything is validated on load; errors name the key path and the valid
values.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from typing import TYPE_CHECKING, Any

from ogcp.benchmarks.suite.record import CellParams
from ogcp.planner.methods.registry import EXTERNAL
from ogcp.planner.objects.fetchable import FETCHABLE_OBJECTS

if TYPE_CHECKING:
    from ogcp.planner.records.grasps import ExternalGrasps

SCHEMA_VERSION = 1
# Built-in suites: assets/suites/NAME.toml (see ogcp.planner.infra.assets).
SUITES_FOLDER = "suites"
GROUP_KEYS = (
    "contact_seeds",
    "contacts",
    "cone_edges",
    "contact_model",
    "description",
    "diagonal",
    "methods",
    "m",
    "mu",
    "name",
    "objects",
    "simulate",
    "tip_radius",
    "torsional_friction",
)
TOP_KEYS = (*GROUP_KEYS, "group", "schema_version", "simulation")
#: ``tip_radius`` of a cell's id and params when the contacts are kept for the default fingertip.
DEFAULT_TIP = "default"
#: The method name of external grasps in a suite (``method = "external"``, ``grasps = "file.json"``):
#: not a planner of :mod:`ogcp.planner.methods`, whose ``method_spec`` refuses it with this hint.
EXTERNAL_METHOD = EXTERNAL
#: Version of the canonical cell form; part of every id so a change of form never matches old ids.
CELL_FORM = 1


def best_grasp(grasps: ExternalGrasps) -> int:
    """Index of the grasp an external cell reports (its plan's grasp and m): the highest score, else the first.

    Scores are the planner's own, on any scale, higher taken as better; ties go to the earlier grasp.
    """
    scored = [(g.score, -i) for i, g in enumerate(grasps.grasps) if g.score is not None]
    return -max(scored)[1] if scored else 0


@dataclasses.dataclass(frozen=True)
class ObjectSpec:
    """An object as a suite names it.

    Attributes:
        spec: The name or path as written in the suite.
        path: Absolute mesh path (None for a named object).
        sha256: Hash of the mesh file (None for a named object).
    """

    spec: str
    path: str | None = None
    sha256: str | None = None

    @property
    def key(self) -> str:
        """Identity in cell ids: the name, or the mesh's content hash (moving the file keeps it)."""
        return f"mesh:{self.sha256}" if self.sha256 else self.spec


@dataclasses.dataclass(frozen=True)
class Cell:
    """One run: an object's contact set, m and one method variant.

    Attributes:
        object: The object.
        contacts: Number of contacts n.
        contact_seed: Seed of the contact sampling (None for external grasps: nothing is sampled).
        m: Number of fingers.
        mu: Friction coefficient.
        cone_edges: Friction-cone edges k.
        diagonal: Bounding-box diagonal [m] (None for a mesh file at its own size).
        method: Method name.
        variant: Canonical method parameters, sorted by name (external grasps: the file's sha256).
        label: Label for plots (not part of the id).
        groups: Names of the suite groups that list this cell (not part of the id).
        simulate: Whether the cell is simulated when the suite's simulation is enabled
            (not part of the id).
        tip_radius: Fingertip radius the contacts are sampled for [m]: 0 = the paper's plain
            sampling of the whole surface, None = the simulation's default fingertip
            (:func:`ogcp.planner.grasp.reach.default_tip_radius` of the object, resolved when sampling).
        grasps_path: Absolute path of the ``ogcp.grasps/1`` file of an external cell, else None
            (not part of the id: its content hash, in ``variant``, is).
        torsional_friction: Torsional friction coefficient of soft fingers [m]; 0 = hard fingers.
    """

    object: ObjectSpec
    contacts: int
    contact_seed: int | None
    m: int
    mu: float
    cone_edges: int
    diagonal: float | None
    method: str
    variant: tuple[tuple[str, Any], ...]
    label: str
    groups: tuple[str, ...] = ()
    simulate: bool = True
    tip_radius: float | None = None
    grasps_path: str | None = None
    torsional_friction: float = 0.0

    @property
    def tip_radius_key(self) -> float | str | None:
        """The tip radius in ids and records: ``"default"``, a radius > 0 [m], or None for plain sampling."""
        if self.tip_radius is None:
            return DEFAULT_TIP
        return self.tip_radius if self.tip_radius > 0 else None

    def canonical(self) -> dict[str, Any]:
        """The parameters that define the cell's result (hashed into the id).

        The tip radius is included only for reach-aware sampling, so cells with the paper's
        plain sampling keep the ids they had before contacts knew the fingertip, and every
        cell whose contacts may differ from those gets a new id.
        """
        form = {
            "form": CELL_FORM,
            "object": self.object.key,
            "contacts": self.contacts,
            "contact_seed": self.contact_seed,
            "m": self.m,
            "mu": self.mu,
            "cone_edges": self.cone_edges,
            "diagonal": self.diagonal,
            "method": self.method,
            "variant": dict(self.variant),
        }
        if self.tip_radius_key is not None:
            form["tip_radius"] = self.tip_radius_key
        if self.torsional_friction > 0:  # hard cells keep the ids they had before soft fingers
            form["torsional_friction"] = self.torsional_friction
        return form

    @property
    def id(self) -> str:
        """Stable id: 16 hex digits of the sha256 of the canonical parameters."""
        text = json.dumps(self.canonical(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def params(self) -> dict[str, Any]:
        """The ``params`` block of the cell's result record."""
        return CellParams(
            object=self.object.spec,
            contacts=self.contacts,
            contact_seed=self.contact_seed,
            m=self.m,
            mu=self.mu,
            cone_edges=self.cone_edges,
            diagonal=self.diagonal,
            method=self.method,
            variant=dict(self.variant),
            label=self.label,
            tip_radius=self.tip_radius_key,
            torsional_friction=self.torsional_friction or None,
        ).to_dict()


@dataclasses.dataclass(frozen=True)
class Suite:
    """A validated suite.

    Attributes:
        name: Suite name (``name`` key, else the file's stem).
        source: Where it came from (built-in name or file path).
        text: The file's full content.
        cells: Every cell, deduplicated, in file order.
        simulation: The ``[simulation]`` table as written (``enabled`` defaults to false).
    """

    name: str
    source: str
    text: str
    cells: tuple[Cell, ...]
    simulation: dict[str, Any]

    @property
    def simulate(self) -> bool:
        """Whether cells run the simulation."""
        return bool(self.simulation.get("enabled", False))

    @property
    def hash(self) -> str:
        """Hash of what the suite runs: the set of cells with labels and groups, and the simulation settings.

        Independent of the order of the file's entries, comments and descriptions.
        """
        cells = sorted([c.id, c.label, sorted(c.groups), c.simulate and self.simulate] for c in self.cells)
        text = json.dumps({"cells": cells, "simulation": self.simulation}, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def without_simulation(self) -> Suite:
        """The same suite with the simulation switched off (its hash differs)."""
        return Suite(self.name, self.source, self.text, self.cells, {**self.simulation, "enabled": False})

    def unfetched_objects(self) -> list[str]:
        """Fetchable objects the suite uses that are not in the cache yet (``ogcp assets fetch``)."""
        from ogcp.planner.objects.fetch import is_cached  # lazy: the asset tools are needed only here

        names = {c.object.spec for c in self.cells if c.object.path is None and c.object.spec in FETCHABLE_OBJECTS}
        return sorted(name for name in names if not is_cached(name))

    def seeds(self) -> dict[str, list[int]]:
        """Every contact seed and method seed the suite uses."""
        method = {dict(c.variant)["seed"] for c in self.cells if "seed" in dict(c.variant)}
        contact = {c.contact_seed for c in self.cells if c.contact_seed is not None}  # external grasps have none
        return {"contact_seeds": sorted(contact), "method_seeds": sorted(method)}
