"""Hand grasps another planner posed (ogcp.grasps/1 hand blocks, DexGraspBench records), simulated as ogcp's own."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.benchmarks.studies import convert_dexgraspbench
from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.planner.infra import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.grasps import ExternalGrasps, load_grasps, save_grasps
from ogcp.planner.records.hand_poses import HandStage
from ogcp.sim_eval.external import evaluate_grasps
from ogcp.sim_eval.hand.given import pad_points, resolve_pose, resolve_stage
from ogcp.sim_eval.hand.root_pose import model_joints, root_qpos, stage_from_root_qpos
from ogcp.sim_eval.settings import SimSettings
from tests.planner.hands.hand_files import write_mesh_hand

DIAGONAL = 0.1
BOX, _ = resolve_object("box", DIAGONAL)
#: The gripper's jaws touch the box's y faces: a pad lies 0.041 m - q from the palm's z axis.
CLOSED = 0.041 - BOX.extents[1] / 2


def _pinch(pregrasp: float | None = None, squeeze: float | None = None, **extra) -> dict:
    block: dict = {"palm_position": [0.0, 0.0, -0.07], "palm_quaternion": [1.0, 0.0, 0.0, 0.0]}
    block["joint_angles"] = {"left": CLOSED, "right": CLOSED}
    if pregrasp is not None:
        block["pregrasp"] = {"joint_angles": {"left": pregrasp, "right": pregrasp}}
    if squeeze is not None:
        block["squeeze"] = {"joint_angles": {"left": squeeze, "right": squeeze}}
    return {"label": "pinch", "hand": {**block, **extra}}


def _record(*grasps: dict, hand: str = "parallel_gripper") -> dict:
    return {
        "schema": "ogcp.grasps/1",
        "object": {"mesh": "box", "diagonal": DIAGONAL},
        "mu": 0.5,
        "contact_model": "soft",
        "torsional_friction": 0.01,
        "hand": hand,
        "grasps": list(grasps),
    }


def test_a_posed_pinch_is_simulated_from_its_own_stages_as_ogcps_own():
    record = ExternalGrasps.from_dict(_record(_pinch(CLOSED - 0.006, CLOSED + 0.002), _pinch()))
    result = evaluate_grasps(None, record, SimSettings(directions=4))
    staged, plain = result.grasps
    for grasp in (staged, plain):
        assert grasp.error is None and grasp.valid, grasp.invalid_reasons
        assert grasp.hand["name"] == "parallel_gripper" and grasp.hand["fit"]["fingers"] == ["left", "right"]
        assert max(grasp.hand["fit_residuals"]) < 1e-6  # the pads are the contacts
        assert grasp.gates["pads_on_contacts"] == [True, True]
    assert staged.hand["given"] == {"pregrasp": True, "squeeze": True}
    assert staged.hand["pregrasp"] == pytest.approx([CLOSED - 0.006] * 2)
    assert plain.hand["given"] == {"pregrasp": False, "squeeze": False}
    # Both squeeze the jaws to their 20 N limit: the same grasp resists the same loads.
    assert staged.measured == pytest.approx(plain.measured, rel=0.05, abs=0.05)
    # Along the line between the jaws the pinch holds past the ramp's end (censored, left out).
    assert np.isfinite(staged.fidelity).sum() >= len(staged.fidelity) - 4
    assert np.nanmedian(staged.fidelity) < 0.8


def test_the_contacts_of_a_posed_grasp_are_its_pads():
    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    record = ExternalGrasps.from_dict(_record(_pinch()))
    pose, points, normals = resolve_pose(kinematics, record.grasps[0].hand, BOX, "r: grasps[0].hand")
    assert pose.fingers == (0, 1)
    assert points[:, 1] == pytest.approx([BOX.extents[1] / 2, -BOX.extents[1] / 2])
    assert normals == pytest.approx(np.array([[0, -1, 0], [0, 1, 0]]))
    opened = _pinch()
    opened["hand"]["joint_angles"] = {"left": 0.0, "right": CLOSED}
    record = ExternalGrasps.from_dict(_record(opened))
    with pytest.raises(OgcpError, match=r"only 1 pad\(s\) lie within 1 pad radius of the surface \(right 0.0 mm"):
        resolve_pose(kinematics, record.grasps[0].hand, BOX, "r: grasps[0].hand")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda b: b["joint_angles"].update(wrist=0.1),
            r"grasps\[0\]\.hand\.joint_angles\.wrist: .* its finger joints are",
        ),
        (lambda b: b["joint_angles"].pop("left"), r"grasps\[0\]\.hand\.joint_angles: missing joint\(s\) left"),
        (lambda b: b["joint_angles"].update(left=0.5), r"joint_angles: .*joint left = 0.5 is outside its range"),
        (lambda b: b.update(fingers=["left", "thumb"]), r"grasps\[0\]\.hand\.fingers: .* no finger 'thumb'"),
        (lambda b: b.update(pregrasp={"joint_angles": {"left": 0.0}}), r"pregrasp\.joint_angles: missing joint"),
    ],
)
def test_a_bad_pose_is_one_line_naming_its_path(edit, message):
    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    entry = _pinch()
    edit(entry["hand"])
    record = ExternalGrasps.from_dict(_record(entry), where="mine.json")
    with pytest.raises(OgcpError, match=message) as info:
        resolve_pose(kinematics, record.grasps[0].hand, BOX, "mine.json: grasps[0].hand")
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda r: r.pop("hand"), r"grasps\[0\]\.hand: the record names no hand"),
        (lambda r: r["grasps"][0]["hand"].pop("palm_position"), r"grasps\[0\]\.hand\.palm_position: missing"),
        (lambda r: r["grasps"][0]["hand"].update(palm_quaternion=[2, 0, 0, 0]), "expected a unit quaternion"),
        (lambda r: r["grasps"][0]["hand"].update(joint_angles={"left": "x"}), r"joint_angles\.left: expected a finite"),
        (lambda r: r["grasps"][0]["hand"].update(colour=1), r"grasps\[0\]\.hand\.colour: unknown key"),
        (lambda r: r.update(hand=3), "hand: expected a built-in hand's name"),
    ],
)
def test_a_bad_hand_block_is_refused_when_read(edit, message):
    record = _record(_pinch(0.0, 0.03))
    edit(record)
    with pytest.raises(OgcpError, match=message):
        ExternalGrasps.from_dict(record, where="mine.json")


def test_a_hand_record_round_trips_through_its_file(tmp_path):
    record = ExternalGrasps.from_dict(_record(_pinch(0.0, 0.03, fingers=["right", "left"])))
    path = tmp_path / "hand.json"
    save_grasps(record, path)
    again = load_grasps(path)
    assert again.to_dict() == record.to_dict() and again.hand == "parallel_gripper"
    assert again.grasps[0].hand.fingers == ("right", "left") and len(again.grasps[0].positions) == 0


def test_a_descriptor_path_hand_is_relative_to_the_record(tmp_path):
    write_mesh_hand(tmp_path / "hands")
    record = _record(_pinch(), hand="hands/claw.toml")
    path = tmp_path / "claw_grasps.json"
    path.write_text(json.dumps(record))
    assert load_grasps(path).hand_spec == str(tmp_path / "hands" / "claw.toml")


def test_root_poses_round_trip_through_the_hands_forward_kinematics(tmp_path):
    # The claw's palm sits off its root body and turned: the palm pose must come out of MuJoCo's FK.
    kinematics = HandKinematics(load_descriptor(write_mesh_hand(tmp_path)))
    angles = dict(zip(kinematics.joint_names, [0.3, 0.5, -0.1, 0.9, 0.2, 0.0], strict=True))
    stage = HandStage(angles, np.array([0.01, -0.02, 0.15]), np.array([0.5, 0.5, -0.5, 0.5]))
    order = model_joints(kinematics)
    qpos = root_qpos(kinematics, stage, order)
    back = stage_from_root_qpos(kinematics, qpos, order, "r")
    assert back.palm_position == pytest.approx(stage.palm_position, abs=1e-12)
    assert abs(back.palm_quaternion @ stage.palm_quaternion) == pytest.approx(1.0, abs=1e-12)  # q and -q: one turn
    assert back.joint_angles == pytest.approx(angles)
    resolved = resolve_stage(kinematics, back, None, "r")
    pads, _ = pad_points(kinematics, resolved)
    # The same pads as the hand model placed with its root at the pose.
    local, _ = kinematics.pads(resolved.joint_angles)
    assert pads == pytest.approx(local @ resolved.rotation.T + resolved.translation)


def test_a_dexgraspbench_record_converts_and_simulates(tmp_path, capsys):
    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    order = model_joints(kinematics)
    palm = {"palm_position": np.array([0.0, 0.0, -0.07]), "palm_quaternion": np.array([1.0, 0.0, 0.0, 0.0])}
    rows = {
        key: root_qpos(kinematics, HandStage({"left": q, "right": q}, **palm), order).tolist()
        for key, q in (("pregrasp_qpos", CLOSED - 0.006), ("grasp_qpos", CLOSED), ("squeeze_qpos", CLOSED + 0.002))
    }
    source = tmp_path / "grasp_0.json"
    source.write_text(json.dumps(rows))
    out = tmp_path / "grasps.json"
    argv = [str(source), "-o", str(out), "--hand", "parallel_gripper", "--mesh", "box", "--mu", "0.5"]
    assert convert_dexgraspbench.main([*argv, "--diagonal", str(DIAGONAL)]) == 0
    converted = load_grasps(out)
    block = converted.grasps[0].hand
    assert converted.hand == "parallel_gripper" and converted.method == "dexgraspbench"
    assert block.grasp.joint_angles == pytest.approx({"left": CLOSED, "right": CLOSED})
    assert block.pregrasp.joint_angles["left"] == pytest.approx(CLOSED - 0.006)
    assert block.grasp.palm_position == pytest.approx([0.0, 0.0, -0.07])
    assert main(["evaluate", str(out), "--directions", "4", "-o", str(tmp_path / "sim.json")]) == 0
    (result,) = json.loads((tmp_path / "sim.json").read_text())["grasps"]
    assert result["valid"] and result["hand"]["given"] == {"pregrasp": True, "squeeze": True}
    pickled = tmp_path / "grasp_1.npy"
    np.save(pickled, np.array({key: np.array(value) for key, value in rows.items()}, dtype=object))
    argv[0] = str(pickled)
    assert convert_dexgraspbench.main(argv) == 2
    assert "--allow-pickle" in capsys.readouterr().err
    assert convert_dexgraspbench.main([*argv, "--allow-pickle"]) == 0
