"""One grasp tested with a real hand: fitted, closed by its servos, settled, gated, ramped to failure.

The pads aim at the realised contacts, the points where pads of their rounding touch the parts
actually simulated (:func:`ogcp.sim_eval.scene.collision.place_tips`), as fingertips do. The hand is
fitted there from the reachability model's nearest samples (:mod:`ogcp.sim_eval.hand.fit`); a
grasp it cannot realise is recorded as unreachable with the finger and its residual, or the link
and its depth, and not simulated. A realised one is closed (:mod:`ogcp.sim_eval.hand.scene`) with
the strongest balanced grip of :data:`~ogcp.sim_eval.hand.scene.SQUEEZE_LADDER` that settles
steadily, and gated by the fingertip protocol, with one more gate: each chosen pad must press on
the object with a patch that passes within :data:`~ogcp.sim_eval.hand.pads.PAD_REACH_RADII` pad
radii of its contact (:mod:`ogcp.sim_eval.hand.pads`).
Contacts of other links are kept in the record (``hand.extra_contacts``), never hidden. The prediction is the same hand's
(:mod:`ogcp.sim_eval.hand.predict`): its realised contacts, friction and actuator limits.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.quality import q1_certificate
from ogcp.sim_eval.decomposition.ladder import ContactFit
from ogcp.sim_eval.hand.fit import HandFit, measure_pose, tolerance_scale
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.given import GIVEN_MAX_PENETRATION, GivenPose, given_scene
from ogcp.sim_eval.hand.lean import failure_reach, lean_scene
from ogcp.sim_eval.hand.pads import pad_gate, pad_off_contact
from ogcp.sim_eval.hand.predict import hand_resistance, realised_contacts
from ogcp.sim_eval.hand.scene import SQUEEZE_LADDER, HandScene, build_hand_scene, close_hand, squeezed
from ogcp.sim_eval.hand.setup import HandSetup, SqueezeCheck, fit_grasp
from ogcp.sim_eval.hand.squeeze import take_up_slack
from ogcp.sim_eval.protocols.dexgraspbench import hold_test, physics_settings, use_object_defaults
from ogcp.sim_eval.protocols.directions import direction_set
from ogcp.sim_eval.protocols.gates import gate_failures, not_in_force_closure
from ogcp.sim_eval.protocols.metrics import fidelity
from ogcp.sim_eval.protocols.phases import FULL_STATE, Settled, settle
from ogcp.sim_eval.protocols.trial import (
    DEXGRASPBENCH,
    FIDELITY_FLOOR,
    ObjectBody,
    failed_result,
    ramp_to_failure,
    realized_summary,
    weight_test,
)
from ogcp.sim_eval.result import GraspSimResult
from ogcp.sim_eval.scene.collision import TipPlacement, place_tips
from ogcp.sim_eval.settings import SimSettings


@dataclasses.dataclass(frozen=True, eq=False)
class ClosedGrasp:
    """A hand closed on one grasp and settled: what the protocol tests, and what a picture shows.

    Attributes:
        closed: The compiled scene with the hand closed by the chosen squeeze.
        settled: The settled state and its gates.
        share: The share of the balanced grip that settled (1.0 where there is no ladder).
        posed: The fit (or the given pose, measured).
        order: Contact index (into the grasp) each chosen finger takes, in finger order.
        placement: Where pads of the hand's rounding touch the simulated parts, per contact.
        points: The pads' targets in finger order, shape (m, 3) [m].
        settings: The settings the trial ran with (DexGraspBench's physics in that mode).
        mu: The friction coefficient simulated.
        hand: The record's ``hand`` block so far (descriptor, fit, ``seconds``).
    """

    closed: HandScene
    settled: Settled
    share: float
    posed: HandFit
    order: tuple[int, ...]
    placement: TipPlacement
    points: NDArray[np.float64]
    settings: SimSettings
    mu: float
    hand: dict[str, Any]


def close_on_grasp(
    contacts: ContactSet,
    grasp: tuple[int, ...],
    label: str,
    fit: ContactFit,
    body: ObjectBody,
    settings: SimSettings,
    setup: HandSetup,
    mu: float,
    torsion: float,
    given: GivenPose | None = None,
) -> ClosedGrasp | GraspSimResult:
    """Fit the hand to one grasp, close it and settle: the trial before its protocol.

    Takes the arguments of :func:`simulate_hand_grasp`.

    Returns:
        The closed, settled hand; or, for a grasp the hand cannot realise (or a given pose inside
        the object), the trial's result, with ``error`` and ``hand.fit`` saying why.
    """
    kinematics = setup.kinematics
    compat = settings.protocol == "dexgraspbench"
    if compat:  # their step, solver and hand contacts; their friction unless one was asked for
        settings = physics_settings(settings)
        mu = settings.mu if settings.mu is not None else float(DEXGRASPBENCH["mu"])
    started = time.perf_counter()
    placement, points, inward = _targets(contacts, grasp, fit, setup)
    parts = fit.decomposition.parts
    if given is None:
        posed, order = fit_to_contacts(contacts, grasp, fit, body, settings, setup, mu, (points, inward))
    else:
        around = FitScene(kinematics, parts, tolerance_scale(body.diagonal))
        pose = (given.grasp.joint_angles, given.grasp.rotation, given.grasp.translation)
        posed = measure_pose(around, given.fingers, points, inward, pose)
        order = tuple(range(len(grasp)))
    hand: dict[str, Any] = {
        **kinematics.descriptor.to_dict(),
        "finger_contacts": [grasp[i] for i in order],
        "fit": posed.to_dict(kinematics.joint_names),
    }
    hand["fit_residuals"] = hand["fit"]["fit_residuals"]
    hand["joint_angles"] = hand["fit"]["joint_angles"]
    seconds = {"fit": time.perf_counter() - started}
    hand["seconds"] = seconds  # [s] wall time of each phase: where a hand trial's cost goes
    if given is not None:
        hand["given"] = {"pregrasp": given.pregrasp is not None, "squeeze": given.squeeze is not None}
        if posed.penetration > GIVEN_MAX_PENETRATION:
            reason = f"the given pose puts link {posed.worst_link} {posed.penetration * 1e3:.1f} mm inside the object"
            failed = failed_result(contacts, grasp, label, reason, "")
            return dataclasses.replace(failed, gates={"valid": False, "reachable": False}, hand=hand)
    elif not posed.realised:
        reason = f"unreachable for the {kinematics.descriptor.name} hand: {posed.reason}"
        failed = failed_result(contacts, grasp, label, reason, "")
        return dataclasses.replace(failed, gates={"valid": False, "reachable": False}, hand=hand)
    ordered_points, ordered_normals = points[list(order)], inward[list(order)]
    scene_args = (kinematics, posed, ordered_points, ordered_normals, parts, body.com, body.inertia, settings, mu)
    own_approach = given is None or given.pregrasp is None  # a given pregrasp replaces ogcp's approach
    opened = build_hand_scene(*scene_args, contacts.torque_scale, torsion, approach=own_approach)
    if given is not None:
        opened = given_scene(opened, given)
    if compat:
        use_object_defaults(opened.scene)  # in the compiled model, which every share shares
    # The strongest balanced grip that settles steadily; DexGraspBench closes once, to its squeeze.
    ladder = SQUEEZE_LADDER if opened.grip is not None and not compat else (1.0,)
    for share in ladder:
        closed = close_hand(squeezed(opened, share), steady_object=not compat)
        settled = settle(closed.scene, settings)
        if settled.gates["valid"]:
            break
    if not compat and not settled.gates["diverged"]:
        data = _settled_data(closed, settled)
        taken = take_up_slack(closed.scene.model, data, closed.scene.preload_ctrl)
        closed = dataclasses.replace(closed, scene=dataclasses.replace(closed.scene, preload_ctrl=taken))
    seconds["close"] = time.perf_counter() - started - seconds["fit"]
    return ClosedGrasp(closed, settled, share, posed, order, placement, ordered_points, settings, mu, hand)


def _targets(
    contacts: ContactSet, grasp: tuple[int, ...], fit: ContactFit, setup: HandSetup
) -> tuple[TipPlacement, NDArray[np.float64], NDArray[np.float64]]:
    """Where pads of the hand's rounding touch the simulated parts, and the pads' targets, (m, 3) each."""
    idx = np.asarray(grasp, dtype=np.intp)
    positions, normals = contacts.positions[idx], contacts.normals[idx]
    radius = max(f.radius for f in setup.kinematics.fingers)
    placement = place_tips(fit.surface, positions, normals, radius, max_inward=radius)
    points = np.where(placement.placed[:, None], placement.points, positions)
    inward = np.where(placement.placed[:, None], placement.normals, normals)
    return placement, points, inward


def fit_to_contacts(
    contacts: ContactSet,
    grasp: tuple[int, ...],
    fit: ContactFit,
    body: ObjectBody,
    settings: SimSettings,
    setup: HandSetup,
    mu: float,
    targets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[HandFit, tuple[int, ...]]:
    """The hand fitted to one grasp as its trial fits it (:func:`close_on_grasp`), and the order in
    which the fingers take its contacts; nothing closed, nothing loaded. ``targets``: the pads'
    points and inward normals (m, 3) each where they are placed already; None: placed here."""
    points, inward = targets if targets is not None else _targets(contacts, grasp, fit, setup)[1:]
    around = FitScene(setup.kinematics, fit.decomposition.parts, tolerance_scale(body.diagonal))
    check = SqueezeCheck(body.com, contacts.torque_scale, mu, settings.max_normal_force)
    return fit_grasp(setup, around, contacts, grasp, points, inward, check)


def simulate_hand_grasp(
    contacts: ContactSet,
    grasp: tuple[int, ...],
    label: str,
    fit: ContactFit,
    body: ObjectBody,
    settings: SimSettings,
    setup: HandSetup,
    mu: float,
    torsion: float,
    given: GivenPose | None = None,
) -> GraspSimResult:
    """Fit, close and test the hand on one grasp.

    Args:
        contacts: The contact set the grasp indexes.
        grasp: Contact indices, length m.
        label: Where the grasp came from.
        fit: The decomposition chosen for the grasp (its parts are what collides).
        body: Mass properties and size of the object.
        settings: Simulation settings, lengths scaled to the object.
        setup: The hand.
        mu: Friction coefficient of hand-object contacts.
        torsion: Torsional friction [m]; 0: hard contacts.
        given: The hand as another planner posed it (not fitted; finger k takes contact k), or
            None: fitted here.

    Returns:
        The result; an unreachable grasp's has ``error`` and ``hand.fit`` saying why.
    """
    outcome = close_on_grasp(contacts, grasp, label, fit, body, settings, setup, mu, torsion, given)
    if isinstance(outcome, GraspSimResult):
        return outcome
    started = time.perf_counter()
    closed, settled, placement, hand = outcome.closed, outcome.settled, outcome.placement, outcome.hand
    settings, mu, posed = outcome.settings, outcome.mu, outcome.posed
    compat = settings.protocol == "dexgraspbench"
    idx = np.asarray(grasp, dtype=np.intp)
    positions = contacts.positions[idx]
    seconds = hand["seconds"]
    planned = q1_certificate(contacts.subset_wrenches(idx))
    moved = dataclasses.replace(contacts, positions=placement.points, normals=placement.normals, source={})
    achieved = q1_certificate(moved.wrenches.reshape(-1, 6))
    dirs = direction_set(
        settings.directions, settings.direction_seed, planned.direction if planned.force_closure else None
    )
    model = closed.scene.model
    data = _settled_data(closed, settled)
    realised = realised_contacts(model, data, closed.hand, closed.scene.object_geoms)
    predicted = hand_resistance(
        model,
        data,
        closed.hand,
        realised,
        body.com,
        contacts.torque_scale,
        mu,
        settings.prediction_cone_edges,
        dirs.vectors,
        travel=settings.move_threshold,  # the servos' stiffness bounds what they resist within it
        torsion=closed.scene.torsion,  # soft fingers twist, as simulated
    )
    pads = pad_gate(closed, realised, outcome.points, data)
    pads_ok, extra = pads.on, pads.extra
    gates = dict(settled.gates)
    gates["pads_on_contacts"] = pads_ok.tolist()
    gates["valid"] = bool(gates["valid"] and pads_ok.all())
    nan = np.full(len(predicted), math.nan)
    measured, censored, fid = nan.copy(), np.zeros(len(predicted), dtype=bool), nan.copy()
    holds: dict[str, Any] = {}
    # The loads run on the scene with the palm and the idle fingers welded where they settled.
    reach = failure_reach(settings.move_threshold, settings.rotation_threshold, body.diagonal)
    still = settings.creep_tolerance
    lean = lean_scene(closed, settled, reach, still) if not compat and not settled.gates["diverged"] else None
    if lean is not None:
        hand["protocol_scene"] = lean.summary
    if not settled.gates["diverged"] and settings.weight_test and not settings.gravity:
        loaded = lean.scene if lean is not None else closed.scene
        holds["weight"] = weight_test(loaded, settings)  # gravity is off: m g along each axis as a load
    if compat:  # their verdict, on ogcp's gates (the pads' one included); no ramps, as for tips
        holds["dexgraspbench"] = hold_test(closed.scene, dataclasses.replace(settled, gates=gates), settings)
    elif lean is not None:
        ramped = time.perf_counter()
        measured, censored = ramp_to_failure(
            lean.scene, lean.settled, dirs.vectors, predicted, contacts.torque_scale, settings
        )
        seconds["ramps"] = time.perf_counter() - ramped  # within "protocol": what no fit or closing can save
        fid = fidelity(measured, predicted, FIDELITY_FLOOR * settings.max_normal_force)
        fid[censored] = math.nan
    seconds["protocol"] = time.perf_counter() - started
    hand.update(
        {
            "extra_contacts": extra,
            "settled_joint_angles": data.qpos[closed.hand.qpos].tolist(),
            "palm_rotation": posed.rotation.tolist(),
            "palm_position": posed.translation.tolist(),
            "pregrasp": closed.pregrasp.tolist(),
            "squeeze_forces": closed.squeeze_forces.tolist(),
            "squeeze_share": outcome.share,
        }
    )
    reasons = list(gate_failures(settled.gates, settled.normal_forces, settings))
    lost = {r.finger for r in reasons if r.gate == "contact"}  # a finger that presses nothing is said once
    reasons += [
        pad_off_contact(int(k), float(pads.off[k]), float(pads.reach[k]))
        for k in np.flatnonzero(~pads_ok)
        if int(k) not in lost
    ]
    if reasons and not achieved.force_closure:  # the first thing to change, as for fingertips
        reasons.insert(0, not_in_force_closure(achieved.q1))
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
        gates,
        settled.normal_forces,
        fit.surface.signed_distance(positions, nearest=False)[0],
        holds,
        invalid_reasons=tuple(r.to_dict() for r in reasons),
        realized=realized_summary(placement, planned.q1, achieved.q1),
        collision={**fit.to_dict(), "note": fit.note(body.diagonal)},
        hand=hand,
    )


def _settled_data(closed: HandScene, settled: Settled) -> mujoco.MjData:
    model = closed.scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    data.ctrl[:] = closed.scene.preload_ctrl
    mujoco.mj_forward(model, data)
    return data
