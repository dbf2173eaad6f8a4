"""Analytic resistance of a fingertip grasp under a per-finger normal-force budget.

The simulated hand presses m point fingertips on the object, each with a normal force of at
most ``F_max`` (the grip budget) and Coulomb friction ``mu`` linearised by the same cone edges
as the planner (:func:`ogcp.planner.grasp.wrench.contact_wrenches`, normal component 1, so the weights of
one finger's edges sum to its normal force). A disturbance ``s d`` (``d`` a unit 6-vector in
the planner's scaled wrench space ``[force, torque / rho]``) is resisted when contact forces
``lambda_ij >= 0`` exist with::

    sum_ij lambda_ij w_ij + s d = 0,    sum_j lambda_ij <= F_max for every finger i.

The predicted resistance along ``d`` is the largest such ``s``: a linear program. It is the
distance from the origin to the boundary of the resistible set
``P = sum_i conv({0} U {F_max w_ij})`` along the ray ``-d``.

The LP is homogeneous in ``F_max``, so it is solved once with a unit budget and scaled; the
constraint matrix is built once per grasp and only the column of ``d`` changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

from ogcp.planner.grasp.wrench import contact_wrenches
from ogcp.planner.infra.errors import OgcpError

DIM = 6
#: Allowed deviation of a normal or direction norm from 1.
UNIT_TOL = 1e-6
#: Resistances below this fraction of F_max are reported as exactly 0: HiGHS returns
#: values of order 1e-12 where only s = 0 is feasible, and a simulation cannot tell them apart.
ZERO_RESISTANCE_REL = 1e-9


@dataclass(frozen=True)
class Prediction:
    """Predicted resistance of one grasp along a set of disturbance directions.

    Attributes:
        resistance: Largest resisted disturbance magnitude s per direction, shape (D,) [N]
            (scaled space: force [N], torque / rho [N]). NaN where the solver failed.
        normal_forces: Per-finger normal forces of one optimal solution, shape (D, m) [N].
            The optimum is often not unique; these are HiGHS's choice, for diagnosis only.
            NaN rows where the solver failed.
    """

    resistance: NDArray[np.float64]
    normal_forces: NDArray[np.float64]


def _readonly(array: NDArray[np.float64]) -> NDArray[np.float64]:
    array.setflags(write=False)
    return array


def _finite_array(value: object, name: str, shape_text: str, ndim: int, last: int | None) -> NDArray[np.float64]:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"{name} must be numbers with shape {shape_text}: {exc}") from None
    if array.ndim != ndim or (last is not None and array.shape[-1] != last):
        raise OgcpError(f"{name} must have shape {shape_text}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise OgcpError(f"{name} contain NaN or infinite values")
    return array


def _positive(value: object, name: str, unit: str, allow_zero: bool = False) -> float:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise OgcpError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(number) or number < 0 or (number == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise OgcpError(f"{name} must be finite and {bound}{unit}, got {value!r}")
    return number


def _cone_edge_count(value: object) -> int:
    try:
        whole = not isinstance(value, bool) and int(value) == value  # type: ignore[call-overload]
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole or int(value) < 3:  # type: ignore[call-overload]
        raise OgcpError(f"cone_edges must be an integer >= 3, got {value!r}")
    return int(value)  # type: ignore[call-overload]


def validate_directions(directions: object) -> NDArray[np.float64]:
    """Check disturbance directions: finite unit 6-vectors.

    Args:
        directions: Directions in scaled wrench space, shape (D, 6).

    Returns:
        The directions as a float array, shape (D, 6).

    Raises:
        OgcpError: Wrong shape, non-finite entries or a norm differing from 1 by more than 1e-6.
    """
    d = _finite_array(directions, "directions", "(D, 6)", 2, DIM)
    norms = np.linalg.norm(d, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > UNIT_TOL)
    if bad.size:
        raise OgcpError(f"direction {int(bad[0])} must be a unit vector, has norm {norms[bad[0]]:.6g}")
    return d


class ResistanceLP:
    """The resistance LP of one grasp, built once and solved per direction.

    Variables are ``[lambda (m k), s]`` for a unit budget: equalities ``W lambda + s d = 0``
    (6 rows), inequalities ``sum_j lambda_ij <= 1`` (m rows), all variables >= 0.

    Args:
        positions: Fingertip contact points, shape (m, 3) [m].
        normals: Inward unit contact normals, shape (m, 3).
        com: Object centre of mass (torque reference), shape (3,) [m].
        torque_scale: rho [m]; torques are divided by it.
        mu: Coulomb friction coefficient (>= 0).
        cone_edges: Number of friction-cone edges k (>= 3).
        max_normal_force: Per-finger normal-force cap F_max [N].
        torsion: Torsional friction coefficient of soft fingers [m] (0 = hard fingers); their
            elliptic set is linearised densely (:func:`ogcp.planner.grasp.wrench.soft_directions`,
            inradius 0.993 at k = 32).

    Raises:
        OgcpError: Any invalid argument.
    """

    def __init__(
        self,
        positions: NDArray[np.float64],
        normals: NDArray[np.float64],
        com: NDArray[np.float64],
        torque_scale: float,
        mu: float,
        cone_edges: int,
        max_normal_force: float,
        torsion: float = 0.0,
    ) -> None:
        p = _finite_array(positions, "contact positions", "(m, 3)", 2, 3)
        if len(p) == 0:
            raise OgcpError("a grasp needs at least one contact")
        n = _finite_array(normals, "contact normals", str(p.shape), 2, 3)
        if n.shape != p.shape:
            raise OgcpError(f"contact normals must have shape {p.shape}, got {n.shape}")
        lengths = np.linalg.norm(n, axis=1)
        bad = np.flatnonzero(np.abs(lengths - 1.0) > UNIT_TOL)
        if bad.size:
            raise OgcpError(f"contact normal {int(bad[0])} must be a unit vector, has norm {lengths[bad[0]]:.6g}")
        c = _finite_array(com, "centre of mass", "(3,)", 1, 3)
        rho = _positive(torque_scale, "torque scale rho", " m")
        mu_f = _positive(mu, "friction coefficient mu", "", allow_zero=True)
        k = _cone_edge_count(cone_edges)
        self.max_normal_force = _positive(max_normal_force, "max normal force F_max", " N")
        torsion_f = _positive(torsion, "torsional friction coefficient", " m", allow_zero=True)
        self.wrenches = _readonly(contact_wrenches(p, n, c, rho, mu_f, k, torsion_f, dense=True))  # (m, K, 6)
        self.fingers, self.edges = len(p), self.wrenches.shape[1]
        k = self.edges
        columns = self.fingers * k
        self._a_eq = np.zeros((DIM, columns + 1))
        self._a_eq[:, :columns] = self.wrenches.reshape(columns, DIM).T
        self._a_ub = np.zeros((self.fingers, columns + 1))
        self._a_ub[:, :columns] = np.kron(np.eye(self.fingers), np.ones(k))
        self._b_ub = np.ones(self.fingers)
        self._b_eq = np.zeros(DIM)
        self._cost = np.zeros(columns + 1)
        self._cost[-1] = -1.0

    def solve(self, direction: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        """Largest resisted magnitude along one validated unit direction.

        Args:
            direction: Unit disturbance direction in scaled space, shape (6,).

        Returns:
            ``(s, normal_forces)``: s [N] (0 when only s = 0 is feasible, NaN if HiGHS
            fails) and the per-finger normal forces of the optimum, shape (m,) [N].
        """
        self._a_eq[:, -1] = direction
        # Every variable is >= 0 and s is bounded (the lambdas are), so the LP is always
        # feasible (s = 0) and bounded; a non-zero status is a numerical failure.
        res = linprog(
            self._cost,
            A_ub=self._a_ub,
            b_ub=self._b_ub,
            A_eq=self._a_eq,
            b_eq=self._b_eq,
            bounds=(0, None),
            method="highs",
        )
        if res.status != 0:
            return float("nan"), np.full(self.fingers, np.nan)
        s = float(res.x[-1])
        if s <= ZERO_RESISTANCE_REL:
            s = 0.0
        forces = res.x[:-1].reshape(self.fingers, self.edges).sum(axis=1)
        return s * self.max_normal_force, forces * self.max_normal_force

    def predict(self, directions: NDArray[np.float64]) -> Prediction:
        """Predicted resistance along many directions.

        Args:
            directions: Unit disturbance directions in scaled space, shape (D, 6).

        Returns:
            The :class:`Prediction` (resistance (D,) [N], normal forces (D, m) [N]).

        Raises:
            OgcpError: Directions of the wrong shape, non-finite or not unit length.
        """
        d = validate_directions(directions)
        resistance = np.empty(len(d))
        normal_forces = np.empty((len(d), self.fingers))
        for row, direction in enumerate(d):
            resistance[row], normal_forces[row] = self.solve(direction)
        return Prediction(_readonly(resistance), _readonly(normal_forces))


def predicted_resistance(
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    com: NDArray[np.float64],
    torque_scale: float,
    mu: float,
    cone_edges: int,
    max_normal_force: float,
    directions: NDArray[np.float64],
    torsion: float = 0.0,
) -> Prediction:
    """Largest disturbance magnitude a grasp resists along each direction.

    For each unit direction d the applied external wrench is ``s d`` (scaled space); the
    result is the largest ``s >= 0`` that cone-edge forces with per-finger normal force at
    most ``F_max`` can balance (see the module docstring).

    Args:
        positions: Fingertip contact points, shape (m, 3) [m].
        normals: Inward unit contact normals, shape (m, 3).
        com: Object centre of mass (torque reference), shape (3,) [m].
        torque_scale: rho [m].
        mu: Coulomb friction coefficient (>= 0).
        cone_edges: Number of friction-cone edges k (>= 3).
        max_normal_force: Per-finger normal-force cap F_max [N].
        directions: Unit disturbance directions, shape (D, 6).
        torsion: Torsional friction coefficient of soft fingers [m]; 0 = hard fingers.

    Returns:
        The :class:`Prediction`: ``resistance`` (D,) [N] and ``normal_forces`` (D, m) [N].

    Raises:
        OgcpError: Any invalid argument.
    """
    lp = ResistanceLP(positions, normals, com, torque_scale, mu, cone_edges, max_normal_force, torsion)
    return lp.predict(directions)


def physical_wrench(
    direction: NDArray[np.float64], magnitude: float, torque_scale: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The physical force and torque of the scaled disturbance ``magnitude * direction``.

    MuJoCo's ``xfrc_applied`` takes a force and a torque at the body's centre of mass in
    the world frame; this undoes the planner's torque scaling.

    Args:
        direction: Unit disturbance direction in scaled space, shape (6,).
        magnitude: Disturbance magnitude s [N] (scaled space).
        torque_scale: rho [m].

    Returns:
        ``(force, torque)``: force shape (3,) [N], torque about the COM shape (3,) [N·m].

    Raises:
        OgcpError: A direction that is not a finite unit 6-vector, a non-finite magnitude
            or a non-positive rho.
    """
    d = _finite_array(direction, "direction", "(6,)", 1, DIM)
    validate_directions(d[None, :])
    rho = _positive(torque_scale, "torque scale rho", " m")
    try:
        s = float(magnitude)
    except (TypeError, ValueError):
        raise OgcpError(f"magnitude must be a number, got {magnitude!r}") from None
    if not math.isfinite(s):
        raise OgcpError(f"magnitude must be finite, got {magnitude!r}")
    return s * d[:3], s * d[3:] * rho
