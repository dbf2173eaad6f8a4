"""Analytic resistance of a closed hand: its realised contacts, friction, and its actuators' limits.

For fingertips (:mod:`ogcp.sim_eval.protocols.predict`) each finger's normal force is capped; a hand's
fingers are capped by its actuators instead, through its Jacobian. With the hand's realised
contacts k (point p_k on hand body b_k, inward normal n_k) and the friction cone linearised by the
planner's edges e_kj (normal component 1), a disturbance ``s d`` (``d`` a unit 6-vector in the
planner's scaled wrench space ``[force, torque / rho]``) is resisted when

    sum_kj lambda_kj w_kj + s d = 0                              (the object balances)
    sum_kj lambda_kj J_k^T e_kj = M^T u + E^T eta                 (the hand balances)
    lambda >= 0,  u_lo <= u <= u_hi

where ``J_k`` is the translational Jacobian of p_k on b_k over the hand's joints, ``M`` the
actuators' moment arms with their force ranges ``u``, and ``E`` the rows of the hand's
equalities, MuJoCo's own constraint rows (a coupled joint is held by its driver, a closed loop's
passive joints by the loop), with free multipliers ``eta``. The palm is
held by the weld and takes whatever it must. A position servo is also a spring, and so is a
MuJoCo joint limit: within the trial's failure distance a servo changes its force only so much
(:class:`~ogcp.sim_eval.hand.travel.ServoTravel` adds those rows around the settled forces) and a
resting stop pushes only so hard (:func:`~ogcp.sim_eval.hand.travel.stop_reach` bounds its
reaction), so a soft hand is predicted to resist what it builds before the object has moved that
far. The prediction is the largest ``s``: a linear program per
direction, the same meaning of "fidelity" as for fingertips.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from ogcp.planner.grasp.wrench import cone_edges, contact_wrenches
from ogcp.planner.hands.model_checks import equality_jacobian
from ogcp.sim_eval.hand.mount import MountedHand, in_subtree
from ogcp.sim_eval.hand.travel import ServoTravel, actuator_moments, stop_reach

_MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
#: A joint this close to a limit rests on it [rad or m] (past it too: MuJoCo's limits are soft).
AT_LIMIT = 1e-3
#: An equality row whose largest entry over the hand's joints is below this (relative) touches none.
EQUALITY_FLOOR = 1e-9


@dataclass(frozen=True, eq=False)
class RealisedContacts:
    """The hand's contacts with the object at one state.

    Attributes:
        points: Contact points, shape (K, 3) [m].
        normals: Inward unit normals (into the object), shape (K, 3).
        bodies: The hand body each contact is on, shape (K,).
        geoms: The hand geom, shape (K,).
        forces: Normal force of each, shape (K,) [N].
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    bodies: NDArray[np.intp]
    geoms: NDArray[np.intp]
    forces: NDArray[np.float64]


def realised_contacts(
    model: mujoco.MjModel, data: mujoco.MjData, hand: MountedHand, object_geoms: NDArray[np.intp]
) -> RealisedContacts:
    """The hand-object contacts of a state (after ``mj_forward``), each MuJoCo contact point its own.

    A flat pad touches at several points (a patch), which is what lets two pads resist a torque
    about the line between them; one point per pad would predict none.
    """
    objects = {int(g) for g in object_geoms}
    hand_geoms = {int(g) for g in hand.geoms}
    wrench = np.zeros(6)
    points, normals, bodies, geoms, forces = [], [], [], [], []
    for c in range(data.ncon):
        contact = data.contact[c]
        a, b = int(contact.geom1), int(contact.geom2)
        if not ((a in objects and b in hand_geoms) or (b in objects and a in hand_geoms)):
            continue
        mujoco.mj_contactForce(model, data, c, wrench)
        normal = contact.frame[:3].copy()  # from geom1 to geom2
        geom = b if a in objects else a
        points.append(contact.pos.copy())
        normals.append(-normal if a in objects else normal)  # from the hand into the object
        bodies.append(int(model.geom_bodyid[geom]))
        geoms.append(geom)
        forces.append(max(float(wrench[0]), 0.0))
    return RealisedContacts(
        np.array(points).reshape(-1, 3),
        np.array(normals).reshape(-1, 3),
        np.array(bodies, dtype=np.intp),
        np.array(geoms, dtype=np.intp),
        np.array(forces),
    )


def hand_resistance(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    hand: MountedHand,
    contacts: RealisedContacts,
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    cone_edge_count: int,
    directions: NDArray[np.float64],
    travel: float | None = None,
    torsion: float = 0.0,
) -> NDArray[np.float64]:
    """Largest resisted disturbance along each direction, shape (D,) [N in scaled wrench space].

    Args:
        model: The scene.
        data: Its state (kinematics computed), where the contacts were realised.
        hand: The hand's parts in the scene.
        contacts: The realised contacts.
        com: Object centre of mass, shape (3,) [m].
        torque_scale: rho [m] of the scaled wrench space.
        mu: Friction coefficient.
        cone_edge_count: Edges of the linearised cone.
        directions: Unit disturbance directions, shape (D, 6).
        travel: How far the object may move before the trial counts a failure [m]: the
            position servos' force changes are limited by the joint travel that moves each
            contact at most this far (:class:`~ogcp.sim_eval.hand.travel.ServoTravel`), and the
            resting stops' reactions by their softness (:func:`~ogcp.sim_eval.hand.travel.stop_reach`).
            None: the force ranges alone and rigid stops.
        torsion: Torsional friction of soft-finger contacts [m]; 0: hard point contacts.

    Returns:
        The resistance per direction; 0 with no contact, NaN where the solver failed.
    """
    if len(contacts.points) == 0:
        return np.zeros(len(directions))
    statics = hand_statics(
        model,
        data,
        hand,
        contacts.points,
        contacts.normals,
        contacts.bodies,
        com,
        torque_scale,
        mu,
        cone_edge_count,
        torsion=torsion,
    )
    first = len(contacts.points) * statics.edges  # the actuator forces' columns
    size = statics.size + 1
    points, bodies = contacts.points, contacts.bodies
    limits = ServoTravel.of(model, data, points, bodies, travel, first, size) if travel is not None else None
    cost = np.zeros(size)
    cost[-1] = -1.0
    bounds = [*statics.bounds, (0.0, None)]
    if travel is not None:  # a resting stop pushes only as far as its softness lets it within the travel
        stops = resting_limits(model, data, hand)
        for k, (joint, _) in enumerate(stops):  # the stops' reactions are the statics' last variables
            reach = stop_reach(model, data, points, bodies, travel, joint)
            bounds[statics.size - len(stops) + k] = (0.0, None if math.isinf(reach) else reach)
    bottom = np.hstack([statics.hand_balance, np.zeros((len(statics.hand_balance), 1))])
    resistance = np.full(len(directions), math.nan)
    for i, d in enumerate(directions):
        top = np.hstack([statics.object_balance, d[:, None]])
        rows = np.vstack([top, bottom])
        result = linprog(
            cost,
            A_ub=limits.rows if limits is not None and len(limits.rows) else None,
            b_ub=limits.bounds if limits is not None and len(limits.rows) else None,
            A_eq=rows,
            b_eq=statics.balance_rhs,
            bounds=bounds,
            method="highs",
        )
        if result.status == 0:
            resistance[i] = float(result.x[-1])
        elif result.status == 3:  # unbounded: some direction needs no actuator (an unlimited servo)
            resistance[i] = math.inf
    return resistance


@dataclass(frozen=True, eq=False)
class HandStatics:
    """The linear statics of a hand pressing on an object at K contacts, for linear programs.

    The variables are ``[lambda (K E cone-edge weights), u (nu actuator forces), eta (joint
    equality forces), s (reactions of the joint limits the hand rests on, >= 0)]``, ``size`` in
    all; a program appends its own (a load magnitude, a grip).

    Attributes:
        object_balance: The object's wrench (scaled space) per variable, shape (6, size).
        hand_balance: The hand's joint-space balance per variable, shape (J, size): the contact
            forces' joint torques minus the actuators', the equalities' and the limits'.
        bounds: Each variable's (low, high), None where unbounded.
        edges: Cone edges per contact E.
        springs: The joints' spring torques at the state (MuJoCo's ``qfrc_spring``: joint and
            tendon stiffness), shape (J,) [N·m or N]: what ``hand_balance`` must equal.
    """

    object_balance: NDArray[np.float64]
    hand_balance: NDArray[np.float64]
    bounds: list[tuple[float | None, float | None]]
    edges: int
    springs: NDArray[np.float64]

    @property
    def size(self) -> int:
        """Number of variables."""
        return len(self.bounds)

    @property
    def balance_rhs(self) -> NDArray[np.float64]:
        """Right-hand side of ``[object_balance; hand_balance] x = rhs``: no net wrench on the
        object, and the hand's joints balanced against its springs, shape (6 + J,)."""
        return np.concatenate([np.zeros(6), self.springs])


def hand_statics(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    hand: MountedHand,
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    bodies: NDArray[np.intp] | Sequence[int],
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    edge_count: int,
    stops: bool = True,
    torsion: float = 0.0,
    passive_stops: bool = False,
) -> HandStatics:
    """The statics of contacts ``points`` (K, 3) [m] with inward ``normals`` on hand ``bodies``, in a state.

    With ``stops``, the joints resting on a limit get its reaction (:func:`limit_reactions`): a
    load that pushes a joint into its limit meets the limit. A grip leaves them out: limits only
    react, and two of them against each other would squeeze the object with no actuator at all;
    with ``passive_stops`` it keeps those of joints no actuator moves (an underactuated finger's
    passive joint held on its stop, as the Robotiq 2F-85 pinches with its coupler on its stop).
    Joint and tendon springs push as MuJoCo's ``qfrc_spring`` at the state (``springs``).
    With ``torsion`` [m] > 0 the contacts are soft fingers, as MuJoCo simulates them (condim 4):
    each contact's primitives (:func:`~ogcp.planner.grasp.wrench.contact_wrenches`) add a twist
    about its normal of up to ``torsion`` times its normal force, which the hand supplies through
    its rotational Jacobian.
    """
    count = len(points)
    primitives = contact_wrenches(points, normals, com, torque_scale, mu, edge_count, torsion)  # (K, P, 6)
    per = primitives.shape[1]
    if torsion > 0:  # soft fingers: each primitive also twists about its normal
        forces = primitives[:, :, :3]
        arms = np.asarray(points, dtype=float)[:, None, :] - np.asarray(com, dtype=float)
        twists = primitives[:, :, 3:] * torque_scale - np.cross(np.broadcast_to(arms, forces.shape), forces)
    else:
        forces, twists = cone_edges(normals, mu, edge_count), np.zeros((count, per, 3))  # (K, E, 3)
    wrenches = primitives.reshape(count * per, 6).T
    dofs = model.jnt_dofadr[hand_joints(model, hand)]
    contact_torques = np.zeros((len(dofs), count * per))
    along, about = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    for k in range(count):
        mujoco.mj_jac(model, data, along, about, points[k], int(bodies[k]))
        block = along[:, dofs].T @ forces[k].T + about[:, dofs].T @ twists[k].T
        contact_torques[:, k * per : (k + 1) * per] = block
    moment = actuator_moments(model, data)[:, dofs].T  # (J, nu)
    couplings = equality_rows(model, data, dofs)  # (n_eq, J)
    if stops:
        limits = limit_reactions(model, data, hand)  # (J, L)
    elif passive_stops:
        joints = hand_joints(model, hand)
        passive = {j for k, j in enumerate(joints) if not np.abs(moment[k]).max(initial=0.0) > 0}
        limits = limit_reactions(model, data, hand, only=passive)
    else:
        limits = np.zeros((len(dofs), 0))
    mujoco.mj_passive(model, data)  # the springs' forces at this pose (damping needs no velocity here)
    springs = np.asarray(data.qfrc_spring[dofs], dtype=float).copy()
    low, high = force_ranges(model)
    extra = model.nu + len(couplings) + limits.shape[1]
    return HandStatics(
        np.hstack([wrenches, np.zeros((6, extra))]),
        np.hstack([contact_torques, -moment, -couplings.T, -limits]),
        [(0.0, None)] * (count * per)
        + list(zip(low, high, strict=True))
        + [(None, None)] * len(couplings)
        + [(0.0, None)] * limits.shape[1],
        per,
        springs,
    )


def hand_joints(model: mujoco.MjModel, hand: MountedHand) -> list[int]:
    """Every hinge and slide joint of the hand (its subtree below the mount), in model order."""
    return [
        j
        for j in range(model.njnt)
        if in_subtree(model, int(model.jnt_bodyid[j]), hand.mount) and int(model.jnt_type[j]) in _MOVABLE
    ]


def resting_limits(model: mujoco.MjModel, data: mujoco.MjData, hand: MountedHand) -> list[tuple[int, float]]:
    """The hand's joints resting on a limit at a state, as (joint id, side): +1 on its lower limit, -1 on its upper.

    A joint within :data:`AT_LIMIT` [rad or m] of a limit (or past it: MuJoCo's limits are soft) rests on it.
    """
    resting = []
    for joint in hand_joints(model, hand):
        if not model.jnt_limited[joint]:
            continue
        value = data.qpos[model.jnt_qposadr[joint]]
        low, high = model.jnt_range[joint]
        for side, near in ((1.0, value - low <= AT_LIMIT), (-1.0, high - value <= AT_LIMIT)):
            if near:
                resting.append((joint, side))
    return resting


def limit_reactions(
    model: mujoco.MjModel, data: mujoco.MjData, hand: MountedHand, only: set[int] | None = None
) -> NDArray[np.float64]:
    """Torques the joint limits can supply at a pose: one column per resting limit (:func:`resting_limits`;
    of the joints ``only`` names, if given), shape (J, L).

    The limit pushes back with any torque >= 0 along its column (away from the limit); within the
    trial's failure distance only as much as its softness lets it (:func:`~ogcp.sim_eval.hand.travel.stop_reach`).
    """
    joints = hand_joints(model, hand)
    row = {joint: k for k, joint in enumerate(joints)}
    resting = [(joint, side) for joint, side in resting_limits(model, data, hand) if only is None or joint in only]
    columns = [side * np.eye(len(joints))[row[joint]] for joint, side in resting]
    return np.array(columns).T if columns else np.zeros((len(joints), 0))


def force_ranges(model: mujoco.MjModel) -> tuple[list[float | None], list[float | None]]:
    low: list[float | None] = []
    high: list[float | None] = []
    for a in range(model.nu):
        if model.actuator_forcelimited[a]:
            low.append(float(model.actuator_forcerange[a, 0]))
            high.append(float(model.actuator_forcerange[a, 1]))
        else:
            low.append(None)
            high.append(None)
    return low, high


def equality_rows(model: mujoco.MjModel, data: mujoco.MjData, dofs: NDArray[np.intp]) -> NDArray[np.float64]:
    """The active equalities' constraint Jacobian over the hand's ``dofs``, shape (n_eq, J).

    MuJoCo's own rows at the state (``mj_fwdPosition`` done): a joint equality ties a coupled joint
    to its driver at its slope there, and a ``connect`` or ``weld`` between two of the hand's
    bodies closes a loop (a four-bar linkage), so the loop's passive joints are held by the loop's
    force. Rows that touch none of the hand's joints (the palm's mocap weld) are left out.
    """
    block = equality_jacobian(model, data)[:, np.asarray(dofs, dtype=np.intp)]
    scale = np.abs(block).max(axis=1) if block.size else np.zeros(len(block))
    return np.asarray(block[scale > EQUALITY_FLOOR * max(1.0, float(scale.max(initial=0.0)))], dtype=float)
