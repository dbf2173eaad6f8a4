"""Hand models: kinematics of the robot hands that execute planned grasps (Schunk SDH)."""

from ogcp.planner.hands.sdh import (
    FINGER_BASES,
    FINGER_NAMES,
    JOINT_LIMITS,
    JOINT_NAMES,
    MJCF_JOINT_INDEX,
    TIP_SITES,
    FingertipPoses,
    forward_kinematics,
    random_configurations,
    sdh_model_path,
    validate_configuration,
)

__all__ = [
    "FINGER_BASES",
    "FINGER_NAMES",
    "JOINT_LIMITS",
    "JOINT_NAMES",
    "MJCF_JOINT_INDEX",
    "TIP_SITES",
    "FingertipPoses",
    "forward_kinematics",
    "random_configurations",
    "sdh_model_path",
    "validate_configuration",
]
