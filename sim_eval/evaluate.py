"""Evaluate planned grasps in MuJoCo: measured resistance per direction against the analytic limit.

Typical use::

    from ogcp.planner import builtin_mesh, sample_contacts
    from ogcp.sim_eval import GraspEvaluator

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
from typing import TYPE_CHECKING, Any

import numpy as np
import trimesh
from tqdm.auto import tqdm

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.reach import REACH_TOLERANCE, default_tip_radius, reachable
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.provenance import provenance
from ogcp.sim_eval.decomposition.decompose import Decomposition, DecompositionSettings, decompose
from ogcp.sim_eval.decomposition.ladder import DecompositionLadder
from ogcp.sim_eval.protocols.dexgraspbench import set_summary
from ogcp.sim_eval.protocols.metrics import set_metrics
from ogcp.sim_eval.protocols.trial import ObjectBody, contact_torsion, failed_result, simulate_grasp
from ogcp.sim_eval.result import GraspSimResult, SimResult
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings, scaled_lengths

if TYPE_CHECKING:
    from ogcp.sim_eval.hand.fit_result import HandFit
    from ogcp.sim_eval.hand.given import GivenPose
    from ogcp.sim_eval.hand.setup import HandSetup


class GraspEvaluator:
    """Simulates grasps on one object and compares them with the analytic prediction.

    Args:
        settings: Simulation settings (default :class:`SimSettings`).
        decomposition: Convex decomposition settings (default CoACD with its defaults).
        cache: Decomposition cache folder (default ``$OGCP_CACHE/decompositions``).
        progress: Show progress bars on stderr.
        hand: Test the grasps with this hand instead of fingertip spheres
            (:class:`ogcp.sim_eval.hand.trial.HandSetup`); None: fingertips.
    """

    def __init__(
        self,
        settings: SimSettings | None = None,
        decomposition: DecompositionSettings | None = None,
        cache: str | Path | None = None,
        progress: bool = False,
        hand: HandSetup | None = None,
    ) -> None:
        self.settings = settings
        self.decomposition = decomposition
        self.cache = None if cache is None else Path(cache)
        self.progress = progress
        self.hand = hand

    def _object(
        self, mesh: trimesh.Trimesh, settings: SimSettings, parts: Decomposition | None
    ) -> tuple[ObjectBody, DecompositionLadder, Decomposition]:
        """The simulated object's body, the ladder of its decompositions and its first one."""
        diagonal = object_diagonal(mesh)
        decomposition = self.decomposition or DecompositionSettings()
        if parts is None:
            parts = decompose(mesh, decomposition, cache=self.cache, progress=self.progress)
        com, inertia = object_inertia(mesh, settings.body_mass)
        radius = tip_radius(mesh, settings)
        ladder = DecompositionLadder(mesh, decomposition, diagonal, radius, self.cache, self.progress, first=parts)
        return ObjectBody(com, inertia, radius, diagonal), ladder, parts

    def fit_hand(
        self, mesh: trimesh.Trimesh, contacts: ContactSet, grasp: Sequence[int], parts: Decomposition | None = None
    ) -> HandFit:
        """The hand fitted to one grasp as :meth:`evaluate` fits it before closing it: against the
        object's convex parts, from the nearest samples, where its servos can press (nothing simulated).

        Raises:
            OgcpError: Without a hand, or for a grasp that is not one of ``contacts``.
        """
        if self.hand is None:
            raise OgcpError("fitting a hand needs a hand (GraspEvaluator(hand=...))")
        chosen = tuple(int(i) for i in grasp)
        _check_grasp(chosen, contacts)
        from ogcp.sim_eval.hand.trial import fit_to_contacts

        settings = (self.settings or SimSettings()).scaled(object_diagonal(mesh))
        body, ladder, _ = self._object(mesh, settings, parts)
        idx = np.asarray(chosen, dtype=np.intp)
        fit = ladder.fit(contacts.positions[idx], contacts.normals[idx])
        mu = settings.mu if settings.mu is not None else contacts.mu
        return fit_to_contacts(contacts, chosen, fit, body, settings, self.hand, mu)[0]

    def evaluate(
        self,
        mesh: trimesh.Trimesh,
        contacts: ContactSet,
        grasps: Sequence[Sequence[int]],
        labels: Sequence[str] | None = None,
        parts: Decomposition | None = None,
        poses: Sequence[GivenPose | None] | None = None,
    ) -> SimResult:
        """Simulate every grasp.

        Args:
            mesh: The object's (watertight) mesh, in the contact set's coordinates [m].
            contacts: The contact set the grasps index.
            grasps: Grasps as contact indices, each of length m >= 2.
            labels: Optional label per grasp (default ``grasp-<i>``).
            parts: A decomposition to reuse (default: decomposed here, through the cache).
            poses: Per grasp, the hand as another planner posed it (not fitted), or None: fitted
                here; only with a hand.

        Returns:
            Per-grasp results and set-level metrics. A grasp that cannot be simulated gets its
            error recorded; the others go on. A grasp with a contact the fingertip cannot
            touch without cutting the object (contacts sampled without a tip, or for a
            smaller one) is reported as unreachable and not simulated: the tip would start
            inside the object, so the simulation would test another grasp.
        """
        given = self.settings or SimSettings()
        # One absolute value for everything below: the lengths scaled to this object's size.
        diagonal = object_diagonal(mesh)
        scale = given.length_scale(diagonal)
        settings = given.scaled(diagonal)
        start = time.perf_counter()
        chosen = [tuple(int(i) for i in g) for g in grasps]
        labels = list(labels) if labels is not None else [f"grasp-{i}" for i in range(len(chosen))]
        if len(labels) != len(chosen):
            raise OgcpError(f"got {len(labels)} labels for {len(chosen)} grasps")
        given_poses = list(poses) if poses is not None else [None] * len(chosen)
        if len(given_poses) != len(chosen) or (self.hand is None and any(p is not None for p in given_poses)):
            raise OgcpError(f"got {len(given_poses)} hand poses for {len(chosen)} grasps (poses need a hand)")
        for g in chosen:
            _check_grasp(g, contacts)
        body, ladder, parts = self._object(mesh, settings, parts)
        radius = body.tip_radius
        # A hand's fit decides what it reaches; the fingertip's own check is for spheres.
        unreachable = _unreachable_contacts(mesh, contacts, chosen, radius) if self.hand is None else set()
        results = []
        bar = tqdm(total=len(chosen), desc="simulate", unit="grasp", disable=not self.progress)
        for grasp, label, pose in zip(chosen, labels, given_poses, strict=True):
            fingers = tuple(f for f, i in enumerate(grasp) if i in unreachable)
            if fingers:
                results.append(_unreachable(contacts, grasp, label, fingers, radius))
                bar.update()
                continue
            try:
                idx = np.asarray(grasp, dtype=np.intp)
                fit = ladder.fit(contacts.positions[idx], contacts.normals[idx])
                if self.hand is None:
                    results.append(simulate_grasp(contacts, grasp, label, fit, body, settings))
                else:
                    from ogcp.sim_eval.hand.trial import simulate_hand_grasp

                    mu = settings.mu if settings.mu is not None else contacts.mu
                    torsion = contact_torsion(contacts, settings)
                    results.append(
                        simulate_hand_grasp(
                            contacts, grasp, label, fit, body, settings, self.hand, mu, torsion, given=pose
                        )
                    )
            except Exception as exc:  # noqa: BLE001 - one bad grasp must not sink the batch
                reason = " ".join(f"{type(exc).__name__}: {exc}".split())  # one line (MuJoCo's errors span two)
                results.append(failed_result(contacts, grasp, label, reason, traceback.format_exc(limit=3)))
            bar.update()
        bar.close()
        return SimResult(
            # rho turns the scaled torques of the torque directions into N·m for a reader.
            object={**contacts.source, "torque_scale": contacts.torque_scale},
            grasps=tuple(results),
            set_metrics=_set_level(results, settings, diagonal),
            settings={
                **given.to_dict(),
                # The scale and the absolute lengths it gave (given x length_scale).
                "length_scale": scale,
                "object_diagonal": diagonal,
                "scaled_lengths": scaled_lengths(settings),
                "decomposition": (self.decomposition or DecompositionSettings()).to_dict(),
                # What the simulation and the prediction used: Q1 keeps the contact set's own model.
                "contact_model": contact_model_record(contacts, settings),
                **({"hand": self.hand.kinematics.describe()} if self.hand is not None else {}),
            },
            decomposition=_decomposition_meta(parts, ladder),
            wall_seconds=time.perf_counter() - start,
            provenance=provenance(),
        )


def contact_model_record(contacts: ContactSet, settings: SimSettings) -> dict[str, Any]:
    """The contact models of a simulation: Q1's (the contact set's) and the simulated one.

    Returns:
        ``{"q1": "hard"|"soft", "q1_torsional_friction": [m], "simulated": ..., "simulated_torsional_friction": [m]}``.
    """
    simulated = contact_torsion(contacts, settings)
    return {
        "q1": contacts.contact_model,
        "q1_torsional_friction": contacts.torsional_friction,
        "simulated": "soft" if simulated > 0 else "hard",
        "simulated_torsional_friction": simulated,
    }


def object_diagonal(mesh: trimesh.Trimesh) -> float:
    """The object's bounding-box diagonal [m]: the size the simulation's lengths scale with."""
    return float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))


def tip_radius(mesh: trimesh.Trimesh, settings: SimSettings) -> float:
    """The simulated fingertip radius [m]: ``settings.tip_radius``, else the ratio x the object's diagonal."""
    return settings.tip_radius or default_tip_radius(mesh, settings.tip_radius_ratio)


def _decomposition_meta(first: Decomposition, ladder: DecompositionLadder) -> dict[str, Any]:
    """The coarsest decomposition's metadata, plus that of each finer level some grasp needed."""
    finer = [dict(parts.meta) for threshold, parts in sorted(ladder.used.items(), reverse=True) if parts is not first]
    return {**dict(first.meta), "refined": finer}


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
    result = failed_result(contacts, grasp, label, reason, "")
    gates = {"valid": False, "reachable": False, "tip_radius": radius}
    return dataclasses.replace(result, gates=gates, unreachable=fingers)


def _set_level(results: Sequence[GraspSimResult], settings: SimSettings, diagonal: float) -> dict[str, Any]:
    valid = [r for r in results if r.valid and np.all(np.isfinite(r.measured)) and len(r.measured)]
    simulated = [r for r in results if r.error is None]
    fidelities = [r.median_fidelity for r in valid if math.isfinite(r.median_fidelity)]
    metrics: dict[str, Any] = {
        "n_simulated": len(results),
        "n_valid": len(valid),
        "n_errors": sum(r.error is not None for r in results),
        "n_unreachable": sum(bool(r.unreachable) for r in results),
        "n_outside_collision_tolerance": sum(r.collision.get("within_tolerance") is False for r in results),
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
    if settings.protocol == "dexgraspbench":
        # That protocol measures no resistance (n_valid counts none): its own success rate and AUCs.
        metrics["dexgraspbench"] = set_summary(results)
    depths = [float(r.gates["initial_penetration"]) for r in simulated if "initial_penetration" in r.gates]
    metrics["max_initial_penetration"] = max(depths) if depths else None
    metrics["max_initial_penetration_ratio"] = max(depths) / diagonal if depths else None
    changes = [r.realized["q1_change"] for r in simulated if r.realized.get("q1_change") is not None]
    metrics["median_q1_change"] = float(np.median(changes)) if changes else None
    offsets = [o for r in simulated for o in r.realized.get("offsets", [])]
    metrics["median_realized_offset_ratio"] = float(np.median(offsets)) / diagonal if offsets else None
    return metrics


def evaluate_plan(
    record: dict[str, Any],
    settings: SimSettings | dict[str, Any] | None = None,
    decomposition: DecompositionSettings | dict[str, Any] | None = None,
    progress: bool = False,
    max_grasps: int | None = None,
    plan_file: str | Path | None = None,
    tips: bool = False,
) -> SimResult:
    """Simulate the grasps of an ``ogcp.plan/1`` record (best grasp, ES top grasps, HFTS runs).

    A plan made with a hand is tested with that hand (its descriptor, the fingers it chose),
    unless ``tips`` asks for fingertip spheres.

    Args:
        record: The plan record.
        settings: Simulation settings or a mapping of them (unknown keys are errors).
        decomposition: Decomposition settings or a mapping of them.
        progress: Show progress bars on stderr.
        max_grasps: Simulate at most this many of the plan's distinct grasps (best first), >= 1;
            None: all.
        plan_file: Where the record was read from: a mesh file is looked for next to it first
            (a plan moved together with its mesh still evaluates).
        tips: Test with fingertip spheres even when the plan has a hand.

    Returns:
        The simulation result.
    """
    from ogcp.sim_eval.inputs.plan_input import plan_input

    if max_grasps is not None and (isinstance(max_grasps, bool) or not isinstance(max_grasps, int) or max_grasps < 1):
        raise OgcpError(f"max_grasps must be an integer >= 1 or None, got {max_grasps!r}")
    if not isinstance(settings, SimSettings):
        settings = SimSettings.from_dict(settings)
    if decomposition is not None and not isinstance(decomposition, DecompositionSettings):
        decomposition = DecompositionSettings(**dict(decomposition))
    plan = plan_input(record, plan_file)
    grasps, labels = plan.grasps[:max_grasps], plan.labels[:max_grasps]
    hand = None if tips else plan_hand(record)
    evaluator = GraspEvaluator(settings, decomposition, progress=progress, hand=hand)
    return evaluator.evaluate(plan.mesh, plan.contacts, grasps, labels)


def _check_grasp(grasp: tuple[int, ...], contacts: ContactSet) -> None:
    """One line for a grasp that is not m >= 2 distinct contacts of ``contacts``."""
    if len(grasp) < 2 or min(grasp) < 0 or max(grasp) >= len(contacts) or len(set(grasp)) != len(grasp):
        raise OgcpError(f"grasp {list(grasp)} must hold >= 2 distinct indices in 0..{len(contacts) - 1}")


def plan_hand(record: dict[str, Any]) -> HandSetup | None:
    """The hand a plan was made for, compiled, with the fingers it chose; None for a plan without one.

    Raises:
        OgcpError: If the hand's descriptor is gone or changed since the plan (its sha256 differs).
    """
    from ogcp.planner.hands.kinematics import HandKinematics
    from ogcp.planner.hands.registry import resolve_hand
    from ogcp.planner.records.plan import PlanView
    from ogcp.sim_eval.hand.setup import HandSetup

    block = PlanView(record).hand
    if block is None:
        return None
    source = block.descriptor or block.name
    if source is None:
        raise OgcpError("the plan's hand block names no hand (no descriptor, no name)")
    descriptor = resolve_hand(source)
    if block.descriptor_sha256 is not None and descriptor.sha256 != block.descriptor_sha256:
        raise OgcpError(
            f"hand descriptor {descriptor.path} changed since the plan (sha256 {descriptor.sha256[:12]}, "
            f"the plan has {block.descriptor_sha256[:12]}); re-plan, or evaluate with --tips"
        )
    return HandSetup.of(HandKinematics(descriptor), block.fingers or None, block.samples)
