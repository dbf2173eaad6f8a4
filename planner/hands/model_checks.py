"""Hand models that compile but that ogcp would close wrongly: servos that cannot hold every pose
ogcp fits, and descriptors whose pads are not on the tip's surface.

ogcp fits every joint of a finger (and of the loops it closes) and holds the fit with the hand's
servos. A finger whose servos span fewer directions than the finger can move in, once its joint
equalities and closed loops are respected, is *underactuated* (one tendon servo over two joints,
as Menagerie's Shadow hand drives J1 and J2): the fit poses every joint, and one servo cannot hold
that pose. It gets a one-line :class:`~ogcp.planner.hands.kinematics.HandModelWarning` rather than
results that silently mean something else.

A descriptor's ``tip_offset`` is the point where the pad touches, ``pad_normal`` out of it: the fit
puts that point on the contact. A point inside the tip's collision geometry (a pad box's inner
face, 1.5 mm behind the fingertip's bumps on the Franka hand) puts the geometry into the object,
and the fit then reports the finger as unable to reach; a point floating off it leaves the pad
short. :func:`pad_surface_offsets` finds how far each pad's surface lies from its point.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Protocol

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.descriptor import HandDescriptor
from ogcp.planner.hands.self_collision import DesignedOverlaps

#: [rad] A hand none of whose finger hinges moves more than this (2 degrees) gets a warning.
STIFF_HINGE = np.radians(2.0)
#: Singular values below this fraction of the largest count as none (servo arms, equality rows).
RANK_TOLERANCE = 1e-6
#: How far [m] a pad's point may lie from its tip's surface, along the pad normal, before loading warns.
PAD_SURFACE_TOLERANCE = 5e-4
#: How far out along the pad normal [m] the rays that find the surface start.
_RAY_START = 0.05


def pad_surface_offsets(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    pads: Sequence[tuple[int, NDArray[np.float64], NDArray[np.float64], float]],
) -> list[float | None]:
    """How far each pad's surface lies beyond its point along its normal [m] (> 0: the point is
    inside the geometry, < 0: it floats off it), in a state after ``mj_kinematics``; None where no
    geometry lies under the pad.

    The surface is the outermost point, along the normal, of the collision geoms that move rigidly
    with the tip body (its weld group: a URDF's pad link carries none of its own), met by rays cast
    back along the normal at the point and on rings of half and one pad radius around it (a pad
    whose outer face is four small bumps, as the Franka hand's, touches with those).

    Args:
        model: The hand's model.
        data: Its state.
        pads: Per finger: tip body, pad point and unit normal in the body's frame, pad radius [m].
    """
    found: list[float | None] = []
    for body, offset, normal, radius in pads:
        frame = data.xmat[body].reshape(3, 3)
        point, out = data.xpos[body] + frame @ offset, frame @ normal
        weld = model.body_weldid[body]
        geoms = [
            g
            for g in range(model.ngeom)
            if model.body_weldid[model.geom_bodyid[g]] == weld and (model.geom_contype[g] or model.geom_conaffinity[g])
        ]
        side = np.cross(out, [1.0, 0.0, 0.0] if abs(out[0]) < 0.9 else [0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        other = np.cross(out, side)
        angles = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
        ring = np.outer(np.cos(angles), side) + np.outer(np.sin(angles), other)
        starts = np.vstack([point, point + 0.5 * radius * ring, point + radius * ring]) + _RAY_START * out
        nearest = min(
            (t for start in starts for g in geoms if (t := _ray(model, data, g, start, -out)) >= 0), default=None
        )
        found.append(None if nearest is None else _RAY_START - nearest)
    return found


def _ray(
    model: mujoco.MjModel, data: mujoco.MjData, geom: int, start: NDArray[np.float64], direction: NDArray[np.float64]
) -> float:
    """Distance along ``direction`` from ``start`` to a geom's surface; -1 where the ray misses it."""
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_MESH:
        return float(mujoco.mj_rayMesh(model, data, geom, start, direction))
    return float(
        mujoco.mju_rayGeom(
            data.geom_xpos[geom], data.geom_xmat[geom], model.geom_size[geom], start, direction, model.geom_type[geom]
        )
    )


class HandModelWarning(UserWarning):
    """A hand model that compiles but is most likely not what its author meant."""


class _Pad(Protocol):
    """What the checks read of a finger (:class:`~ogcp.planner.hands.kinematics.Finger`)."""

    @property
    def name(self) -> str: ...
    @property
    def body(self) -> int: ...
    @property
    def joints(self) -> tuple[int, ...]: ...
    @property
    def offset(self) -> NDArray[np.float64]: ...
    @property
    def normal(self) -> NDArray[np.float64]: ...
    @property
    def radius(self) -> float: ...


class _CompiledHand(Protocol):
    """What the checks read of a compiled hand (:class:`~ogcp.planner.hands.kinematics.HandKinematics`)."""

    descriptor: HandDescriptor
    model: mujoco.MjModel
    data: mujoco.MjData
    joint_ids: NDArray[np.intp]
    limits: NDArray[np.float64]
    reference_qpos: NDArray[np.float64]
    overlaps: DesignedOverlaps

    @property
    def fingers(self) -> Sequence[_Pad]: ...


def warn_about_model(kin: _CompiledHand) -> None:
    """One :class:`HandModelWarning` line for each way a compiled hand is most likely not what its
    author meant: hinge ranges in degrees read as radians, underactuated fingers, pad points off
    their tips' surfaces, links of one chain that overlap in most poses."""
    _warn_if_degrees_meant_radians(kin)
    _warn_if_underactuated(kin)
    _warn_if_pads_off_surface(kin)
    _warn_if_chain_overlaps(kin)


def _warn_if_degrees_meant_radians(kin: _CompiledHand) -> None:
    """Warn when no finger hinge moves more than :data:`STIFF_HINGE` [rad]: the model's ranges
    were most likely written in radians where MJCF reads degrees (its default)."""
    hinges = [k for k, j in enumerate(kin.joint_ids) if kin.model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    if not hinges:
        return
    widest = float(np.max(kin.limits[hinges, 1] - kin.limits[hinges, 0]))
    if widest < STIFF_HINGE:
        warnings.warn(
            f"{kin.descriptor.path}: no finger hinge of the {kin.descriptor.name} hand moves more than "
            f"{np.degrees(widest):.2g} degrees; MJCF reads angles in degrees unless the model says "
            '<compiler angle="radian"/>',
            HandModelWarning,
            stacklevel=5,
        )


def _warn_if_underactuated(kin: _CompiledHand) -> None:
    """Warn about fingers whose servos cannot hold every fitted pose (:mod:`ogcp.planner.hands.model_checks`)."""
    fingers = [(finger.name, finger.joints) for finger in kin.fingers]
    short = underactuated_fingers(kin.model, kin.reference_qpos, fingers)
    if short:
        warnings.warn(
            f"{kin.descriptor.path}: the {kin.descriptor.name} hand has fingers with fewer servo directions "
            f"than directions of motion: {'; '.join(short)}; the fit poses every joint, and the servos may not "
            "hold that pose when the hand closes",
            HandModelWarning,
            stacklevel=5,
        )


def _warn_if_pads_off_surface(kin: _CompiledHand) -> None:
    """Say which pads' points are not on their tips' surfaces in the reference pose (:func:`pad_surface_offsets`)."""
    kin.data.qpos[:] = kin.reference_qpos
    mujoco.mj_kinematics(kin.model, kin.data)
    pads = [(f.body, f.offset, f.normal, f.radius) for f in kin.fingers]
    faults = []
    for finger, offset in zip(kin.fingers, pad_surface_offsets(kin.model, kin.data, pads), strict=True):
        body = kin.model.body(finger.body).name
        if offset is None:
            faults.append(f"{finger.name} (no geometry of {body} under it)")
        elif abs(offset) > PAD_SURFACE_TOLERANCE:
            where = f"inside {body}" if offset > 0 else f"off {body}'s surface"
            # Where the surface is along the normal: what a descriptor written blind most often needs.
            onto = ", ".join(f"{x:.4g}" for x in np.asarray(finger.offset) + offset * np.asarray(finger.normal))
            faults.append(f"{finger.name} ({abs(offset) * 1e3:.2f} mm {where}; tip_offset = [{onto}] is on it)")
    if faults:
        warnings.warn(
            f"{kin.descriptor.path}: pad points not on their tips' surfaces along pad_normal: {', '.join(faults)}; "
            "tip_offset should be where the pad touches, pad_normal out of it, or the fit keeps those fingers short",
            HandModelWarning,
            stacklevel=5,
        )


def _warn_if_chain_overlaps(kin: _CompiledHand) -> None:
    """Say which links of one chain overlap through most of their range: ignored as collisions."""
    if not kin.overlaps.on_chain:
        return
    found: dict[tuple[str, str], float] = {}
    for (g, h), share in kin.overlaps.on_chain.items():
        a, b = sorted(kin.model.body(int(kin.model.geom_bodyid[k])).name for k in (g, h))
        found[a, b] = max(share, found.get((a, b), 0.0))
    listed = ", ".join(f"{a} and {b} ({share:.0%})" for (a, b), share in sorted(found.items()))
    warnings.warn(
        f"{kin.descriptor.path}: links of one chain of the {kin.descriptor.name} hand overlap in most sampled "
        f"poses, so their collision geometry is coarser than the hand (a convex hull of a non-convex mesh?): "
        f"{listed}; their contacts are ignored (list more pairs under ignore_collisions)",
        HandModelWarning,
        stacklevel=5,
    )


def equality_jacobian(model: mujoco.MjModel, data: mujoco.MjData) -> NDArray[np.float64]:
    """The active equalities' constraint rows at a state (``mj_fwdPosition`` done), shape (n_eq, nv).

    MuJoCo's own rows: a joint equality, a tendon equality, and a ``connect`` or ``weld`` that closes a
    loop.
    """
    rows = np.flatnonzero(data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    if not len(rows):
        return np.zeros((0, model.nv))
    if mujoco.mj_isSparse(model):
        dense = np.zeros((data.nefc, model.nv))
        mujoco.mju_sparse2dense(dense, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
    else:
        dense = np.asarray(data.efc_J[: data.nefc * model.nv]).reshape(data.nefc, model.nv)
    return np.asarray(dense[rows], dtype=float)


def _rank(matrix: NDArray[np.float64]) -> int:
    if not matrix.size:
        return 0
    values = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(values > RANK_TOLERANCE * values.max())) if values.max() > 0 else 0


def underactuated_fingers(
    model: mujoco.MjModel,
    qpos: NDArray[np.float64],
    fingers: Sequence[tuple[str, Sequence[int]]],
) -> list[str]:
    """The fingers with fewer independent servo directions than directions of motion, in words.

    A finger moves in the directions its joints' equalities leave free: the null space of their
    rows over its joints and the joints they tie it to (another finger's driver, as a gripper's two
    jaws share one servo); its servos must span their moment arms over those directions.

    Args:
        model: The hand's compiled model, servos added.
        qpos: A configuration to take the moment arms and equality rows at (the reference), shape (nq,).
        fingers: Each finger's name and joint ids.
    """
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_fwdPosition(model, data)
    moments = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(moments, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind)
    equalities = equality_jacobian(model, data)
    found = []
    for name, joints in fingers:
        dofs = _tied_dofs(equalities, model.jnt_dofadr[list(joints)])
        tied = equalities[:, dofs]
        tied = tied[np.abs(tied).max(axis=1) > 0] if len(tied) else tied
        _, values, basis = np.linalg.svd(tied) if len(tied) else (None, np.zeros(0), np.eye(len(dofs)))
        kept = int(np.sum(values > RANK_TOLERANCE * values.max())) if values.size and values.max() > 0 else 0
        free = basis[kept:].T  # (J, directions): the motions the equalities allow
        if not free.shape[1]:
            continue
        rank = _rank(moments[:, dofs] @ free)
        if rank < free.shape[1]:
            joint_names = ", ".join(
                mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}" for j in joints
            )
            found.append(
                f"{name} ({len(joints)} joints, {joint_names}; {free.shape[1]} direction{'s' * (free.shape[1] != 1)} "
                f"of motion, {rank} servo direction{'s' * (rank != 1)})"
            )
    return found


def _tied_dofs(equalities: NDArray[np.float64], dofs: NDArray[np.intp]) -> NDArray[np.intp]:
    """``dofs`` and every dof an equality row ties to them, directly or through others, in model order."""
    found = {int(d) for d in dofs}
    active = np.abs(equalities) > 0
    grown = True
    while grown:
        grown = False
        for row in active:
            touched = set(np.flatnonzero(row).tolist())
            if touched & found and not touched <= found:
                found |= touched
                grown = True
    return np.array(sorted(found), dtype=np.intp)
