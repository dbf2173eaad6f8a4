"""Schunk SDH model: the numpy kinematics against MuJoCo on the MJCF, geometry and validation."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from ogcp.planner.hands import (
    FINGER_BASES,
    JOINT_LIMITS,
    JOINT_NAMES,
    MJCF_JOINT_INDEX,
    TIP_SITES,
    forward_kinematics,
    random_configurations,
    sdh,
    sdh_model_path,
)
from ogcp.planner.infra import OgcpError

TIP_HEIGHT = 0.0745 + 0.0165 + 0.0865 + 0.0685


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(sdh_model_path()))


def mujoco_tips(model: mujoco.MjModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fingertip site positions and x axes from MuJoCo for one 7-vector configuration."""
    data = mujoco.MjData(model)
    for name, index in MJCF_JOINT_INDEX.items():
        data.qpos[model.joint(name).qposadr[0]] = q[index]
    mujoco.mj_kinematics(model, data)
    sites = [model.site(name).id for name in TIP_SITES]
    return data.site_xpos[sites].copy(), data.site_xmat[sites][:, [0, 3, 6]].copy()


def horizontal_distance(points: np.ndarray) -> np.ndarray:
    return np.linalg.norm(points[..., :2], axis=-1)


# ---------------------------------------------------------------- the MJCF


def test_mjcf_joints_sites_and_coupling_match_the_numpy_model(model):
    assert sorted(model.joint(i).name for i in range(model.njnt)) == sorted(MJCF_JOINT_INDEX)
    for name, index in MJCF_JOINT_INDEX.items():
        joint = model.joint(name)
        assert joint.type[0] == mujoco.mjtJoint.mjJNT_HINGE
        assert joint.limited[0] == 1
        np.testing.assert_allclose(joint.range, JOINT_LIMITS[index], atol=1e-15)
    assert all(model.site(name).id >= 0 for name in TIP_SITES)
    # Both base joints take the same value: q(base_2) = 0 + 1 * q(base_1).
    assert model.neq == 1 and model.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT
    assert model.joint(int(model.eq_obj1id[0])).name == "base_2"
    assert model.joint(int(model.eq_obj2id[0])).name == "base_1"
    np.testing.assert_array_equal(model.eq_data[0, :5], [0, 1, 0, 0, 0])


def test_mjcf_hand_geoms_collide_with_objects_but_not_with_each_other(model):
    contype, conaffinity = model.geom_contype, model.geom_conaffinity
    assert np.all(contype & conaffinity[:, None] == 0)  # every hand-hand pair
    assert np.all((contype | conaffinity) & 1)  # MuJoCo's default object geom is 1 / 1


def test_model_path_missing_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(sdh, "_MODEL_ASSET", "hands/missing.xml")
    with pytest.raises(OgcpError, match="hands/missing.xml not found"):
        sdh_model_path()


# ---------------------------------------------------------------- kinematics


def test_forward_kinematics_equals_mujoco_on_random_configurations(model):
    configurations = random_configurations(200, seed=7)
    # The limits themselves are the likeliest place for a sign or range slip.
    corners = np.array(list(itertools.product(*JOINT_LIMITS[[0, 1, 2]])))
    extremes = np.zeros((len(corners), 7))
    extremes[:, [0, 1, 2]] = corners
    extremes[:, [3, 4]] = corners[:, 1:]
    extremes[:, [5, 6]] = corners[:, 1:][::-1]
    configurations = np.vstack([configurations, extremes])
    positions, normals = forward_kinematics(configurations)
    assert positions.shape == normals.shape == (len(configurations), 3, 3)
    for q, p, n in zip(configurations, positions, normals):
        site_p, site_x = mujoco_tips(model, q)
        np.testing.assert_allclose(p, site_p, rtol=0, atol=1e-9)
        np.testing.assert_allclose(n, site_x, rtol=0, atol=1e-9)


def test_batch_equals_single_configurations():
    configurations = random_configurations(5, seed=3)
    batch = forward_kinematics(configurations)
    for i, q in enumerate(configurations):
        single = forward_kinematics(q)
        assert single.positions.shape == (3, 3)
        np.testing.assert_allclose(single.positions, batch.positions[i], rtol=0, atol=1e-15)
        np.testing.assert_allclose(single.normals, batch.normals[i], rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(batch.normals, axis=-1), 1.0, rtol=0, atol=1e-12)
    assert not batch.positions.flags.writeable


def test_zero_configuration_points_every_finger_straight_up():
    positions, normals = forward_kinematics(np.zeros(7))
    np.testing.assert_allclose(positions[:, 2], TIP_HEIGHT, rtol=0, atol=1e-12)
    np.testing.assert_allclose(positions[:, :2], FINGER_BASES[:, :2], rtol=0, atol=1e-12)
    assert np.all(positions[:, 2] > FINGER_BASES[:, 2])
    # Pads face the palm axis: horizontal, along minus the base's horizontal position.
    inward = -FINGER_BASES[:, :2] / np.linalg.norm(FINGER_BASES[:, :2], axis=1, keepdims=True)
    np.testing.assert_allclose(normals[:, :2], inward, rtol=0, atol=1e-12)
    np.testing.assert_allclose(normals[:, 2], 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("finger", range(3))
@pytest.mark.parametrize("flexion", [0.1, 0.3, 0.5])
def test_positive_proximal_flexion_moves_the_tip_toward_the_palm_axis(finger, flexion):
    # Only up to ~0.51 rad: the fingers are long enough (0.155 m against a base 0.038 m
    # from the axis) that larger flexions carry the tip across the palm axis.
    q = np.zeros(7)
    q[1 + 2 * finger] = flexion
    before = horizontal_distance(forward_kinematics(np.zeros(7)).positions[finger])
    after = horizontal_distance(forward_kinematics(q).positions[finger])
    assert after < before
    q[1 + 2 * finger] = -flexion
    assert horizontal_distance(forward_kinematics(q).positions[finger]) > before


@pytest.mark.parametrize("finger", range(3))
def test_proximal_flexion_always_moves_the_tip_inward(finger):
    flexions = np.linspace(0.0, np.pi / 2, 50)
    q = np.zeros((len(flexions), 7))
    q[:, 1 + 2 * finger] = flexions
    tips = forward_kinematics(q).positions[:, finger]
    inward = -FINGER_BASES[finger, :2] / np.linalg.norm(FINGER_BASES[finger, :2])
    travel = (tips[:, :2] - FINGER_BASES[finger, :2]) @ inward
    assert np.all(np.diff(travel) > 0)


def test_positive_distal_flexion_turns_the_pad_down_and_in():
    q = np.zeros(7)
    q[[2, 4, 6]] = 0.5
    positions, normals = forward_kinematics(q)
    assert np.all(normals[:, 2] < 0)
    assert np.all(horizontal_distance(positions) < horizontal_distance(FINGER_BASES))


def test_rotating_fingers_mirror_each_other_about_the_xz_plane():
    rng = np.random.default_rng(11)
    q = random_configurations(100, seed=5)
    q[:, [3, 4]] = q[:, [1, 2]]
    q[:3, 0] = [0.0, np.pi / 4, np.pi / 2]
    positions, normals = forward_kinematics(q)
    mirror = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(positions[:, 1], positions[:, 0] * mirror, rtol=0, atol=1e-12)
    np.testing.assert_allclose(normals[:, 1], normals[:, 0] * mirror, rtol=0, atol=1e-12)
    # The base angle turns finger 1 counter-clockwise (seen from +z) and finger 2 clockwise.
    base = np.zeros(7)
    base[0] = rng.uniform(0.2, 1.4)
    turned = forward_kinematics(base).normals
    flat = forward_kinematics(np.zeros(7)).normals
    cross_z = flat[:, 0] * turned[:, 1] - flat[:, 1] * turned[:, 0]
    np.testing.assert_allclose(cross_z, [np.sin(base[0]), -np.sin(base[0]), 0.0], rtol=0, atol=1e-12)


def test_finger_bases_form_an_equilateral_triangle_around_the_palm_axis():
    sides = [np.linalg.norm(FINGER_BASES[i] - FINGER_BASES[j]) for i, j in ((0, 1), (1, 2), (2, 0))]
    np.testing.assert_allclose(sides, 0.066, rtol=0, atol=1e-3)
    np.testing.assert_allclose(FINGER_BASES.mean(axis=0)[:2], 0.0, rtol=0, atol=1e-4)
    np.testing.assert_allclose(FINGER_BASES[:, 2], 0.0745, rtol=0, atol=0)


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize("shape", [(6,), (8,), (7, 1), (2, 3, 7), ()])
def test_wrong_shape_is_rejected(shape):
    with pytest.raises(OgcpError, match=r"shape \(7,\) or \(B, 7\).*base, prox_1"):
        forward_kinematics(np.zeros(shape))


def test_non_numbers_and_non_finite_values_are_rejected():
    with pytest.raises(OgcpError, match="must be numbers"):
        forward_kinematics(["a"] * 7)
    q = np.zeros((3, 7))
    q[2, 4] = np.nan
    with pytest.raises(OgcpError, match="dist_2 is nan in configuration 2"):
        forward_kinematics(q)
    q[2, 4] = 0.0
    q[0, 5] = np.inf
    with pytest.raises(OgcpError, match="prox_3 is inf"):
        forward_kinematics(q)


@pytest.mark.parametrize("joint", range(7))
def test_joint_outside_its_range_names_the_joint(joint):
    low, high = JOINT_LIMITS[joint]
    for value in (low - 0.01, high + 0.01):
        q = np.zeros(7)
        q[joint] = value
        with pytest.raises(OgcpError, match=rf"joint {JOINT_NAMES[joint]} = .* outside its range \[") as info:
            forward_kinematics(q)
        assert "\n" not in str(info.value)


def test_limit_overshoot_within_tolerance_is_accepted():
    q = JOINT_LIMITS[:, 1].astype(np.float32).astype(float)  # float32 rounds pi/2 up
    forward_kinematics(q)
    forward_kinematics(JOINT_LIMITS[:, 0] - 1e-8)


def test_input_is_not_modified():
    q = random_configurations(4, seed=2)
    copy = q.copy()
    forward_kinematics(q)
    np.testing.assert_array_equal(q, copy)


# ---------------------------------------------------------------- random configurations


def test_random_configurations_are_seeded_and_within_limits():
    first = random_configurations(500, seed=42)
    assert first.shape == (500, 7)
    np.testing.assert_array_equal(first, random_configurations(500, seed=42))
    assert not np.array_equal(first, random_configurations(500, seed=43))
    assert np.all(first >= JOINT_LIMITS[:, 0]) and np.all(first <= JOINT_LIMITS[:, 1])
    # Uniform over the whole range, not a corner of it.
    assert np.all(first.min(axis=0) < JOINT_LIMITS[:, 0] + 0.1)
    assert np.all(first.max(axis=0) > JOINT_LIMITS[:, 1] - 0.1)
    assert random_configurations(0, seed=1).shape == (0, 7)


@pytest.mark.parametrize(("count", "seed"), [(-1, 0), (2.5, 0), (True, 0), ("3", 0), (3, -1), (3, float("nan"))])
def test_random_configurations_reject_invalid_arguments(count, seed):
    with pytest.raises(OgcpError, match="must be a non-negative integer"):
        random_configurations(count, seed)
