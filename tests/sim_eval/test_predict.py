"""The resistance LP of ogcp.sim_eval.protocols.predict: closed forms, LP duality and input validation.

Closed forms are derived by hand from the README's cone convention. Pinch: fingers at
(+-a, 0, 0) with inward normals (-+1, 0, 0) have ``|n_x| >= 0.9``, so ``e = (0, 1, 0)``:
finger at +a: ``a = (0, 0, -1)``, ``b = (0, -1, 0)``; finger at -a: ``a = (0, 0, 1)``,
``b = (0, -1, 0)``. In the (y, z) plane the edge tangents of both fingers then point at
the angles ``pi/2 + 2 pi j / k`` (the same set for even k), a regular k-gon of
circumradius ``mu N``. Its ray length at angle theta is ``cos(pi/k) / cos(delta)`` with
delta the angle from theta to the nearest edge midpoint.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from ogcp.planner.grasp import contact_wrenches
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval.protocols.predict import Prediction, ResistanceLP, physical_wrench, predicted_resistance

HALF_WIDTH = 0.04  # a [m]
RHO = 0.1  # [m]


def polygon_ray(theta: float, k: int, first_vertex: float) -> float:
    """Ray length of a regular k-gon of circumradius 1 at angle theta."""
    step = 2.0 * math.pi / k
    delta = (theta - first_vertex) % step - step / 2.0
    return math.cos(math.pi / k) / math.cos(delta)


def pinch(mu: float, k: int, f_max: float) -> ResistanceLP:
    positions = np.array([[HALF_WIDTH, 0.0, 0.0], [-HALF_WIDTH, 0.0, 0.0]])
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    return ResistanceLP(positions, normals, np.zeros(3), RHO, mu, k, f_max)


def unit(*components: float) -> np.ndarray:
    v = np.array(components, dtype=float)
    return v / np.linalg.norm(v)


@pytest.mark.parametrize("k", [4, 6, 8])
@pytest.mark.parametrize("phi_deg", [90.0, 90.0 + 22.5, 0.0, 37.0, 161.0, 270.0])
def test_pinch_in_plane_force_is_the_friction_polygon(k: int, phi_deg: float) -> None:
    mu, f_max = 0.5, 7.0
    phi = math.radians(phi_deg)
    d = np.array([0.0, math.cos(phi), math.sin(phi), 0.0, 0.0, 0.0])
    s, forces = pinch(mu, k, f_max).solve(d)
    # Torque balance forces equal tangential forces, x balance equal normal forces; the
    # polygon is centrally symmetric (even k), so -d and d have the same ray length.
    expected = 2.0 * mu * f_max * polygon_ray(phi, k, math.pi / 2.0)
    assert s == pytest.approx(expected, rel=1e-9)
    np.testing.assert_allclose(forces, [f_max, f_max], rtol=1e-9)


def test_pinch_vertex_and_mid_edge_values() -> None:
    mu, f_max, k = 0.3, 5.0, 8
    lp = pinch(mu, k, f_max)
    s_vertex, _ = lp.solve(unit(0, 0, 1, 0, 0, 0))
    mid = math.pi / 2.0 + math.pi / k
    s_mid, _ = lp.solve(np.array([0.0, math.cos(mid), math.sin(mid), 0, 0, 0]))
    assert s_vertex == pytest.approx(2 * mu * f_max, rel=1e-9)
    assert s_mid == pytest.approx(2 * mu * f_max * math.cos(math.pi / k), rel=1e-9)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pinch_axis_load_is_one_finger_budget(sign: float) -> None:
    f_max = 6.0
    s, forces = pinch(0.5, 8, f_max).solve(unit(sign, 0, 0, 0, 0, 0))
    assert s == pytest.approx(f_max, rel=1e-9)
    # Load +x is balanced by the finger at +a pushing -x alone, and vice versa.
    pushing = 0 if sign > 0 else 1
    assert forces[pushing] == pytest.approx(f_max, rel=1e-9)
    assert forces[1 - pushing] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pinch_cannot_resist_torque_about_its_axis(sign: float) -> None:
    s, forces = pinch(0.8, 8, 10.0).solve(unit(0, 0, 0, sign, 0, 0))
    assert s == 0.0
    assert np.all(np.isfinite(forces))


@pytest.mark.parametrize("k", [6, 8])
def test_pinch_torque_across_axis_uses_the_lever_arm(k: int) -> None:
    mu, f_max = 0.5, 4.0
    lp = pinch(mu, k, f_max)
    # Torque about z needs opposite tangential y forces (ray angle 0), about y opposite z
    # forces (angle pi/2, a vertex); scaled torque = physical torque / rho.
    s_z, _ = lp.solve(unit(0, 0, 0, 0, 0, 1))
    s_y, _ = lp.solve(unit(0, 0, 0, 0, -1, 0))
    assert s_z == pytest.approx(2 * HALF_WIDTH * mu * f_max * polygon_ray(0.0, k, math.pi / 2) / RHO, rel=1e-9)
    assert s_y == pytest.approx(2 * HALF_WIDTH * mu * f_max / RHO, rel=1e-9)


def equator_tips(radius: float) -> tuple[np.ndarray, np.ndarray]:
    # All three normals have |n_x| < 0.9 and n_y != 0, so a = (0, 0, -sign n_y): edge j = 0
    # (and j = k/2 for even k) is vertical, and b is the horizontal tangent.
    alpha = np.radians([90.0, 210.0, 330.0])
    outward = np.stack([np.cos(alpha), np.sin(alpha), np.zeros(3)], axis=1)
    return radius * outward, -outward


@pytest.mark.parametrize("k", [4, 8, 12])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_three_equator_tips_hold_polar_load_with_full_friction(k: int, sign: float) -> None:
    mu, f_max, radius = 0.4, 3.0, 0.05
    positions, normals = equator_tips(radius)
    pred = predicted_resistance(positions, normals, np.zeros(3), RHO, mu, k, f_max, unit(0, 0, sign, 0, 0, 0)[None])
    assert pred.resistance[0] == pytest.approx(3 * mu * f_max, rel=1e-9)
    np.testing.assert_allclose(pred.normal_forces[0], f_max, rtol=1e-9)


@pytest.mark.parametrize("k", [4, 8])
def test_three_equator_tips_polar_torque(k: int) -> None:
    # k divisible by 4 puts an edge on the horizontal tangent b (t = pi/2).
    mu, f_max, radius = 0.4, 3.0, 0.05
    positions, normals = equator_tips(radius)
    lp = ResistanceLP(positions, normals, np.zeros(3), RHO, mu, k, f_max)
    s, _ = lp.solve(unit(0, 0, 0, 0, 0, 1))
    assert s == pytest.approx(3 * radius * mu * f_max / RHO, rel=1e-9)


def test_resistance_scales_with_budget_and_zero_friction_pinch_cannot_hold_shear() -> None:
    d = unit(0.3, -0.2, 0.5, 0.1, 0.4, -0.2)
    s1, _ = pinch(0.5, 8, 1.0).solve(d)
    s7, _ = pinch(0.5, 8, 7.0).solve(d)
    assert s7 == pytest.approx(7.0 * s1, rel=1e-9)
    s, _ = pinch(0.0, 8, 5.0).solve(unit(0, 1, 0, 0, 0, 0))
    assert s == 0.0


def random_grasp(rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fingertips near a great circle of a sphere, normals tilted: often but not always in closure."""
    angles = np.sort(rng.uniform(0, 2 * np.pi, m))
    outward = np.stack([np.cos(angles), np.sin(angles), rng.normal(0, 0.2, m)], axis=1)
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    normals = -outward + rng.normal(0, 0.1, (m, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return 0.05 * outward, normals, rng.normal(0, 0.005, 3)


def dual_value(wrenches: np.ndarray, f_max: float, d: np.ndarray) -> tuple[float, np.ndarray]:
    """min over u with (-d).u = 1 of the support h(u) = sum_i F_max max(0, max_j w_ij.u).

    Written as its own LP in variables [u (6), t (m)]: t_i >= w_ij.u, t_i >= 0.
    """
    m, k, _ = wrenches.shape
    cost = np.concatenate([np.zeros(6), np.full(m, f_max)])
    a_ub = np.zeros((m * k, 6 + m))
    a_ub[:, :6] = wrenches.reshape(m * k, 6)
    a_ub[np.arange(m * k), 6 + np.repeat(np.arange(m), k)] = -1.0
    a_eq = np.concatenate([-d, np.zeros(m)])[None]
    bounds = [(None, None)] * 6 + [(0, None)] * m
    res = linprog(cost, A_ub=a_ub, b_ub=np.zeros(m * k), A_eq=a_eq, b_eq=[1.0], bounds=bounds, method="highs")
    assert res.status == 0
    return float(res.fun), res.x[:6]


def support(wrenches: np.ndarray, f_max: float, u: np.ndarray) -> np.ndarray:
    """h(u) of the resistible set for directions u (n, 6)."""
    return f_max * np.maximum(0.0, np.einsum("ijc,nc->nij", wrenches, u).max(axis=2)).sum(axis=1)


@pytest.mark.parametrize("seed", range(6))
def test_lp_value_equals_the_support_function_dual(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m, mu, k, f_max = int(rng.integers(2, 5)), 0.6, 6, 2.5
    positions, normals, com = random_grasp(rng, m)
    directions = rng.normal(size=(12, 6))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    pred = predicted_resistance(positions, normals, com, RHO, mu, k, f_max, directions)
    wrenches = contact_wrenches(positions, normals, com, RHO, mu, k)
    probes = rng.normal(size=(400, 6))
    h = support(wrenches, f_max, probes)
    for d, s in zip(directions, pred.resistance, strict=True):
        value, u = dual_value(wrenches, f_max, d)
        assert s == pytest.approx(value, rel=1e-7, abs=1e-8)
        # Weak duality for every probe: -s d lies in the resistible set.
        assert np.all(s * (probes @ -d) <= h + 1e-9)
        assert support(wrenches, f_max, u[None])[0] == pytest.approx(s, rel=1e-7, abs=1e-8)
    assert np.all(pred.normal_forces <= f_max * (1 + 1e-9))
    assert np.all(pred.normal_forces >= -1e-9)


def test_predicted_resistance_shapes_and_read_only() -> None:
    positions, normals = equator_tips(0.05)
    directions = np.eye(6)
    pred = predicted_resistance(positions, normals, np.zeros(3), RHO, 0.5, 8, 1.0, directions)
    assert isinstance(pred, Prediction)
    assert pred.resistance.shape == (6,) and pred.normal_forces.shape == (6, 3)
    assert not pred.resistance.flags.writeable
    empty = predicted_resistance(positions, normals, np.zeros(3), RHO, 0.5, 8, 1.0, np.zeros((0, 6)))
    assert empty.resistance.shape == (0,) and empty.normal_forces.shape == (0, 3)


def test_physical_wrench_undoes_torque_scaling() -> None:
    d = unit(1, 2, 3, 4, 5, 6)
    force, torque = physical_wrench(d, 2.0, 0.25)
    np.testing.assert_allclose(force, 2.0 * d[:3])
    np.testing.assert_allclose(torque, 2.0 * d[3:] * 0.25)
    # Round trip through the scaled space.
    np.testing.assert_allclose(np.concatenate([force, torque / 0.25]) / 2.0, d)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"positions": np.zeros((2, 2))}, "contact positions"),
        ({"normals": np.array([[-2.0, 0, 0], [1, 0, 0]])}, "unit vector"),
        ({"normals": np.array([[np.nan, 0, 0], [1, 0, 0]])}, "NaN"),
        ({"com": np.zeros(2)}, "centre of mass"),
        ({"torque_scale": 0.0}, "rho"),
        ({"mu": -0.1}, "mu"),
        ({"cone_edges": 2}, "cone_edges"),
        ({"cone_edges": 3.5}, "cone_edges"),
        ({"max_normal_force": 0.0}, "F_max"),
        ({"max_normal_force": math.inf}, "F_max"),
        ({"directions": np.ones((3, 6))}, "unit vector"),
        ({"directions": np.ones((3, 5))}, "directions"),
    ],
)
def test_invalid_inputs_raise_one_line_errors(change: dict, message: str) -> None:
    args = {
        "positions": np.array([[HALF_WIDTH, 0, 0], [-HALF_WIDTH, 0, 0]]),
        "normals": np.array([[-1.0, 0, 0], [1, 0, 0]]),
        "com": np.zeros(3),
        "torque_scale": RHO,
        "mu": 0.5,
        "cone_edges": 8,
        "max_normal_force": 1.0,
        "directions": np.eye(6),
    }
    args.update(change)
    with pytest.raises(OgcpError, match=message) as info:
        predicted_resistance(**args)
    assert "\n" not in str(info.value)


def test_physical_wrench_rejects_non_unit_direction() -> None:
    with pytest.raises(OgcpError, match="unit vector"):
        physical_wrench(np.ones(6), 1.0, RHO)
    with pytest.raises(OgcpError, match="rho"):
        physical_wrench(np.eye(6)[0], 1.0, -1.0)
