"""Every invalid grasp says why: which gate, which finger, by how much, and what to change."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.sim_eval import Decomposition, DecompositionSettings, GraspEvaluator, SimGraspRecord, SimSettings
from ogcp.sim_eval.protocols.gates import CONTACT_FRACTION, gate_failures

SETTINGS = SimSettings()
PASSING = {"initial_penetration": 2e-4, "tip_penetration": [2e-4, 1e-4, 0.0], "creep": 1e-6, "diverged": False}
FORCES = [10.0, 9.0, 8.0]


def test_a_grasp_that_passes_every_gate_has_no_reason():
    assert gate_failures(PASSING, FORCES, SETTINGS) == ()


def test_penetration_names_the_finger_and_the_depth_against_the_limit():
    gates = {**PASSING, "tip_penetration": [2e-4, 3.5e-3, 0.0]}
    (failure,) = gate_failures(gates, FORCES, SETTINGS)
    assert (failure.gate, failure.finger, failure.value, failure.limit) == (
        "penetration",
        1,
        3.5e-3,
        SETTINGS.penetration_tolerance,
    )
    assert failure.message.startswith("finger 1 starts 3.50 mm inside the collision parts (limit 1.00 mm)")
    assert "--threshold" in failure.message and "--tip-radius" in failure.message


def test_a_tip_without_force_and_creep_are_both_reported():
    gates = {**PASSING, "creep": 4.2e-3}
    failures = gate_failures(gates, [10.0, 0.0, 10.0], SETTINGS)
    assert [(f.gate, f.finger) for f in failures] == [("creep", None), ("contact", 1)]
    assert "drifts 4.20 mm" in failures[0].message and "(limit 20 um)" in failures[0].message
    assert failures[1].limit == pytest.approx(CONTACT_FRACTION * SETTINGS.max_normal_force)


def test_divergence_is_the_only_reason_it_gives():
    gates = {**PASSING, "diverged": True, "creep": np.inf}
    (failure,) = gate_failures(gates, [0.0, 0.0, 0.0], SETTINGS)
    assert failure.gate == "diverged" and "timestep" in failure.message


def test_reasons_round_trip_through_the_sim_record():
    failures = gate_failures({**PASSING, "tip_penetration": [5e-3, 0.0, 0.0]}, FORCES, SETTINGS)
    entry = {"label": "best", "invalid_reasons": [f.to_dict() for f in failures]}
    assert SimGraspRecord.from_dict(entry).invalid_reasons == (failures[0].message,)
    assert SimGraspRecord.from_dict({"label": "old record"}).invalid_reasons == ()


def test_collision_parts_standing_proud_move_the_tip_out_and_are_reported_on_that_finger():
    box = trimesh.creation.box([0.1, 0.08, 0.06])
    proud = trimesh.creation.box([0.1, 0.08, 0.066])  # the top of the part is 3 mm above the mesh's
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    positions = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]])
    contacts = ContactSet(positions, normals, np.zeros(3), 0.1, 0.5, 8, {})
    parts = Decomposition(((np.asarray(proud.vertices), np.asarray(proud.faces)),), {"hull_count": 1})
    settings = SimSettings(directions=0, threads=1)
    result = GraspEvaluator(settings, DecompositionSettings(method="convex_hull")).evaluate(
        box, contacts, [(0, 1, 2)], parts=parts
    )
    grasp = result.grasps[0]
    # The top tip starts on the part, 3 mm above the planned contact, not 3 mm inside it.
    assert grasp.error is None and grasp.valid and grasp.gates["initial_penetration"] < 1e-6
    np.testing.assert_allclose(grasp.realized["offsets"], [0.0, 0.0, 3e-3], atol=1e-6)
    np.testing.assert_allclose(grasp.realized["travel"], [0.0, 0.0, 3e-3], atol=1e-6)
    np.testing.assert_allclose(grasp.collision["offsets"], [0.0, 0.0, -3e-3], atol=1e-9)
    assert grasp.collision["within_tolerance"] is False
    assert "finger 2" in grasp.collision["note"] and "3 mm" in grasp.collision["note"]
    assert result.set_metrics["n_outside_collision_tolerance"] == 1


def test_a_grasp_out_of_force_closure_says_so_before_its_gates():
    box = trimesh.creation.box([0.1, 0.08, 0.06])
    # Three tips on one face and its neighbour: nothing pushes back along +x.
    normals = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
    positions = np.array([[0.02, 0.02, 0.03], [-0.02, -0.02, 0.03], [0.05, 0.0, 0.0]])
    contacts = ContactSet(positions, normals, np.zeros(3), 0.1, 0.5, 8, {})
    parts = Decomposition(((np.asarray(box.vertices), np.asarray(box.faces)),), {"hull_count": 1})
    result = GraspEvaluator(SimSettings(directions=0, threads=1), DecompositionSettings(method="convex_hull")).evaluate(
        box, contacts, [(0, 1, 2)], parts=parts
    )
    grasp = result.grasps[0]
    assert not grasp.valid
    first = grasp.invalid_reasons[0]
    assert first["gate"] == "force_closure" and "not in force closure" in first["message"]
    assert len(grasp.invalid_reasons) > 1  # the gates that failed follow
