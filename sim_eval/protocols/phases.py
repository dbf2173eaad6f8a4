"""The loading protocol: preload and settle, then ramp disturbance wrenches until the object moves.

Every direction's trial starts from the same settled state and runs in a batch through
``mujoco.rollout`` (threads), with the disturbance as a per-step ``xfrc_applied`` control on
the object: force and torque at its centre of mass, world frame. :func:`serial_trials` runs
the same trials with a plain ``mj_step`` loop (the reference the rollout is checked against).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import mujoco
import numpy as np
from mujoco import rollout
from numpy.typing import NDArray

from ogcp.sim_eval.scene.grasp_scene import GraspScene
from ogcp.sim_eval.settings import SimSettings

FULL_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
CONTROL_SPEC = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_XFRC_APPLIED
QPOS_OFFSET = 1  # the full physics state starts with the time, then qpos
CREEP_WINDOW = 0.1  # [s] the end of settling over which the object must be still
CONTACT_FRACTION = 0.01  # a tip touches when its normal force exceeds this fraction of F_max
DIRECTIONS_PER_BATCH = 16  # bounds the rollout's state buffer
RAMP_SLICE = 200  # steps a ramped trial runs between checks for its failure
RUNAWAY_RADII = 50.0  # a slide this many tip radii from its start has diverged


@dataclass(frozen=True, eq=False)
class Settled:
    """The preloaded grasp after settling.

    Attributes:
        state: Full physics state, shape (nstate,).
        pose: Object position [m] and quaternion, shape (7,).
        gates: Validity gates: ``initial_penetration`` [m] (deepest contact), ``tip_penetration``
            (per tip, shape (m,) [m]), ``tips_in_contact`` (count),
            ``creep`` [m], ``diverged`` (bool), and ``valid`` (all passed).
        normal_forces: Normal force of each tip on the object after settling, shape (m,) [N].
    """

    state: NDArray[np.float64]
    pose: NDArray[np.float64]
    gates: dict[str, float | int | bool | list[float]]
    normal_forces: NDArray[np.float64]

    def tip_centres(self, scene: GraspScene) -> NDArray[np.float64] | None:
        """Centres of the fingertip spheres after settling, in the object's own frame, shape (m, 3) [m].

        The object body starts at the world origin unrotated, so its frame is the mesh's: these
        are where the settled tips sit on the mesh as drawn. None when the settled state is not
        finite (a diverged settle).
        """
        if not (np.all(np.isfinite(self.state)) and np.all(np.isfinite(self.pose))):
            return None
        data = mujoco.MjData(scene.model)
        mujoco.mj_setState(scene.model, data, self.state, FULL_STATE)
        mujoco.mj_kinematics(scene.model, data)
        world = data.geom_xpos[scene.tip_geoms]
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, self.pose[3:7])
        # Rows (x - p) R: each row is R^T (x - p), the world point in the object's frame.
        return np.asarray((world - self.pose[:3]) @ rotation.reshape(3, 3), dtype=float)


@dataclass(frozen=True, eq=False)
class TrialResult:
    """Outcome of ramped trials.

    Attributes:
        failure_load: Load magnitude at which the object first moved beyond the thresholds, shape
            (D,) [N, scaled wrench]; the ramp's final load where it never moved.
        failed: Whether each trial reached the thresholds, shape (D,).
        diverged: Whether each trial produced non-finite states, shape (D,).
        steps: Physics steps per trial.
    """

    failure_load: NDArray[np.float64]
    failed: NDArray[np.bool_]
    diverged: NDArray[np.bool_]
    steps: int
    extra: dict[str, float] = field(default_factory=dict)


def tip_normal_forces(scene: GraspScene, data: mujoco.MjData) -> NDArray[np.float64]:
    """Summed normal force of each tip's contacts with the object, shape (m,) [N]."""
    forces = np.zeros(scene.fingers)
    wrench = np.zeros(6)
    tip_index = scene.geom_fingers()
    for c in range(data.ncon):
        contact = data.contact[c]
        for geom in (contact.geom1, contact.geom2):
            if geom in tip_index:
                mujoco.mj_contactForce(scene.model, data, c, wrench)
                forces[tip_index[geom]] += wrench[0]
    return forces


def _penetration(scene: GraspScene, data: mujoco.MjData) -> tuple[float, NDArray[np.float64]]:
    """Deepest penetration of any contact, and of each tip's contacts, shape (m,) [m]."""
    depth, tips = 0.0, np.zeros(scene.fingers)
    tip_index = scene.geom_fingers()
    for c in range(data.ncon):
        contact = data.contact[c]
        depth = max(depth, -float(contact.dist))
        for geom in (contact.geom1, contact.geom2):
            if geom in tip_index:
                tips[tip_index[geom]] = max(tips[tip_index[geom]], -float(contact.dist))
    return depth, tips


def _displacement(pose: NDArray[np.float64], reference: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Translation [m] and rotation angle [deg] of poses (..., 7) relative to one reference pose."""
    shift = np.linalg.norm(pose[..., :3] - reference[:3], axis=-1)
    dots = np.abs(np.clip(np.einsum("...i,i->...", pose[..., 3:7], reference[3:7]), -1.0, 1.0))
    angle = np.degrees(2.0 * np.arccos(np.minimum(dots, 1.0)))
    return shift, angle


def settle(scene: GraspScene, settings: SimSettings) -> Settled:
    """Preload the grasp, let it settle and check the validity gates.

    Args:
        scene: The compiled grasp model.
        settings: Simulation settings (``settle_time``, tolerances).

    Returns:
        The settled state with its gates.
    """
    model = scene.model
    data = mujoco.MjData(model)
    start = scene.start()
    data.qpos[:] = start
    data.ctrl[:] = scene.preload_ctrl
    mujoco.mj_forward(model, data)
    penetration, tip_penetration = _penetration(scene, data)
    steps = max(1, round(settings.settle_time / model.opt.timestep))
    window = min(steps, max(1, round(CREEP_WINDOW / model.opt.timestep)))
    q = slice(scene.object_qpos, scene.object_qpos + 7)
    diverged = False
    # Tips flung far from the object (an unstable step size) count as divergence too.
    slides = scene.watched_qpos
    if slides is None:
        slides = np.setdiff1d(np.arange(model.nq), np.arange(scene.object_qpos, scene.object_qpos + 7))
    runaway = RUNAWAY_RADII * scene.tip_radius
    window_start = data.qpos[q].copy()
    for k in range(steps):
        if k == steps - window:
            window_start = data.qpos[q].copy()
        mujoco.mj_step(model, data)
        if not np.all(np.isfinite(data.qpos)) or np.max(np.abs(data.qpos[slides] - start[slides])) > runaway:
            diverged = True
            break
    # MuJoCo resets the data when the acceleration blows up, so a rewound clock also means divergence.
    rewound = data.time < (steps - 0.5) * model.opt.timestep
    diverged = diverged or rewound or bool(data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)
    pose = data.qpos[q].copy()
    shift, _ = _displacement(pose, window_start) if not diverged else (np.inf, np.inf)
    forces = tip_normal_forces(scene, data) if not diverged else np.zeros(scene.fingers)
    touching = int(np.sum(forces > CONTACT_FRACTION * settings.max_normal_force))
    gates: dict[str, float | int | bool | list[float]] = {
        "initial_penetration": penetration,
        "tip_penetration": tip_penetration.tolist(),
        "tips_in_contact": touching,
        "creep": float(shift),
        "diverged": diverged,
    }
    gates["valid"] = bool(
        not diverged
        and penetration <= settings.penetration_tolerance
        and touching == scene.fingers
        and float(shift) <= settings.creep_tolerance
    )
    state = np.empty(mujoco.mj_stateSize(model, FULL_STATE))
    mujoco.mj_getState(model, data, state, FULL_STATE)
    return Settled(state, pose, gates, forces)


def unloaded_drift(scene: GraspScene, settled: Settled) -> float:
    """Farthest the object moves from a settled state, with no load, over :data:`CREEP_WINDOW` [m]; inf if it diverges."""
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    data.ctrl[:] = scene.preload_ctrl
    q = slice(scene.object_qpos, scene.object_qpos + 3)
    start = data.qpos[q].copy()
    farthest = 0.0
    for _ in range(max(1, round(CREEP_WINDOW / model.opt.timestep))):
        mujoco.mj_step(model, data)
        if not np.all(np.isfinite(data.qpos)):
            return math.inf
        farthest = max(farthest, float(np.linalg.norm(data.qpos[q] - start)))
    return farthest


def settle_further(scene: GraspScene, settled: Settled, seconds: float) -> Settled:
    """A settled state run on with no load for ``seconds``: its state and the object's pose (the gates kept)."""
    model = scene.model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, settled.state, FULL_STATE)
    data.ctrl[:] = scene.preload_ctrl
    for _ in range(max(1, round(seconds / model.opt.timestep))):
        mujoco.mj_step(model, data)
    state = np.empty(mujoco.mj_stateSize(model, FULL_STATE))
    mujoco.mj_getState(model, data, state, FULL_STATE)
    pose = data.qpos[scene.object_qpos : scene.object_qpos + 7].copy()
    return Settled(state, pose, settled.gates, settled.normal_forces)


def _physical(directions: NDArray[np.float64], torque_scale: float) -> NDArray[np.float64]:
    """Scaled directions (D, 6) -> xfrc rows (D, 6): force [N] and torque [N·m] per unit load."""
    rows = np.array(directions, dtype=float)
    rows[:, 3:] *= torque_scale
    return rows


def _controls(scene: GraspScene, loads: NDArray[np.float64], rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per-step controls (D, nstep, nu + 6 nbody): preload ctrl and the object's xfrc."""
    model = scene.model
    trials, nstep = loads.shape
    controls = np.zeros((trials, nstep, model.nu + 6 * model.nbody))
    controls[:, :, : model.nu] = scene.preload_ctrl
    start = model.nu + 6 * scene.object_body
    controls[:, :, start : start + 6] = loads[:, :, None] * rows[:, None, :]
    return controls


def _first_failure(
    poses: NDArray[np.float64], reference: NDArray[np.float64], settings: SimSettings
) -> tuple[NDArray[np.intp], NDArray[np.bool_], NDArray[np.bool_]]:
    shift, angle = _displacement(poses, reference)
    finite = np.all(np.isfinite(poses), axis=-1)
    moved = (shift > settings.move_threshold) | (angle > settings.rotation_threshold) | ~finite
    failed = moved.any(axis=1)
    first = np.where(failed, moved.argmax(axis=1), poses.shape[1] - 1)
    return first, failed, ~finite.all(axis=1)


def ramp_trials(
    scene: GraspScene,
    settled: Settled,
    directions: NDArray[np.float64],
    rates: NDArray[np.float64],
    duration: float,
    torque_scale: float,
    settings: SimSettings,
) -> TrialResult:
    """Ramp a load along each direction from the settled state (batched rollout over threads).

    Args:
        scene: The compiled grasp model.
        settled: The settled state the trials start from.
        directions: Unit disturbance directions in scaled wrench space, shape (D, 6).
        rates: Load rate of each direction, shape (D,) [N/s, scaled wrench].
        duration: Length of every ramp [s].
        torque_scale: rho [m] that turns scaled torques into N·m.
        settings: Simulation settings (thresholds, threads).

    Returns:
        Failure loads and flags per direction.
    """
    model = scene.model
    nstep = max(1, int(np.ceil(duration / model.opt.timestep)))
    rows = _physical(directions, torque_scale)
    rates = np.asarray(rates, dtype=float)
    threads = settings.threads or os.cpu_count() or 1
    datas = [mujoco.MjData(model) for _ in range(threads)]
    count = len(directions)
    first = np.full(count, nstep - 1, dtype=np.intp)
    failed = np.zeros(count, dtype=bool)
    diverged = np.zeros(count, dtype=bool)
    done = np.zeros(count, dtype=np.intp)  # steps each trial has run
    state = np.tile(settled.state, (count, 1))
    q = slice(QPOS_OFFSET + scene.object_qpos, QPOS_OFFSET + scene.object_qpos + 7)
    # Trials run in slices and leave once they fail: most fail near their prediction, well before
    # the ramp's end, and a hand's step costs several fingertip steps. Freed places take new trials.
    pending, running = list(range(count)), list[int]()
    while pending or running:
        while pending and len(running) < DIRECTIONS_PER_BATCH:
            running.append(pending.pop(0))
        trials = np.array(running)
        steps = done[trials][:, None] + np.arange(RAMP_SLICE)[None, :]
        loads = rates[trials][:, None] * (steps * model.opt.timestep)
        controls = _controls(scene, loads, rows[trials])
        out, _ = rollout.rollout(model, datas, state[trials], controls, control_spec=CONTROL_SPEC)
        for k, trial in enumerate(trials):
            ahead = min(RAMP_SLICE, nstep - int(done[trial]))  # the last slice runs past the ramp's end
            at, hit, bad = _first_failure(out[k : k + 1, :ahead, q], settled.pose, settings)
            if hit[0] or bad[0] or done[trial] + ahead >= nstep:
                first[trial] = done[trial] + at[0]
                failed[trial], diverged[trial] = hit[0], bad[0]
                running.remove(int(trial))
            else:
                state[trial] = out[k, -1]
            done[trial] += ahead
    failure = rates * first * model.opt.timestep
    return TrialResult(failure, failed, diverged, nstep)


def serial_trials(
    scene: GraspScene,
    settled: Settled,
    directions: NDArray[np.float64],
    rates: NDArray[np.float64],
    duration: float,
    torque_scale: float,
    settings: SimSettings,
) -> TrialResult:
    """The same trials as :func:`ramp_trials` with a plain serial ``mj_step`` loop (reference)."""
    model = scene.model
    data = mujoco.MjData(model)
    nstep = max(1, int(np.ceil(duration / model.opt.timestep)))
    rows = _physical(directions, torque_scale)
    failure = np.empty(len(directions))
    failed = np.zeros(len(directions), dtype=bool)
    diverged = np.zeros(len(directions), dtype=bool)
    q = slice(scene.object_qpos, scene.object_qpos + 7)
    for t, (row, rate) in enumerate(zip(rows, rates, strict=True)):
        mujoco.mj_setState(model, data, settled.state, FULL_STATE)
        data.ctrl[:] = scene.preload_ctrl
        failure[t] = rate * (nstep - 1) * model.opt.timestep
        for k in range(nstep):
            load = rate * k * model.opt.timestep
            data.xfrc_applied[scene.object_body] = load * row
            mujoco.mj_step(model, data)
            pose = data.qpos[q]
            if not np.all(np.isfinite(pose)):
                failure[t], failed[t], diverged[t] = load, True, True
                break
            shift, angle = _displacement(pose, settled.pose)
            if shift > settings.move_threshold or angle > settings.rotation_threshold:
                failure[t], failed[t] = load, True
                break
    return TrialResult(failure, failed, diverged, nstep)


def hold_poses(
    scene: GraspScene,
    settled: Settled,
    loads: NDArray[np.float64],
    duration: float,
    settings: SimSettings,
) -> NDArray[np.float64]:
    """The object's pose after every step of constant-load trials from the settled state.

    Args:
        scene: The compiled grasp model.
        settled: The settled start state.
        loads: Physical wrenches on the object (force [N], torque [N·m]), shape (L, 6).
        duration: Duration of each trial [s].
        settings: Simulation settings (threads).

    Returns:
        Position [m] and quaternion after steps 1..n of each trial, shape (L, n, 7); NaN once
        a trial diverged.
    """
    model = scene.model
    nstep = max(1, int(np.ceil(duration / model.opt.timestep)))
    threads = settings.threads or os.cpu_count() or 1
    datas = [mujoco.MjData(model) for _ in range(threads)]
    controls = _controls(scene, np.ones((len(loads), nstep)), np.asarray(loads, dtype=float))
    initial = np.tile(settled.state, (len(loads), 1))
    state, _ = rollout.rollout(model, datas, initial, controls, control_spec=CONTROL_SPEC)
    poses: NDArray[np.float64] = state[:, :, QPOS_OFFSET + scene.object_qpos : QPOS_OFFSET + scene.object_qpos + 7]
    return poses


def hold_trials(
    scene: GraspScene,
    settled: Settled,
    loads: NDArray[np.float64],
    duration: float,
    move_limit: float,
    rotation_limit: float,
    settings: SimSettings,
) -> NDArray[np.bool_]:
    """Constant-load trials (the weight test): does the grasp hold at every step?

    Args:
        scene: The compiled grasp model.
        settled: The settled start state, also the reference pose.
        loads: Physical wrenches on the object (force [N], torque [N·m]), shape (L, 6).
        duration: Duration of each trial [s].
        move_limit: Largest displacement that still passes [m].
        rotation_limit: Largest rotation that still passes [deg].
        settings: Simulation settings (threads).

    Returns:
        Pass flag per load, shape (L,).
    """
    poses = hold_poses(scene, settled, loads, duration, settings)
    shift, angle = _displacement(poses, settled.pose)
    finite = np.all(np.isfinite(poses), axis=(1, 2))
    return finite & (np.nanmax(shift, axis=1) < move_limit) & (np.nanmax(angle, axis=1) < rotation_limit)
