"""Which bodies each actuator, tendon and equality of a model acts on (their joint bodies, ``body_weldid``).

The lean protocol scene (:mod:`~ogcp.sim_eval.hand.lean`) welds what cannot move before the object
fails, and keeps moving whatever one of these ties to a moving body.
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco


class UnknownTie(Exception):
    """A transmission or equality type this module does not know (the lean scene then is not built)."""


def tied_bodies(model: mujoco.MjModel) -> Iterable[set[int]]:
    """The joint bodies (``body_weldid``) each actuator, tendon and equality acts on."""
    for tendon in range(model.ntendon):
        yield tendon_bodies(model, tendon)
    for actuator in range(model.nu):
        yield actuator_bodies(model, actuator)
    for equality in range(model.neq):
        yield equality_bodies(model, equality)


def _root(model: mujoco.MjModel, body: int) -> int:
    """The body's joint body: the first at or above it that a joint moves (or the world)."""
    return int(model.body_weldid[body])


def tendon_bodies(model: mujoco.MjModel, tendon: int) -> set[int]:
    """The joint bodies a tendon's path passes: its joints', sites' and wrapping geoms' bodies."""
    bodies = set()
    first = int(model.tendon_adr[tendon])
    for wrap in range(first, first + int(model.tendon_num[tendon])):
        kind, target = int(model.wrap_type[wrap]), int(model.wrap_objid[wrap])
        if kind == mujoco.mjtWrap.mjWRAP_JOINT:
            bodies.add(_root(model, int(model.jnt_bodyid[target])))
        elif kind == mujoco.mjtWrap.mjWRAP_SITE:
            bodies.add(_root(model, int(model.site_bodyid[target])))
        elif kind in (mujoco.mjtWrap.mjWRAP_SPHERE, mujoco.mjtWrap.mjWRAP_CYLINDER):
            bodies.add(_root(model, int(model.geom_bodyid[target])))
    return bodies


def actuator_bodies(model: mujoco.MjModel, actuator: int) -> set[int]:
    """The joint bodies an actuator's transmission acts on.

    Raises:
        UnknownTie: For a transmission this module does not know.
    """
    kind = int(model.actuator_trntype[actuator])
    target = int(model.actuator_trnid[actuator, 0])
    if kind in (mujoco.mjtTrn.mjTRN_JOINT, mujoco.mjtTrn.mjTRN_JOINTINPARENT):
        return {_root(model, int(model.jnt_bodyid[target]))}
    if kind == mujoco.mjtTrn.mjTRN_TENDON:
        return tendon_bodies(model, target)
    if kind == mujoco.mjtTrn.mjTRN_BODY:
        return {_root(model, target)}
    if kind in (mujoco.mjtTrn.mjTRN_SITE, mujoco.mjtTrn.mjTRN_SLIDERCRANK):
        sites = [s for s in model.actuator_trnid[actuator] if s >= 0]
        return {_root(model, int(model.site_bodyid[s])) for s in sites}
    raise UnknownTie(f"actuator {actuator}'s transmission ({kind}) is not one the lean scene knows")


def equality_bodies(model: mujoco.MjModel, equality: int) -> set[int]:
    """The joint bodies an equality ties.

    Raises:
        UnknownTie: For an equality this module does not know.
    """
    kind = int(model.eq_type[equality])
    first, second = int(model.eq_obj1id[equality]), int(model.eq_obj2id[equality])
    if kind == mujoco.mjtEq.mjEQ_JOINT:
        joints = [first] + ([second] if second >= 0 else [])
        return {_root(model, int(model.jnt_bodyid[j])) for j in joints}
    if kind == mujoco.mjtEq.mjEQ_TENDON:
        return tendon_bodies(model, first) | (tendon_bodies(model, second) if second >= 0 else set())
    if kind in (mujoco.mjtEq.mjEQ_CONNECT, mujoco.mjtEq.mjEQ_WELD):
        if model.eq_objtype[equality] == mujoco.mjtObj.mjOBJ_SITE:
            first, second = int(model.site_bodyid[first]), int(model.site_bodyid[second])
        return {_root(model, first), _root(model, max(second, 0))}
    raise UnknownTie(f"equality {equality} ({kind}) is not one the lean scene knows")
