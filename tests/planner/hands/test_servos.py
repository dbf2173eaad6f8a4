"""A hand's actuators that hold no pose (motors, velocity servos) give way to position servos within their own limits."""

from __future__ import annotations

import pytest

from ogcp.planner.hands import HandKinematics, load_descriptor
from ogcp.planner.hands.servos import HandActuatorWarning, holds_pose

from .hand_files import write_gripper_variant


def _gripper(folder, actuators: str) -> HandKinematics:
    path = write_gripper_variant(
        folder, lambda text: text.replace("</worldbody>", f"</worldbody><actuator>{actuators}</actuator>")
    )
    return HandKinematics(load_descriptor(path))


def _limit(kinematics: HandKinematics, joint: str) -> float:
    return float(kinematics.model.actuator(f"ogcp_servo_{joint}").forcerange[1])


def test_motors_and_velocity_servos_are_replaced_within_their_own_limits(tmp_path):
    actuators = (
        '<motor name="m" joint="left" gear="3" ctrlrange="-2 2"/>'  # 3 x 2: 6 N
        '<velocity name="v" joint="right" kv="5" forcerange="-7 7"/>'  # its force range: 7 N
    )
    with pytest.warns(HandActuatorWarning, match=r"actuators m, v hold no pose .* kp 20000"):
        kinematics = _gripper(tmp_path, actuators)
    assert kinematics.replaced_actuators == ("m", "v") and kinematics.servos == ("left", "right")
    model = kinematics.model
    assert model.nu == 2 and all(holds_pose(model, a) for a in range(model.nu))
    assert _limit(kinematics, "left") == pytest.approx(6.0) and _limit(kinematics, "right") == pytest.approx(7.0)
    assert kinematics.describe()["actuators_replaced"] == ["m", "v"]


def test_an_integrated_velocity_servo_is_replaced_too(tmp_path):
    """Its command is a velocity that its activation integrates into the target: no target ogcp can set."""
    with pytest.warns(HandActuatorWarning, match=r"actuators iv hold no pose"):
        kinematics = _gripper(
            tmp_path, '<intvelocity name="iv" joint="left" kp="500" actrange="0 0.04" forcerange="-9 9"/>'
        )
    assert kinematics.replaced_actuators == ("iv",) and _limit(kinematics, "left") == pytest.approx(9.0)


def test_an_unlimited_motor_takes_the_descriptors_force_range(tmp_path):
    with pytest.warns(HandActuatorWarning):
        kinematics = _gripper(tmp_path, '<motor name="m" joint="left"/><position name="p" joint="right" kp="500"/>')
    assert kinematics.replaced_actuators == ("m",) and kinematics.servos == ("left",)  # the servo is kept
    assert _limit(kinematics, "left") == pytest.approx(kinematics.descriptor.actuation.force_range)
    assert holds_pose(kinematics.model, kinematics.model.actuator("p").id)


def test_servos_are_kept_as_they_are(tmp_path, recwarn):
    kinematics = _gripper(
        tmp_path, '<position name="l" joint="left" kp="500"/><position name="r" joint="right" kp="500"/>'
    )
    assert kinematics.replaced_actuators == () and kinematics.servos == ()
    assert not [w for w in recwarn if issubclass(w.category, HandActuatorWarning)]
