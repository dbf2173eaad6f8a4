"""What a hand's servos and joint stops resist before the object has moved the trial's failure distance.

A position servo is a spring, and so is a MuJoCo joint limit: a soft constraint whose stiffness
follows its ``solref``, ``solimp`` and the joint's inertia. Within the few millimetres the
resistance trial allows, neither reaches the force the hand's statics alone would let it
(a servo's force range, a stop's unbounded reaction): :class:`ServoTravel` bounds the servos'
changes by the motion of the contacts they allow, :func:`stop_reach` each resting stop's push.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.model_checks import equality_jacobian


def stop_stiffness(model: mujoco.MjModel, joint: int) -> float:
    """[N·m/rad or N/m] How hard a joint's limit pushes back per unit it is passed, steadily, at full impedance.

    MuJoCo's reference acceleration ``-k d r`` (``k`` from ``solref``, ``d`` the impedance) and its
    regularisation ``R = (1 - d) / d A`` (``A`` the joint's inverse inertia, ``dof_invweight0``) hold a
    steady load ``tau`` with the limit passed by ``r = tau (1 - d) A / (k d^2)``. The impedance is its
    largest, ``solimp``'s dmax (past the width), which gives the stiffest stop.
    """
    timeconst, ratio = (float(v) for v in model.jnt_solref[joint, :2])
    dmax = float(model.jnt_solimp[joint, 1])
    if timeconst > 0:  # MuJoCo keeps the time constant at two steps or more (unless told not to)
        if not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE:
            timeconst = max(timeconst, 2.0 * float(model.opt.timestep))
        k = 1.0 / (dmax**2 * timeconst**2 * ratio**2)
    else:  # the direct form: (-stiffness, -damping)
        k = -timeconst / dmax**2
    inverse_inertia = float(model.dof_invweight0[model.jnt_dofadr[joint]])
    return k * dmax**2 / ((1.0 - dmax) * max(inverse_inertia, 1e-12))


@dataclass(frozen=True, eq=False)
class ServoTravel:
    """Linear rows that keep the servos' force changes within what the failure distance allows.

    A servo whose force falls with its length (MuJoCo's affine bias ``b1 < 0``: a ``<position>``
    actuator, or a ``<general>`` one with ``biasprm="0 -kp -kv"``) is a spring of stiffness
    ``s = -b1`` along its length, on a joint, a tendon or a site. Its force changes by ``du = s dL``
    when its length does, ``dL = M dq`` (M its moment arms, gear and tendon coefficients in).
    Each servo's force change is taken as the least joint motion ``dq`` (per unit force, a column
    of :attr:`motion`) that changes its own length by ``du / s``, keeps the other servos' lengths,
    and moves as the hand's equalities tie it (a tendon split over two jaws that an equality
    couples moves both). A hand body b that carries contacts then moves its contact point p_b by
    ``J_b dq``, and the trial counts a failure once the object, which the contacts hold, moved
    ``travel``. So to first order the force changes satisfy, per body and axis,

        -h  <=  sum_a J_b motion[:, a] (u_a - u0_a)  <=  h,     h = travel / sqrt(3)

    around the settled forces u0: the box of half-width h is the largest inside the sphere of
    radius ``travel``, so every motion it allows stays short of the failure distance. The program
    then finds the resistance the servos build before the object has moved that far, not the
    force range they would reach after a larger motion. For a servo on a joint, the motion is
    that joint's alone, ``du / (kp |gear|)``. Where joints no servo drives and no equality ties
    (passive links) let the servo move without the pads, the least motion moves the pads less
    than the hand will, and the bound is loose.

    Attributes:
        rows: ``A_ub`` over the program's variables, shape (R, n).
        bounds: ``b_ub``, shape (R,).
    """

    rows: NDArray[np.float64]
    bounds: NDArray[np.float64]

    @classmethod
    def of(
        cls,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        points: NDArray[np.float64],
        bodies: NDArray[np.intp],
        travel: float,
        first_force: int,
        size: int,
    ) -> ServoTravel:
        """The rows for a state (``mj_forward`` done): contacts ``points`` (K, 3) [m] on hand ``bodies``
        (K,); actuator a's force is column ``first_force + a`` of ``size`` variables."""
        servos = np.flatnonzero(-model.actuator_biasprm[:, 1] > 0)
        motion = servo_motion(model, data, servos)  # (nv, servos)
        rows, limits = [], []
        settled = np.asarray(data.actuator_force[servos], dtype=float)
        for jacobian in _carrying_jacobians(model, data, points, bodies):
            moves = jacobian @ motion  # (3, servos): contact motion per unit force change
            for axis in range(3):
                if not np.abs(moves[axis]).max(initial=0.0) > 0:
                    continue
                for sign in (1.0, -1.0):
                    row = np.zeros(size)
                    row[first_force + servos] = sign * moves[axis]
                    rows.append(row)
                    limits.append(travel / math.sqrt(3.0) + sign * float(moves[axis] @ settled))
        return cls(np.array(rows).reshape(-1, size), np.array(limits))


def actuator_moments(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """The actuators' moment arms (d length / d qvel), dense, shape (nu, nv)."""
    dense = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(dense, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind)
    return dense


def servo_motion(model: mujoco.MjModel, data: mujoco.MjData, servos: NDArray[np.intp]) -> NDArray[np.float64]:
    """The least joint motion per unit force change of each servo, the others' lengths and the equalities kept, shape (nv, S).

    Column a solves ``M dq = e_a / s_a`` (M the servos' moment arms, s their stiffnesses) with the
    equalities' rows ``E dq = 0`` (a joint coupling that moves two jaws as one, a loop that carries a
    pad hung from a passive link), in the least-squares sense where those conflict.
    """
    if not len(servos):
        return np.zeros((model.nv, 0))
    stiffness = -model.actuator_biasprm[servos, 1]
    moments = actuator_moments(model, data)[servos]
    tied = equality_jacobian(model, data)
    system = np.vstack([moments, tied])
    wanted = np.vstack([np.diag(1.0 / stiffness), np.zeros((len(tied), len(servos)))])
    return np.asarray(np.linalg.lstsq(system, wanted, rcond=None)[0])


def stop_reach(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    points: NDArray[np.float64],
    bodies: NDArray[np.intp],
    travel: float,
    joint: int,
) -> float:
    """[N·m or N] The most a resting joint's limit pushes with before the object moves ``travel``.

    The joint may press into its limit only as far as moves no contact more than ``travel /
    sqrt(3)`` along an axis (as :class:`ServoTravel` bounds the servos). It moves the contacts
    with the least motion of the other joints that its equalities ask for (a loop's follower
    moves its jaw through the loop; state after ``mj_forward``). The limit then pushes with its
    force in the state plus :func:`stop_stiffness` times that. A joint that moves no contact keeps
    an unbounded stop (inf).
    """
    dof = int(model.jnt_dofadr[joint])
    tied = equality_jacobian(model, data)
    unit = np.zeros((1, model.nv))
    unit[0, dof] = 1.0
    wanted = np.zeros(len(tied) + 1)
    wanted[-1] = 1.0
    motion = np.linalg.lstsq(np.vstack([tied, unit]), wanted, rcond=None)[0]  # (nv,) per unit of this joint
    jacobians = _carrying_jacobians(model, data, points, bodies)
    lever = max((float(np.abs(jacobian @ motion).max()) for jacobian in jacobians), default=0.0)
    if lever <= 1e-12:
        return math.inf
    return _limit_force(data, joint) + stop_stiffness(model, joint) * travel / math.sqrt(3.0) / lever


def _limit_force(data: mujoco.MjData, joint: int) -> float:
    """[N·m or N] The force a joint's limit presses with in a state (``mj_forward`` done); 0 when not pressed."""
    rows = (data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT) & (
        data.efc_id[: data.nefc] == joint
    )
    return float(data.efc_force[: data.nefc][rows].sum())


def _carrying_jacobians(
    model: mujoco.MjModel, data: mujoco.MjData, points: NDArray[np.float64], bodies: NDArray[np.intp]
) -> list[NDArray[np.float64]]:
    """The translational Jacobian (3, nv) of each contact-carrying body at the mean of its contacts."""
    found = []
    for body in sorted({int(b) for b in bodies}):
        jacobian = np.zeros((3, model.nv))
        mujoco.mj_jac(model, data, jacobian, None, points[bodies == body].mean(axis=0), body)
        found.append(jacobian)
    return found
