"""The protocol's lean scene: the palm and the fingers clear of the object welded where they settled."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.sim_eval.hand.fit import fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.lean import failure_reach, lean_scene
from ogcp.sim_eval.hand.scene import HandScene, build_hand_scene, close_hand
from ogcp.sim_eval.protocols.phases import FULL_STATE, Settled, ramp_trials, settle
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings
from tests.planner.hands.hand_files import write_gripper_variant

MU = 0.5
BOX = trimesh.creation.box(extents=(0.04, 0.03, 0.04))
POINTS = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
NORMALS = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
#: A third finger on the palm's edge, a hinge whose link points away from the object.
SPARE_BODY = (
    '<body name="spare" pos="0.018 0 0.01"><joint name="spare" axis="0 1 0" range="-0.5 0.5" damping="0.1"/>'
    '<geom name="spare" type="box" pos="0.01 0 0" size="0.01 0.004 0.004"/></body>'
)
SPARE_FINGER = """
[[fingers]]
name = "spare"
tip_body = "spare"
tip_offset = [0.02, 0.0, 0.0]
pad_normal = [1.0, 0.0, 0.0]
tip_radius = 0.004
"""


#: The spare finger inside a frame, turned by Euler angles in the model's radians (a scene compiles in degrees).
FRAMED_SPARE = (
    '<frame pos="0.018 0 0.01" euler="0 0 0.5"><body name="spare" euler="0 0 -0.5"><joint name="spare" '
    'axis="0 1 0" range="-0.5 0.5" damping="0.1"/><geom name="spare" type="box" pos="0.01 0 0" '
    'size="0.01 0.004 0.004"/></body></frame>'
)


def _three_jaws(folder: Path, coupled: bool = False, framed: bool = False) -> HandKinematics:
    """The parallel gripper with a spare finger that the two-contact grasps leave open."""
    spare = FRAMED_SPARE if framed else SPARE_BODY

    def edit(text: str) -> str:
        text = text.replace('<body name="left"', spare + '<body name="left"')
        if coupled:  # the spare follows the left jaw
            text = text.replace(
                "</worldbody>", '</worldbody><equality><joint joint1="spare" joint2="left"/></equality>'
            )
        return text

    descriptor = write_gripper_variant(
        folder, edit, lambda text: text.replace("[actuation]", SPARE_FINGER + "\n[actuation]")
    )
    return HandKinematics(load_descriptor(descriptor))


def _closed(kinematics: HandKinematics, settings: SimSettings) -> tuple[HandScene, Settled]:
    parts = [(BOX.vertices, BOX.faces)]
    fit = fit_hand(FitScene(kinematics, parts), [0, 1], POINTS, NORMALS)
    assert fit.realised
    com, inertia = object_inertia(BOX)
    closed = close_hand(build_hand_scene(kinematics, fit, POINTS, NORMALS, parts, com, inertia, settings, MU, 0.05))
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"]
    return closed, settled


def _reach(settings: SimSettings) -> float:
    diagonal = float(np.linalg.norm(BOX.extents))
    return failure_reach(settings.move_threshold, settings.rotation_threshold, diagonal)


def _poses(model: mujoco.MjModel, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, FULL_STATE)
    mujoco.mj_kinematics(model, data)
    return data.xpos.copy(), data.xquat.copy()


@pytest.mark.parametrize("framed", [False, True])
def test_the_palm_and_an_idle_finger_are_welded_where_they_settled_and_the_pinch_holds_two_mu_f(framed, tmp_path):
    """Along and across the jaws the lean pinch fails at 2 mu F; the full scene's weld lets the light palm turn."""
    settings = SimSettings()
    closed, settled = _closed(_three_jaws(tmp_path, framed=framed), settings)
    lean = lean_scene(closed, settled, _reach(settings))
    full = closed.scene.model
    assert lean.summary["lean"] is True
    assert lean.summary["welded_joints"] == ["ogcp_mount_free", "hand/spare"]
    assert (lean.summary["full_dofs"], lean.summary["dofs"]) == (full.nv, full.nv - 7)
    assert lean.scene.model.nu == full.nu - 1  # the spare's servo went with its joint
    assert lean.scene.model.neq == 0  # and the palm's weld with the palm's free joint
    lean_poses = _poses(lean.scene.model, lean.settled.state)
    for settled_pose, lean_pose in zip(_poses(full, settled.state), lean_poses, strict=True):
        np.testing.assert_allclose(lean_pose, settled_pose, atol=1e-9)
    closed_form = 2 * MU * closed.hand.kinematics.descriptor.actuation.force_range
    directions = np.array([[0, 0, 1, 0, 0, 0], [0, 0, -1, 0, 0, 0], [1, 0, 0, 0, 0, 0]], dtype=float)
    rate = np.full(3, 2 * closed_form / settings.ramp_time)
    duration = settings.ramp_extent * settings.ramp_time
    trials = ramp_trials(lean.scene, lean.settled, directions, rate, duration, 1.0, settings)
    assert trials.failed.all() and not trials.diverged.any()
    np.testing.assert_allclose(trials.failure_load, closed_form, rtol=0.05)
    # On the weld, a load across the jaws, 7 cm above the 0.1 kg palm, turns the palm and carries
    # the object past the failure distance before the pads slip.
    welded = ramp_trials(closed.scene, settled, directions[2:], rate[2:], duration, 1.0, settings)
    assert welded.failure_load[0] < 0.8 * closed_form


def test_a_finger_coupled_to_a_moving_one_keeps_moving(tmp_path):
    settings = SimSettings()
    closed, settled = _closed(_three_jaws(tmp_path, coupled=True), settings)
    lean = lean_scene(closed, settled, _reach(settings))
    assert lean.summary["welded_joints"] == ["ogcp_mount_free"]
    assert lean.scene.model.neq == 1  # the coupling stays


def test_a_finger_within_the_clearance_keeps_moving(tmp_path):
    settings = SimSettings()
    closed, settled = _closed(_three_jaws(tmp_path), settings)
    lean = lean_scene(closed, settled, reach=1.0)  # the object could move a metre before failing
    assert lean.summary["welded_joints"] == ["ogcp_mount_free"]


@pytest.mark.parametrize("fault", ["no spec", "diverged"])
def test_without_a_spec_or_a_finite_state_the_protocol_keeps_the_full_scene(fault):
    settings = SimSettings()
    closed, settled = _closed(HandKinematics(resolve_hand("parallel_gripper")), settings)
    if fault == "no spec":
        closed = dataclasses.replace(closed, spec=None)
    else:
        settled = dataclasses.replace(settled, state=np.full_like(settled.state, np.nan))
    lean = lean_scene(closed, settled, _reach(settings))
    assert lean.scene is closed.scene and lean.settled is settled
    assert lean.summary["lean"] is False and lean.summary["reason"]


def test_a_lean_scene_that_does_not_hold_the_object_still_settles_again_or_gives_way(tmp_path, monkeypatch):
    """The lean scene must hold the unloaded object as still as the full scene does; where it moves it more,
    it settles again, and where it still does, the protocol keeps the full scene."""
    from ogcp.sim_eval.hand import lean as lean_module

    settings = SimSettings()
    closed, settled = _closed(_three_jaws(tmp_path), settings)
    still = lean_scene(closed, settled, _reach(settings), creep=settings.creep_tolerance)
    assert still.summary["lean"] is True and "settled_again" not in still.summary
    moved = {"calls": 0}
    real_drift = lean_module.unloaded_drift

    def drifting_once(scene, state):  # the lean scene's mapped state moves; settled again, it does not
        moved["calls"] += 1
        return 1.0 if moved["calls"] == 1 else real_drift(scene, state)  # call 2: the full scene

    monkeypatch.setattr(lean_module, "unloaded_drift", drifting_once)
    again = lean_scene(closed, settled, _reach(settings), creep=settings.creep_tolerance)
    assert again.summary["lean"] is True and again.summary["settled_again"] is True
    assert again.settled.state is not settled.state and len(again.settled.pose) == 7
    monkeypatch.setattr(lean_module, "unloaded_drift", lambda scene, state: 0.0 if scene is closed.scene else 1.0)
    kept = lean_scene(closed, settled, _reach(settings), creep=settings.creep_tolerance)
    assert kept.scene is closed.scene and kept.settled is settled and kept.summary["lean"] is False
    assert "even after settling again" in kept.summary["reason"]


def test_a_tendon_from_the_palm_to_a_jaw_keeps_the_palm_welded(tmp_path):
    """A spatial tendon ties the palm's rigid group to a moving jaw: the jaw keeps moving, the palm stays held."""

    def edit(text: str) -> str:
        text = text.replace('<geom name="palm"', '<site name="anchor" pos="0 0.05 0"/><geom name="palm"')
        text = text.replace('<geom name="left"', '<site name="strap_end" pos="0 0 0.03"/><geom name="left"')
        strap = '<tendon><spatial name="strap"><site site="anchor"/><site site="strap_end"/></spatial></tendon>'
        return text.replace("</worldbody>", "</worldbody>" + strap)

    settings = SimSettings()
    closed, settled = _closed(HandKinematics(load_descriptor(write_gripper_variant(tmp_path, edit))), settings)
    assert closed.scene.model.ntendon == 1
    lean = lean_scene(closed, settled, _reach(settings), creep=settings.creep_tolerance)
    assert lean.summary["lean"] is True and lean.summary["welded_joints"] == ["ogcp_mount_free"]
    assert lean.scene.model.ntendon == 1
