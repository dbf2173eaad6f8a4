"""``--protocol dexgraspbench`` follows DexGraspBench (JYChen18/DexGraspBench@1e7a5a6): physics, gates, checks, AUC."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval import Decomposition, DecompositionSettings, GraspEvaluator, SimSettings
from ogcp.sim_eval.protocols import dexgraspbench as dg
from ogcp.sim_eval.protocols.metrics import binned_roc, roc_auc
from ogcp.sim_eval.protocols.phases import Settled, settle
from ogcp.sim_eval.result import GraspSimResult
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.grasp_scene import build_scene

HULL = DecompositionSettings(method="convex_hull")
BOX = trimesh.creation.box([0.1, 0.08, 0.06])
# A pinch along x and a tip on top: firm against 1 N in every direction (as in test_sim).
FIRM_P = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]])
FIRM_N = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
# Two tips on the same face: no force closure, the object is pushed away.
LOOSE_P = np.array([[0.05, 0.02, 0.0], [0.05, -0.02, 0.0], [0.0, 0.0, 0.03]])
LOOSE_N = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def _evaluate(positions, normals, grasps, **settings):
    contacts = ContactSet(positions, normals, np.zeros(3), 0.1, 0.5, 8, {})
    parts = Decomposition(((np.asarray(BOX.vertices), np.asarray(BOX.faces)),), {"hull_count": 1})
    chosen = SimSettings(protocol="dexgraspbench", threads=2, **settings)
    return GraspEvaluator(chosen, HULL).evaluate(BOX, contacts, grasps, parts=parts)


def _scene(settings: SimSettings, compat: bool = True):
    com, inertia = object_inertia(BOX, settings.body_mass)
    parts = [(np.asarray(BOX.vertices), np.asarray(BOX.faces))]
    torsion = dg.PROTOCOL.torsional_friction if compat else 0.0
    scene = build_scene(parts, com, inertia, FIRM_P, FIRM_N, settings, dg.PROTOCOL.mu, 0.008, torsion=torsion)
    if compat:
        dg.use_object_defaults(scene)
    return scene


# --- physics ------------------------------------------------------------------------------------


def test_the_protocol_fixes_their_step_and_contacts_and_the_default_protocol_keeps_ogcps():
    given = SimSettings(protocol="dexgraspbench", timestep=0.001, noslip_iterations=50, cone="pyramidal")
    compat = dg.physics_settings(given.scaled(0.2))
    assert (compat.timestep, compat.noslip_iterations, compat.cone, compat.impratio) == (0.004, 2, "elliptic", 10.0)
    assert (compat.contact_solref, compat.contact_solimp) == ((0.005, 1.0), (0.5, 0.99, 1e-4))
    # The tips still press with F_max against the softer contacts: their target lies 2 mm deeper.
    depth = compat.target_factor * compat.servo_compliance
    assert depth == pytest.approx(given.target_factor * given.servo_compliance + 2e-3)
    default = SimSettings()
    assert (default.timestep, default.noslip_iterations, default.contact_solref) == (0.002, 30, (0.004, 1.0))
    assert default.contact_solimp == (0.95, 0.99, 1e-4) and default.target_factor == 1.5


def test_the_compiled_model_has_condim_4_torsion_and_their_contact_parameters():
    scene = _scene(dg.physics_settings(SimSettings().scaled(0.2)))
    model = scene.model
    geoms = np.concatenate([scene.tip_geoms, scene.object_geoms])
    assert np.all(model.geom_condim[geoms] == 4)
    np.testing.assert_allclose(model.geom_friction[geoms, :2], [[0.6, 0.02]] * len(geoms))
    np.testing.assert_allclose(model.geom_solref[scene.tip_geoms], [[0.005, 1.0]] * 3)
    np.testing.assert_allclose(model.geom_solimp[scene.tip_geoms, :3], [[0.5, 0.99, 1e-4]] * 3)
    # The object keeps MuJoCo's defaults (solref 0.02, 1; solimp 0.9, 0.95, 1 mm).
    np.testing.assert_allclose(model.geom_solref[scene.object_geoms], [[0.02, 1.0]])
    np.testing.assert_allclose(model.geom_solimp[scene.object_geoms], [[0.9, 0.95, 1e-3, 0.5, 2.0]])
    assert model.opt.timestep == 0.004 and model.opt.noslip_iterations == 2
    # MuJoCo mixes the pair (equal solmix): each tip-object contact gets the mean, as theirs.
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon >= 1
    for contact in data.contact[: data.ncon]:
        assert contact.dim == 4
        np.testing.assert_allclose(contact.solref, [0.0125, 1.0])
        np.testing.assert_allclose(contact.solimp, [0.7, 0.97, 5.5e-4, 0.5, 2.0])


def test_the_resistance_protocol_still_compiles_hard_fingers_with_ogcps_contacts():
    scene = _scene(SimSettings().scaled(0.2), compat=False)
    geoms = np.concatenate([scene.tip_geoms, scene.object_geoms])
    assert np.all(scene.model.geom_condim[geoms] == 3)
    np.testing.assert_allclose(scene.model.geom_solref[geoms], [[0.004, 1.0]] * len(geoms))
    assert scene.model.opt.timestep == 0.002


# --- the test of one grasp ------------------------------------------------------------------------


def test_a_firm_grasp_succeeds_with_per_axis_motion_from_the_initial_pose():
    result = _evaluate(FIRM_P, FIRM_N, [(0, 1, 2)])
    grasp = result.grasps[0]
    test = grasp.hold_tests["dexgraspbench"]
    assert grasp.valid and test["success"] and test["failures"] == []
    assert test["axes"] == ["-x", "+x", "-y", "+y", "-z", "+z"] and test["passed"] == [True] * 6
    assert test["checks"] == 10 and test["check_interval"] == 0.2 and test["reference"] == "initial"
    assert all(0 <= d < 0.05 for d in test["delta_pos"]) and all(0 <= a < 15 for a in test["delta_angle"])
    assert test["reported"]["delta_pos"] == test["delta_pos"][-1]
    physics = test["physics"]
    assert physics["timestep"] == 0.004 and physics["noslip_iterations"] == 2
    assert physics["tip"]["condim"] == 4 and physics["tip"]["friction"][:2] == [0.6, 0.02]
    assert physics["object"]["solref"] == [0.02, 1.0]
    summary = result.set_metrics["dexgraspbench"]
    assert result.set_metrics["n_valid"] == 0  # no resistance is measured in this protocol
    assert (summary["n_evaluated"], summary["n_success"], summary["success_rate"]) == (1, 1, 1.0)


def test_motion_is_measured_from_the_pose_before_the_tips_press(monkeypatch):
    # The preload pushes the object (the top tip is opposed only by friction): that motion
    # counts, as motion while their hand closes does. The loads' rollouts are replaced by the
    # settled pose held still, so all that is measured is the motion while pressing.
    settings = dg.physics_settings(SimSettings(threads=2).scaled(0.2))
    scene = _scene(settings)
    settled = settle(scene, settings)
    initial = scene.model.qpos0[scene.object_qpos : scene.object_qpos + 7]
    shift, turn = dg.delta_qpos(initial, settled.pose)
    assert shift > 1e-4 and settled.gates["valid"]
    monkeypatch.setattr(dg, "hold_poses", lambda *a: np.tile(settled.pose, (6, 500, 1)))
    test = dg.hold_test(scene, settled, settings)
    np.testing.assert_allclose(test["delta_pos"], [shift] * 6, rtol=1e-9)
    np.testing.assert_allclose(test["delta_angle"], [turn] * 6, rtol=1e-9)


def test_a_grasp_failing_an_ogcp_gate_never_succeeds_even_if_it_holds():
    # An impossible creep limit fails the gate; the loads are still held.
    grasp = _evaluate(FIRM_P, FIRM_N, [(0, 1, 2)], creep_tolerance=1e-15).grasps[0]
    test = grasp.hold_tests["dexgraspbench"]
    assert not grasp.valid and test["passed"] == [True] * 6
    assert test["success"] is False and test["gates_passed"] is False
    assert "validity gates" in test["failures"][0]


def test_set_summary_gives_their_success_rate_and_both_aucs():
    positions, normals = np.vstack([FIRM_P, LOOSE_P]), np.vstack([FIRM_N, LOOSE_N])
    result = _evaluate(positions, normals, [(0, 1, 2), (3, 4, 5)])
    firm, loose = (g.hold_tests["dexgraspbench"] for g in result.grasps)
    assert firm["success"] and not loose["success"]
    summary = result.set_metrics["dexgraspbench"]
    assert (summary["n_evaluated"], summary["n_success"], summary["success_rate"]) == (2, 1, 0.5)
    assert summary["source"] == "JYChen18/DexGraspBench@1e7a5a6"
    auc = summary["auc_q1"]
    assert (auc["mann_whitney"], auc["dexgraspbench"], auc["bins"], auc["n"]) == (1.0, 1.0, 2, 2)


def _hold(monkeypatch, poses: np.ndarray | None, **gates):
    settings = dg.physics_settings(SimSettings().scaled(0.2))
    scene = _scene(settings)
    if poses is None:
        monkeypatch.setattr(dg, "hold_poses", lambda *a: pytest.fail("a gated grasp must not be simulated"))
    else:
        monkeypatch.setattr(dg, "hold_poses", lambda *a: poses)
    values = {"initial_penetration": 0.0, "diverged": False, "valid": True, **gates}
    return dg.hold_test(scene, Settled(np.zeros(1), np.zeros(7), values, np.zeros(3)), settings)


def _still(steps: int = 500) -> np.ndarray:
    poses = np.zeros((6, steps, 7))
    poses[..., 3] = 1.0
    return poses


def test_limits_are_checked_every_0_2_s_only(monkeypatch):
    poses = _still()
    poses[0, 48, 0] = 0.2  # -x: 20 cm one step before its first check: not seen, as theirs
    poses[1, 49, 0] = 0.06  # +x: 6 cm at the first check (step 50 = 0.2 s): fails there
    poses[1, 99:, 0] = 0.01
    test = _hold(monkeypatch, poses)
    assert test["passed"] == [True, False, True, True, True, True]
    assert test["delta_pos"][1] == pytest.approx(0.06)
    assert test["reported"]["delta_pos"] == pytest.approx(0.06) and not test["success"]


def test_rotation_is_measured_as_theirs(monkeypatch):
    poses = _still()
    half = math.radians(16.0) / 2
    poses[4, 199:, 3:7] = [math.cos(half), 0.0, 0.0, math.sin(half)]  # -z: 16 degrees from 0.8 s on
    test = _hold(monkeypatch, poses)
    assert test["passed"] == [True, True, True, True, False, True]
    assert test["delta_angle"][4] == pytest.approx(16.0)


def test_grasps_starting_more_than_1_cm_inside_fail_unsimulated(monkeypatch):
    test = _hold(monkeypatch, None, initial_penetration=0.0101)
    assert not test["success"] and not test["penetration_passed"] and test["passed"] == [None] * 6
    assert test["reported"] == {"delta_pos": 100.0, "delta_angle": 100.0}
    assert "10.1 mm inside" in test["failures"][-1]
    assert _hold(monkeypatch, _still(), initial_penetration=0.01)["penetration_passed"]


def test_a_diverged_grasp_fails_unsimulated(monkeypatch):
    test = _hold(monkeypatch, None, diverged=True, valid=False)
    assert not test["success"] and test["failures"] == ["the simulation diverged while the tips pressed"]


# --- their measures --------------------------------------------------------------------------------


def test_delta_qpos_is_their_distance_and_angle():
    reference = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    half = math.radians(90.0) / 2
    pose = np.array([0.03, 0.04, 0.0, math.cos(half), math.sin(half), 0.0, 0.0])
    shift, angle = dg.delta_qpos(reference, pose)
    assert shift == pytest.approx(0.05) and angle == pytest.approx(90.0)
    # w rounded above 1 counts as no rotation (their clamp), not as NaN.
    assert dg.delta_qpos(reference, np.array([0, 0, 0, 1 + 1e-12, 0, 0, 0]))[1] == 0.0


def test_axis_loads_are_their_directions_in_their_order():
    loads = dg.axis_loads(1.0)
    np.testing.assert_array_equal(loads[:, :3], [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]])
    assert not loads[:, 3:].any()


def test_binned_roc_follows_their_groups_and_trapezoid():
    energy = np.array([0.1, 0.2, 0.3, 0.4, 0.5])
    success = np.array([True, False, True, False, False])
    roc = binned_roc(energy, success, max_bins=2)  # groups of 3 and 2
    np.testing.assert_allclose(roc.tpr, [0.0, 1.0, 1.0])
    np.testing.assert_allclose(roc.fpr, [0.0, 1 / 3, 1.0])
    np.testing.assert_allclose(roc.thresholds, [0.1, 0.4, 0.5])
    assert roc.auc == pytest.approx(5 / 6)
    # One group: the diagonal, whatever the scores; Mann-Whitney still ranks every pair.
    assert binned_roc(energy, success, max_bins=1).auc == pytest.approx(0.5)
    assert roc_auc(-energy, success) == pytest.approx(5 / 6)


def test_binned_roc_equals_mann_whitney_for_few_distinct_scores_and_differs_on_ties():
    rng = np.random.default_rng(0)
    scores = rng.normal(size=80)
    success = rng.random(80) < 0.4
    assert binned_roc(-scores, success).auc == pytest.approx(roc_auc(scores, success))
    tied = np.array([0.0, 0.0, 1.0])
    flags = np.array([False, True, True])
    assert roc_auc(tied, flags) == pytest.approx(0.75)
    assert binned_roc(-tied, flags).auc in (0.5, 1.0)  # their order of ties decides


def test_binned_roc_of_250_grasps_uses_100_groups_the_larger_first_and_one_class_is_nan():
    energy = np.arange(250.0)
    roc = binned_roc(energy, energy % 3 == 0)
    # 250 = 50 groups of 3, then 50 of 2; the last threshold is the last grasp's.
    assert len(roc.tpr) == 101 and list(roc.thresholds[[1, 50, 51, 100]]) == [3.0, 150.0, 152.0, 249.0]
    assert math.isnan(binned_roc(energy, np.ones(250, dtype=bool)).auc)
    with pytest.raises(OgcpError, match="at least one grasp"):
        binned_roc([], [])
    with pytest.raises(OgcpError, match="max_bins >= 1"):
        binned_roc(energy, energy > 1, max_bins=0)


def test_set_summary_counts_unreachable_as_failures_and_errors_apart():
    def result(q1: float, success: bool | None, error: str | None = None, unreachable=()) -> GraspSimResult:
        empty = np.zeros(0)
        tests = {} if success is None else {"dexgraspbench": {"success": success, "gates_passed": success}}
        return GraspSimResult(
            (0, 1, 2), "g", q1, np.zeros((0, 6)), (), empty, empty, np.zeros(0, bool), empty, {}, empty, empty,
            tests, error, unreachable,
        )  # fmt: skip

    results = [result(0.3, True), result(0.1, False), result(0.2, None, "unreachable", (1,)), result(0.5, None, "x")]
    summary = dg.set_summary(results)
    assert (summary["n_evaluated"], summary["n_success"], summary["n_errors"], summary["n_unreachable"]) == (3, 1, 1, 1)
    assert summary["success_rate"] == pytest.approx(1 / 3) and summary["n_gates_failed"] == 1
    assert summary["auc_q1"]["mann_whitney"] == 1.0 == summary["auc_q1"]["dexgraspbench"]


def test_a_check_interval_that_is_not_whole_steps_is_an_error():
    with pytest.raises(OgcpError, match="not a whole number"):
        dg._steps(0.2, 0.003, "check interval")
