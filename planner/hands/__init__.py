"""Hands: the ``ogcp.hand/1`` descriptor, MuJoCo kinematics of any hand, and reachability as a grasp constraint.

The descriptor and the registry are plain Python; :mod:`~ogcp.planner.hands.kinematics` (and the
sampling of a reachability model) compiles the hand in MuJoCo, the one kinematic truth. Names load
on first use, so that reading a descriptor does not import MuJoCo.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.hands.descriptor import Actuation, FingerSpec, HandDescriptor, load_descriptor
    from ogcp.planner.hands.kinematics import HandKinematics
    from ogcp.planner.hands.reachability import HandReachability, Reach, SDHReachability
    from ogcp.planner.hands.registry import BUILTIN_HANDS, resolve_hand

#: Public name -> the module that defines it.
_EXPORTS = {
    "Actuation": "ogcp.planner.hands.descriptor",
    "BUILTIN_HANDS": "ogcp.planner.hands.registry",
    "FingerSpec": "ogcp.planner.hands.descriptor",
    "HandDescriptor": "ogcp.planner.hands.descriptor",
    "HandKinematics": "ogcp.planner.hands.kinematics",
    "HandReachability": "ogcp.planner.hands.reachability",
    "Reach": "ogcp.planner.hands.reachability",
    "SDHReachability": "ogcp.planner.hands.reachability",
    "load_descriptor": "ogcp.planner.hands.descriptor",
    "resolve_hand": "ogcp.planner.hands.registry",
}

__all__ = [
    "BUILTIN_HANDS",
    "Actuation",
    "FingerSpec",
    "HandDescriptor",
    "HandKinematics",
    "HandReachability",
    "Reach",
    "SDHReachability",
    "load_descriptor",
    "resolve_hand",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
