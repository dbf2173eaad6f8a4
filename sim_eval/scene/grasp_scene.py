"""The MuJoCo model of one grasp: a free object made of convex parts and m actuated fingertips.

The object keeps its mesh coordinates: at the start its frame coincides with the world, so
the planned contacts, normals and centre of mass are world quantities. Fingertip ``i`` is a
sphere whose centre sits ``radius`` outside contact ``i`` along the normal, on three slides
(normal, then the planner's fixed tangent basis a, b). Only tip-object pairs collide.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.wrench import tangent_basis
from ogcp.sim_eval.settings import SimSettings

_INTEGRATORS = {
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}
_CONES = {"elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC, "pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL}
_SOLVERS = {"Newton": mujoco.mjtSolver.mjSOL_NEWTON, "CG": mujoco.mjtSolver.mjSOL_CG, "PGS": mujoco.mjtSolver.mjSOL_PGS}
GRAVITY = 9.81


@dataclass(frozen=True, eq=False)
class GraspScene:
    """A compiled grasp model and the indices the protocol needs.

    Attributes:
        model: The compiled MuJoCo model.
        object_body: Body id of the object.
        object_qpos: Address of the object's free-joint qpos (7 values: position, quaternion).
        object_geoms: Geom ids of the object's convex parts, shape (parts,).
        tip_geoms: Geom ids of the fingertips, shape (m,).
        preload_ctrl: Control vector that preloads the grasp, shape (nu,).
        tip_radius: Fingertip radius [m].
        mu: Friction coefficient of every tip-object contact.
        torsion: Torsional friction coefficient of every tip-object contact [m]; 0 = hard
            fingers (condim 3), else soft fingers (condim 4).
        finger_geoms: The geoms that are each finger's pad (a hand's tip-body geoms); None: the
            tip spheres, one per finger.
        watched_qpos: qpos entries whose drift from the start beyond ``RUNAWAY_RADII`` tip radii
            counts as divergence; None: every entry but the object's (the tips' slides).
        start_qpos: The state the protocol starts from (a closed hand), shape (nq,); None: the
            model's ``qpos0``. (``qpos0`` itself is the joints' reference and is never changed.)
    """

    model: mujoco.MjModel
    object_body: int
    object_qpos: int
    object_geoms: NDArray[np.intp]
    tip_geoms: NDArray[np.intp]
    preload_ctrl: NDArray[np.float64]
    tip_radius: float
    mu: float
    torsion: float = 0.0
    finger_geoms: tuple[NDArray[np.intp], ...] | None = None
    watched_qpos: NDArray[np.intp] | None = None
    start_qpos: NDArray[np.float64] | None = None

    def start(self) -> NDArray[np.float64]:
        """The qpos the protocol starts from, shape (nq,)."""
        return self.model.qpos0.copy() if self.start_qpos is None else self.start_qpos.copy()

    @property
    def fingers(self) -> int:
        """Number of fingers m."""
        return len(self.tip_geoms)

    def geom_fingers(self) -> dict[int, int]:
        """Geom id -> the finger it belongs to, for the geoms that are the fingers' pads."""
        if self.finger_geoms is None:
            return {int(g): i for i, g in enumerate(self.tip_geoms)}
        return {int(g): i for i, geoms in enumerate(self.finger_geoms) for g in geoms}


def contact_friction(mu: float, torsion: float) -> dict[str, Any]:
    """Geom attributes of a contact: sliding friction only (condim 3), or with torsion (condim 4).

    MuJoCo takes a pair's friction from the larger of its geoms' values and its condim from
    the larger condim, so tips and parts carry the same values.
    """
    if torsion > 0:
        return {"condim": 4, "friction": [mu, torsion, 0.0]}
    return {"condim": 3, "friction": [mu, 0.0, 0.0]}


def set_options(spec: mujoco.MjSpec, settings: SimSettings, gravity: bool) -> None:
    opt = spec.option
    opt.timestep = settings.timestep
    opt.integrator = _INTEGRATORS[settings.integrator]
    opt.cone = _CONES[settings.cone]
    opt.impratio = settings.impratio
    opt.noslip_iterations = settings.noslip_iterations
    opt.solver = _SOLVERS[settings.solver]
    opt.iterations = settings.solver_iterations
    # The object's mass is divided by inertia_scale's inverse; gravity is multiplied by it, so
    # that its weight stays object_mass g at every size.
    opt.gravity = [0.0, 0.0, -GRAVITY / settings.inertia_scale if gravity else 0.0]


def add_object(
    spec: mujoco.MjSpec,
    parts: Sequence[tuple[NDArray[np.float64], NDArray[np.int64]]],
    com: NDArray[np.float64],
    inertia: NDArray[np.float64],
    mass: float,
    settings: SimSettings,
    mu: float,
    torsion: float,
) -> None:
    body = spec.worldbody.add_body(name="object")
    body.add_freejoint(name="object_free")
    # Mass and inertia come from the watertight mesh: the parts overlap, so summing them would double-count.
    body.explicitinertial = True
    body.mass = mass
    body.ipos = np.asarray(com, dtype=float)
    i = np.asarray(inertia, dtype=float)
    body.fullinertia = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
    for k, (vertices, faces) in enumerate(parts):
        spec.add_mesh(
            name=f"part{k}",
            uservert=np.asarray(vertices, dtype=float).ravel().tolist(),
            userface=np.asarray(faces, dtype=np.int64).ravel().tolist(),
        )
        body.add_geom(
            name=f"part{k}",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=f"part{k}",
            contype=1,
            conaffinity=0,
            **contact_friction(mu, torsion),
            density=0.0,
            solref=list(settings.contact_solref),
            solimp=[*settings.contact_solimp, 0.5, 2.0],
            rgba=[0.75, 0.72, 0.65, 1.0],
        )


def _add_tip(
    spec: mujoco.MjSpec,
    i: int,
    centre: NDArray[np.float64],
    axes: NDArray[np.float64],
    radius: float,
    settings: SimSettings,
    mu: float,
    torsion: float,
) -> None:
    body = spec.worldbody.add_body(name=f"tip{i}", pos=centre.tolist())
    for name, axis in zip(("n", "a", "b"), axes, strict=True):
        body.add_joint(
            name=f"tip{i}_{name}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=axis.tolist(),
            armature=settings.slide_armature,
        )
    body.add_geom(
        name=f"tip{i}",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[radius, 0.0, 0.0],
        mass=settings.tip_mass,
        contype=0,
        conaffinity=1,
        **contact_friction(mu, torsion),
        solref=list(settings.contact_solref),
        solimp=[*settings.contact_solimp, 0.5, 2.0],
        rgba=[0.2, 0.45, 0.8, 1.0],
    )
    armature_mass = settings.tip_mass + settings.slide_armature
    for name, stiffness, limit in (
        ("n", settings.servo_stiffness, settings.max_normal_force),
        ("a", settings.tangential_stiffness, None),
        ("b", settings.tangential_stiffness, None),
    ):
        act = spec.add_actuator(name=f"tip{i}_{name}", target=f"tip{i}_{name}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        # Critical damping of the slide's mass keeps the servos from ringing under a ramp.
        act.set_to_position(kp=stiffness, kv=2.0 * np.sqrt(stiffness * armature_mass))
        if limit is not None:
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.forcerange = [-limit, limit]


def build_scene(
    parts: Sequence[tuple[NDArray[np.float64], NDArray[np.int64]]],
    com: NDArray[np.float64],
    inertia: NDArray[np.float64],
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    settings: SimSettings,
    mu: float,
    tip_radius: float,
    gravity: bool | None = None,
    torsion: float = 0.0,
) -> GraspScene:
    """Compile the grasp model.

    Args:
        parts: Convex parts of the object, each ``(vertices (v, 3) [m], faces (f, 3))``.
        com: Object centre of mass, shape (3,) [m].
        inertia: Inertia tensor about the COM, shape (3, 3) [kg·m²] (for ``settings.body_mass``).
        positions: Planned contacts, shape (m, 3) [m].
        normals: Inward unit normals at the contacts, shape (m, 3).
        settings: Simulation settings.
        mu: Friction coefficient of the tip-object contacts.
        tip_radius: Fingertip sphere radius [m].
        gravity: Override of ``settings.gravity`` (the weight test turns it on).
        torsion: Torsional friction coefficient of the tip-object contacts [m]; 0 for hard
            fingers (point contacts), > 0 for soft fingers (condim 4).

    Returns:
        The compiled scene.
    """
    positions = np.asarray(positions, dtype=float)
    normals = np.asarray(normals, dtype=float)
    spec = mujoco.MjSpec()
    spec.modelname = "ogcp_grasp"
    set_options(spec, settings, settings.gravity if gravity is None else gravity)
    add_object(spec, parts, com, inertia, settings.body_mass, settings, mu, torsion)
    a, b = tangent_basis(normals)
    for i in range(len(positions)):
        centre = positions[i] - tip_radius * normals[i]
        _add_tip(spec, i, centre, np.stack([normals[i], a[i], b[i]]), tip_radius, settings, mu, torsion)
    model = spec.compile()
    object_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")
    joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "object_free")
    object_geoms = np.array(
        [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"part{k}") for k in range(len(parts))], dtype=np.intp
    )
    tip_geoms = np.array(
        [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"tip{i}") for i in range(len(positions))], dtype=np.intp
    )
    normal_acts = np.array(
        [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"tip{i}_n") for i in range(len(positions))],
        dtype=np.intp,
    )
    ctrl = np.zeros(model.nu)
    ctrl[normal_acts] = settings.target_factor * settings.servo_compliance
    return GraspScene(
        model,
        object_body,
        int(model.jnt_qposadr[joint]),
        object_geoms,
        tip_geoms,
        ctrl,
        float(tip_radius),
        float(mu),
        float(torsion),
    )
