"""Hand grasps in ``ogcp.grasps/1``: a palm pose and joint angles, with an optional pregrasp and squeeze.

A record whose top level names a ``hand`` (a built-in name, or an ``ogcp.hand/1`` descriptor path
relative to the record) may give each grasp a ``hand`` block::

    "hand": {
      "palm_position": [x, y, z],               # [m], object frame: the descriptor's palm body
      "palm_quaternion": [w, x, y, z],          # palm frame to object frame
      "joint_angles": {"joint": angle, ...},    # [rad or m], the hand's finger joints by name
      "fingers": ["thumb", "index"],            # optional: the pads that take the contacts
      "pregrasp": {"joint_angles": {...}, "palm_position": [...], "palm_quaternion": [...]},
      "squeeze": {"joint_angles": {...}}        # both optional; a stage's palm defaults to the grasp's
    }

Such a grasp needs no ``contacts``: they are where the named pads (default: every pad near the
surface) touch the object. This module checks types and shapes only; joint and finger names are
checked against the compiled hand when the grasps are simulated
(:mod:`ogcp.sim_eval.hand.given`), where every error names its JSON path as here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError

#: A palm quaternion's length may differ from 1 by this much; it is then normalised.
QUATERNION_TOLERANCE = 1e-3
_POSE_KEYS = ("palm_position", "palm_quaternion", "joint_angles", "fingers", "pregrasp", "squeeze")
_STAGE_KEYS = ("palm_position", "palm_quaternion", "joint_angles")


@dataclass(frozen=True, eq=False)
class HandStage:
    """A configuration of the hand: palm pose and joint angles.

    Attributes:
        joint_angles: Angle [rad] (slide: position [m]) by joint name.
        palm_position: Palm origin in the object frame, shape (3,) [m]; None: the grasp's.
        palm_quaternion: Palm orientation (w, x, y, z), unit, shape (4,); None: the grasp's.
    """

    joint_angles: dict[str, float]
    palm_position: NDArray[np.float64] | None = None
    palm_quaternion: NDArray[np.float64] | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (an absent palm left out)."""
        entry: dict[str, Any] = {}
        if self.palm_position is not None:
            entry["palm_position"] = self.palm_position.tolist()
        if self.palm_quaternion is not None:
            entry["palm_quaternion"] = self.palm_quaternion.tolist()
        entry["joint_angles"] = dict(self.joint_angles)
        return entry


@dataclass(frozen=True, eq=False)
class HandPose:
    """One hand grasp as another planner gives it.

    Attributes:
        grasp: The grasp configuration; its palm is always set.
        fingers: Names of the pads that take the contacts, or None: every pad near the surface.
        pregrasp: Where the closing starts; None: ogcp's pregrasp (pads backed off their contacts).
        squeeze: Where the servos aim after the grasp; None: ogcp's balanced squeeze.
    """

    grasp: HandStage
    fingers: tuple[str, ...] | None = None
    pregrasp: HandStage | None = None
    squeeze: HandStage | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form of the grasp's ``hand`` block."""
        entry = self.grasp.to_dict()
        if self.fingers is not None:
            entry["fingers"] = list(self.fingers)
        for name, stage in (("pregrasp", self.pregrasp), ("squeeze", self.squeeze)):
            if stage is not None:
                entry[name] = stage.to_dict()
        return entry


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _numbers(where: str, path: str, value: Any, count: int) -> NDArray[np.float64]:
    if not (isinstance(value, list) and len(value) == count and all(_finite(v) for v in value)):
        raise OgcpError(f"{where}: {path}: expected {count} finite numbers, got {_short(value)}")
    return np.array(value, dtype=float)


def _quaternion(where: str, path: str, value: Any) -> NDArray[np.float64]:
    quat = _numbers(where, path, value, 4)
    length = float(np.linalg.norm(quat))
    if abs(length - 1.0) > QUATERNION_TOLERANCE:
        raise OgcpError(f"{where}: {path}: expected a unit quaternion (w, x, y, z), got length {length:.6g}")
    return quat / length


def _angles(where: str, path: str, value: Any) -> dict[str, float]:
    if not isinstance(value, dict) or not value:
        raise OgcpError(f"{where}: {path}: expected an object of joint name -> angle, got {_short(value)}")
    for name, angle in value.items():
        if not _finite(angle):
            raise OgcpError(f"{where}: {path}.{name}: expected a finite number, got {_short(angle)}")
    return {str(name): float(angle) for name, angle in value.items()}


def _stage(where: str, path: str, data: Any, palm_required: bool) -> HandStage:
    if not isinstance(data, dict):
        raise OgcpError(f"{where}: {path}: expected an object with joint_angles, got {_short(data)}")
    unknown = sorted(set(data) - set(_STAGE_KEYS if not palm_required else _POSE_KEYS))
    if unknown:
        valid = _POSE_KEYS if palm_required else _STAGE_KEYS
        raise OgcpError(f"{where}: {path}.{unknown[0]}: unknown key; valid keys are {', '.join(valid)}")
    for key in ("joint_angles", *(("palm_position", "palm_quaternion") if palm_required else ())):
        if key not in data:
            raise OgcpError(f"{where}: {path}.{key}: missing")
    position = data.get("palm_position")
    quaternion = data.get("palm_quaternion")
    return HandStage(
        _angles(where, f"{path}.joint_angles", data["joint_angles"]),
        None if position is None else _numbers(where, f"{path}.palm_position", position, 3),
        None if quaternion is None else _quaternion(where, f"{path}.palm_quaternion", quaternion),
    )


def parse_hand_pose(where: str, path: str, data: Any) -> HandPose:
    """A grasp's ``hand`` block, checked (types and shapes; names are checked against the hand later).

    Args:
        where: The record's name in messages (its file).
        path: The block's JSON path, e.g. ``grasps[3].hand``.
        data: The parsed block.

    Raises:
        OgcpError: One line naming the JSON path of the first bad field.
    """
    grasp = _stage(where, path, data, palm_required=True)
    fingers = data.get("fingers")
    if fingers is not None:
        if not (isinstance(fingers, list) and fingers and all(isinstance(f, str) and f for f in fingers)):
            raise OgcpError(f"{where}: {path}.fingers: expected a list of finger names, got {_short(fingers)}")
        if len(set(fingers)) != len(fingers):
            raise OgcpError(f"{where}: {path}.fingers: a finger is named twice in {_short(fingers)}")
        fingers = tuple(fingers)
    stages = {
        name: _stage(where, f"{path}.{name}", data[name], palm_required=False) if data.get(name) is not None else None
        for name in ("pregrasp", "squeeze")
    }
    return HandPose(grasp, fingers, stages["pregrasp"], stages["squeeze"])


def parse_hand_name(where: str, value: Any) -> str:
    """The record's top-level ``hand``: a built-in hand's name or a descriptor path."""
    if not isinstance(value, str) or not value.strip():
        raise OgcpError(f"{where}: hand: expected a built-in hand's name or an ogcp.hand/1 file, got {_short(value)}")
    return value
