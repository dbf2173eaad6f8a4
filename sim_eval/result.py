"""Simulation results and their versioned JSON form (schema ``ogcp.sim/2``), written and read here.

:class:`SimResult` and :class:`GraspSimResult` build the record; :class:`SimRecord` and
:class:`SimGraspRecord` read it back (a suite's ``results.jsonl``, ``ogcp evaluate -o``), so
no other module spells its keys. Reading is lenient: a key that is missing or of the wrong
type reads as None, an empty value or NaN, so partial and hand-written records still read.

``ogcp.sim/2`` differs from ``ogcp.sim/1`` in one meaning: the tips start on the simulated
collision surface, so ``predicted`` (and ``fidelity``, measured against it) is the analytic
limit of the *realized* contacts; the planned contacts' prediction is ``predicted_planned``.
Added: ``realized`` (per finger point, normal, offset; realized Q1 and its change) and
``collision`` (the collision surface's offset from the mesh at each contact). In a
``/1`` record the tips started at the planned contacts, so ``predicted`` there is both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

SIM_SCHEMA = "ogcp.sim/2"
#: The schemas :class:`SimRecord` reads.
SIM_SCHEMAS = ("ogcp.sim/1", SIM_SCHEMA)


def _json(value: Any) -> Any:
    """NaN/inf -> None, numpy -> Python, recursively."""
    if isinstance(value, dict):
        return {k: _json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    return value


@dataclass(frozen=True, eq=False)
class GraspSimResult:
    """Simulated resistance of one grasp.

    Attributes:
        grasp: Contact indices into the contact set.
        label: Where the grasp came from (``best``, ``hfts-run-3``, ``random-7``, ...).
        q1: Ferrari-Canny Q1 of the grasp [-].
        directions: Disturbance directions (scaled wrench space), shape (D, 6).
        direction_labels: Their labels, length D.
        predicted: Analytic resistance of the same actuation model at the realized contacts,
            shape (D,) [N].
        measured: Load at which the object moved beyond the thresholds, shape (D,) [-]; for
            censored directions the ramp's final load (a lower bound); NaN when not simulated.
        censored: Directions where the object never moved before the ramp ended, shape (D,).
        fidelity: ``|measured / predicted - 1|`` per direction, shape (D,); NaN where the
            prediction is ~0 or the direction is censored.
        gates: Validity gates of the preload (``valid`` summarises them).
        normal_forces: Tip normal forces after settling, shape (m,) [N].
        surface_distance: Distance of each planned contact from the decomposed surface, shape (m,) [m].
        hold_tests: Pass/fail of constant-load tests: ``weight``, and ``dexgraspbench`` (per axis
            ``passed``, ``delta_pos`` [m], ``delta_angle`` [deg], ``success``, ``failures``; see
            :func:`ogcp.sim_eval.protocols.dexgraspbench.hold_test`).
        error: Why the grasp could not be simulated, if it could not.
        unreachable: Fingers (positions in ``grasp``) whose contact the simulated fingertip
            cannot touch without cutting the object; such a grasp is not simulated.
        invalid_reasons: Each failed validity gate in JSON form (gate, finger, value, limit,
            unit, message; see :mod:`ogcp.sim_eval.protocols.gates`); empty for a valid grasp.
        predicted_planned: Analytic resistance at the planned contacts, shape (D,) [N].
        realized: The contacts the tips start on (``points``, ``normals``, ``offsets`` [m] from
            the plan, ``normal_angles`` [deg], ``travel`` [m]) and their ``q1`` and ``q1_change``
            (relative to the planned Q1); empty when not simulated.
        collision: The decomposition the grasp ran on (``threshold``, ``hull_count``) and the
            collision surface's ``offsets`` [m] from the mesh along each contact normal,
            ``tolerance``, ``within_tolerance``, ``tried`` and a ``note`` when it was not met.
        hand: For a grasp tested with a hand (empty for fingertips): ``name``,
            ``descriptor_sha256``, ``finger_contacts``, ``fit`` (realised, reason, residuals),
            ``fit_residuals`` [m] per finger, ``joint_angles`` (the fit's), ``settled_joint_angles``,
            the palm pose, ``pregrasp``, ``squeeze``, and ``extra_contacts`` (other links' contacts:
            link and force [N]).
    """

    grasp: tuple[int, ...]
    label: str
    q1: float
    directions: NDArray[np.float64]
    direction_labels: tuple[str, ...]
    predicted: NDArray[np.float64]
    measured: NDArray[np.float64]
    censored: NDArray[np.bool_]
    fidelity: NDArray[np.float64]
    gates: dict[str, Any]
    normal_forces: NDArray[np.float64]
    surface_distance: NDArray[np.float64]
    hold_tests: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    unreachable: tuple[int, ...] = ()
    invalid_reasons: tuple[dict[str, Any], ...] = ()
    predicted_planned: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    realized: dict[str, Any] = field(default_factory=dict)
    collision: dict[str, Any] = field(default_factory=dict)
    hand: dict[str, Any] = field(default_factory=dict)

    @property
    def valid(self) -> bool:
        """Simulated without error and every preload gate passed."""
        return self.error is None and bool(self.gates.get("valid", False))

    @property
    def measured_min(self) -> float:
        """Smallest measured resistance over the directions [N] (NaN if not simulated)."""
        finite = self.measured[np.isfinite(self.measured)]
        return float(finite.min()) if len(finite) == len(self.measured) and len(finite) else math.nan

    @property
    def predicted_min(self) -> float:
        """Smallest predicted resistance over the directions [N]."""
        finite = self.predicted[np.isfinite(self.predicted)]
        return float(finite.min()) if len(finite) else math.nan

    @property
    def median_fidelity(self) -> float:
        """Median of the per-direction fidelity (NaN if none is defined)."""
        finite = self.fidelity[np.isfinite(self.fidelity)]
        return float(np.median(finite)) if len(finite) else math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return _json(
            {
                "grasp": list(self.grasp),
                "label": self.label,
                "q1": self.q1,
                "valid": self.valid,
                "error": self.error,
                "gates": self.gates,
                "normal_forces": self.normal_forces,
                "surface_distance": self.surface_distance,
                "directions": self.direction_labels,
                "direction_vectors": self.directions,
                "predicted": self.predicted,
                "measured": self.measured,
                "censored": self.censored,
                "fidelity": self.fidelity,
                "predicted_min": self.predicted_min,
                "measured_min": self.measured_min,
                "median_fidelity": self.median_fidelity,
                "hold_tests": self.hold_tests,
                "unreachable": list(self.unreachable),
                "invalid_reasons": list(self.invalid_reasons),
                "predicted_planned": self.predicted_planned,
                "realized": self.realized,
                "collision": self.collision,
                **({"hand": self.hand} if self.hand else {}),
            }
        )


@dataclass(frozen=True, eq=False)
class SimResult:
    """Simulation of a set of grasps on one object.

    Attributes:
        object: Description of the object (source record of the contact set).
        grasps: Per-grasp results.
        set_metrics: Correlations, AUC and median fidelity over the valid grasps.
        settings: Every simulation setting used.
        decomposition: Metadata of the convex decomposition.
        wall_seconds: Wall time of the evaluation [s].
        provenance: Versions, git commit, machine.
    """

    object: dict[str, Any]
    grasps: tuple[GraspSimResult, ...]
    set_metrics: dict[str, Any]
    settings: dict[str, Any]
    decomposition: dict[str, Any]
    wall_seconds: float
    provenance: dict[str, Any]

    def to_dict(self) -> dict[str, Any]:
        """JSON form, schema ``ogcp.sim/2``."""
        return _json(
            {
                "schema": SIM_SCHEMA,
                "object": self.object,
                "grasps": [g.to_dict() for g in self.grasps],
                "set_metrics": self.set_metrics,
                "median_fidelity": self.set_metrics.get("median_fidelity"),
                "settings": self.settings,
                "decomposition": self.decomposition,
                "wall_seconds": self.wall_seconds,
                "provenance": self.provenance,
            }
        )


def _number(value: Any) -> float | None:
    """A finite float, else None (JSON writes NaN as null; a bool is not a number)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def _floats(values: Any) -> NDArray[np.float64]:
    """A JSON list of numbers as a float array, NaN for nulls; empty for anything but a list."""
    if not isinstance(values, list):
        return np.zeros(0)
    return np.array([math.nan if _number(v) is None else float(v) for v in values], dtype=float)


def _mapping(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


@dataclass(frozen=True, eq=False)
class SimGraspRecord:
    """One grasp of an ``ogcp.sim/1`` or ``/2`` record, as read back; see :class:`GraspSimResult`.

    Attributes:
        label: Where the grasp came from (``"None"`` when the record has no label).
        grasp: Contact indices, or None when not recorded.
        q1: Ferrari-Canny Q1 [-], None when not finite.
        valid: Whether the preload passed every gate; None when not recorded.
        error: Why the grasp could not be simulated, if it could not.
        gates: Validity gates of the preload.
        normal_forces: Tip normal forces after settling, shape (m,) [N].
        surface_distance: Distance of each contact from the decomposed surface, shape (m,) [m].
        direction_labels: Labels of the disturbance directions, length D.
        directions: Disturbance directions (scaled wrench space), shape (D, 6).
        predicted: Analytic resistance per direction, shape (D,) [N]; NaN where null.
        measured: Measured resistance per direction, shape (D,) [N]; NaN where null.
        censored: Directions held to the end of the ramp, shape (D,).
        fidelity: ``|measured / predicted - 1|`` per direction, shape (D,); NaN where null.
        predicted_min: Smallest predicted resistance [N], None when undefined.
        measured_min: Smallest measured resistance [N], None unless every direction was measured.
        median_fidelity: Median per-direction fidelity, None when undefined.
        hold_tests: Pass/fail of the constant-load tests.
        unreachable: Fingers whose contact the fingertip cannot touch (empty in records
            made before this key).
        invalid_reasons: One line per failed validity gate: which finger, by how much, and
            what to change (empty for valid grasps and in records made before this key).
        predicted_planned: Analytic resistance at the planned contacts, shape (D,) [N]; in a
            ``/1`` record the tips started there, so it is ``predicted``.
        realized: Realized contacts and Q1 (empty in ``/1`` records).
        collision: Collision-surface offsets at the contacts (empty in ``/1`` records).
        hand: The hand block of a grasp tested with a hand (empty for fingertips and older records).
    """

    label: str
    grasp: tuple[int, ...] | None
    q1: float | None
    valid: bool | None
    error: str | None
    gates: dict[str, Any]
    normal_forces: NDArray[np.float64]
    surface_distance: NDArray[np.float64]
    direction_labels: tuple[str, ...]
    directions: NDArray[np.float64]
    predicted: NDArray[np.float64]
    measured: NDArray[np.float64]
    censored: NDArray[np.bool_]
    fidelity: NDArray[np.float64]
    predicted_min: float | None
    measured_min: float | None
    median_fidelity: float | None
    hold_tests: dict[str, Any]
    unreachable: tuple[int, ...] = ()
    invalid_reasons: tuple[str, ...] = ()
    predicted_planned: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    realized: dict[str, Any] = field(default_factory=dict)
    collision: dict[str, Any] = field(default_factory=dict)
    hand: dict[str, Any] = field(default_factory=dict)

    @property
    def q1_realized(self) -> float | None:
        """Q1 of the realized contacts [-] (None when not recorded)."""
        return _number(self.realized.get("q1"))

    @property
    def q1_change(self) -> float | None:
        """Relative change of Q1 from the planned to the realized contacts (None when not recorded)."""
        return _number(self.realized.get("q1_change"))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SimGraspRecord:
        """Read one entry of a record's ``grasps`` list (never raises for missing keys)."""
        grasp, labels, censored = data.get("grasp"), data.get("directions"), data.get("censored")
        valid, error, unreachable = data.get("valid"), data.get("error"), data.get("unreachable")
        try:
            directions = np.array(data.get("direction_vectors"), dtype=float).reshape(-1, 6)
        except (TypeError, ValueError):
            directions = np.zeros((0, 6))
        return cls(
            label=str(data.get("label")),
            grasp=tuple(int(i) for i in grasp) if isinstance(grasp, list) else None,
            q1=_number(data.get("q1")),
            valid=valid if isinstance(valid, bool) else None,
            error=None if error is None else str(error),
            gates=_mapping(data.get("gates")),
            normal_forces=_floats(data.get("normal_forces")),
            surface_distance=_floats(data.get("surface_distance")),
            direction_labels=tuple(str(v) for v in labels) if isinstance(labels, list) else (),
            directions=directions,
            predicted=_floats(data.get("predicted")),
            measured=_floats(data.get("measured")),
            censored=np.array([bool(v) for v in censored] if isinstance(censored, list) else [], dtype=bool),
            fidelity=_floats(data.get("fidelity")),
            predicted_min=_number(data.get("predicted_min")),
            measured_min=_number(data.get("measured_min")),
            median_fidelity=_number(data.get("median_fidelity")),
            hold_tests=_mapping(data.get("hold_tests")),
            unreachable=tuple(int(i) for i in unreachable if _number(i) is not None)
            if isinstance(unreachable, list)
            else (),
            invalid_reasons=_messages(data.get("invalid_reasons")),
            predicted_planned=_floats(data.get("predicted_planned", data.get("predicted"))),
            realized=_mapping(data.get("realized")),
            collision=_mapping(data.get("collision")),
            hand=_mapping(data.get("hand")),
        )


@dataclass(frozen=True, eq=False)
class SimRecord:
    """An ``ogcp.sim/1`` or ``ogcp.sim/2`` record, as read back; see :class:`SimResult`.

    Attributes:
        schema: The record's ``schema`` (None when absent; not checked, so that partial
            records read).
        object: Description of the object.
        grasps: Per-grasp results (entries that are not JSON objects are skipped).
        set_metrics: Correlations, AUC, holding load and median fidelity over the valid grasps.
        settings: Every simulation setting used.
        decomposition: Metadata of the convex decomposition.
        wall_seconds: Wall time of the evaluation [s], None when not recorded.
        provenance: Versions, git commit, machine.
    """

    schema: str | None
    object: dict[str, Any]
    grasps: tuple[SimGraspRecord, ...]
    set_metrics: dict[str, Any]
    settings: dict[str, Any]
    decomposition: dict[str, Any]
    wall_seconds: float | None
    provenance: dict[str, Any]

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SimRecord:
        """Read an ``ogcp.sim/1`` or ``/2`` record (never raises for missing keys)."""
        grasps = data.get("grasps")
        schema = data.get("schema")
        return cls(
            schema=schema if isinstance(schema, str) else None,
            object=_mapping(data.get("object")),
            grasps=tuple(SimGraspRecord.from_dict(g) for g in grasps if isinstance(g, dict))
            if isinstance(grasps, list)
            else (),
            set_metrics=_mapping(data.get("set_metrics")),
            settings=_mapping(data.get("settings")),
            decomposition=_mapping(data.get("decomposition")),
            wall_seconds=_number(data.get("wall_seconds")),
            provenance=_mapping(data.get("provenance")),
        )


def _messages(value: Any) -> tuple[str, ...]:
    """The ``message`` of each ``invalid_reasons`` entry that has one."""
    if not isinstance(value, list):
        return ()
    return tuple(str(v["message"]) for v in value if isinstance(v, dict) and isinstance(v.get("message"), str))
