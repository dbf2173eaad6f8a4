"""Hand inputs (issue 39, item 5): descriptors and posed hand grasps that are wrong, each refused in
one line that names the file and the field, with nothing written."""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from ogcp.benchmarks.cli import main

HANDS = Path(__file__).resolve().parents[2] / "assets" / "hands"


def _ogcp(argv: list[str]) -> tuple[int, list[str]]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, err.getvalue().splitlines()


def _descriptor(folder: Path, case: str) -> Path:
    shutil.copy(HANDS / "sdh.xml", folder / "sdh.xml")
    text = (HANDS / "sdh.toml").read_text(encoding="utf-8")
    if case == "unknown body":
        text = text.replace('tip_body = "distal_1"', 'tip_body = "distal_9"')
    elif case == "missing model":
        text = text.replace('mjcf = "sdh.xml"', 'mjcf = "missing.xml"')
    elif case == "URDF MuJoCo cannot compile":
        (folder / "bad.urdf").write_text(
            '<robot name="r"><link name="a"/><joint name="j" type="revolute"><parent link="a"/>'
            '<child link="zz"/></joint></robot>',
            encoding="utf-8",
        )
        text = text.replace('mjcf = "sdh.xml"', 'mjcf = "bad.urdf"')
    path = folder / "hand.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("case", "phrase"),
    [
        ("unknown body", "fingers[0].tip_body = 'distal_9' is not a body of sdh.xml"),
        ("missing model", "mjcf = 'missing.xml': no such file"),
        ("URDF MuJoCo cannot compile", "mjcf = bad.urdf: MuJoCo cannot compile it"),
    ],
)
def test_a_bad_hand_descriptor_is_one_line_naming_file_and_field(tmp_path: Path, case: str, phrase: str) -> None:
    hand = _descriptor(tmp_path, case)
    out = tmp_path / "plan.json"
    status, lines = _ogcp(["plan", "box", "-n", "30", "-m", "3", "--hand", str(hand), "-o", str(out)])
    assert status == 2 and len(lines) == 1 and lines[0].startswith(f"ogcp: error: {hand}: ")
    assert phrase in lines[0] and not out.exists()


POSED: dict[str, Any] = {
    "schema": "ogcp.grasps/1",
    "object": {"mesh": "box", "diagonal": 0.1},
    "mu": 0.5,
    "hand": "parallel_gripper",
    "grasps": [
        {
            "label": "pinch",
            "hand": {
                "palm_position": [0.0, 0.0, -0.07],
                "palm_quaternion": [1.0, 0.0, 0.0, 0.0],
                "joint_angles": {"left": 0.0151, "right": 0.0151},
                "fingers": ["left", "right"],
            },
        }
    ],
}


@pytest.mark.parametrize(
    ("field", "value", "phrase"),
    [
        ("joint_angles", {"left": 5.0, "right": 0.0151}, "joint left = 5 is outside its range [0, 0.04]"),
        ("joint_angles", {"left": 0.0151, "right": 0.0151, "wrist": 0.0}, "joint_angles.wrist: the parallel_gripper"),
        ("palm_quaternion", [0.0, 0.0, 0.0, 0.0], "palm_quaternion: expected a unit quaternion"),
    ],
)
def test_a_bad_posed_hand_grasp_is_one_line_naming_its_json_path(
    tmp_path: Path, field: str, value: Any, phrase: str
) -> None:
    record = json.loads(json.dumps(POSED))
    record["grasps"][0]["hand"][field] = value
    source = tmp_path / "grasps.json"
    source.write_text(json.dumps(record), encoding="utf-8")
    out = tmp_path / "sim.json"
    status, lines = _ogcp(["evaluate", str(source), "--directions", "2", "-o", str(out)])
    assert status == 2 and len(lines) == 1 and "grasps[0].hand." in lines[0] and phrase in lines[0], lines
    assert not out.exists()
