"""The fit's analytic Jacobian (the pads' solve) equals central differences of its residuals to 1e-6."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize
from scipy.spatial.transform import Rotation

import ogcp.sim_eval.hand.fit as fit_module
from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.sim_eval.hand.fit_jacobian import so3_left_jacobian
from ogcp.sim_eval.hand.fit_scene import FitScene
from tests.planner.hands.hand_files import write_mesh_hand


def _central(fun, x, args, step=1e-7):
    columns = []
    for i in range(len(x)):
        up, down = x.copy(), x.copy()
        up[i] += step
        down[i] -= step
        columns.append((fun(up, *args) - fun(down, *args)) / (2 * step))
    return np.column_stack(columns)


class _Recorder:
    """Stands in for least_squares: compares the Jacobian with central differences, then solves."""

    def __init__(self):
        self.errors = []
        self.real = scipy.optimize.least_squares

    def __call__(self, fun, x0, jac, bounds, args, **options):
        if not callable(jac):  # the collision solve differences its residuals
            return self.real(fun, x0, jac=jac, bounds=bounds, args=args, **options)
        rng = np.random.default_rng(0)
        for shake in (0.0, 0.05, 0.1):
            x = np.clip(x0 + shake * rng.normal(size=x0.shape), bounds[0] + 1e-6, bounds[1] - 1e-6)
            analytic, numeric = jac(x, *args), _central(fun, x, args)
            scale = max(1e-9, float(np.abs(numeric).max()))
            self.errors.append(float(np.abs(analytic - numeric).max()) / scale)
        return self.real(fun, x0, jac=jac, bounds=bounds, args=args, **options)


@pytest.mark.parametrize("hand", ["sdh", "claw", "parallel_gripper"])
def test_the_pads_rows_match_central_differences(hand, tmp_path, monkeypatch):
    kinematics = HandKinematics(load_descriptor(write_mesh_hand(tmp_path)) if hand == "claw" else resolve_hand(hand))
    scene = FitScene(kinematics)
    recorder = _Recorder()
    monkeypatch.setattr(fit_module, "least_squares", recorder)
    fingers = list(range(min(3, len(kinematics.fingers))))
    truth = kinematics.sample(1, 5)[0]
    points, normals = kinematics.pads(truth)
    turn = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    fit_module.fit_hand(scene, fingers, points[fingers] @ turn.T + 0.1, normals[fingers] @ turn.T)
    assert recorder.errors and max(recorder.errors) < 1e-6  # coupled joints (the SDH's) included


def test_the_left_jacobian_of_so3_is_first_order_exact():
    w = np.array([0.7, -0.4, 1.9])
    d = 1e-6 * np.array([0.3, 0.8, -0.5])
    exact = Rotation.from_rotvec(w + d).as_matrix()
    approx = Rotation.from_rotvec(so3_left_jacobian(w) @ d).as_matrix() @ Rotation.from_rotvec(w).as_matrix()
    assert np.abs(exact - approx).max() < 1e-11
