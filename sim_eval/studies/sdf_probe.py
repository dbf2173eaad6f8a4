"""Probe: can a MuJoCo signed distance field stand in for CoACD's convex parts as the object's collider?

Run: ``python -m ogcp.sim_eval.studies.sdf_probe [--objects donut,amphora,bunny] [--points 50]``.

``import mujoco`` loads every library in ``mujoco/plugin/`` (``libsdf_plugin.so`` among them),
but the wheel's SDF library registers only the analytic bolt, bowl, gear, nut and torus. So the
probe uses ``mujoco.sdf.sdflib`` where a build has it, else MuJoCo's own mesh SDF (``geom
type="sdf"`` on a mesh without a plugin: an octree built at compile time). Per object and
collider it measures:

* accuracy: a sphere of radius r (4 % of the diagonal) centred ``r + g`` outside surface points
  along the outward normal, g in :data:`GAPS`; the smallest ``contact.dist`` MuJoCo reports
  against the exact signed distance minus r: |error| median/p90/max and the signed median, in %
  of the diagonal; ``miss``: no contact reported although the sphere's margin is 2 % of the
  diagonal; ``ncon``: median contacts of the one pair; ``normal``: median/max angle between the
  deepest contact's normal and the exact one (centre minus nearest surface point);
* speed and stability: compile time, steps/s of the object held by 3 preloaded tips (the A*
  grasp of 50 contacts; tips on 3 slides with servos as in :mod:`ogcp.sim_eval.scene.grasp_scene`), contacts per
  step, and over the second half of 2 x settle_time: object and tip drift [% diag] and the
  normal-force spread std/mean of the worst tip.
"""

from __future__ import annotations

import argparse
import itertools
import time
from typing import Any

import mujoco  # a study of MuJoCo itself, so it lives in sim_eval
import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.grasp.mesh_distance import SurfaceIndex
from ogcp.planner.grasp.wrench import tangent_basis
from ogcp.sim_eval.decomposition.decompose import decompose
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings

SDFLIB = (
    '<extension><plugin plugin="mujoco.sdf.sdflib"><instance name="sdf"><config key="aabb" value="0"/>'
    "</instance></plugin></extension>"
)
GAPS = (0.005, 0.0, -0.005)  # sphere gap to the surface [fraction of the diagonal]
_ASSET_NAMES = itertools.count()
Parts = list[tuple[NDArray[np.float64], NDArray[np.int64]]]


def sdf_xml(mode: str, mesh_file: str) -> str:
    """A free body "object" whose one geom is the SDF of the mesh in ``mesh_file``."""
    plugin = '<plugin instance="sdf"/>' if mode == "sdflib" else ""
    return (
        f"<mujoco>{SDFLIB if mode == 'sdflib' else ''}<asset><mesh name='obj' file='{mesh_file}'>{plugin}</mesh>"
        "</asset><worldbody><body name='object'><freejoint/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/>"
        f"<geom type='sdf' mesh='obj' density='0'>{plugin}</geom></body></worldbody></mujoco>"
    )


def sdf_mode() -> str | None:
    """'sdflib' (the plugin), 'octree' (MuJoCo's own mesh SDF) or None when neither compiles."""
    tetrahedron = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    )
    for mode in ("sdflib", "octree"):
        try:
            mujoco.MjModel.from_xml_string(
                sdf_xml(mode, "t.obj"), {"t.obj": trimesh.exchange.obj.export_obj(tetrahedron).encode()}
            )
        except ValueError:
            continue
        return mode
    return None


def object_spec(mesh: trimesh.Trimesh, parts: Parts | None, **geom: Any) -> mujoco.MjSpec:
    """A spec with the free body "object": its convex parts as mesh geoms, or (parts None) the mesh as an SDF."""
    if parts is None:  # XML: in 3.17 MjSpec's plugin references were refused (or crashed) where this compiles
        # A new file name each time: MuJoCo caches compiled meshes (and their octrees) by asset name.
        file = f"o{next(_ASSET_NAMES)}.obj"
        spec = mujoco.MjSpec.from_string(
            sdf_xml(MODE or "", file), assets={file: trimesh.exchange.obj.export_obj(mesh).encode()}
        )
    else:
        spec = mujoco.MjSpec()
        body = spec.worldbody.add_body(name="object")
        body.add_freejoint()  # a free body: two static bodies never collide
        for k, (v, f) in enumerate(parts):
            spec.add_mesh(name=f"p{k}", uservert=np.ravel(v).tolist(), userface=np.ravel(f).tolist())
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"p{k}", density=0.0)
    for g in spec.geoms:
        for key, value in {"contype": 1, "conaffinity": 0, **geom}.items():
            setattr(g, key, value)
    return spec


def accuracy(mesh: trimesh.Trimesh, parts: Parts | None, r: float, diag: float, points: int) -> list[str]:
    """Table cells per gap: |error| median/p90/max, signed median [% diag], misses, contacts per pair."""
    spec = object_spec(mesh, parts)
    body = spec.body("object")
    body.explicitinertial, body.mass, body.inertia = True, 1.0, [1.0, 1.0, 1.0]
    tip = spec.worldbody.add_body(name="tip", mocap=True)
    tip.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[r, 0, 0], contype=0, conaffinity=1, margin=0.02 * diag)
    model = spec.compile()
    data = mujoco.MjData(model)
    surface, face = trimesh.sample.sample_surface(mesh, points, seed=0)
    index = SurfaceIndex(mesh)
    cells = []
    for gap in GAPS:
        centres = surface + (r + gap * diag) * mesh.face_normals[face]
        near = index.nearest(centres)
        exact = np.where(near.outside, near.distance, -near.distance) - r
        normal = (centres - near.point) / np.linalg.norm(centres - near.point, axis=1)[:, None]
        got, angle, counts = np.full(len(centres), np.nan), np.full(len(centres), np.nan), []
        for k, centre in enumerate(centres):
            data.mocap_pos[0] = centre
            mujoco.mj_forward(model, data)
            counts.append(data.ncon)
            if data.ncon:
                deepest = int(np.argmin(data.contact.dist[: data.ncon]))
                got[k] = data.contact.dist[deepest]
                cosine = abs(float(data.contact.frame[deepest, :3] @ normal[k]))  # frame: geom1 -> geom2
                angle[k] = np.degrees(np.arccos(min(cosine, 1.0)))
        err = (got - exact)[~np.isnan(got)] / diag * 100
        stats = "-"
        if len(err):
            stats = "/".join(f"{v:.3f}" for v in np.percentile(np.abs(err), [50, 90, 100]))
            stats += f" ({np.median(err):+.3f}) normal {np.nanmedian(angle):.1f}/{np.nanmax(angle):.1f} deg"
        cells.append(f"{stats} miss {int(np.isnan(got).sum())} ncon {np.median(counts):.0f}")
    return cells


def grasp_model(
    mesh: trimesh.Trimesh, parts: Parts | None, settings: SimSettings, r: float, initpoints: int | None
) -> tuple[mujoco.MjModel, NDArray[np.float64], float]:
    """The object (free) held by 3 tips at the A* grasp of 50 contacts, as in :func:`ogcp.sim_eval.scene.grasp_scene.build_scene`.

    Returns:
        ``(model, preload ctrl, compile seconds)``.
    """
    contacts = sample_contacts(mesh, 50, 0, tip_radius=r)
    grasp = list(GraspPlanner().plan(contacts, 3).grasp)
    positions, normals = contacts.positions[grasp], contacts.normals[grasp]
    contact = {
        "condim": 3,
        "friction": [contacts.mu, 0.0, 0.0],
        "solref": list(settings.contact_solref),
        "solimp": [*settings.contact_solimp, 0.5, 2.0],
    }
    spec = object_spec(mesh, parts, **contact)
    opt = spec.option
    opt.timestep, opt.impratio, opt.gravity = settings.timestep, settings.impratio, [0.0, 0.0, 0.0]
    opt.integrator, opt.cone = mujoco.mjtIntegrator.mjINT_IMPLICITFAST, mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.noslip_iterations, opt.iterations = settings.noslip_iterations, settings.solver_iterations
    if initpoints is not None:
        opt.sdf_initpoints = initpoints
    body = spec.body("object")
    com, inertia = object_inertia(mesh, settings.body_mass)
    body.explicitinertial, body.mass, body.ipos = True, settings.object_mass, com
    body.inertia = [0.0, 0.0, 0.0]  # the SDF's XML gives a placeholder diagonal inertia
    body.fullinertia = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
    a, b = tangent_basis(normals)
    ctrl = []
    for i in range(3):
        tip = spec.worldbody.add_body(name=f"tip{i}", pos=(positions[i] - r * normals[i]).tolist())
        for name, axis in zip("nab", (normals[i], a[i], b[i]), strict=True):
            slide = tip.add_joint(name=f"t{i}{name}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis.tolist())
            slide.armature = settings.slide_armature
            kp = settings.servo_stiffness if name == "n" else settings.tangential_stiffness
            act = spec.add_actuator(target=f"t{i}{name}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_position(kp=kp, kv=2.0 * np.sqrt(kp * (settings.tip_mass + settings.slide_armature)))
            if name == "n":
                act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
                act.forcerange = [-settings.max_normal_force, settings.max_normal_force]
            ctrl.append(settings.target_factor * settings.servo_compliance if name == "n" else 0.0)
        sphere = {"type": mujoco.mjtGeom.mjGEOM_SPHERE, "size": [r, 0, 0], "mass": settings.tip_mass}
        tip.add_geom(**sphere, contype=0, conaffinity=1, **contact)
    start = time.perf_counter()
    model = spec.compile()
    return model, np.array(ctrl), time.perf_counter() - start


def hold(
    model: mujoco.MjModel, ctrl: NDArray[np.float64], steps: int, diag: float
) -> tuple[float, str, float, float, float]:
    """Steps/s, contacts per step (min-max) and, over the second half, object and tip drift [% diag], force spread."""
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    tips = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"tip{i}") for i in range(3)]
    force, wrench, ncon, qpos = np.zeros((steps, 3)), np.zeros(6), [], np.zeros((steps, model.nq))
    elapsed = 0.0
    for k in range(steps):
        start = time.perf_counter()
        mujoco.mj_step(model, data)
        elapsed += time.perf_counter() - start
        ncon.append(data.ncon)
        qpos[k] = data.qpos
        for c in range(data.ncon):
            mujoco.mj_contactForce(model, data, c, wrench)
            bodies = model.geom_bodyid[data.contact.geom[c]]
            force[k, tips.index(next(b for b in bodies if b in tips))] += wrench[0]
    late = slice(steps // 2, steps)
    obj = float(np.linalg.norm(qpos[-1, :3] - qpos[steps // 2, :3])) / diag * 100
    tip = float(np.abs(qpos[-1, 7:] - qpos[steps // 2, 7:]).max()) / diag * 100
    spread = float((force[late].std(axis=0) / np.maximum(force[late].mean(axis=0), 1e-9)).max())
    return steps / elapsed, f"{min(ncon[late])}-{max(ncon[late])}", obj, tip, spread


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="donut,amphora,bunny")
    parser.add_argument("--points", type=int, default=50)
    args = parser.parse_args()
    if MODE is None:
        print("sdf_probe: skipped: this MuJoCo has neither the mujoco.sdf.sdflib plugin nor mesh SDF geoms")
        return
    print(f"mujoco {mujoco.__version__}, SDF: {MODE}; accuracy per gap {GAPS} of the diagonal:")
    print("|error| median/p90/max (signed median) [% diag], normal error, misses, contacts of the pair")
    settings = SimSettings()
    for name in args.objects.split(","):
        mesh, _ = resolve_object(name)
        diag = float(np.linalg.norm(mesh.extents))
        scaled, r = settings.scaled(diag), settings.tip_radius_ratio * diag
        parts = [(np.asarray(v), np.asarray(f)) for v, f in decompose(mesh).parts]
        steps = round(2 * settings.settle_time / settings.timestep)
        for label, use, initpoints in (("coacd", parts, None), ("sdf", None, None), ("sdf init10", None, 10)):
            cells = accuracy(mesh, use, r, diag, args.points) if initpoints is None else ["-"]
            model, ctrl, compile_s = grasp_model(mesh, use, scaled, r, initpoints)
            rate, ncon, obj, tip, spread = hold(model, ctrl, steps, diag)
            print(f"{name:8s} {label:10s} " + " | ".join(cells))
            print(
                f"{'':20s}compile {compile_s:5.2f} s {rate:7.0f} steps/s  contacts {ncon}  drift object "
                f"{obj:.4f} % tip {tip:.4f} %  force std/mean {spread:.4f}"
            )


MODE = sdf_mode()

if __name__ == "__main__":
    main()
