"""One grasp's simulated test: tips placed on the collision surface, preload, gates, ramps, hold tests.

The tips start where they touch the parts actually simulated (:func:`~ogcp.sim_eval.scene.collision.place_tips`),
never inside them. What they touch there are the *realized* contacts: the prediction the
measurement is compared with, the ramp's targets and Q1's weakest direction all come from them,
and the planned contacts' Q1 and prediction are reported next to them, so that the share of the
analytic quality that survives contact with the geometry is a number in the result.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.quality import Q1Certificate, q1_certificate
from ogcp.sim_eval.decomposition.ladder import ContactFit
from ogcp.sim_eval.protocols.dexgraspbench import PROTOCOL, hold_test, physics_settings, use_object_defaults
from ogcp.sim_eval.protocols.directions import direction_set
from ogcp.sim_eval.protocols.gates import GateFailure, gate_failures, not_in_force_closure
from ogcp.sim_eval.protocols.metrics import fidelity
from ogcp.sim_eval.protocols.phases import Settled, hold_trials, ramp_trials, settle
from ogcp.sim_eval.protocols.predict import predicted_resistance
from ogcp.sim_eval.result import GraspSimResult
from ogcp.sim_eval.scene.collision import TipPlacement, place_tips
from ogcp.sim_eval.scene.grasp_scene import GRAVITY, GraspScene, build_scene
from ogcp.sim_eval.settings import SimSettings

#: DexGraspBench's test at commit 1e7a5a6 (load, limits, friction, step; see ogcp.sim_eval.protocols.dexgraspbench).
DEXGRASPBENCH = PROTOCOL.constants()
WEIGHT_TEST_DURATION = 2.0  # [s]
FIDELITY_FLOOR = 1e-3  # predictions below this fraction of F_max have no fidelity


@dataclasses.dataclass(frozen=True, eq=False)
class ObjectBody:
    """What every grasp on one object shares.

    Attributes:
        com: Centre of mass, shape (3,) [m].
        inertia: Inertia about the COM, shape (3, 3) [kg·m²].
        tip_radius: Fingertip radius [m].
        diagonal: Bounding-box diagonal [m].
    """

    com: NDArray[np.float64]
    inertia: NDArray[np.float64]
    tip_radius: float
    diagonal: float


def _axis_loads(magnitude: float) -> tuple[NDArray[np.float64], list[str]]:
    loads = np.zeros((6, 6))
    labels = []
    for k, (axis, sign) in enumerate((a, s) for a in range(3) for s in (1.0, -1.0)):
        loads[k, axis] = sign * magnitude
        labels.append(f"{'+' if sign > 0 else '-'}{'xyz'[axis]}")
    return loads, labels


def realized_summary(
    placement: TipPlacement,
    q1_planned: float,
    q1_realized: float,
    settled: Settled | None = None,
    scene: GraspScene | None = None,
) -> dict[str, Any]:
    """The ``realized`` entry of a simulated grasp: per finger point, normal and offset from the plan.

    With the settled state and its scene it also holds ``settled_centres``: each fingertip sphere's
    centre after preload and settling, in the object's frame (shape (m, 3) [m]), the tips as the
    disturbance trials start from them (absent when settling diverged).
    """
    change = (q1_realized - q1_planned) / q1_planned if q1_planned > 0 else None
    summary: dict[str, Any] = {
        "points": placement.points.tolist(),
        "normals": placement.normals.tolist(),
        "offsets": placement.offsets.tolist(),
        "normal_angles": placement.normal_angles.tolist(),
        "travel": placement.travel.tolist(),
        "q1": q1_realized,
        "q1_change": change,
    }
    centres = settled.tip_centres(scene) if settled is not None and scene is not None else None
    if centres is not None:
        summary["settled_centres"] = centres.tolist()
    return summary


def _lost_tips(placement: TipPlacement, max_inward: float) -> str:
    fingers = ", ".join(str(f) for f in np.flatnonzero(~placement.placed))
    return (
        f"finger(s) {fingers}: no collision part within {max_inward * 1e3:.3g} mm beyond the planned contact "
        f"along its normal (the decomposition lost that region of the mesh); try a smaller --threshold"
    )


def contact_torsion(contacts: ContactSet, settings: SimSettings) -> float:
    """Torsional friction coefficient of the simulated contacts [m]: 0 = hard fingers (condim 3).

    The settings' override, else the protocol's (DexGraspBench's condim 4), else the contact
    set's own model.
    """
    if settings.torsional_friction is not None:
        return float(settings.torsional_friction)
    if settings.protocol == "dexgraspbench":
        return float(DEXGRASPBENCH["torsional_friction"])
    return contacts.torsional_friction


def simulate_grasp(
    contacts: ContactSet,
    grasp: tuple[int, ...],
    label: str,
    fit: ContactFit,
    body: ObjectBody,
    settings: SimSettings,
) -> GraspSimResult:
    """Simulate one grasp on the parts of ``fit``.

    Args:
        contacts: The contact set the grasp indexes.
        grasp: Contact indices, length m.
        label: Where the grasp came from.
        fit: The decomposition chosen for this grasp and its offsets at the contacts.
        body: Mass properties, tip radius and size of the object.
        settings: Simulation settings, lengths already scaled to the object.

    Returns:
        The grasp's result; an error result when a tip finds no collision surface.
    """
    idx = np.asarray(grasp, dtype=np.intp)
    positions, normals = contacts.positions[idx], contacts.normals[idx]
    compat = settings.protocol == "dexgraspbench"
    if compat:
        # Their 4 ms step, solver and hand contact parameters (absolute lengths, like theirs).
        settings = physics_settings(settings)
    mu = settings.mu if settings.mu is not None else (DEXGRASPBENCH["mu"] if compat else contacts.mu)
    torsion = contact_torsion(contacts, settings)
    planned = q1_certificate(contacts.subset_wrenches(idx))
    collision = {**fit.to_dict(), "note": fit.note(body.diagonal)}
    placement = place_tips(fit.surface, positions, normals, body.tip_radius, max_inward=body.tip_radius)
    if not placement.placed.all():
        failed = failed_result(contacts, grasp, label, _lost_tips(placement, body.tip_radius), "")
        return dataclasses.replace(failed, collision=collision)
    realized = dataclasses.replace(contacts, positions=placement.points, normals=placement.normals, source={})
    achieved = q1_certificate(realized.wrenches.reshape(-1, 6))
    weakest = _weakest(achieved, planned)
    dirs = direction_set(settings.directions, settings.direction_seed, weakest)

    def predict(at: NDArray[np.float64], inward: NDArray[np.float64]) -> NDArray[np.float64]:
        return predicted_resistance(
            at,
            inward,
            contacts.com,
            contacts.torque_scale,
            mu,
            settings.prediction_cone_edges,
            settings.max_normal_force,
            dirs.vectors,
            torsion,
        ).resistance

    predicted = predict(placement.points, placement.normals)
    args = (fit.decomposition.parts, body.com, body.inertia, placement.points, placement.normals, settings, mu)
    scene = build_scene(*args, body.tip_radius, torsion=torsion)
    if compat:
        use_object_defaults(scene)
    settled = settle(scene, settings)
    nan = np.full(len(predicted), math.nan)
    measured, censored, fid = nan.copy(), np.zeros(len(predicted), dtype=bool), nan.copy()
    holds: dict[str, Any] = {}
    if compat:
        # Every grasp gets DexGraspBench's verdict, a diverged or gated one too (a failure).
        holds["dexgraspbench"] = _dexgraspbench(scene, settled, settings)
    if not settled.gates["diverged"]:
        if not compat:
            measured, censored = ramp_to_failure(
                scene, settled, dirs.vectors, predicted, contacts.torque_scale, settings
            )
            fid = fidelity(measured, predicted, FIDELITY_FLOOR * settings.max_normal_force)
            fid[censored] = math.nan
        if settings.weight_test:
            weightless = build_scene(*args, body.tip_radius, gravity=False, torsion=torsion)
            if compat:
                use_object_defaults(weightless)
            holds["weight"] = weight_test(weightless, settings)
    return GraspSimResult(
        grasp,
        label,
        planned.q1,
        dirs.vectors,
        tuple(dirs.labels),
        predicted,
        measured,
        censored,
        fid,
        dict(settled.gates),
        settled.normal_forces,
        fit.surface.signed_distance(positions, nearest=False)[0],
        holds,
        invalid_reasons=tuple(f.to_dict() for f in _reasons(settled, settings, achieved)),
        predicted_planned=predict(positions, normals),
        realized=realized_summary(placement, planned.q1, achieved.q1, settled, scene),
        collision=collision,
    )


def _reasons(settled: Settled, settings: SimSettings, achieved: Q1Certificate) -> list[GateFailure]:
    failures = list(gate_failures(settled.gates, settled.normal_forces, settings))
    if failures and not achieved.force_closure:
        failures.insert(0, not_in_force_closure(achieved.q1))
    return failures


def _weakest(achieved: Q1Certificate, planned: Q1Certificate) -> NDArray[np.float64] | None:
    """Q1's weakest direction of the simulated grasp (of the planned one if the realized is not in closure)."""
    if achieved.force_closure:
        return achieved.direction
    return planned.direction if planned.force_closure else None


def ramp_to_failure(
    scene: GraspScene,
    settled: Settled,
    directions: NDArray[np.float64],
    predicted: NDArray[np.float64],
    torque_scale: float,
    settings: SimSettings,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Each direction's ramp reaches its prediction after ``ramp_time`` (a floor keeps ~0 ones moving)."""
    finite = np.where(np.isfinite(predicted), predicted, 0.0)
    floor = settings.min_ramp_fraction * max(float(finite.max()), settings.holding_load)
    targets = np.maximum(finite, floor)
    trials = ramp_trials(
        scene,
        settled,
        directions,
        targets / settings.ramp_time,
        settings.ramp_extent * settings.ramp_time,
        torque_scale,
        settings,
    )
    measured = np.where(trials.diverged, math.nan, trials.failure_load)
    return measured, ~trials.failed


def _dexgraspbench(scene: GraspScene, settled: Settled, settings: SimSettings) -> dict[str, Any]:
    """DexGraspBench's verdict (:func:`ogcp.sim_eval.protocols.dexgraspbench.hold_test`): their six loads from the initial pose."""
    return hold_test(scene, settled, settings)


def weight_test(scene: GraspScene, settings: SimSettings) -> dict[str, Any]:
    """Weight m g along the six force axes: gravity off, the weight applied as an external force."""
    settled = settle(scene, settings)
    loads, labels = _axis_loads(settings.object_mass * GRAVITY)
    passed = hold_trials(
        scene, settled, loads, WEIGHT_TEST_DURATION, settings.move_threshold, settings.rotation_threshold, settings
    )
    return {
        "axes": labels,
        "passed": passed.tolist(),
        "success": bool(passed.all()),
        "load": settings.object_mass * GRAVITY,
    }


def failed_result(contacts: ContactSet, grasp: tuple[int, ...], label: str, error: str, trace: str) -> GraspSimResult:
    """The result of a grasp that could not be simulated (its planned Q1 and the reason)."""
    empty = np.zeros(0)
    q1 = q1_certificate(contacts.subset_wrenches(np.asarray(grasp, dtype=np.intp))).q1
    return GraspSimResult(
        grasp,
        label,
        q1,
        np.zeros((0, 6)),
        (),
        empty,
        empty,
        np.zeros(0, dtype=bool),
        empty,
        {"valid": False, "traceback": trace},
        empty,
        empty,
        {},
        error,
    )
