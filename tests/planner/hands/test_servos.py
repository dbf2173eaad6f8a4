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


def test_an_asymmetric_range_stays_asymmetric_through_the_gear(tmp_path):
    """A finger that flexes harder than it extends (Menagerie's DEX-EE: -0.35 to 1.2 N·m) keeps both
    limits; a negative gear swaps them."""
    actuators = (
        '<motor name="m" joint="left" forcerange="-0.35 1.2"/>'
        '<motor name="g" joint="right" gear="-2" ctrlrange="-1 3"/>'  # -2 x (-1 .. 3): -6 .. 2
    )
    with pytest.warns(HandActuatorWarning):
        kinematics = _gripper(tmp_path, actuators)
    ranges = {
        joint: kinematics.model.actuator(f"ogcp_servo_{joint}").forcerange.tolist() for joint in ("left", "right")
    }
    assert ranges["left"] == pytest.approx([-0.35, 1.2]) and ranges["right"] == pytest.approx([-6.0, 2.0])


def test_a_plugin_actuator_such_as_mujocos_pid_is_replaced_within_its_range(tmp_path):
    """MuJoCo's ``mujoco.pid`` plugin actuators (Menagerie's DEX-EE) hold a target, but through their
    own state, not a stiffness ogcp can read: they give way to servos like a motor."""
    path = write_gripper_variant(
        tmp_path,
        lambda text: text.replace(
            "<worldbody>",
            '<extension><plugin plugin="mujoco.pid"><instance name="pid"><config key="kp" value="3"/>'
            '<config key="ki" value="1"/><config key="imax" value="0.1"/></instance></plugin></extension>'
            "<worldbody>",
        ).replace(
            "</worldbody>",
            '</worldbody><actuator><plugin name="p" plugin="mujoco.pid" instance="pid" joint="left" actdim="1" '
            'forcerange="-4 9"/></actuator>',
        ),
    )
    with pytest.warns(HandActuatorWarning, match="actuators p hold no pose"):
        kinematics = HandKinematics(load_descriptor(path))
    assert kinematics.servos == ("left", "right")
    assert kinematics.model.actuator("ogcp_servo_left").forcerange.tolist() == pytest.approx([-4.0, 9.0])


def test_a_joints_clamp_on_its_actuator_force_narrows_the_servos_range(tmp_path):
    """MuJoCo clamps a joint's total actuator force at its ``actuatorfrcrange`` (a URDF's effort limit
    becomes one): the servo's range says what the joint gets, through its gear, kept or added."""
    path = write_gripper_variant(
        tmp_path,
        lambda text: text.replace('range="0 0.04"', 'range="0 0.04" actuatorfrcrange="-5 3"').replace(
            "</worldbody>",
            '</worldbody><actuator><position name="p" joint="left" kp="500" gear="2" forcerange="-20 20"/></actuator>',
        ),
    )
    kinematics = HandKinematics(load_descriptor(path))
    assert kinematics.servos == ("right",)
    assert kinematics.model.actuator("p").forcerange.tolist() == pytest.approx([-2.5, 1.5])  # (-5, 3) / 2
    assert kinematics.model.actuator("ogcp_servo_right").forcerange.tolist() == pytest.approx([-5.0, 3.0])


def test_a_clamp_that_does_not_meet_the_range_leaves_the_actuators_own():
    """MuJoCo would refuse a range whose low end passed its high end."""
    from ogcp.planner.hands.servos import _within

    assert _within((2.0, 5.0), (-1.0, 1.0), 1.0) == (2.0, 5.0)
    assert _within((-4.0, 9.0), (-1.0, 3.0), 2.0) == (-0.5, 1.5)
    assert _within((-4.0, 9.0), None, 2.0) == (-4.0, 9.0)


def test_joints_a_spatial_tendon_or_a_site_drives_get_no_servo_of_their_own(tmp_path, recwarn):
    """The Tetheria Aero hand flexes its fingers through spatial tendons routed over sites: ogcp read
    only fixed tendons' joints as driven and gave every finger joint a servo of [actuation] too,
    a stronger hand than the model."""

    def edit(text: str) -> str:
        text = text.replace('<geom name="palm"', '<site name="anchor" pos="0 0 0"/><geom name="palm"', 1)
        text = text.replace('<geom name="left"', '<site name="left_end" pos="0 0 0.035"/><geom name="left"', 1)
        text = text.replace('<geom name="right"', '<site name="right_end" pos="0 0 0.035"/><geom name="right"', 1)
        return text.replace(
            "</worldbody>",
            '</worldbody><tendon><spatial name="pull"><site site="anchor"/><site site="left_end"/></spatial></tendon>'
            '<actuator><position name="t" tendon="pull" kp="500" ctrlrange="0 0.1"/>'
            '<position name="s" site="right_end" gear="0 1 0 0 0 0" kp="500"/></actuator>',
        )

    kinematics = HandKinematics(load_descriptor(write_gripper_variant(tmp_path, edit)))
    assert kinematics.servos == () and kinematics.replaced_actuators == ()
    assert kinematics.model.nu == 2
    assert not [w for w in recwarn if issubclass(w.category, HandActuatorWarning)]
