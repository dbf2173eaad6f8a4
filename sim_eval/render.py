"""Offscreen picture of a settled grasp (needs an OpenGL backend: ``MUJOCO_GL=egl`` or ``osmesa``)."""

from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.decomposition.decompose import DecompositionSettings
from ogcp.sim_eval.decomposition.ladder import DecompositionLadder
from ogcp.sim_eval.evaluate import object_diagonal, tip_radius
from ogcp.sim_eval.protocols.phases import FULL_STATE, Settled, settle
from ogcp.sim_eval.protocols.trial import ObjectBody, contact_torsion
from ogcp.sim_eval.result import GraspSimResult
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.collision import place_tips
from ogcp.sim_eval.scene.grasp_scene import GraspScene, build_scene
from ogcp.sim_eval.settings import SimSettings


def render_grasp(
    scene: GraspScene,
    settled: Settled,
    width: int = 640,
    height: int = 480,
    azimuth: float = 135.0,
    elevation: float = -25.0,
    framed: NDArray[np.intp] | None = None,
) -> NDArray[np.uint8]:
    """Render the settled grasp from a free camera looking at the object.

    Args:
        scene: The compiled grasp model.
        settled: The settled state to show.
        width: Image width [px].
        height: Image height [px].
        azimuth: Camera azimuth [deg].
        elevation: Camera elevation [deg].
        framed: Geom ids the picture must show (e.g. a hand's palm and fingers, not its forearm);
            None: every geom.

    Returns:
        RGB image, shape (height, width, 3).

    Raises:
        OgcpError: When no OpenGL context can be created (no display, EGL or OSMesa).
    """
    model = scene.model
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    model.vis.headlight.ambient[:] = 0.45  # the scene has no lights of its own
    model.vis.headlight.diffuse[:] = 0.7
    renderer = _renderer(model, height, width)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    mujoco.mj_forward(model, data)
    camera = mujoco.MjvCamera()
    lookat, distance = _frame(model, data, scene, framed)
    camera.lookat[:] = lookat
    camera.distance = distance
    camera.azimuth, camera.elevation = azimuth, elevation
    try:
        renderer.update_scene(data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()


def _frame(
    model: mujoco.MjModel, data: mujoco.MjData, scene: GraspScene, framed: NDArray[np.intp] | None
) -> tuple[NDArray[np.float64], float]:
    """Where the camera looks and from how far [m]: the object and whatever grips it (tips, or a hand).

    The bounding spheres of the framed geoms give the box to show; planes (rbound 0) are left out.
    """
    shown = model.geom_rbound > 0
    if framed is not None:
        shown &= np.isin(np.arange(model.ngeom), np.concatenate([framed, scene.object_geoms]))
    centres, radii = data.geom_xpos[shown], model.geom_rbound[shown][:, None]
    low, high = (centres - radii).min(axis=0), (centres + radii).max(axis=0)
    half = 0.5 * float(np.linalg.norm(high - low))
    # A sphere of radius r fills the 45-degree default field of view from r / sin(22.5 deg) = 2.6 r.
    own = 4.0 * float(np.max(model.geom_rbound[scene.object_geoms])) + 10 * scene.tip_radius
    return 0.5 * (low + high), max(own, 2.4 * half)


def check_offscreen_rendering() -> None:
    """Raise at once when this machine cannot render offscreen (before any simulation is spent).

    Raises:
        OgcpError: When no OpenGL context can be created (no display, EGL or OSMesa).
    """
    _renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8).close()


def _renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """A MuJoCo renderer, or one line saying why there is none.

    GLFW's own warnings (no DISPLAY, not initialised) are kept off the terminal: the error says it all.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return mujoco.Renderer(model, height, width)
    except Exception as exc:
        raise OgcpError(
            "offscreen rendering is not available here: set MUJOCO_GL=egl or MUJOCO_GL=osmesa "
            f"with the matching library installed (e.g. Debian's libosmesa6) ({type(exc).__name__})"
        ) from exc


def render_plan(
    record: dict,
    settings: SimSettings | None = None,
    decomposition: DecompositionSettings | None = None,
    grasp_index: int = 0,
    width: int = 640,
    height: int = 480,
    tips: bool = False,
    plan_file: str | Path | None = None,
) -> NDArray[np.uint8]:
    """Picture of one grasp of an ``ogcp.plan/1`` record after settling (default: the best grasp).

    The grasp is the one ``evaluate`` simulates: on the decomposition the grasp's contacts call
    for, with the tips started on its surface; or, for a plan made with a hand, that hand fitted,
    closed by its servos and settled (``tips``: fingertip spheres even then).

    Args:
        record: The plan record.
        settings: Simulation settings (default :class:`SimSettings`).
        decomposition: Decomposition settings (default CoACD with its defaults).
        grasp_index: Which of the plan's grasps, best first.
        width: Image width [px].
        height: Image height [px].
        tips: Draw fingertip spheres even when the plan has a hand.
        plan_file: Where the record was read from (a mesh next to it is looked for first).

    Returns:
        RGB image, shape (height, width, 3).

    Raises:
        OgcpError: For a grasp index outside the plan, a hand that cannot realise the grasp, or
            no OpenGL context.
    """
    from ogcp.sim_eval.evaluate import plan_hand
    from ogcp.sim_eval.inputs.plan_input import plan_input

    plan = plan_input(record, plan_file)
    diagonal = object_diagonal(plan.mesh)
    settings = (settings or SimSettings()).scaled(diagonal)
    if not 0 <= grasp_index < len(plan.grasps):
        raise OgcpError(f"grasp index {grasp_index} outside the plan's {len(plan.grasps)} grasps")
    grasp = tuple(int(i) for i in plan.grasps[grasp_index])
    idx = np.asarray(grasp, dtype=np.intp)
    com, inertia = object_inertia(plan.mesh, settings.body_mass)
    mu = settings.mu if settings.mu is not None else plan.contacts.mu
    radius = tip_radius(plan.mesh, settings)
    ladder = DecompositionLadder(plan.mesh, decomposition or DecompositionSettings(), diagonal, radius)
    positions, normals = plan.contacts.positions[idx], plan.contacts.normals[idx]
    fit = ladder.fit(positions, normals)
    hand = None if tips else plan_hand(record)
    if hand is not None:
        from ogcp.sim_eval.hand.trial import close_on_grasp

        body = ObjectBody(com, inertia, radius, diagonal)
        torsion = contact_torsion(plan.contacts, settings)
        closed = close_on_grasp(plan.contacts, grasp, "render", fit, body, settings, hand, mu, torsion)
        if isinstance(closed, GraspSimResult):
            raise OgcpError(f"nothing to draw for grasp {grasp_index}: {closed.error} (--tips draws fingertips)")
        from ogcp.sim_eval.hand.mount import PREFIX

        scene = closed.closed.scene
        palm = PREFIX + hand.kinematics.descriptor.palm
        framed = palm_and_fingers(scene.model, palm)
        azimuth = side_azimuth(scene, closed.settled, palm)
        return render_grasp(scene, closed.settled, width, height, azimuth=azimuth, framed=framed)
    placed = place_tips(fit.surface, positions, normals, radius, max_inward=radius)
    scene = build_scene(fit.decomposition.parts, com, inertia, placed.points, placed.normals, settings, mu, radius)
    return render_grasp(scene, settle(scene, settings), width, height)


def palm_and_fingers(model: mujoco.MjModel, palm_body: str) -> NDArray[np.intp]:
    """Geom ids of the body ``palm_body`` and every body below it: the grip, without a forearm or an arm."""
    palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, palm_body)
    below = np.zeros(model.nbody, dtype=bool)
    below[palm] = palm >= 0
    for body in range(1, model.nbody):  # MuJoCo numbers a parent before its children
        below[body] |= below[model.body_parentid[body]]
    return np.flatnonzero(below[model.geom_bodyid]).astype(np.intp)


def side_azimuth(scene: GraspScene, settled: Settled, palm_body: str) -> float:
    """[deg] A camera azimuth that looks across the line from the palm to the object, not along it.

    Looking along it, the palm hides the grasp or the object hides the fingers; from the side both
    show. The view direction is the horizontal perpendicular of that line (any azimuth when the
    line is vertical: the default's 135 degrees).
    """
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    mujoco.mj_kinematics(model, data)
    palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, palm_body)
    across = np.cross(data.xipos[scene.object_body] - data.xpos[palm], [0.0, 0.0, 1.0])
    if palm < 0 or np.linalg.norm(across[:2]) < 1e-9:
        return 135.0
    return float(np.degrees(np.arctan2(across[1], across[0])))
