"""Offscreen picture of a settled grasp (needs an OpenGL backend: ``MUJOCO_GL=egl`` or ``osmesa``)."""

from __future__ import annotations

import warnings

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.decomposition.decompose import DecompositionSettings
from ogcp.sim_eval.decomposition.ladder import DecompositionLadder
from ogcp.sim_eval.evaluate import object_diagonal, tip_radius
from ogcp.sim_eval.protocols.phases import FULL_STATE, Settled, settle
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
) -> NDArray[np.uint8]:
    """Render the settled grasp from a free camera looking at the object.

    Args:
        scene: The compiled grasp model.
        settled: The settled state to show.
        width: Image width [px].
        height: Image height [px].
        azimuth: Camera azimuth [deg].
        elevation: Camera elevation [deg].

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
    camera.lookat[:] = data.xipos[scene.object_body]
    camera.distance = 4.0 * float(np.max(model.geom_rbound[scene.object_geoms])) + 10 * scene.tip_radius
    camera.azimuth, camera.elevation = azimuth, elevation
    try:
        renderer.update_scene(data, camera)
        return renderer.render().copy()
    finally:
        renderer.close()


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
) -> NDArray[np.uint8]:
    """Picture of one grasp of an ``ogcp.plan/1`` record after settling (default: the best grasp).

    The grasp is the one ``evaluate`` simulates: on the decomposition the grasp's contacts call
    for, with the tips started on its surface.
    """
    from ogcp.sim_eval.inputs.plan_input import plan_input

    plan = plan_input(record)
    settings = (settings or SimSettings()).scaled(object_diagonal(plan.mesh))
    if not 0 <= grasp_index < len(plan.grasps):
        raise OgcpError(f"grasp index {grasp_index} outside the plan's {len(plan.grasps)} grasps")
    idx = np.asarray(plan.grasps[grasp_index], dtype=np.intp)
    com, inertia = object_inertia(plan.mesh, settings.body_mass)
    mu = settings.mu if settings.mu is not None else plan.contacts.mu
    radius = tip_radius(plan.mesh, settings)
    ladder = DecompositionLadder(
        plan.mesh, decomposition or DecompositionSettings(), object_diagonal(plan.mesh), radius
    )
    positions, normals = plan.contacts.positions[idx], plan.contacts.normals[idx]
    fit = ladder.fit(positions, normals)
    placed = place_tips(fit.surface, positions, normals, radius, max_inward=radius)
    scene = build_scene(fit.decomposition.parts, com, inertia, placed.points, placed.normals, settings, mu, radius)
    return render_grasp(scene, settle(scene, settings), width, height)
