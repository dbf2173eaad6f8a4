"""Every setting of a simulated grasp test, in one validated value recorded with each result."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from ogcp.planner.config.options import MAX_SEED, Option
from ogcp.planner.grasp.defaults import (
    DEFAULT_TIP_RADIUS_RATIO,
    MAX_DIAGONAL,
    MAX_MU,
    MAX_TORSIONAL_FRICTION,
    MIN_DIAGONAL,
)
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.objects.builtin import DEFAULT_DIAGONAL

#: The bounding-box diagonal [m] at which the length settings are given (the built-ins' size, so
#: 0.2 m objects are simulated with exactly these values).
REFERENCE_DIAGONAL = DEFAULT_DIAGONAL
#: The settings that are lengths [m] and scale with the object (besides ``contact_solimp``'s width).
LENGTH_SETTINGS = (
    "servo_compliance",
    "tangential_compliance",
    "creep_tolerance",
    "penetration_tolerance",
    "move_threshold",
)
#: The fingertip slides' masses [kg], divided by the length scale (see :meth:`SimSettings.scaled`).
SERVO_MASSES = ("tip_mass", "slide_armature")


def _range(low: float, high: float, kind: str = "float", exclusive: bool = True) -> Option:
    return Option(kind, None, minimum=low, exclusive=exclusive and kind == "float", maximum=high)


#: Valid range of every number among the settings, as given (lengths and the slides' masses at
#: the reference diagonal; :func:`_absolute` widens them for absolute settings). Each keeps a
#: test finite in time and memory and away from overflow (F_max = 10^308 N made every measured
#: value NaN): forces to 10 kN (the default F_max is 10 N); masses to 1 t; lengths to the reference
#: object's own size (a tolerance as large as the object tolerates anything); friction as for
#: planning; steps from 10 us (200x the default 2 ms's steps) to 0.1 s (past stability already:
#: the gates report the divergence); times to minutes; directions to 10^4 (each is a rollout;
#: 10^9 asked for 45 GB at once); solver iterations to 10^3 and 10^4 (each runs every step).
RANGES: dict[str, Option] = {
    "max_normal_force": _range(0, 1e4),
    "tip_radius": _range(0, MAX_DIAGONAL),
    "tip_radius_ratio": _range(0, 1),  # of the object's diagonal: a tip as large as the object
    "tip_mass": _range(0, 1e3),
    "slide_armature": _range(0, 1e3),
    "servo_compliance": _range(0, REFERENCE_DIAGONAL),
    "tangential_compliance": _range(0, REFERENCE_DIAGONAL),
    "target_factor": _range(1, 100),  # > 1 saturates the preload; 100 is a target 100 F_max deep
    "object_mass": _range(0, 1e3),
    "inertia_scale": _range(0, 1e3),
    "mu": _range(0, MAX_MU),
    "torsional_friction": _range(0, MAX_TORSIONAL_FRICTION, exclusive=False),
    "timestep": _range(1e-5, 0.1, exclusive=False),
    "impratio": _range(0, 1e4),
    "noslip_iterations": _range(0, 1000, "int"),
    "solver_iterations": _range(1, 10_000, "int"),
    "settle_time": _range(0, 60),
    "creep_tolerance": _range(0, REFERENCE_DIAGONAL),
    "penetration_tolerance": _range(0, REFERENCE_DIAGONAL),
    "directions": _range(0, 10_000, "int"),
    "direction_seed": _range(0, MAX_SEED, "int"),
    "move_threshold": _range(0, REFERENCE_DIAGONAL),
    "rotation_threshold": _range(0, 180),  # degrees: half a turn is any rotation
    "ramp_time": _range(0, 600),
    "ramp_extent": _range(1, 10),  # > 1: the ramp passes the prediction; 10x it finds any failure
    "min_ramp_fraction": _range(0, 1),
    "prediction_cone_edges": _range(3, 1024, "int"),  # polygon error 1 - cos(pi / k): 5e-6 at 1024
    "holding_load": _range(0, 1e4),
    "threads": _range(1, 1024, "int"),  # one MuJoCo data each; more than cores only take turns
}
#: Most MuJoCo steps of one settling or one ramp (the default ramp is 3000): beyond, one
#: direction of one grasp takes hours.
MAX_STEPS = 10**7
#: Settings that may be left unset (None): the object's default tip, the plan's mu, all cores.
UNSET = ("tip_radius", "mu", "torsional_friction", "threads")

PROTOCOLS = ("resistance", "dexgraspbench")
INTEGRATORS = ("implicitfast", "implicit", "euler", "rk4")
CONES = ("elliptic", "pyramidal")
SOLVERS = ("Newton", "CG", "PGS")


@dataclass(frozen=True)
class SimSettings:
    """Physics, actuation and protocol settings of a simulated grasp test.

    Actuation model (the analytic prediction uses the same one): each fingertip is a sphere
    on three slides, one along its contact normal and two tangential. The normal slide is a
    position servo whose force is capped at ``max_normal_force`` F_max; its target lies
    ``target_factor * F_max / kp`` past the contact, so after settling every tip presses with
    up to F_max and can trade normal force within [0, F_max] over ``servo_compliance`` of
    travel. The tangential slides are stiff position servos holding the tip in place.

    Scale: the lengths (:data:`LENGTH_SETTINGS` and ``contact_solimp``'s width) are given at
    the :data:`REFERENCE_DIAGONAL` of 0.2 m and :meth:`scaled` multiplies them by the object's
    diagonal / 0.2 m, so a grasp is gated and failed alike at any size: the servo keeps its
    force-travel curve relative to the object (kp = F_max / compliance) and the gates their
    fraction of it. The fingertip slides' masses (:data:`SERVO_MASSES`) are divided by the same
    factor, so that each servo's natural frequency sqrt(kp / m) is the same at every size.
    The object's simulated mass and inertia are divided by it too (``inertia_scale``) and
    gravity multiplied by it: with forces and times unscaled, every motion is then the
    reference one scaled by the factor (m a = F with m / s and a s), so slip, creep and
    failure happen at the same fraction of the object's size. ``object_mass`` stays the
    physical mass that the weight test and the DexGraspBench loads are computed from.
    ``scale_lengths = false`` uses every setting as given (absolute metres and kilograms) at
    every size.

    Attributes:
        max_normal_force: Per-finger normal-force cap F_max [N].
        tip_radius: Fingertip sphere radius [m]; None = ``tip_radius_ratio`` x the object's
            bounding-box diagonal.
        tip_radius_ratio: Default tip radius as a fraction of the bounding-box diagonal.
        tip_mass: Mass of each fingertip body [kg at the reference diagonal].
        slide_armature: Armature of every slide [kg at the reference diagonal]; keeps stiff
            servos stable at ``timestep``.
        servo_compliance: F_max / kp of the normal servo [m at the reference diagonal].
        tangential_compliance: F_max / kp of the tangential servos [m at the reference diagonal].
        target_factor: Normal servo target depth in units of F_max / kp (> 1 saturates the preload).
        object_mass: Object mass [kg]; inertia comes from the watertight mesh.
        inertia_scale: Factor on the object's simulated mass and inertia, and divisor of
            gravity (set by :meth:`scaled`; 1 at the reference diagonal).
        mu: Friction coefficient; None = the plan's contact-set mu.
        torsional_friction: Torsional friction coefficient [m] of the simulated contacts, an
            absolute length like MuJoCo's (not scaled with the object); 0 = hard fingers
            (condim 3), > 0 = soft (condim 4); None = the contact set's model.
        timestep: Physics step [s].
        integrator: MuJoCo integrator.
        cone: Friction cone type.
        impratio: Frictional-to-normal constraint impedance ratio.
        noslip_iterations: Post-solve no-slip iterations (stop creep under sustained load). Two
            hold a sphere on spheres; tips on the many faces of convex parts slid at 30-80 % of
            the Coulomb limit (creep up to 0.8 mm/s, resistance 10-25 % low) until 30.
        solver: Constraint solver.
        solver_iterations: Maximum solver iterations per step.
        contact_solref: Contact solref (time constant [s], damping ratio).
        contact_solimp: Contact solimp (dmin, dmax, width [m at the reference diagonal]).
        gravity: Whether gravity acts during the resistance protocol.
        settle_time: Duration of the preload phase before loading [s].
        creep_tolerance: Largest object drift over the last 0.1 s of settling [m at the
            reference diagonal].
        penetration_tolerance: Largest initial tip penetration accepted [m at the reference
            diagonal].
        directions: Number of quasi-uniform 6-D directions besides the 12 axes and Q1's weakest.
        direction_seed: Seed of those directions.
        move_threshold: Object displacement that counts as failure [m at the reference diagonal].
        rotation_threshold: Object rotation that counts as failure [deg].
        ramp_time: Time for the load to reach the predicted resistance [s].
        ramp_extent: Ramp end as a multiple of the predicted resistance.
        min_ramp_fraction: Directions predicted (near) zero ramp towards this fraction of the
            grasp's largest prediction.
        prediction_cone_edges: Polygon edges of the friction cones in the prediction LP; MuJoCo's
            cones are elliptic, so the prediction uses a fine polygon (error 1 - cos(pi / k)).
        holding_load: Fixed load a grasp must resist in every direction to count as holding
            (the label of the set-level ROC-AUC) [N, scaled wrench].
        weight_test: Also hold the object's weight m g along the six force axes for 2 s.
        protocol: "resistance" (ramp to failure) or "dexgraspbench" (fixed load, pass/fail).
        threads: Rollout threads; None = all cores.
        scale_lengths: Scale the lengths (and the slides' masses) with the object, or use every
            setting as given.
    """

    max_normal_force: float = 10.0
    tip_radius: float | None = None
    tip_radius_ratio: float = DEFAULT_TIP_RADIUS_RATIO
    tip_mass: float = 0.05
    slide_armature: float = 0.5
    servo_compliance: float = 2e-4
    tangential_compliance: float = 1e-4
    target_factor: float = 1.5
    object_mass: float = 0.1
    inertia_scale: float = 1.0
    mu: float | None = None
    torsional_friction: float | None = None
    timestep: float = 0.002
    integrator: str = "implicitfast"
    cone: str = "elliptic"
    impratio: float = 10.0
    noslip_iterations: int = 30
    solver: str = "Newton"
    solver_iterations: int = 100
    contact_solref: tuple[float, float] = (0.004, 1.0)
    contact_solimp: tuple[float, float, float] = (0.95, 0.99, 1e-4)
    gravity: bool = False
    settle_time: float = 0.5
    creep_tolerance: float = 2e-5
    penetration_tolerance: float = 1e-3
    directions: int = 64
    direction_seed: int = 0
    move_threshold: float = 2e-3
    rotation_threshold: float = 2.0
    ramp_time: float = 4.0
    ramp_extent: float = 1.5
    min_ramp_fraction: float = 0.1
    prediction_cone_edges: int = 32
    holding_load: float = 1.0
    weight_test: bool = False
    protocol: str = "resistance"
    threads: int | None = None
    scale_lengths: bool = True

    def __post_init__(self) -> None:
        for name in ("gravity", "weight_test", "scale_lengths"):
            if not isinstance(getattr(self, name), bool):
                raise OgcpError(f"simulation setting {name} must be true or false, got {getattr(self, name)!r}")
        for name, declared in RANGES.items():
            value = getattr(self, name)
            if value is None and name in UNSET:
                continue
            object.__setattr__(self, name, _absolute(declared, name, self.scale_lengths).check(_where(name), value))
        for name, choices in (
            ("protocol", PROTOCOLS),
            ("integrator", INTEGRATORS),
            ("cone", CONES),
            ("solver", SOLVERS),
        ):
            if getattr(self, name) not in choices:
                raise choice_error(f"simulation setting {name}", getattr(self, name), choices)
        object.__setattr__(self, "contact_solref", _solref(self.contact_solref))
        object.__setattr__(self, "contact_solimp", _solimp(self.contact_solimp, self.scale_lengths))
        for what, seconds in (
            ("settle_time", self.settle_time),
            ("ramp_time x ramp_extent", self.ramp_time * self.ramp_extent),
        ):
            if seconds / self.timestep > MAX_STEPS:
                raise OgcpError(
                    f"simulation settings {what} / timestep = {seconds:g} s / {self.timestep:g} s is "
                    f"{seconds / self.timestep:.3g} MuJoCo steps; at most {MAX_STEPS:.0e} per settling or "
                    "ramp: shorten it or take a longer timestep"
                )

    @property
    def body_mass(self) -> float:
        """The object's simulated mass [kg]: ``object_mass`` times ``inertia_scale``."""
        return self.object_mass * self.inertia_scale

    @property
    def servo_stiffness(self) -> float:
        """kp of the normal servo [N/m]."""
        return self.max_normal_force / self.servo_compliance

    @property
    def tangential_stiffness(self) -> float:
        """kp of the tangential servos [N/m]."""
        return self.max_normal_force / self.tangential_compliance

    def length_scale(self, diagonal: float) -> float:
        """The factor the lengths are multiplied by for an object: diagonal / 0.2 m, or 1 if not scaled.

        Args:
            diagonal: The object's bounding-box diagonal [m].
        """
        if not (math.isfinite(diagonal) and diagonal > 0):
            raise OgcpError(f"object diagonal must be a positive number of metres, got {diagonal!r}")
        if not self.scale_lengths:
            return 1.0
        factor = diagonal / REFERENCE_DIAGONAL
        # A mesh normalised to 0.2 m measures it only to rounding: keep today's values bit for bit.
        return 1.0 if math.isclose(factor, 1.0, rel_tol=1e-9) else factor

    def scaled(self, diagonal: float) -> SimSettings:
        """The settings for an object of this size, every length in absolute metres.

        The scene and the protocol read lengths as given, so they are handed this value. At
        the reference diagonal the lengths are returned unchanged (bit for bit), and the result
        has ``scale_lengths = False``, so scaling it again changes nothing.

        Args:
            diagonal: The object's bounding-box diagonal [m].
        """
        factor = self.length_scale(diagonal)
        if factor == 1.0:
            return replace(self, scale_lengths=False)
        lengths = {name: getattr(self, name) * factor for name in LENGTH_SETTINGS}
        # kp = F_max / compliance grows as 1 / factor; the slides' masses follow it so that each
        # servo keeps its natural frequency, hence its accuracy at the fixed step (masses fixed,
        # a 5 cm object's servos ring near the step's limit and resist ~20 % less).
        masses = {name: getattr(self, name) / factor for name in SERVO_MASSES}
        # The object's mass follows for the same reason: fixed, a 5 cm object was 16x heavier
        # relative to its servos and crept past the gate where the 0.2 m one held.
        masses["inertia_scale"] = self.inertia_scale / factor
        dmin, dmax, width = self.contact_solimp
        return replace(self, **lengths, **masses, contact_solimp=(dmin, dmax, width * factor), scale_lengths=False)

    def with_updates(self, **changes: Any) -> SimSettings:
        """A copy with some settings changed (validated)."""
        return replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (recorded with every result)."""
        data = asdict(self)
        data["contact_solref"] = list(self.contact_solref)
        data["contact_solimp"] = list(self.contact_solimp)
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any] | None) -> SimSettings:
        """Settings from a mapping (suite files, CLI); unknown keys are errors that list the valid ones."""
        data = dict(data or {})
        valid = [f.name for f in fields(cls)]
        for key in data:
            if key not in valid:
                raise choice_error("simulation setting", key, valid)
        return cls(**data)


def _where(name: str) -> str:
    return f"simulation setting {name}"


def _absolute(declared: Option, name: str, scale_lengths: bool) -> Option:
    """The range of a setting given in absolute units: lengths up to the largest object, masses
    as heavy as the smallest object's slides are (so :meth:`SimSettings.scaled` stays in range)."""
    if scale_lengths or declared.maximum is None:
        return declared
    if name in LENGTH_SETTINGS:
        factor = MAX_DIAGONAL / REFERENCE_DIAGONAL
    elif name in (*SERVO_MASSES, "inertia_scale"):
        factor = REFERENCE_DIAGONAL / MIN_DIAGONAL
    else:
        return declared
    return replace(declared, maximum=declared.maximum * factor)


def _numbers(name: str, value: Any, count: int) -> tuple[float, ...]:
    """``count`` finite numbers from a list or tuple (TOML and JSON give lists)."""
    ok = isinstance(value, (list, tuple)) and len(value) == count
    if ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value):
        return tuple(float(v) for v in value)
    raise OgcpError(f"{_where(name)}: expected a list of {count} finite numbers, got {value!r}")


def _solref(value: Any) -> tuple[float, float]:
    """MuJoCo's solref: (time constant [s] > 0, damping ratio > 0), or (-stiffness < 0, -damping <= 0)."""
    timeconst, damping = _numbers("contact_solref", value, 2)
    if not ((timeconst > 0 and damping > 0) or (timeconst < 0 and damping <= 0)):
        raise OgcpError(
            f"{_where('contact_solref')}: expected (time constant > 0, damping ratio > 0) or MuJoCo's "
            f"(-stiffness < 0, -damping <= 0), got {list(value)!r}"
        )
    return timeconst, damping


def _solimp(value: Any, scale_lengths: bool) -> tuple[float, float, float]:
    """MuJoCo's solimp: 0 < dmin <= dmax < 1 and a width > 0 [m at the reference diagonal]."""
    dmin, dmax, width = _numbers("contact_solimp", value, 3)
    if not 0 < dmin <= dmax < 1:
        raise OgcpError(f"{_where('contact_solimp')}: expected 0 < dmin <= dmax < 1, got {list(value)!r}")
    length = _absolute(RANGES["creep_tolerance"], "creep_tolerance", scale_lengths)
    return dmin, dmax, length.check(f"{_where('contact_solimp')} width", width)


def scaled_lengths(settings: SimSettings) -> dict[str, float]:
    """The length settings of (scaled) settings [m], as recorded next to the given ones, and the
    object's simulated mass [kg]."""
    return {
        **{name: getattr(settings, name) for name in LENGTH_SETTINGS},
        "contact_solimp_width": settings.contact_solimp[2],
        "body_mass": settings.body_mass,
    }
