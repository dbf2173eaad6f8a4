"""The balanced grip asks only what the servos can press: targets within ctrlrange, never a joint limit."""

from __future__ import annotations

import mujoco
import numpy as np
import trimesh

from ogcp.planner.hands import HandKinematics, resolve_hand
from ogcp.sim_eval.hand.fit import fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.scene import build_hand_scene
from ogcp.sim_eval.hand.squeeze import balanced_grip
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings

MU = 0.5
BOX = trimesh.creation.box(extents=(0.04, 0.03, 0.04))
POINTS = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
NORMALS = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])


def _pinch():
    """The gripper's scene at its fitted pinch of the box, the grasp's qpos and a grip function."""
    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    parts = [(BOX.vertices, BOX.faces)]
    fit = fit_hand(FitScene(kinematics, parts), [0, 1], POINTS, NORMALS)
    com, inertia = object_inertia(BOX)
    opened = build_hand_scene(kinematics, fit, POINTS, NORMALS, parts, com, inertia, SimSettings(), MU, 0.05)
    model, hand = opened.scene.model, opened.hand
    qpos = opened.scene.start().copy()
    qpos[hand.qpos] = fit.joint_angles

    def grip():
        return balanced_grip(model, hand, qpos, fit.fingers, POINTS, NORMALS, com, 0.05, MU, 10.0)

    left = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, "hand/ogcp_servo_left")
    joint = int(model.actuator_trnid[left, 0])
    return model, qpos, grip, left, joint


def test_a_servo_whose_target_cannot_pass_the_pose_presses_nothing():
    model, qpos, grip, left, joint = _pinch()
    found = grip()
    assert found is not None and found.pad_forces.min() > 0  # both jaws press, at their limits
    here = float(qpos[model.jnt_qposadr[joint]])
    model.actuator_ctrllimited[left] = 1
    model.actuator_ctrlrange[left] = [0.0, here]  # the left jaw's target is clamped where it stands
    assert grip() is None  # the right jaw alone balances nothing


def test_joint_limits_alone_squeeze_nothing():
    model, qpos, grip, left, _ = _pinch()
    right = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, "hand/ogcp_servo_right")
    for actuator in (left, right):
        here = float(qpos[model.jnt_qposadr[int(model.actuator_trnid[actuator, 0])]])
        model.actuator_ctrllimited[actuator] = 1
        model.actuator_ctrlrange[actuator] = [0.0, here]
        model.jnt_range[int(model.actuator_trnid[actuator, 0])] = [here, 0.04]  # each jaw rests on a limit
    # Two limits pressing the object between them would make any grip, with no servo pressing:
    # a grip must come from the actuators.
    assert grip() is None
