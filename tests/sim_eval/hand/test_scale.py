"""Hands nobody here wrote: a gripper scaled with its object from 5 cm to 1.2 m, a hand with a shared
spread joint, hands laid out as other projects write them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.sim_eval.hand.fit import LINK_TOLERANCE, RESIDUAL_TOLERANCE, HandFit, tolerance_scale
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.settings import REFERENCE_DIAGONAL
from tests.planner.hands.hand_files import (
    write_gripper_variant,
    write_scaled_gripper,
    write_side_by_side_gripper,
    write_spread_hand,
)


def test_the_fits_tolerances_grow_with_objects_past_the_reference_as_the_gates_do():
    assert tolerance_scale(0.05) == tolerance_scale(REFERENCE_DIAGONAL) == 1.0
    assert tolerance_scale(1.2) == pytest.approx(6.0)
    fit = HandFit(
        joint_angles=np.zeros(2),
        rotation=np.eye(3),
        translation=np.zeros(3),
        fingers=(0, 1),
        residuals=np.array([3e-3, 0.0]),
        normal_angles=np.zeros(2),
        penetration=2.5e-3,
        self_penetration=0.0,
        worst_link=None,
        finger_names=("left", "right"),
    )
    assert not fit.realised and "tolerance 1 mm" in str(fit.reason)
    large = HandFit(**{**fit.__dict__, "length_scale": tolerance_scale(1.2)})
    assert large.realised
    assert (large.tolerance, large.link_tolerance) == pytest.approx((6 * RESIDUAL_TOLERANCE, 6 * LINK_TOLERANCE))
    with pytest.raises(ValueError, match="length_scale must be a positive number"):
        FitScene(None, (), 0.0)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("factor", "diagonal", "force", "flat"),
    [(0.4, 0.05, 5.0, True), (15.0, 1.2, 200.0, False)],
    ids=["36 mm flat jaws on a 5 cm box", "1.35 m round jaws on a 1.2 m box"],
)
def test_a_gripper_scaled_with_its_object_plans_fits_closes_and_holds(
    capsys, tmp_path, monkeypatch, factor, diagonal, force, flat
):
    """The built-in gripper scaled with its object (20,000 N/m servos): the plan's grasp spans no
    more than the jaws open (the 5 cm box is 39 mm long where they open 33 mm), the fit realises it
    within tolerances that grow past 0.2 m (round 1.35 m jaws tilted 1.4 degrees to opposite
    contacts leave 2.5-4 mm), and the hand holds it."""
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    (tmp_path / "hand").mkdir()
    descriptor = write_scaled_gripper(
        tmp_path / "hand", factor, kp=20000.0, force=force, pad_width=0.02 * factor if flat else None
    )
    plan, sim = tmp_path / "plan.json", tmp_path / "sim.json"
    common = ["-n", "60", "-m", "2", "--diagonal", str(diagonal), "--contact-model", "soft"]
    assert main(["plan", "box", *common, "--hand", str(descriptor), "-o", str(plan)]) == 0
    assert main(["evaluate", str(plan), "--directions", "4", "-o", str(sim)]) == 0
    capsys.readouterr()
    (grasp,) = json.loads(sim.read_text())["grasps"]
    assert grasp["hand"]["fit"]["realised"], grasp["hand"]["fit"]["reason"]
    assert grasp["hand"]["fit"]["tolerance"] == pytest.approx(RESIDUAL_TOLERANCE * tolerance_scale(diagonal))
    assert grasp["valid"], grasp.get("invalid_reasons")
    assert np.nanmedian(np.asarray(grasp["fidelity"], dtype=float)) < 0.3


def test_a_hand_whose_two_fingers_share_a_spread_joint_plans_fits_closes_and_holds(capsys, tmp_path, monkeypatch):
    """A Barrett-like hand written from a description: one joint equality ties two fingers' spread."""
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_spread_hand(tmp_path)
    plan, sim = tmp_path / "plan.json", tmp_path / "sim.json"
    args = ["plan", "sphere", "-n", "40", "-m", "3", "--diagonal", "0.12", "--hand", str(descriptor), "-o", str(plan)]
    assert main(args) == 0
    assert main(["evaluate", str(plan), "--directions", "4", "-o", str(sim)]) == 0
    capsys.readouterr()
    (grasp,) = json.loads(sim.read_text())["grasps"]
    assert grasp["hand"]["fit"]["realised"], grasp["hand"]["fit"]["reason"]
    angles = dict(zip(grasp["hand"]["fit"]["joint_names"], grasp["hand"]["fit"]["joint_angles"], strict=True))
    assert angles["j21"] == pytest.approx(angles["j11"], abs=1e-6)  # the equality holds in the fit
    assert grasp["valid"], grasp.get("invalid_reasons")
    assert np.nanmedian(np.asarray(grasp["fidelity"], dtype=float)) < 0.3


@pytest.mark.parametrize("layout", ["side by side", "mocap palm"])
def test_a_hand_laid_out_as_other_projects_write_them_plans_fits_closes_and_holds(
    capsys, tmp_path, monkeypatch, layout
):
    """Menagerie's DEX-EE puts its palm and fingers on the world side by side: gathered below one body
    and mounted. A teleoperation scene moves the palm as a mocap body: the mount moves it instead
    (before, MuJoCo refused the scene in two lines)."""
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    if layout == "side by side":
        descriptor = write_side_by_side_gripper(tmp_path)
    else:
        descriptor = write_gripper_variant(
            tmp_path, lambda text: text.replace('<body name="palm">', '<body name="palm" mocap="true">')
        )
    plan, sim = tmp_path / "plan.json", tmp_path / "sim.json"
    common = ["-n", "60", "-m", "2", "--diagonal", "0.08", "--contact-model", "soft"]
    assert main(["plan", "box", *common, "--hand", str(descriptor), "-o", str(plan)]) == 0
    assert main(["evaluate", str(plan), "--directions", "4", "-o", str(sim)]) == 0
    capsys.readouterr()
    (grasp,) = json.loads(sim.read_text())["grasps"]
    assert grasp.get("error") is None, grasp["error"]
    assert grasp["hand"]["fit"]["realised"], grasp["hand"]["fit"]["reason"]
    assert grasp["valid"], grasp.get("invalid_reasons")
    assert np.nanmedian(np.asarray(grasp["fidelity"], dtype=float)) < 0.3
