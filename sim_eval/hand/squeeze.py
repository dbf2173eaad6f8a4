"""The squeeze: servo targets under which the hand presses balanced forces on the object.

Squeezing by geometry (targets past the surface) presses with whatever forces the servos' errors
give, generally unbalanced: the object slides until the fingers' geometry balances them, and a
pad that rolls can push it out. Instead, the squeeze solves a grasp-force linear program at the
fitted pose: contact forces f_k in the linearised friction cones at the pads (the grasp's
contacts), with

    sum_k [f_k, (p_k - c) x f_k / rho] = 0           (no net wrench: the object stays put)
    sum_k J_k^T f_k = M^T u + E^T eta + L s + tau,  u within the actuators' force ranges

(``eta`` the equalities' forces, ``s >= 0`` the reactions of the stops that passive joints rest on,
``tau`` the springs' torques at the pose), maximising the smallest normal force. A hand with an actuator that has no force limit is capped at
``max_normal_force`` (F_max) there, as fingertips are, and then presses the least total force that
keeps every pad at that level.
Each position servo's control is then the one under which, at its length at the pose, it pushes
exactly ``u`` (its length plus ``u / kp`` for MuJoCo's ``<position>``; :func:`servo_ctrl` for any
affine servo, such as a gripper's 0-255 command), so the hand holds the object with those balanced
forces, at its actuators' limits where the program needs them (as fingertips press at F_max).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from ogcp.sim_eval.hand.mount import MountedHand
from ogcp.sim_eval.hand.predict import hand_statics

#: Cone edges of the program (the planner's default count).
EDGES = 8
#: Once the hand has settled, a servo held past its force limit asks for this share more than its
#: limit at its settled length, no more: the squeeze asked for twice the limit (the pads sink into
#: the soft contacts), and that excess is travel over which a jaw follows the object at its limit
#: and resists nothing. A 1.35 m gripper (20,000 N/m, 200 N) on a 1.2 m box resisted 53 N along
#: the line between its jaws, against the 139 N its servos' stiffness predicts over the failure
#: threshold, while it had 10 mm of such slack.
SLACK_SHARE = 0.1


@dataclass(frozen=True, eq=False)
class Grip:
    """The largest balanced grip at the fitted pose.

    Attributes:
        length: Each actuator's length at the pose, shape (nu,).
        forces: Each actuator's force in the grip, shape (nu,) [N or N·m].
        pad_forces: Each chosen pad's normal force, shape (m,) [N].
    """

    length: NDArray[np.float64]
    forces: NDArray[np.float64]
    pad_forces: NDArray[np.float64]

    def targets(self, model: mujoco.MjModel, share: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Servo targets (nu,) that press ``share`` of the grip, and the pads' normal forces (m,) [N].

        Each position servo's control pushes ``u`` at the pose (:func:`servo_ctrl`); one the grip
        puts at its force limit asks for twice that, since the pads sink a little into the soft
        contacts and it still presses at its limit (where its force is clamped).
        """
        u = share * self.forces
        # The limit on the side the servo pushes: a range may be asymmetric.
        limit = np.where(u >= 0, model.actuator_forcerange[:, 1], -model.actuator_forcerange[:, 0])
        at_limit = model.actuator_forcelimited.astype(bool) & (np.abs(u) >= (1 - 1e-6) * limit)
        targets = servo_ctrl(model, self.length, np.where(at_limit, 2.0, 1.0) * u)
        limited = model.actuator_ctrllimited.astype(bool)
        targets[limited] = np.clip(
            targets[limited], model.actuator_ctrlrange[limited, 0], model.actuator_ctrlrange[limited, 1]
        )
        return targets, share * self.pad_forces


def balanced_grip(
    model: mujoco.MjModel,
    hand: MountedHand,
    grasp_qpos: NDArray[np.float64],
    fingers: Sequence[int],
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    max_normal_force: float,
) -> Grip | None:
    """The largest balanced grip on the contacts, or None when none exists (not in force closure for this hand).

    Args:
        model: The scene.
        hand: The hand in it.
        grasp_qpos: The scene's qpos with the hand in the fitted grasp, shape (nq,).
        fingers: The chosen fingers, one per contact.
        points: The contacts, shape (m, 3) [m].
        normals: Their inward normals, shape (m, 3).
        com: The object's centre of mass, shape (3,) [m].
        torque_scale: rho [m].
        mu: Friction coefficient.
        max_normal_force: Cap on the smallest normal force of a hand with an actuator that has no
            force limit, or whose grip nothing else bounds [N].
    """
    data = mujoco.MjData(model)
    data.qpos[:] = grasp_qpos
    mujoco.mj_fwdPosition(model, data)
    m = len(fingers)
    bodies = [int(hand.pads[finger]) for finger in fingers]
    statics = hand_statics(
        model, data, hand, points, normals, bodies, com, torque_scale, mu, EDGES, stops=False, passive_stops=True
    )
    n_lambda, n_u = m * EDGES, model.nu
    # Variables [statics', t]: maximise t, every pad's normal force (its edges' weights) >= t.
    cost = np.zeros(statics.size + 1)
    cost[-1] = -1.0
    equalities = np.vstack([statics.object_balance, statics.hand_balance])
    equalities = np.hstack([equalities, np.zeros((len(equalities), 1))])
    at_least = np.zeros((m, statics.size + 1))
    for k in range(m):
        at_least[k, k * EDGES : (k + 1) * EDGES] = -1.0
    at_least[:, -1] = 1.0
    bounds = _servo_reach(model, data, statics.bounds, n_lambda)
    problem = {"A_ub": at_least, "b_ub": np.zeros(m), "A_eq": equalities, "b_eq": statics.balance_rhs}
    # An actuator without a force limit (a model that leaves them out) presses as far as its
    # control range lets a stiff servo: tens of newtons, which it holds only while nothing slips.
    # Such a hand grips as fingertips do, its weakest pad at F_max.
    capped = not model.actuator_forcelimited.all()
    result = linprog(cost, bounds=[*bounds, (0.0, max_normal_force if capped else None)], method="highs", **problem)
    if result.status == 3:  # unbounded: no actuator limits the grip, so the settings' F_max does
        capped = True
        result = linprog(cost, bounds=[*bounds, (0.0, max_normal_force)], method="highs", **problem)
    if result.status != 0 or result.x[-1] <= 0:
        return None
    if capped:  # the least total force with every pad at that level: none presses more than balance needs
        weakest = float(result.x[-1])
        least = np.zeros_like(cost)
        least[:n_lambda] = 1.0
        bounds_least = [*bounds, ((1.0 - 1e-9) * weakest, weakest)]
        tighter = linprog(least, bounds=bounds_least, method="highs", **problem)
        result = tighter if tighter.status == 0 else result
    return Grip(
        data.actuator_length.copy(),
        result.x[n_lambda : n_lambda + n_u].copy(),
        result.x[:n_lambda].reshape(m, EDGES).sum(axis=1),
    )


def take_up_slack(model: mujoco.MjModel, data: mujoco.MjData, ctrl: NDArray[np.float64]) -> NDArray[np.float64]:
    """Controls (nu,) under which every position servo that ``ctrl`` holds past its force limit in
    the settled ``data`` asks for :data:`SLACK_SHARE` more than its limit, no more; the others as given.

    The forces at the settled state do not change (a servo past its limit pushes its limit), only
    how far the servo gives before its force falls.
    """
    ctrl = np.array(ctrl, dtype=float)
    servo = position_servos(model) & model.actuator_forcelimited.astype(bool)
    gain, bias = model.actuator_gainprm[:, 0], model.actuator_biasprm
    length = data.actuator_length
    asked = gain * ctrl + bias[:, 0] + bias[:, 1] * length
    low, high = model.actuator_forcerange[:, 0], model.actuator_forcerange[:, 1]
    enough = np.where(asked > high, high + SLACK_SHARE * np.abs(high), low - SLACK_SHARE * np.abs(low))
    slack = servo & ((asked > high) | (asked < low)) & (np.abs(enough) < np.abs(asked))
    taken = servo_ctrl(model, length, enough)
    ctrl[slack] = taken[slack]
    limited = slack & model.actuator_ctrllimited.astype(bool)
    ctrl[limited] = np.clip(ctrl[limited], model.actuator_ctrlrange[limited, 0], model.actuator_ctrlrange[limited, 1])
    return ctrl


def position_servos(model: mujoco.MjModel) -> NDArray[np.bool_]:
    """Which actuators are position servos: force ``g ctrl + b0 + b1 length + b2 velocity`` with
    ``g > 0`` and ``b1 < 0`` (``kp (ctrl - length) - kv velocity`` for MuJoCo's ``<position>``), shape (nu,)."""
    return np.asarray((model.actuator_biasprm[:, 1] < 0) & (model.actuator_gainprm[:, 0] > 0))


def servo_ctrl(model: mujoco.MjModel, length: NDArray[np.float64], force: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Controls (nu,) under which each position servo pushes ``force`` at rest at ``length``, unclamped.

    ``(force - b0 - b1 length) / g``: the length itself plus ``force / kp`` for a ``<position>``
    servo, and the command a general affine servo needs (the Robotiq 2F-85's takes 0-255 for
    0-0.8 rad). Other actuators get their length, as before.
    """
    ctrl = np.array(length, dtype=float)
    servo = position_servos(model)
    push = np.broadcast_to(np.asarray(force, dtype=float), ctrl.shape)
    gain, bias = model.actuator_gainprm[servo, 0], model.actuator_biasprm[servo]
    ctrl[servo] = (push[servo] - bias[:, 0] - bias[:, 1] * ctrl[servo]) / gain
    return ctrl


def _servo_reach(
    model: mujoco.MjModel, data: mujoco.MjData, bounds: list[tuple[float | None, float | None]], first: int
) -> list[tuple[float | None, float | None]]:
    """The actuator forces' bounds narrowed to what each position servo can press within its control range.

    A servo's force at rest is ``g ctrl + b0 + b1 length`` (``kp (ctrl - length)``) and its control
    is clamped to ``ctrlrange``: a grip that needs a control past it is never pressed (soft servos
    need targets far past the pose), so the finger it relies on lets go of the object.
    """
    narrowed = list(bounds)
    gains, bias = model.actuator_gainprm[:, 0], model.actuator_biasprm
    position = position_servos(model)
    for a in range(model.nu):
        if not (position[a] and model.actuator_ctrllimited[a]):
            continue
        reach = gains[a] * model.actuator_ctrlrange[a] + bias[a, 0] + bias[a, 1] * data.actuator_length[a]
        low, high = narrowed[first + a]
        low = float(reach[0]) if low is None else max(low, float(reach[0]))
        high = float(reach[1]) if high is None else min(high, float(reach[1]))
        narrowed[first + a] = (min(low, 0.0), max(high, 0.0))  # zero force stays feasible
    return narrowed
