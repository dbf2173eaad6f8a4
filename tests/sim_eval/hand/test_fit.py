"""The hand fit: pads on contacts within limits, the palm placed, links kept out of the object."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval.hand.fit import LINK_TOLERANCE, RESIDUAL_TOLERANCE, fit_hand, rigid_fit
from ogcp.sim_eval.hand.fit_scene import FitScene
from tests.planner.hands.hand_files import write_gripper_variant, write_mesh_hand


@pytest.fixture(scope="module")
def sdh():
    return HandKinematics(resolve_hand("sdh"))


def _posed_pads(kinematics, angles, rotation, shift, fingers):
    points, normals = kinematics.pads(angles)
    return points[fingers] @ rotation.T + shift, normals[fingers] @ rotation.T


def test_rigid_fit_recovers_a_rotation_and_shift():
    rng = np.random.default_rng(0)
    source = rng.normal(size=(6, 3))
    turn = Rotation.from_rotvec([0.3, -0.5, 0.9]).as_matrix()
    rotation, shift = rigid_fit(source, source @ turn.T + [1.0, 2.0, 3.0])
    np.testing.assert_allclose(rotation, turn, atol=1e-12)
    np.testing.assert_allclose(shift, [1.0, 2.0, 3.0], atol=1e-12)


@pytest.mark.parametrize("hand", ["sdh", "claw"])
def test_a_known_hand_pose_is_recovered_from_another_start(hand, sdh, tmp_path):
    kinematics = sdh if hand == "sdh" else HandKinematics(load_descriptor(write_mesh_hand(tmp_path)))
    rng = np.random.default_rng(1)
    collision_free = [q for q in kinematics.sample(200, 3) if not kinematics.collisions(q[None])[0].any()]
    truth = collision_free[0]
    rotation = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    shift = np.array([0.05, -0.02, 0.3])
    fingers = [0, 1, 2]
    points, normals = _posed_pads(kinematics, truth, rotation, shift, fingers)
    start = np.clip(truth + rng.normal(scale=0.15, size=truth.shape), kinematics.limits[:, 0], kinematics.limits[:, 1])
    fit = fit_hand(FitScene(kinematics), fingers, points, normals, kinematics.complete(start))
    assert fit.realised and fit.residuals.max() < 1e-5 and fit.normal_angles.max() < 1e-3
    assert ((fit.joint_angles >= kinematics.limits[:, 0]) & (fit.joint_angles <= kinematics.limits[:, 1])).all()


def test_a_grasp_the_hand_cannot_span_is_not_realised_and_says_which_finger(sdh):
    points = np.array([[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.5, 0.0]])  # a metre across: beyond the SDH
    normals = -points / np.linalg.norm(points, axis=1, keepdims=True)
    fit = fit_hand(FitScene(sdh), [0, 1, 2], points, normals)
    assert not fit.realised and fit.residuals.max() > 0.1
    assert fit.reason is not None and fit.reason.startswith("finger ") and "cannot reach its contact" in fit.reason
    record = fit.to_dict(sdh.joint_names)
    assert record["realised"] is False and len(record["fit_residuals"]) == 3 and record["joint_names"][0] == "base_1"


def test_a_link_through_the_object_is_caught():
    # The gripper pinches the middle of a wide thin plate: its fingers (70 mm) reach no edge, so
    # every placement puts a link inside the plate.
    gripper = HandKinematics(resolve_hand("parallel_gripper"))
    slab = trimesh.creation.box(extents=(0.3, 0.03, 0.3))
    points = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
    normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    free = fit_hand(FitScene(gripper), [0, 1], points, normals)
    assert free.realised and free.residuals.max() < RESIDUAL_TOLERANCE  # kinematically fine
    scene = FitScene(gripper, [(slab.vertices, slab.faces)])
    scene.pose(free.joint_angles, free.rotation, free.translation)
    assert scene.depths()[0].max() > 0.05  # the kinematic fit puts the palm deep inside the plate
    fit = fit_hand(scene, [0, 1], points, normals)
    # With the plate, the best fit either stays inside it or leaves the contacts: never realised.
    assert not fit.realised and fit.reason is not None
    assert fit.penetration > LINK_TOLERANCE or fit.residuals.max() > RESIDUAL_TOLERANCE


def test_a_plate_edge_within_reach_is_pinched_from_the_side_without_touching_anything_else():
    gripper = HandKinematics(resolve_hand("parallel_gripper"))
    slab = trimesh.creation.box(extents=(0.1, 0.03, 0.03))
    points = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
    normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    fit = fit_hand(FitScene(gripper, [(slab.vertices, slab.faces)]), [0, 1], points, normals)
    assert fit.realised and fit.penetration <= LINK_TOLERANCE
    np.testing.assert_allclose(fit.joint_angles, [0.045 - 0.004 - 0.015 - 0.0] * 2, atol=1e-4)  # each jaw at the face


def test_bad_inputs_are_refused(sdh):
    scene = FitScene(sdh)
    with pytest.raises(OgcpError, match="shape \\(3, 3\\)"):
        fit_hand(scene, [0, 1, 2], np.zeros((2, 3)), np.ones((2, 3)))
    with pytest.raises(OgcpError, match="distinct indices below 3"):
        fit_hand(scene, [0, 0, 2], np.zeros((3, 3)), np.ones((3, 3)))
    with pytest.raises(OgcpError, match="joint prox_1"):
        fit_hand(scene, [0, 1, 2], np.zeros((3, 3)), np.ones((3, 3)), [0, 3, 0, 0, 0, 0, 0, 0])


def test_a_floating_hand_model_is_mounted_without_its_free_joint(tmp_path):
    floating = '<body name="palm" pos="0.1 0.2 0.3"><freejoint name="float"/>'
    descriptor = write_gripper_variant(tmp_path, lambda text: text.replace('<body name="palm">', floating))
    gripper = HandKinematics(load_descriptor(descriptor))
    points = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
    normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    fit = fit_hand(FitScene(gripper), [0, 1], points, normals)
    assert fit.realised and fit.residuals.max() < 1e-6


def test_a_flat_jaw_is_laid_flat_on_contacts_that_are_not_exactly_opposite(tmp_path):
    """Contacts 1.6 mm apart along the faces of a 3.5 cm box: rounded pads reach both and tilt the jaws by
    the line's angle; jaws with a pad_width lie flat, each sliding along its face (anywhere within half its
    width), also where the contacts are 12 mm apart."""
    box = trimesh.creation.box(extents=(0.0466, 0.0466, 0.0466))
    parts = [(box.vertices, box.faces)]
    points = np.array([[0.0, 0.0233, 0.0038], [0.0, -0.0233, 0.0054]])
    normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    rounded = HandKinematics(resolve_hand("parallel_gripper"))
    widened = write_gripper_variant(
        tmp_path,
        lambda text: text,
        lambda text: text.replace("tip_radius = 0.004", "tip_radius = 0.004\npad_width = 0.02"),
    )
    flat = HandKinematics(load_descriptor(widened))
    assert [f.width for f in flat.fingers] == [0.02, 0.02] and [f.width for f in rounded.fingers] == [0.0, 0.0]
    tilted = fit_hand(FitScene(rounded, parts), [0, 1], points, normals)
    laid = fit_hand(FitScene(flat, parts), [0, 1], points, normals)
    assert tilted.realised and laid.realised
    assert np.degrees(tilted.normal_angles.min()) > 1.0 and tilted.residuals.max() < 0.1e-3
    assert np.degrees(laid.normal_angles.max()) < 0.3 and laid.residuals.max() < 1e-6
    apart = points + np.array([[0.0, 0.0, -0.006], [0.0, 0.0, 0.006]])
    slid = fit_hand(FitScene(flat, parts), [0, 1], apart, normals)
    assert slid.realised and np.degrees(slid.normal_angles.max()) < 0.3
    assert not fit_hand(FitScene(flat, parts), [0, 1], points + [[0, 0, -0.015], [0, 0, 0.015]], normals).realised
