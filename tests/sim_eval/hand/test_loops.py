"""Hands with closed loops (a four-bar gripper, an adaptive five-bar one): fitted with their loops closed, held by
them, pinching as their closed form."""

from __future__ import annotations

import dataclasses
import json

import mujoco
import numpy as np
import pytest
import trimesh

from ogcp.benchmarks.cli import main
from ogcp.planner.hands import HandKinematics, load_descriptor
from ogcp.planner.hands.kinematics import HandModelWarning
from ogcp.sim_eval.evaluate import evaluate_plan
from ogcp.sim_eval.hand.fit import LOOP_TOLERANCE, fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.lean import failure_reach, lean_scene
from ogcp.sim_eval.hand.predict import AT_LIMIT, equality_rows, hand_joints, hand_statics
from ogcp.sim_eval.hand.scene import build_hand_scene, close_hand
from ogcp.sim_eval.protocols.phases import FULL_STATE, ramp_trials, settle
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings
from tests.planner.hands.hand_files import write_adaptive_gripper, write_fourbar_gripper

MU = 0.5
LINK = 0.05  # [m] driver and follower length of the test gripper
TORQUE = 1.0  # [N·m] its drivers' force range
BOX = trimesh.creation.box(extents=(0.03, 0.04, 0.03))
POINTS = np.array([[0.0, 0.02, 0.0], [0.0, -0.02, 0.0]])  # the jaws' faces at their reference, 40 mm apart
NORMALS = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.fixture(scope="module")
def fourbar(tmp_path_factory):
    return HandKinematics(load_descriptor(write_fourbar_gripper(tmp_path_factory.mktemp("fourbar"))))


def _angles(kinematics, angles):
    return dict(zip(kinematics.joint_names, angles, strict=True))


def test_the_fit_closes_the_loop_from_a_start_that_breaks_it(fourbar):
    start = fourbar.reference()
    start[fourbar.joint_names.index("l_pad")] = 0.4  # the left jaw tilted: its connect 6 mm open
    start[fourbar.joint_names.index("r_driver")] = 0.3  # the right driver turned alone
    points = POINTS + [0.0, 0.0, 0.01]
    fit = fit_hand(FitScene(fourbar), [0, 1], points, NORMALS, start)
    assert fit.realised and fit.loop_gap < 1e-6 and fit.residuals.max() < 1e-5
    angles = _angles(fourbar, fit.joint_angles)
    for side in "lr":  # a parallelogram: the follower turns with the driver, the jaw back by as much
        assert angles[f"{side}_follower"] == pytest.approx(angles[f"{side}_driver"], abs=1e-4)
        assert angles[f"{side}_pad"] == pytest.approx(-angles[f"{side}_driver"], abs=1e-4)
    assert fit.to_dict(fourbar.joint_names)["loop_gap"] == fit.loop_gap


def test_an_open_loop_is_the_reason_a_fit_is_not_realised(fourbar):
    fit = fit_hand(FitScene(fourbar), [0, 1], POINTS, NORMALS)
    broken = dataclasses.replace(fit, loop_gap=3 * LOOP_TOLERANCE)
    assert not broken.realised and broken.reason is not None
    assert broken.reason == "a closed loop of the hand stays 0.30 mm open (tolerance 0.1 mm)"


def test_the_loops_hold_the_passive_joints_in_the_statics(fourbar):
    parts = [(BOX.vertices, BOX.faces)]
    fit = fit_hand(FitScene(fourbar, parts), [0, 1], POINTS, NORMALS)
    com, inertia = object_inertia(BOX)
    opened = build_hand_scene(fourbar, fit, POINTS, NORMALS, parts, com, inertia, SimSettings(), MU, 0.05)
    model = opened.scene.model
    data = mujoco.MjData(model)
    data.qpos[:] = opened.scene.start()
    mujoco.mj_fwdPosition(model, data)
    dofs = model.jnt_dofadr[hand_joints(model, opened.hand)]
    rows = equality_rows(model, data, dofs)
    # Two planar connects, two rows each (the third, along the hinges' axis, moves with no joint);
    # the palm's weld touches none of the hand's joints.
    assert rows.shape == (4, 6)
    jaws = [
        {k for k, d in enumerate(dofs) if (model.joint(int(model.dof_jntid[d])).name.startswith(f"hand/{s}"))}
        for s in "lr"
    ]
    for row in rows:
        assert set(np.flatnonzero(np.abs(row) > 1e-9)) in ({*jaws[0]}, {*jaws[1]})


def test_a_four_bar_pinch_resists_slip_as_two_mu_f(fourbar):
    """A parallelogram jaw translates: its force is the driver's torque over L cos(theta), wherever it touches."""
    settings = SimSettings()
    parts = [(BOX.vertices, BOX.faces)]
    fit = fit_hand(FitScene(fourbar, parts), [0, 1], POINTS, NORMALS)
    assert fit.realised
    com, inertia = object_inertia(BOX)
    opened = build_hand_scene(fourbar, fit, POINTS, NORMALS, parts, com, inertia, settings, MU, 0.05)
    assert not fourbar.servos  # the MJCF drives the drivers; the loops carry it to the jaws
    closed = close_hand(opened)
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"] and settled.gates["tips_in_contact"] == 2
    model, data = closed.scene.model, mujoco.MjData(closed.scene.model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    data.ctrl[:] = closed.scene.preload_ctrl
    mujoco.mj_forward(model, data)
    drivers = [data.qpos[model.joint(f"hand/{s}_driver").qposadr[0]] for s in "lr"]
    jaw_forces = np.abs(np.array([data.actuator_force[model.actuator(f"hand/{s}").id] for s in "lr"]))
    np.testing.assert_allclose(jaw_forces, TORQUE, rtol=0.01)  # the squeeze saturates both drivers
    expected = TORQUE / (LINK * np.cos(drivers))
    np.testing.assert_allclose(settled.normal_forces, expected, rtol=0.03)
    closed_form = 2 * MU * float(np.mean(expected))
    directions = np.array([[1, 0, 0, 0, 0, 0], [-1, 0, 0, 0, 0, 0]], dtype=float)  # along the jaws' faces
    rate = np.full(2, 2 * closed_form / settings.ramp_time)
    lean = lean_scene(closed, settled, failure_reach(settings.move_threshold, settings.rotation_threshold, 0.05))
    assert lean is not None  # the palm held rigidly, as the protocol holds it
    trials = ramp_trials(
        lean.scene, lean.settled, directions, rate, settings.ramp_extent * settings.ramp_time, 1.0, settings
    )
    assert trials.failed.all() and not trials.diverged.any()
    np.testing.assert_allclose(trials.failure_load, closed_form, rtol=0.05)


def test_a_four_bar_gripper_plans_closes_and_is_measured_against_its_own_prediction(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_fourbar_gripper(tmp_path / "hand")
    descriptor.write_text(descriptor.read_text() + "\n[reachability]\nsamples = 2000\n")
    plan = tmp_path / "plan.json"
    args = ["plan", "box", "-n", "60", "-m", "2", "--diagonal", "0.06", "--contact-model", "soft"]
    assert main([*args, "--hand", str(descriptor), "-o", str(plan)]) == 0
    (grasp,) = evaluate_plan(json.loads(plan.read_text()), {"directions": 8}, {"method": "convex_hull"}).grasps
    hand = grasp.hand
    assert grasp.valid and all(grasp.gates["pads_on_contacts"]) and hand["fit"]["loop_gap"] < 1e-6
    settled = dict(zip(hand["fit"]["joint_names"], hand["settled_joint_angles"], strict=True))
    for side in "lr":  # the loops held under the squeeze: the jaws stayed upright
        assert settled[f"{side}_pad"] == pytest.approx(-settled[f"{side}_driver"], abs=0.01)
    # The loops' forces are in the prediction (without them it has none to give: NaN). 0.42 since the servos'
    # travel bound moves each jaw through its loop (it translates, 50 mm from the driver's axis); 0.30 when it
    # turned the driver alone, the pad 80 mm out, which the loop does not let it do.
    assert np.nanmedian(grasp.fidelity) < 0.45


DRIVE_FORCE = 0.6  # [N] the adaptive gripper's tendon force limit: 0.3 N·m on each driven link


def test_an_adaptive_gripper_pinches_with_its_elbows_on_their_stops(tmp_path):
    """Five-bar jaws with one servo: the spring puts each elbow on its stop, where the stop holds the jaw
    parallel against the squeeze, so the grip is the servo's (0.3 N·m over L cos(theta)) and a pinch slips at 2 mu N."""
    with pytest.warns(HandModelWarning, match=r"3 directions of motion, 1 servo direction"):
        kinematics = HandKinematics(load_descriptor(write_adaptive_gripper(tmp_path)))
    assert kinematics.servos == ()  # the tendon servo drives the loops; the passive chains get none
    settings = SimSettings()
    box = trimesh.creation.box(extents=(0.04, 0.03, 0.04))
    points, normals = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]]), NORMALS
    parts = [(box.vertices, box.faces)]
    fit = fit_hand(FitScene(kinematics, parts), [0, 1], points, normals)
    angles = _angles(kinematics, fit.joint_angles)
    assert fit.realised and abs(angles["l_elbow"]) < AT_LIMIT and abs(angles["r_elbow"]) < AT_LIMIT
    com, inertia = object_inertia(box)
    opened = build_hand_scene(kinematics, fit, points, normals, parts, com, inertia, settings, MU, 0.05)
    assert opened.grip is not None  # balanced, with the stops holding the passive chains
    expected = DRIVE_FORCE / 2 / (LINK * np.cos(angles["l_drive"]))
    np.testing.assert_allclose(opened.squeeze_forces, expected, rtol=0.01)
    closed = close_hand(opened)
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"]
    np.testing.assert_allclose(settled.normal_forces, expected, rtol=0.02)
    lean = lean_scene(closed, settled, failure_reach(settings.move_threshold, settings.rotation_threshold, 0.064))
    assert lean.summary["lean"] and lean.scene.model.nu == 1  # the servo's links move: not welded
    closed_form = 2 * MU * float(np.mean(settled.normal_forces))
    directions = np.array([[1, 0, 0, 0, 0, 0], [-1, 0, 0, 0, 0, 0]], dtype=float)  # along the jaws' faces
    rate = np.full(2, 2 * closed_form / settings.ramp_time)
    trials = ramp_trials(
        lean.scene, lean.settled, directions, rate, settings.ramp_extent * settings.ramp_time, 1.0, settings
    )
    assert trials.failed.all() and not trials.diverged.any()
    np.testing.assert_allclose(trials.failure_load, closed_form, rtol=0.05)


@pytest.mark.filterwarnings("ignore::ogcp.planner.hands.kinematics.HandModelWarning")
def test_springs_push_in_the_statics_as_mujoco_computes_them(tmp_path):
    kinematics = HandKinematics(load_descriptor(write_adaptive_gripper(tmp_path, spring=-1.0)))
    settings = SimSettings()
    box = trimesh.creation.box(extents=(0.04, 0.03, 0.04))
    points = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
    fit = fit_hand(FitScene(kinematics, [(box.vertices, box.faces)]), [0, 1], points, NORMALS)
    com, inertia = object_inertia(box)
    parts = [(box.vertices, box.faces)]
    opened = build_hand_scene(kinematics, fit, points, NORMALS, parts, com, inertia, settings, MU, 0.05)
    model, data = opened.scene.model, mujoco.MjData(opened.scene.model)
    data.qpos[:] = opened.scene.start()
    mujoco.mj_forward(model, data)
    bodies = [int(opened.hand.pads[f]) for f in (0, 1)]
    statics = hand_statics(model, data, opened.hand, points, NORMALS, bodies, com, 0.05, MU, 8)
    joints = hand_joints(model, opened.hand)
    for k, joint in enumerate(joints):
        q = data.qpos[model.jnt_qposadr[joint]]
        expected = -model.jnt_stiffness[joint] * (q - model.qpos_spring[model.jnt_qposadr[joint]])
        assert statics.springs[k] == pytest.approx(expected, abs=1e-12)
    assert np.count_nonzero(statics.springs) == 2  # the two elbows
    assert statics.balance_rhs.shape == (6 + len(joints),)
