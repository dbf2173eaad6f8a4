"""Plans made with a hand are tested with that hand: fitted, closed, gated, ramped, and recorded."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner.grasp import sample_contacts
from ogcp.planner.hands import HandKinematics, resolve_hand
from ogcp.planner.infra import OgcpError
from ogcp.planner.objects import builtin_mesh
from ogcp.sim_eval.decomposition import DecompositionSettings
from ogcp.sim_eval.evaluate import GraspEvaluator, evaluate_plan
from ogcp.sim_eval.hand.setup import HandSetup
from ogcp.sim_eval.result import SimRecord
from tests.planner.hands.hand_files import write_mesh_hand

HULL = {"method": "convex_hull"}


def test_a_plan_with_a_hand_is_closed_by_that_hand_and_recorded(sdh_plan):
    result = evaluate_plan(sdh_plan, {"directions": 4}, HULL)
    (grasp,) = result.grasps
    hand = grasp.hand
    assert hand["name"] == "sdh" and hand["descriptor_sha256"] == sdh_plan["hand"]["descriptor_sha256"]
    assert len(hand["fit_residuals"]) == 3 and max(hand["fit_residuals"]) < 1e-3 and hand["fit"]["realised"]
    assert set(hand["seconds"]) == {"fit", "close", "protocol", "ramps"} and min(hand["seconds"].values()) > 0
    assert hand["seconds"]["ramps"] < hand["seconds"]["protocol"]  # the ramps are part of the protocol
    assert len(hand["joint_angles"]) == len(hand["settled_joint_angles"]) == 8
    assert isinstance(hand["extra_contacts"], list) and sorted(hand["finger_contacts"]) == sorted(grasp.grasp)
    assert grasp.valid and grasp.gates["tips_in_contact"] == 3 and all(grasp.gates["pads_on_contacts"])
    assert (grasp.normal_forces > 0).all()
    assert np.isfinite(grasp.predicted).all() and (grasp.predicted > 0).all()
    assert np.isfinite(grasp.measured).all() and (grasp.measured > 0).all()
    assert result.settings["hand"]["name"] == "sdh"
    read = SimRecord.from_dict(json.loads(json.dumps(result.to_dict()))).grasps[0]
    assert read.hand["fit_residuals"] == pytest.approx(hand["fit_residuals"])


def test_tips_test_the_same_plan_with_fingertip_spheres(sdh_plan):
    (grasp,) = evaluate_plan(sdh_plan, {"directions": 4}, HULL, tips=True).grasps
    assert grasp.hand == {} and "hand" not in grasp.to_dict()


def test_a_grasp_the_hand_cannot_span_is_unreachable_and_not_simulated():
    mesh = builtin_mesh("box", 1.5)  # a 1.5 m box: far wider than the SDH opens
    contacts = sample_contacts(mesh, 30, seed=0)
    setup = HandSetup.of(HandKinematics(resolve_hand("sdh")))
    evaluator = GraspEvaluator(decomposition=DecompositionSettings(method="convex_hull"), hand=setup)
    positions = contacts.positions
    spread = max(
        ((i, j, k) for i in range(30) for j in range(i) for k in range(j)),
        key=lambda g: np.ptp(positions[list(g)], axis=0).sum(),
    )
    (grasp,) = evaluator.evaluate(mesh, contacts, [spread]).grasps
    assert grasp.error is not None and grasp.error.startswith("unreachable for the sdh hand: finger ")
    assert grasp.gates == {"valid": False, "reachable": False} and len(grasp.measured) == 0
    assert grasp.hand["fit"]["realised"] is False and max(grasp.hand["fit_residuals"]) > 0.1


def test_a_hand_nobody_here_wrote_plans_fits_closes_and_evaluates(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_mesh_hand(tmp_path / "hand")
    plan = tmp_path / "plan.json"
    args = ["plan", "sphere", "-n", "40", "-m", "3", "--diagonal", "0.08", "--hand", str(descriptor), "-o", str(plan)]
    assert main(args) == 0
    (grasp,) = evaluate_plan(json.loads(plan.read_text()), {"directions": 4}, HULL).grasps
    assert grasp.hand["name"] == "claw"
    # Either it was closed and ramped, or the fit says exactly why not: never an unexplained error.
    assert grasp.error is None or grasp.error.startswith("unreachable for the claw hand")
    if grasp.error is None:
        assert len(grasp.measured) == len(grasp.directions) and np.isfinite(grasp.predicted).all()


def test_a_changed_descriptor_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_mesh_hand(tmp_path / "hand")
    plan = tmp_path / "plan.json"
    args = ["plan", "sphere", "-n", "30", "-m", "3", "--diagonal", "0.08", "--hand", str(descriptor), "-o", str(plan)]
    assert main(args) == 0
    descriptor.write_text(descriptor.read_text().replace("kp = 4.0", "kp = 6.0"))
    with pytest.raises(OgcpError, match="changed since the plan"):
        evaluate_plan(json.loads(plan.read_text()), {"directions": 4}, HULL)
    assert main(["evaluate", str(plan), "--decomposition", "convex_hull"]) == 2
    err = capsys.readouterr().err
    assert "changed since the plan" in err and err.count("\n") == 1


def test_a_plan_of_the_old_sdh_model_still_reads_and_evaluates(sdh_plan):
    from ogcp.planner.records.plan import PlanView

    old = json.loads(json.dumps(sdh_plan))
    old["hand"] = {  # as written before descriptors: seven angles, no descriptor, no finger names
        "name": "sdh",
        "joint_angles": [0.3, 0.2, 0.5, -0.4, 0.9, 0.7, -0.3],
        "residual": 0.2,
        "reachable": True,
        "finger_contacts": sdh_plan["hand"]["finger_contacts"],
    }
    hand = PlanView(old).hand
    assert hand is not None and hand.descriptor is None and hand.fingers == () and len(hand.joint_angles) == 7
    (grasp,) = evaluate_plan(old, {"directions": 4}, HULL).grasps
    assert grasp.hand["name"] == "sdh" and len(grasp.hand["joint_angles"]) == 8


def test_the_weight_test_runs_with_a_hand(sdh_plan):
    (grasp,) = evaluate_plan(sdh_plan, {"directions": 4, "weight_test": True}, HULL).grasps
    weight = grasp.hold_tests["weight"]
    assert weight["axes"] == ["+x", "-x", "+y", "-y", "+z", "-z"] and len(weight["passed"]) == 6
    assert weight["success"] == all(weight["passed"]) and weight["load"] > 0


def test_dexgraspbenchs_test_runs_on_a_closed_hand(sdh_plan):
    (grasp,) = evaluate_plan(sdh_plan, {"protocol": "dexgraspbench"}, HULL).grasps
    test = grasp.hold_tests["dexgraspbench"]
    assert test["physics"]["timestep"] == pytest.approx(0.004) and test["mu"] == pytest.approx(0.6)
    assert None not in test["passed"] and test["success"] == (test["gates_passed"] and all(test["passed"]))
    assert grasp.hand["squeeze_share"] == 1.0  # their sequence closes once: no ladder of grips
    assert np.isnan(grasp.measured).all()  # their fixed loads replace the ramps, as for fingertips


def test_an_invalid_hand_grasp_not_in_force_closure_says_so_first():
    """Its realised contacts resist no wrench in some direction: that is the first reason, as for fingertips."""
    mesh = builtin_mesh("box", 0.1)
    contacts = sample_contacts(mesh, 30, seed=0)
    setup = HandSetup.of(HandKinematics(resolve_hand("sdh")))
    evaluator = GraspEvaluator(decomposition=DecompositionSettings(method="convex_hull"), hand=setup)
    (grasp,) = evaluator.evaluate(
        mesh, contacts, [(0, 1, 26)]
    ).grasps  # inward normals -y, -z, +z: nothing opposes the first
    assert grasp.hand["fit"]["realised"] and grasp.q1 == 0.0
    assert not grasp.valid and len(grasp.invalid_reasons) >= 2
    first = grasp.invalid_reasons[0]
    assert first["gate"] == "force_closure" and first["message"].startswith(
        "the realized contacts are not in force closure"
    )
