"""Simulation results and their versioned JSON form (schema ``ogcp.sim/1``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

SIM_SCHEMA = "ogcp.sim/1"


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
        q1: Ferrari-Canny Q1 of the grasp [N].
        directions: Disturbance directions (scaled wrench space), shape (D, 6).
        direction_labels: Their labels, length D.
        predicted: Analytic resistance of the same actuation model, shape (D,) [N].
        measured: Load at which the object moved beyond the thresholds, shape (D,) [N]; for
            censored directions the ramp's final load (a lower bound); NaN when not simulated.
        censored: Directions where the object never moved before the ramp ended, shape (D,).
        fidelity: ``|measured / predicted - 1|`` per direction, shape (D,); NaN where the
            prediction is ~0 or the direction is censored.
        gates: Validity gates of the preload (``valid`` summarises them).
        normal_forces: Tip normal forces after settling, shape (m,) [N].
        surface_distance: Distance of each planned contact from the decomposed surface, shape (m,) [m].
        hold_tests: Pass/fail of constant-load tests (weight test, DexGraspBench mode).
        error: Why the grasp could not be simulated, if it could not.
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
        """JSON form, schema ``ogcp.sim/1``."""
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
