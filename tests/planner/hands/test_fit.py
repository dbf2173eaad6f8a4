"""SDH inverse kinematics: the refined pose puts the fingertips on reachable contacts, within the joint limits."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ogcp.planner.hands import JOINT_LIMITS, forward_kinematics, random_configurations
from ogcp.planner.hands.fit import HandFit, evaluate_fit, fit_hand, rigid_fit
from ogcp.planner.hands.reachability import SDHReachability, self_collision_free
from ogcp.planner.infra import OgcpError

RADIUS = 0.0095  # the drawn finger's radius [m]


def posed_grasp(q: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Contacts one finger radius beyond the tips of configuration ``q`` in a random palm pose."""
    rng = np.random.default_rng(seed)
    tips, pads = forward_kinematics(q)
    rotation = Rotation.random(random_state=rng).as_matrix()
    normals = pads @ rotation.T
    return tips @ rotation.T + rng.normal(scale=0.1, size=3) + RADIUS * normals, normals


def test_rigid_fit_recovers_a_proper_rotation_and_translation():
    rng = np.random.default_rng(0)
    source = rng.normal(size=(6, 3))
    turn = Rotation.random(random_state=rng).as_matrix()
    rotation, translation = rigid_fit(source, source @ turn.T + [1.0, 2.0, 3.0])
    np.testing.assert_allclose(rotation, turn, atol=1e-12)
    np.testing.assert_allclose(translation, [1.0, 2.0, 3.0], atol=1e-12)


def test_a_reachable_grasp_is_met_from_perturbed_angles():
    configurations = random_configurations(60, 3)
    configurations = configurations[self_collision_free(configurations)][:12]
    rng = np.random.default_rng(7)
    for k, q in enumerate(configurations):
        points, normals = posed_grasp(q, k)
        start = np.clip(q + rng.normal(scale=0.15, size=7), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        before = evaluate_fit(
            start, *rigid_fit(forward_kinematics(start).positions, points - RADIUS * normals), points, normals, RADIUS
        )
        fit = fit_hand(points, normals, start, offset=RADIUS)
        assert isinstance(fit, HandFit) and fit.residuals.shape == (3,)
        assert fit.max_residual < 1e-5 < before.max_residual  # micrometres, not the start's millimetres
        assert np.all(np.degrees(fit.normal_angles) < 1.0)
        assert np.all((JOINT_LIMITS[:, 0] <= fit.joint_angles) & (fit.joint_angles <= JOINT_LIMITS[:, 1]))
        # The residuals are those of the returned angles and pose, recomputed.
        tips = fit.to_world(forward_kinematics(fit.joint_angles).positions)
        np.testing.assert_allclose(
            np.linalg.norm(tips - (points - RADIUS * normals), axis=1), fit.residuals, atol=1e-12
        )


@pytest.fixture(scope="module")
def hand(tmp_path_factory) -> SDHReachability:
    return SDHReachability(samples=4000, seed=1, threshold=0.35, cache_dir=tmp_path_factory.mktemp("cache"))


def test_recorded_angles_of_reachable_grasps_are_refined_onto_the_contacts(hand, object_contacts):
    """The reachability model's nearest sample, placed rigidly, misses by millimetres; the fit does not."""
    contacts = object_contacts("donut", 24, 4)
    reachable = [g for g in itertools.combinations(range(24), 3) if hand.accepts(g, contacts)][:8]
    assert len(reachable) >= 4
    for grasp in reachable:
        reach = hand.reach(grasp, contacts)
        index = [grasp[i] for i in reach.fingers]
        points, normals = contacts.positions[index], contacts.normals[index]
        angles = np.array(reach.joint_angles)
        tips = forward_kinematics(angles).positions
        rigid = evaluate_fit(angles, *rigid_fit(tips, points - RADIUS * normals), points, normals, RADIUS)
        fit = fit_hand(points, normals, angles, offset=RADIUS)
        assert rigid.max_residual > 3e-3  # the old drawing: the recorded angles, rigidly placed
        assert fit.max_residual < 2e-3, (grasp, fit.residuals)


def test_bad_inputs_are_refused_in_one_line():
    points, normals = posed_grasp(np.full(7, 0.3), 0)
    with pytest.raises(OgcpError, match="3 contacts"):
        fit_hand(points[:2], normals[:2], np.zeros(7))
    with pytest.raises(OgcpError, match="7 joint angles"):
        fit_hand(points, normals, np.zeros(6))
    with pytest.raises(OgcpError, match="finite"):
        fit_hand(points * np.nan, normals, np.zeros(7))
    with pytest.raises(OgcpError, match="normal_weight"):
        fit_hand(points, normals, np.zeros(7), normal_weight=-1.0)
