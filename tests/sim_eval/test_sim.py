"""MuJoCo validation against closed-form limits, the LP of the same model, and bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval import GraspEvaluator, SimSettings, evaluate_plan
from ogcp.sim_eval.decomposition import Decomposition, DecompositionSettings
from ogcp.sim_eval.protocols.phases import ramp_trials, serial_trials, settle
from ogcp.sim_eval.protocols.predict import predicted_resistance
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.grasp_scene import build_scene

F_MAX = 10.0
MU = 0.5
HULL = DecompositionSettings(method="convex_hull")


def _parts(mesh: trimesh.Trimesh) -> list:
    return [(np.asarray(mesh.vertices), np.asarray(mesh.faces))]


def _ramp(mesh, positions, normals, direction, expected, settings=None, rho=0.1, torsion=0.0):
    """Failure load of one ramp whose rate reaches ``expected`` after settings.ramp_time (soft fingers: torsion > 0)."""
    settings = settings or SimSettings(threads=1)
    com, inertia = object_inertia(mesh, settings.object_mass)
    scene = build_scene(_parts(mesh), com, inertia, positions, normals, settings, MU, 0.008, torsion=torsion)
    settled = settle(scene, settings)
    assert settled.gates["valid"], settled.gates
    d = np.asarray(direction, dtype=float)[None, :]
    trials = ramp_trials(
        scene,
        settled,
        d,
        np.array([expected / settings.ramp_time]),
        settings.ramp_extent * settings.ramp_time,
        rho,
        settings,
    )
    assert trials.failed[0]
    return float(trials.failure_load[0])


def _pinch():
    box = trimesh.creation.box([0.1, 0.08, 0.06])
    return box, np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


def test_pinch_in_its_plane_resists_two_mu_f():
    box, p, n = _pinch()
    expected = 2 * MU * F_MAX
    for direction in ([0, 0, 1, 0, 0, 0], [0, -1, 0, 0, 0, 0]):
        measured = _ramp(box, p, n, direction, expected)
        assert measured == pytest.approx(expected, rel=0.05)


def test_pinch_along_its_axis_resists_the_force_cap():
    # one finger unloads to 0 while the other holds F_max: the per-finger-cap model's limit
    box, p, n = _pinch()
    assert _ramp(box, p, n, [1, 0, 0, 0, 0, 0], F_MAX) == pytest.approx(F_MAX, rel=0.05)


def _sphere_grasp():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.1)
    centres, normals = sphere.triangles_center, sphere.face_normals
    picks = []
    for angle in (0.0, 2 * math.pi / 3, 4 * math.pi / 3):
        target = np.array([math.cos(angle), math.sin(angle), 0.0])
        picks.append(int(np.argmax(normals @ target)))
    return sphere, centres[picks], -normals[picks]


def test_three_tips_on_a_sphere_resist_three_mu_f_tangentially():
    sphere, p, n = _sphere_grasp()
    closed_form = 3 * MU * F_MAX
    predicted = predicted_resistance(p, n, np.zeros(3), 0.1, MU, 32, F_MAX, np.array([[0, 0, 1.0, 0, 0, 0]]))
    assert predicted.resistance[0] == pytest.approx(closed_form, rel=0.05)
    assert _ramp(sphere, p, n, [0, 0, 1, 0, 0, 0], closed_form) == pytest.approx(closed_form, rel=0.05)


def test_rollout_matches_the_serial_step_loop_and_the_ramp_rate_does_not_matter():
    box, p, n = _pinch()
    settings = SimSettings(threads=2)
    com, inertia = object_inertia(box, settings.object_mass)
    scene = build_scene(_parts(box), com, inertia, p, n, settings, MU, 0.008)
    settled = settle(scene, settings)
    dirs = np.array([[0, 0, 1.0, 0, 0, 0], [1.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1.0]])
    rates = np.array([10.0, 10.0, 5.0]) / settings.ramp_time
    batched = ramp_trials(scene, settled, dirs, rates, 6.0, 0.1, settings)
    serial = serial_trials(scene, settled, dirs, rates, 6.0, 0.1, settings)
    np.testing.assert_allclose(batched.failure_load, serial.failure_load, rtol=0, atol=1e-9)
    slow = ramp_trials(scene, settled, dirs, rates / 2, 12.0, 0.1, settings)
    np.testing.assert_allclose(slow.failure_load, batched.failure_load, rtol=0.02)


@pytest.fixture(scope="module")
def box_grasp_result():
    from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts

    mesh = builtin_mesh("box")
    contacts = sample_contacts(mesh, 60, seed=0, source={"kind": "builtin", "name": "box", "diagonal": 0.2})
    best = GraspPlanner().plan(contacts, 3)
    evaluator = GraspEvaluator(SimSettings(directions=24, threads=2), HULL)
    return evaluator.evaluate(mesh, contacts, [best.grasp, (0, 1, 2)], ["best", "other"])


def test_force_closure_box_grasp_matches_its_prediction(box_grasp_result):
    best = box_grasp_result.grasps[0]
    assert best.q1 > 0 and best.valid
    assert best.invalid_reasons == () and len(best.gates["tip_penetration"]) == 3
    assert len(best.measured) == 12 + 24 + 1  # axes, sphere directions, Q1's weakest
    assert best.median_fidelity <= 0.10
    ok = np.isfinite(best.fidelity)
    assert ok.sum() >= 30  # the comparison covers most directions
    # Measured resistance exceeds the LP only by the ramp's overshoot and, for loads with a
    # torque, by the restoring moment finite tips exert as the object turns towards 2 degrees.
    assert np.all(best.measured[ok] <= best.predicted[ok] * 1.12)
    record = box_grasp_result.to_dict()
    assert record["schema"] == "ogcp.sim/2" and record["grasps"][0]["median_fidelity"] == pytest.approx(
        best.median_fidelity
    )
    json.dumps(record, allow_nan=False)  # valid JSON: NaN written as null


def test_weak_grasp_resists_less_than_the_optimal_one(box_grasp_result):
    best, other = box_grasp_result.grasps
    assert other.q1 < best.q1
    assert other.measured_min < best.measured_min


def test_unstable_settings_are_reported_per_grasp_not_raised():
    box, p, n = _pinch()
    contacts = ContactSet(p, n, np.zeros(3), 0.1, MU, 8, {})
    settings = SimSettings(directions=0, threads=1, timestep=0.05, slide_armature=1e-4, tip_mass=1e-3)
    parts = Decomposition(tuple(_parts(box)), {"hull_count": 1})
    result = GraspEvaluator(settings, HULL).evaluate(box, contacts, [(0, 1)], parts=parts)
    grasp = result.grasps[0]
    assert not grasp.valid and (grasp.gates.get("diverged") or grasp.error)
    assert result.set_metrics["n_valid"] == 0


def test_dexgraspbench_mode_and_weight_test_pass_for_a_firm_grasp():
    box, p, n = _pinch()
    # add a third tip on the top face so the grasp is not free to spin about the pinch axis
    p = np.vstack([p, [0.0, 0.0, 0.03]])
    n = np.vstack([n, [0.0, 0.0, -1.0]])
    contacts = ContactSet(p, n, np.zeros(3), 0.1, MU, 8, {})
    parts = Decomposition(tuple(_parts(box)), {"hull_count": 1})
    settings = SimSettings(protocol="dexgraspbench", weight_test=True, threads=2)
    grasp = GraspEvaluator(settings, HULL).evaluate(box, contacts, [(0, 1, 2)], parts=parts).grasps[0]
    assert grasp.hold_tests["dexgraspbench"]["success"] and grasp.hold_tests["weight"]["success"]
    assert grasp.hold_tests["dexgraspbench"]["load"] == pytest.approx(1.0)


def test_plan_with_contacts_off_the_object_is_refused(tmp_path):
    from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts

    mesh = builtin_mesh("box")
    contacts = sample_contacts(mesh, 30, seed=0, source={"kind": "builtin", "name": "box", "diagonal": 0.2})
    record = (
        GraspPlanner()
        .plan(contacts, 3)
        .to_dict({"size": 30, "com": contacts.com.tolist(), "mu": MU, "cone_edges": 8, "source": dict(contacts.source)})
    )
    record["contacts"]["positions"][0][0] += 0.01
    with pytest.raises(OgcpError, match="not on the object"):
        evaluate_plan(record, {"directions": 0}, HULL)


def test_settings_reject_bad_values():
    with pytest.raises(OgcpError, match="max_normal_force"):
        SimSettings(max_normal_force=-1.0)
    with pytest.raises(OgcpError, match="protocol"):
        SimSettings(protocol="shake")
    with pytest.raises(OgcpError, match="valid choices|one of"):
        SimSettings.from_dict({"max_force": 3})
