"""Evaluate planned grasps in MuJoCo: measured resistance per direction against the analytic limit.

Typical use::

    from planner import builtin_mesh, sample_contacts
    from sim_eval import GraspEvaluator

    mesh = builtin_mesh("box")
    contacts = sample_contacts(mesh, 200, seed=0)
    result = GraspEvaluator().evaluate(mesh, contacts, [(3, 57, 120)])
    print(result.grasps[0].measured_min, result.set_metrics)
"""

from __future__ import annotations

import dataclasses
import math
import time
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray
from tqdm.auto import tqdm

from planner.grasp.contact_set import ContactSet
from planner.grasp.quality import q1_certificate
from planner.grasp.reach import REACH_TOLERANCE, default_tip_radius, reachable
from planner.infra.errors import OgcpError
from planner.infra.provenance import provenance
from sim_eval.body import object_inertia, surface_distance
from sim_eval.decomposition.decompose import Decomposition, DecompositionSettings, decompose
from sim_eval.directions import direction_set
from sim_eval.gates import gate_failures
from sim_eval.metrics import fidelity, set_metrics
from sim_eval.predict import predicted_resistance
from sim_eval.protocol import hold_trials, ramp_trials, settle
from sim_eval.result import GraspSimResult, SimResult
from sim_eval.scene import GRAVITY, GraspScene, build_scene
from sim_eval.settings import SimSettings, scaled_lengths

DEXGRASPBENCH = {"load_per_kg": 10.0, "duration": 2.0, "move_limit": 0.05, "rotation_limit": 15.0, "mu": 0.6}
WEIGHT_TEST_DURATION = 2.0  # [s]
FIDELITY_FLOOR = 1e-3  # predictions below this fraction of F_max have no fidelity


def _axis_loads(magnitude: float) -> tuple[NDArray[np.float64], list[str]]:
    loads = np.zeros((6, 6))
    labels = []
    for k, (axis, sign) in enumerate((a, s) for a in range(3) for s in (1.0, -1.0)):
        loads[k, axis] = sign * magnitude
        labels.append(f"{'+' if sign > 0 else '-'}{'xyz'[axis]}")
    return loads, labels


class GraspEvaluator:
    """Simulates grasps on one object and compares them with the analytic prediction.

    Args:
        settings: Simulation settings (default :class:`SimSettings`).
        decomposition: Convex decomposition settings (default CoACD with its defaults).
        cache: Decomposition cache folder (default ``$OGCP_CACHE/decompositions``).
        progress: Show progress bars on stderr.
    """

    def __init__(
        self,
        settings: SimSettings | None = None,
        decomposition: DecompositionSettings | None = None,
        cache: str | Path | None = None,
        progress: bool = False,
    ) -> None:
        self.settings = settings
        self.decomposition = decomposition
        self.cache = None if cache is None else Path(cache)
        self.progress = progress

    def evaluate(
        self,
        mesh: trimesh.Trimesh,
        contacts: ContactSet,
        grasps: Sequence[Sequence[int]],
        labels: Sequence[str] | None = None,
        parts: Decomposition | None = None,
    ) -> SimResult:
        """Simulate every grasp.

        Args:
            mesh: The object's (watertight) mesh, in the contact set's coordinates [m].
            contacts: The contact set the grasps index.
            grasps: Grasps as contact indices, each of length m >= 2.
            labels: Optional label per grasp (default ``grasp-<i>``).
            parts: A decomposition to reuse (default: decomposed here, through the cache).

        Returns:
            Per-grasp results and set-level metrics. A grasp that cannot be simulated gets its
            error recorded; the others go on. A grasp with a contact the fingertip cannot
            touch without cutting the object (contacts sampled without a tip, or for a
            smaller one) is reported as unreachable and not simulated: the tip would start
            inside the object, so the simulation would test another grasp.
        """
        given = self.settings or SimSettings()
        # One absolute value for everything below: the lengths scaled to this object's size.
        scale = given.length_scale(object_diagonal(mesh))
        settings = given.scaled(object_diagonal(mesh))
        start = time.perf_counter()
        chosen = [tuple(int(i) for i in g) for g in grasps]
        labels = list(labels) if labels is not None else [f"grasp-{i}" for i in range(len(chosen))]
        if len(labels) != len(chosen):
            raise OgcpError(f"got {len(labels)} labels for {len(chosen)} grasps")
        for g in chosen:
            if len(g) < 2 or min(g) < 0 or max(g) >= len(contacts) or len(set(g)) != len(g):
                raise OgcpError(f"grasp {list(g)} must hold >= 2 distinct indices in 0..{len(contacts) - 1}")
        if parts is None:
            parts = decompose(mesh, self.decomposition, cache=self.cache, progress=self.progress)
        com, inertia = object_inertia(mesh, settings.object_mass)
        radius = tip_radius(mesh, settings)
        unreachable = _unreachable_contacts(mesh, contacts, chosen, radius)
        results = []
        bar = tqdm(total=len(chosen), desc="simulate", unit="grasp", disable=not self.progress)
        for grasp, label in zip(chosen, labels, strict=True):
            fingers = tuple(f for f, i in enumerate(grasp) if i in unreachable)
            if fingers:
                results.append(_unreachable(contacts, grasp, label, fingers, radius))
                bar.update()
                continue
            try:
                results.append(self._grasp(mesh, contacts, grasp, label, parts, com, inertia, settings))
            except Exception as exc:  # noqa: BLE001 - one bad grasp must not sink the batch
                results.append(
                    _failed(contacts, grasp, label, f"{type(exc).__name__}: {exc}", traceback.format_exc(limit=3))
                )
            bar.update()
        bar.close()
        return SimResult(
            object=dict(contacts.source),
            grasps=tuple(results),
            set_metrics=_set_level(results, settings),
            settings={
                **given.to_dict(),
                # The scale and the absolute lengths it gave (given x length_scale).
                "length_scale": scale,
                "scaled_lengths": scaled_lengths(settings),
                "decomposition": (self.decomposition or DecompositionSettings()).to_dict(),
            },
            decomposition=dict(parts.meta),
            wall_seconds=time.perf_counter() - start,
            provenance=provenance(),
        )

    def _grasp(
        self,
        mesh: trimesh.Trimesh,
        contacts: ContactSet,
        grasp: tuple[int, ...],
        label: str,
        parts: Decomposition,
        com: NDArray[np.float64],
        inertia: NDArray[np.float64],
        settings: SimSettings,
    ) -> GraspSimResult:
        idx = np.asarray(grasp, dtype=np.intp)
        positions, normals = contacts.positions[idx], contacts.normals[idx]
        compat = settings.protocol == "dexgraspbench"
        mu = settings.mu if settings.mu is not None else (DEXGRASPBENCH["mu"] if compat else contacts.mu)
        cert = q1_certificate(contacts.subset_wrenches(idx))
        dirs = direction_set(
            settings.directions, settings.direction_seed, cert.direction if cert.force_closure else None
        )
        predicted = predicted_resistance(
            positions,
            normals,
            contacts.com,
            contacts.torque_scale,
            mu,
            settings.prediction_cone_edges,
            settings.max_normal_force,
            dirs.vectors,
        ).resistance
        radius = tip_radius(mesh, settings)
        scene = build_scene(parts.parts, com, inertia, positions, normals, settings, mu, radius)
        settled = settle(scene, settings)
        distance = surface_distance(parts.parts, positions)
        nan = np.full(len(predicted), math.nan)
        measured, censored, fid = nan.copy(), np.zeros(len(predicted), dtype=bool), nan.copy()
        holds: dict[str, Any] = {}
        if not settled.gates["diverged"]:
            if compat:
                holds["dexgraspbench"] = self._dexgraspbench(scene, settled, settings)
            else:
                measured, censored = self._ramp(
                    scene, settled, dirs.vectors, predicted, contacts.torque_scale, settings
                )
                fid = fidelity(measured, predicted, FIDELITY_FLOOR * settings.max_normal_force)
                fid[censored] = math.nan
            if settings.weight_test:
                holds["weight"] = self._weight(parts, com, inertia, positions, normals, settings, mu, radius)
        return GraspSimResult(
            grasp,
            label,
            cert.q1,
            dirs.vectors,
            tuple(dirs.labels),
            predicted,
            measured,
            censored,
            fid,
            dict(settled.gates),
            settled.normal_forces,
            distance,
            holds,
            invalid_reasons=tuple(f.to_dict() for f in gate_failures(settled.gates, settled.normal_forces, settings)),
        )

    @staticmethod
    def _ramp(
        scene: GraspScene,
        settled: Any,
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

    @staticmethod
    def _dexgraspbench(scene: GraspScene, settled: Any, settings: SimSettings) -> dict[str, Any]:
        loads, labels = _axis_loads(DEXGRASPBENCH["load_per_kg"] * settings.object_mass)
        passed = hold_trials(
            scene,
            settled,
            loads,
            DEXGRASPBENCH["duration"],
            DEXGRASPBENCH["move_limit"],
            DEXGRASPBENCH["rotation_limit"],
            settings,
        )
        return {
            "axes": labels,
            "passed": passed.tolist(),
            "success": bool(passed.all()),
            "load": DEXGRASPBENCH["load_per_kg"] * settings.object_mass,
            **DEXGRASPBENCH,
        }

    @staticmethod
    def _weight(
        parts: Decomposition,
        com: NDArray[np.float64],
        inertia: NDArray[np.float64],
        positions: NDArray[np.float64],
        normals: NDArray[np.float64],
        settings: SimSettings,
        mu: float,
        radius: float,
    ) -> dict[str, Any]:
        """Weight m g along the six force axes: gravity off, the weight applied as an external force."""
        scene = build_scene(parts.parts, com, inertia, positions, normals, settings, mu, radius, gravity=False)
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


def object_diagonal(mesh: trimesh.Trimesh) -> float:
    """The object's bounding-box diagonal [m]: the size the simulation's lengths scale with."""
    return float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))


def tip_radius(mesh: trimesh.Trimesh, settings: SimSettings) -> float:
    """The simulated fingertip radius [m]: ``settings.tip_radius``, else the ratio x the object's diagonal."""
    return settings.tip_radius or default_tip_radius(mesh, settings.tip_radius_ratio)


def _unreachable_contacts(
    mesh: trimesh.Trimesh, contacts: ContactSet, grasps: Sequence[tuple[int, ...]], radius: float
) -> set[int]:
    """Contacts of the grasps that a fingertip of ``radius`` [m] cannot touch without cutting the object.

    A set sampled for this very tip and tolerance is reachable by construction, so it is not
    tested again; any other set (plain sampling, another tip, a contact file) is.
    """
    tolerance = REACH_TOLERANCE * radius
    if contacts.source.get("tip_radius") == radius and contacts.source.get("reach_tolerance") == tolerance:
        return set()
    used = np.array(sorted({i for g in grasps for i in g}), dtype=np.intp)
    if not len(used):
        return set()
    ok = reachable(mesh, contacts.positions[used], contacts.normals[used], radius, tolerance)
    return {int(i) for i in used[~ok]}


def _unreachable(
    contacts: ContactSet, grasp: tuple[int, ...], label: str, fingers: tuple[int, ...], radius: float
) -> GraspSimResult:
    """The result of a grasp that is not simulated because some of its contacts are unreachable."""
    where = "; ".join(
        f"finger {f} on contact {grasp[f]} at [{', '.join(f'{x:.4g}' for x in contacts.positions[grasp[f]])}] m"
        for f in fingers
    )
    reason = (
        f"unreachable contact: {where}: a fingertip of radius {radius:.4g} m touching there cuts the object; "
        f"re-plan with --tip-radius {radius:.4g} (the default), or evaluate with a smaller --tip-radius"
    )
    result = _failed(contacts, grasp, label, reason, "")
    gates = {"valid": False, "reachable": False, "tip_radius": radius}
    return dataclasses.replace(result, gates=gates, unreachable=fingers)


def _failed(contacts: ContactSet, grasp: tuple[int, ...], label: str, error: str, trace: str) -> GraspSimResult:
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


def _set_level(results: Sequence[GraspSimResult], settings: SimSettings) -> dict[str, Any]:
    valid = [r for r in results if r.valid and np.all(np.isfinite(r.measured)) and len(r.measured)]
    fidelities = [r.median_fidelity for r in valid if math.isfinite(r.median_fidelity)]
    metrics: dict[str, Any] = {
        "n_simulated": len(results),
        "n_valid": len(valid),
        "n_errors": sum(r.error is not None for r in results),
        "n_unreachable": sum(bool(r.unreachable) for r in results),
        "holding_load": settings.holding_load,
    }
    if valid:
        measured = np.array([r.measured_min for r in valid])
        metrics.update(
            set_metrics(
                [r.q1 for r in valid], [r.predicted_min for r in valid], measured, measured >= settings.holding_load
            )
        )
    metrics["median_fidelity"] = float(np.median(fidelities)) if fidelities else None
    return metrics


def evaluate_plan(
    record: dict[str, Any],
    settings: SimSettings | dict[str, Any] | None = None,
    decomposition: DecompositionSettings | dict[str, Any] | None = None,
    progress: bool = False,
    max_grasps: int | None = None,
) -> SimResult:
    """Simulate the grasps of an ``ogcp.plan/1`` record (best grasp, ES top grasps, HFTS runs).

    Args:
        record: The plan record.
        settings: Simulation settings or a mapping of them (unknown keys are errors).
        decomposition: Decomposition settings or a mapping of them.
        progress: Show progress bars on stderr.
        max_grasps: Simulate at most this many of the plan's distinct grasps (best first).

    Returns:
        The simulation result.
    """
    from sim_eval.plan_input import plan_input

    if not isinstance(settings, SimSettings):
        settings = SimSettings.from_dict(settings)
    if decomposition is not None and not isinstance(decomposition, DecompositionSettings):
        decomposition = DecompositionSettings(**dict(decomposition))
    plan = plan_input(record)
    grasps, labels = plan.grasps[:max_grasps], plan.labels[:max_grasps]
    evaluator = GraspEvaluator(settings, decomposition, progress=progress)
    return evaluator.evaluate(plan.mesh, plan.contacts, grasps, labels)
