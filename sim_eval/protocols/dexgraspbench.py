"""DexGraspBench's simulated grasp test, run on ogcp's fingertip scenes (``--protocol dexgraspbench``).

Follows JYChen18/DexGraspBench (github.com/JYChen18/DexGraspBench) at commit 1e7a5a6, read but
not copied (the repository has no licence). Where each value comes from, at that commit:

* ``src/util/hand_util.py`` (``MjHO``): 4 ms step, implicitfast, gravity off, elliptic cones,
  impratio 10, 2 no-slip iterations, condim 4 with friction (0.6, 0.02) on every geom; hand geoms
  solref (0.005, 1) and solimp (0.5, 0.99, 0.0001); object geoms keep MuJoCo's defaults.
* ``src/task/eval_func/fc_mocap.py``: per direction -x, +x, -y, +y, -z, +z the hand closes from
  its pregrasp to its grasp and squeeze poses (2 x 10 x 10 steps: 0.8 s), then a force of
  10 x 0.1 kg N acts at the object's centre of mass for 10 checks of 50 steps (every 0.2 s, 2 s
  in all); the first failing check ends that direction and every later one.
* ``src/task/eval_func/base.py``: a grasp whose hand starts more than ``max_pene`` = 1 cm inside
  the object fails unsimulated (reported as delta 100, 100); motion is measured from the object's
  pose before the hand closes; success is delta_pos < 5 cm and delta_angle < 15 degrees.
* ``src/util/rot_util.py`` (``np_get_delta_qpos``): the distance between positions and
  2 arccos of the relative quaternion's w.
* ``src/task/statistic.py``: their ROC-AUC (:func:`~ogcp.sim_eval.protocols.metrics.binned_roc`) of their Q1
  metric, 2 - Q1, against success.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cache
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.protocols.metrics import binned_roc, roc_auc
from ogcp.sim_eval.protocols.phases import Settled, hold_poses
from ogcp.sim_eval.result import GraspSimResult
from ogcp.sim_eval.scene.grasp_scene import GraspScene
from ogcp.sim_eval.settings import RANGES, SimSettings

SOURCE = "JYChen18/DexGraspBench@1e7a5a6"
#: Their directions, in the order they test them (a failure ends the test).
AXES = ("-x", "+x", "-y", "+y", "-z", "+z")
#: What their evaluation records for a grasp failing the penetration gate (delta_pos, delta_angle).
UNSIMULATED_DELTA = 100.0
#: A check interval or duration within this many steps of a whole number of steps is one.
STEP_ROUNDING = 1e-6
#: Extra depth of the normal servo's target per newton of F_max [m/N]. Their contacts are
#: softer than ogcp's: measured on a box, a tip pressing with 10 N sinks 1.4 mm into it
#: (0.07 mm with ogcp's), past ogcp's target (0.3 mm at 0.2 m), so the tips pressed with only
#: 0.2-0.3 N; 2 mm more lets them press with F_max, as their squeeze pose lies past the object.
SOFT_CONTACT_DEPTH = 2e-4


@dataclass(frozen=True)
class DexGraspBenchProtocol:
    """DexGraspBench's test and physics, as fixed at commit 1e7a5a6 (units as used by MuJoCo).

    Attributes:
        load_per_kg: Force per kilogram of object mass [N/kg].
        duration: Time each load acts [s].
        closing_time: Time their hand closes before the load acts [s]; ogcp's tips press as long.
        check_interval: Time between two checks of the motion limits [s].
        move_limit: Displacement from the reference pose that fails [m] (``trans_thre``).
        rotation_limit: Rotation from the reference pose that fails [deg] (``angle_thre``).
        max_penetration: Initial hand-object penetration beyond which a grasp fails [m] (``max_pene``).
        mu: Sliding friction coefficient.
        torsional_friction: Torsional friction coefficient [m] (condim 4).
        timestep: Physics step [s].
        noslip_iterations: MuJoCo's no-slip iterations.
        impratio: Frictional-to-normal impedance ratio.
        hand_solref: solref of the hand's geoms (time constant [s], damping ratio).
        hand_solimp: solimp of the hand's geoms (dmin, dmax, width [m]).
    """

    load_per_kg: float = 10.0
    duration: float = 2.0
    closing_time: float = 0.8
    check_interval: float = 0.2
    move_limit: float = 0.05
    rotation_limit: float = 15.0
    max_penetration: float = 0.01
    mu: float = 0.6
    torsional_friction: float = 0.02
    timestep: float = 0.004
    noslip_iterations: int = 2
    impratio: float = 10.0
    hand_solref: tuple[float, float] = (0.005, 1.0)
    hand_solimp: tuple[float, float, float] = (0.5, 0.99, 1e-4)

    def constants(self) -> dict[str, float]:
        """The scalar values, as recorded with every grasp's test."""
        return {k: float(v) for k, v in self.__dict__.items() if isinstance(v, (int, float))}


PROTOCOL = DexGraspBenchProtocol()


def physics_settings(settings: SimSettings) -> SimSettings:
    """The settings with DexGraspBench's step, solver and hand contact parameters.

    The protocol fixes them, and the time the tips press before the load (their hand's
    closing time), whatever was asked; ``mu`` and ``torsional_friction`` stay overridable.
    Their lengths are absolute, like theirs: apply this to settings already scaled to the
    object (:meth:`SimSettings.scaled`). The tips' own actuation (mass,
    armature, servo stiffness, force cap) stays ogcp's; only the servo's target lies
    :data:`SOFT_CONTACT_DEPTH` x F_max deeper, so that the tips still press with F_max.
    """
    depth = settings.target_factor * settings.servo_compliance + SOFT_CONTACT_DEPTH * settings.max_normal_force
    deepest = RANGES["target_factor"].maximum or math.inf
    return replace(
        settings,
        timestep=PROTOCOL.timestep,
        integrator="implicitfast",
        cone="elliptic",
        impratio=PROTOCOL.impratio,
        noslip_iterations=PROTOCOL.noslip_iterations,
        # MuJoCo's defaults, which their scene keeps.
        solver="Newton",
        solver_iterations=100,
        gravity=False,
        settle_time=PROTOCOL.closing_time,
        contact_solref=PROTOCOL.hand_solref,
        contact_solimp=PROTOCOL.hand_solimp,
        target_factor=min(depth / settings.servo_compliance, deepest),
    )


@cache
def _mujoco_default_contact() -> tuple[tuple[float, ...], tuple[float, ...]]:
    """MuJoCo's default geom solref and full solimp, read from MuJoCo itself."""
    geom = mujoco.MjSpec().worldbody.add_body().add_geom()
    return tuple(float(v) for v in geom.solref), tuple(float(v) for v in geom.solimp)


def use_object_defaults(scene: GraspScene) -> None:
    """Give the object's geoms MuJoCo's default solref and solimp, as DexGraspBench's objects have.

    The scene builder gives tips and parts the same values; MuJoCo mixes a pair's values
    (equal solmix: the mean), so the tip-object contacts get the mean of the hand's and
    the defaults, as theirs do. Changes the compiled model in place (MuJoCo reads these
    arrays at every collision).
    """
    solref, solimp = _mujoco_default_contact()
    scene.model.geom_solref[scene.object_geoms] = solref
    scene.model.geom_solimp[scene.object_geoms] = solimp


def contact_record(scene: GraspScene) -> dict[str, Any]:
    """What the compiled model simulates: options, and each side's contact parameters."""
    model = scene.model

    def side(geom: int) -> dict[str, Any]:
        return {
            "condim": int(model.geom_condim[geom]),
            "friction": model.geom_friction[geom].tolist(),
            "solref": model.geom_solref[geom].tolist(),
            "solimp": model.geom_solimp[geom].tolist(),
        }

    opt = model.opt
    return {
        "timestep": float(opt.timestep),
        "integrator": mujoco.mjtIntegrator(opt.integrator).name,
        "cone": mujoco.mjtCone(opt.cone).name,
        "impratio": float(opt.impratio),
        "noslip_iterations": int(opt.noslip_iterations),
        "solver": mujoco.mjtSolver(opt.solver).name,
        "iterations": int(opt.iterations),
        "gravity": opt.gravity.tolist(),
        "tip": side(int(scene.tip_geoms[0])),
        "object": side(int(scene.object_geoms[0])),
    }


def delta_qpos(reference: ArrayLike, poses: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Their motion measure: translation [m] and rotation [deg] of poses from a reference pose.

    The angle is 2 arccos(w) of the relative quaternion q q_ref^-1, with w above 1 (rounding)
    set to 1, as ``np_get_delta_qpos`` does.

    Args:
        reference: Position and unit quaternion (w, x, y, z), shape (7,).
        poses: Poses, shape (..., 7).
    """
    ref, p = np.asarray(reference, dtype=float), np.asarray(poses, dtype=float)
    shift = np.linalg.norm(p[..., :3] - ref[:3], axis=-1)
    # The w of q q_ref^-1 is the dot product of the two (the reference is a unit quaternion).
    w = np.einsum("...i,i->...", p[..., 3:7], ref[3:7]) / float(ref[3:7] @ ref[3:7])
    w = np.where(np.abs(w) > 1.0, 1.0, w)
    return shift, np.degrees(2.0 * np.arccos(w))


def _steps(seconds: float, timestep: float, what: str) -> int:
    steps = seconds / timestep
    if round(steps) < 1 or abs(steps - round(steps)) > STEP_ROUNDING:
        raise OgcpError(f"DexGraspBench {what} {seconds:g} s is not a whole number of {timestep:g} s steps")
    return round(steps)


def axis_loads(magnitude: float) -> NDArray[np.float64]:
    """Their six loads in their order (:data:`AXES`): force [N] along -x, +x, ..., no torque, shape (6, 6)."""
    loads = np.zeros((6, 6))
    for k, label in enumerate(AXES):
        loads[k, "xyz".index(label[1])] = magnitude if label[0] == "+" else -magnitude
    return loads


def hold_test(scene: GraspScene, settled: Settled, settings: SimSettings) -> dict[str, Any]:
    """DexGraspBench's verdict on one settled grasp (the ``hold_tests["dexgraspbench"]`` entry).

    Motion is measured from the object's pose before the tips press (the model's initial
    pose), so that motion while pressing counts, as it does while their hand closes. The
    limits are checked every ``check_interval`` only, as theirs are. Every direction is run
    (theirs stop at the first failure; the verdict is the same). A grasp succeeds only if
    ogcp's validity gates passed too.

    Args:
        scene: The compiled grasp model (DexGraspBench's physics).
        settled: The preloaded, settled grasp and its gates.
        settings: The simulation settings the scene was built with.

    Returns:
        JSON-ready: ``axes`` (their order), ``passed``, ``delta_pos`` [m] and ``delta_angle`` [deg]
        per axis (at the first failing check, else at the end; None when not run), ``success``,
        ``gates_passed``, ``penetration`` [m] and ``penetration_passed``, ``failures`` (why it
        failed, one line each), ``reported`` (the single delta pair their evaluation would save),
        ``load`` [N], ``reference``, ``checks``, the protocol's constants and ``physics``.
    """
    load = PROTOCOL.load_per_kg * settings.object_mass
    depth = settled.gates.get("initial_penetration", math.nan)
    penetration = float(depth) if isinstance(depth, (int, float)) else math.nan
    diverged = bool(settled.gates.get("diverged"))
    # Their gate: fail when the deepest contact is more than max_pene deep (at exactly 1 cm it passes).
    deep_ok = not penetration > PROTOCOL.max_penetration
    gates_ok = bool(settled.gates.get("valid"))
    timestep = float(scene.model.opt.timestep)
    every = _steps(PROTOCOL.check_interval, timestep, "check interval")
    checks = _steps(PROTOCOL.duration, timestep, "duration") // every
    passed: list[bool | None] = [None] * len(AXES)
    moved: list[float | None] = [None] * len(AXES)
    turned: list[float | None] = [None] * len(AXES)
    if deep_ok and not diverged:
        poses = hold_poses(scene, settled, axis_loads(load), checks * every * timestep, settings)
        reference = scene.model.qpos0[scene.object_qpos : scene.object_qpos + 7]
        with np.errstate(invalid="ignore"):
            shift, angle = delta_qpos(reference, poses[:, every - 1 :: every][:, :checks])
            failing = ~((shift < PROTOCOL.move_limit) & (angle < PROTOCOL.rotation_limit))
        for k in range(len(AXES)):
            at = int(np.argmax(failing[k])) if failing[k].any() else checks - 1
            passed[k] = not failing[k].any()
            moved[k], turned[k] = _finite(shift[k, at]), _finite(angle[k, at])
    failures = _failures(gates_ok, diverged, deep_ok, penetration, passed)
    return {
        "source": SOURCE,
        "axes": list(AXES),
        "passed": passed,
        "delta_pos": moved,
        "delta_angle": turned,
        "success": not failures,
        "gates_passed": gates_ok,
        "penetration": penetration,
        "penetration_passed": deep_ok,
        "failures": failures,
        "reported": _reported(deep_ok, passed, moved, turned),
        "load": load,
        "reference": "initial",
        "checks": checks,
        **PROTOCOL.constants(),
        "mu": float(scene.mu),
        "torsional_friction": float(scene.torsion),
        "physics": contact_record(scene),
    }


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _failures(
    gates_ok: bool, diverged: bool, deep_ok: bool, penetration: float, passed: Sequence[bool | None]
) -> list[str]:
    """Why the grasp fails DexGraspBench's test, one line each; empty when it succeeds."""
    found = []
    if diverged:
        found.append("the simulation diverged while the tips pressed")
    elif not gates_ok:
        found.append("ogcp's validity gates failed (see invalid_reasons)")
    if not deep_ok:
        found.append(
            f"starts {penetration * 1e3:.3g} mm inside the object (DexGraspBench's limit "
            f"{PROTOCOL.max_penetration * 1e3:g} mm)"
        )
    lost = [axis for axis, ok in zip(AXES, passed, strict=True) if ok is False]
    if lost:
        found.append(
            f"moved {PROTOCOL.move_limit * 1e3:g} mm or turned {PROTOCOL.rotation_limit:g} deg under "
            f"the load along {', '.join(lost)}"
        )
    return found


def _reported(
    deep_ok: bool, passed: Sequence[bool | None], moved: Sequence[float | None], turned: Sequence[float | None]
) -> dict[str, float | None]:
    """The one (delta_pos, delta_angle) pair their evaluation saves: the first failing direction's, else the last's."""
    if not deep_ok:
        return {"delta_pos": UNSIMULATED_DELTA, "delta_angle": UNSIMULATED_DELTA}
    if passed[-1] is None:
        return {"delta_pos": None, "delta_angle": None}
    k = next((k for k, ok in enumerate(passed) if ok is False), len(AXES) - 1)
    return {"delta_pos": moved[k], "delta_angle": turned[k]}


def succeeded(result: GraspSimResult) -> bool:
    """DexGraspBench's success flag of one grasp: False when it was not simulated or has no test."""
    test = result.hold_tests.get("dexgraspbench")
    return result.error is None and isinstance(test, dict) and test.get("success") is True


def set_summary(results: Sequence[GraspSimResult]) -> dict[str, Any]:
    """The set-level DexGraspBench numbers: success rate, counts and ROC-AUC of Q1 both ways.

    As their statistics, the rate is over the grasps evaluated: simulated, or refused for an
    unreachable contact (a tip that would start inside the object; their penetration gate
    fails such grasps); grasps that could not be simulated for another reason are counted
    apart (``n_errors``), as their evaluation drops grasps that raised.

    Returns:
        JSON-ready: ``source``, ``n_evaluated``, ``n_success``, ``success_rate``,
        ``n_gates_failed``, ``n_held_despite_gates`` (gates failed, every load held: successes
        for their test alone), ``n_penetration_failed``, ``n_unreachable``, ``n_errors``, and
        ``auc_q1`` of the planned Q1 against success: ``mann_whitney`` (ogcp's exact
        :func:`~ogcp.sim_eval.protocols.metrics.roc_auc`, ties count 1/2), ``dexgraspbench`` (their binned
        :func:`~ogcp.sim_eval.protocols.metrics.binned_roc` of -Q1), ``bins``, ``roc`` (their fpr, tpr) and ``n``.
    """
    evaluated = [r for r in results if r.error is None or r.unreachable]
    flags = np.array([succeeded(r) for r in evaluated], dtype=bool)
    tests = [r.hold_tests.get("dexgraspbench", {}) for r in evaluated]
    q1 = np.array([r.q1 for r in evaluated], dtype=float)
    summary: dict[str, Any] = {
        "source": SOURCE,
        "n_evaluated": len(evaluated),
        "n_success": int(flags.sum()),
        "success_rate": float(flags.mean()) if len(flags) else None,
        "n_gates_failed": sum(t.get("gates_passed") is False for t in tests),
        "n_held_despite_gates": sum(t.get("gates_passed") is False and t.get("passed") == [True] * 6 for t in tests),
        "n_penetration_failed": sum(t.get("penetration_passed") is False for t in tests),
        "n_unreachable": sum(bool(r.unreachable) for r in evaluated),
        "n_errors": len(results) - len(evaluated),
    }
    scored = np.isfinite(q1)
    auc: dict[str, Any] = {"n": int(scored.sum()), "mann_whitney": None, "dexgraspbench": None, "bins": 0, "roc": None}
    if scored.any():
        roc = binned_roc(-q1[scored], flags[scored])
        auc.update(
            mann_whitney=_finite(roc_auc(q1[scored], flags[scored])),
            dexgraspbench=_finite(roc.auc),
            bins=len(roc.tpr) - 1,
            roc={"fpr": roc.fpr.tolist(), "tpr": roc.tpr.tolist()},
        )
    summary["auc_q1"] = auc
    return summary
