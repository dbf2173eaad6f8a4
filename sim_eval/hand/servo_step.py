"""Servos a time step can integrate: armature for the joints whose position servo would ring.

MuJoCo's implicit integrators take joint damping and a servo's ``kv`` implicitly, but a position
servo's stiffness ``kp`` explicitly. A joint whose servo is stiff against what it moves (a light
distal link: 5e-6 kg·m² under kp 10 N·m/rad in an Allegro-like hand) has omega = sqrt(kp / M)
[rad/s] with omega * dt of 1-9 at a 2 ms step; coupled through the contacts with the object,
such servos made the closing hand fling the object away or shake it loose, though each joint on
its own, damped implicitly, is stable. Armature (rotor inertia on the joint) slows that mode until
omega * dt is :data:`MAX_OMEGA_DT`; it changes how fast the hand moves, never what it holds
(gravity is off, so mass enters no static balance), and it leaves a hand whose servos the step
already integrates (the SDH's reach 0.2, the Shadow hand's 0.16) as it is.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.sim_eval.hand.travel import actuator_moments

#: The largest servo frequency times the time step the scene keeps: the SDH's value. At 0.5 two of
#: four box grasps of an Allegro-like hand still crept; at 0.25 and 0.2 all four held.
MAX_OMEGA_DT = 0.2


def steady_servos(model: mujoco.MjModel, qpos: NDArray[np.float64]) -> None:
    """Give the joints whose servos would ring armature, and the damping that keeps their damping ratio.

    Each such joint's omega * dt becomes :data:`MAX_OMEGA_DT`. Its damping (the joint's own and its
    servos' ``kv``, both integrated implicitly) grows so that its damping ratio stays what it was, up
    to critical: a critically damped servo does not ring with the added inertia, and an overdamped
    one is not made more sluggish.

    Args:
        model: The compiled scene; its ``dof_armature`` and ``dof_damping`` are changed in place.
        qpos: A configuration to take the joint-space inertia at (the grasp), shape (nq,).
    """
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_fwdPosition(model, data)
    # A position servo pushes kp (ctrl - length) - kv d(length)/dt along its moment arms (a joint's
    # gear, or a tendon's coefficients): its stiffness on dof i is kp * moment_i**2.
    servo = model.actuator_biasprm[:, 1] < 0
    squared = actuator_moments(model, data)[servo] ** 2  # (servos, nv)
    stiffness = -model.actuator_biasprm[servo, 1] @ squared
    damping = model.dof_damping + -model.actuator_biasprm[servo, 2] @ squared
    inertia = np.zeros(model.nv)
    for dof in np.flatnonzero(stiffness > 0):
        unit = np.zeros(model.nv)
        unit[dof] = 1.0
        column = np.zeros(model.nv)
        mujoco.mj_mulM(model, data, column, unit)
        inertia[dof] = column[dof]
    needed = stiffness * (model.opt.timestep / MAX_OMEGA_DT) ** 2
    added = np.where(stiffness > 0, np.maximum(needed - inertia, 0.0), 0.0)
    # The damping ratio each servo had, up to critical: an overdamped joint keeps its damping
    # (more would only make the closing sluggish), an underdamped or critical one keeps its ratio.
    critical = 2.0 * np.sqrt(stiffness * np.maximum(inertia, 1e-12))
    ratio = np.minimum(damping / np.maximum(critical, 1e-12), 1.0)
    wanted = ratio * 2.0 * np.sqrt(stiffness * (inertia + added))
    model.dof_armature += added
    model.dof_damping += np.where(added > 0, np.maximum(wanted - damping, 0.0), 0.0)
