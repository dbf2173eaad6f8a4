"""The fit's analytic Jacobian equals central differences of its residuals: the pads' and loops' rows to 1e-6, the depths' to 1e-4."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize
import trimesh
from scipy.spatial.transform import Rotation

import ogcp.sim_eval.hand.fit as fit_module
from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.sim_eval.hand.fit_jacobian import so3_left_jacobian
from ogcp.sim_eval.hand.fit_scene import FitScene
from tests.planner.hands.hand_files import write_fourbar_gripper, write_mesh_hand


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
        rng = np.random.default_rng(0)
        for shake in (0.0, 0.05, 0.1):
            x = np.clip(x0 + shake * rng.normal(size=x0.shape), bounds[0] + 1e-6, bounds[1] - 1e-6)
            analytic, numeric = jac(x, *args), _central(fun, x, args)
            scale = max(1e-9, float(np.abs(numeric).max()))
            self.errors.append(float(np.abs(analytic - numeric).max()) / scale)
        return self.real(fun, x0, jac=jac, bounds=bounds, args=args, **options)


def _hand(hand, folder):
    if hand == "claw":
        return load_descriptor(write_mesh_hand(folder))
    if hand.startswith("fourbar"):
        path = write_fourbar_gripper(folder)
        if hand == "fourbar_weld":  # a weld closes the loops instead: their turning gaps' rows too
            model = folder / "fourbar.xml"
            model.write_text(model.read_text().replace("<connect ", "<weld "))
        return load_descriptor(path)
    return resolve_hand(hand)


@pytest.mark.parametrize("hand", ["sdh", "claw", "parallel_gripper", "fourbar", "fourbar_weld"])
def test_the_pads_rows_match_central_differences(hand, tmp_path, monkeypatch):
    kinematics = HandKinematics(_hand(hand, tmp_path))
    scene = FitScene(kinematics)
    recorder = _Recorder()
    monkeypatch.setattr(fit_module, "least_squares", recorder)
    fingers = list(range(min(3, len(kinematics.fingers))))
    truth = kinematics.sample(1, 5)[0]
    points, normals = kinematics.pads(truth)
    turn = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    fit_module.fit_hand(scene, fingers, points[fingers] @ turn.T + 0.1, normals[fingers] @ turn.T)
    assert recorder.errors and max(recorder.errors) < 1e-6  # coupled joints (the SDH's) and loops included


def test_the_left_jacobian_of_so3_is_first_order_exact():
    w = np.array([0.7, -0.4, 1.9])
    d = 1e-6 * np.array([0.3, 0.8, -0.5])
    exact = Rotation.from_rotvec(w + d).as_matrix()
    approx = Rotation.from_rotvec(so3_left_jacobian(w) @ d).as_matrix() @ Rotation.from_rotvec(w).as_matrix()
    assert np.abs(exact - approx).max() < 1e-11


@pytest.mark.parametrize("hand", ["sdh", "claw"])
def test_the_depth_rows_match_central_differences(hand, tmp_path):
    """A link inside the object: the collision solve's depth rows are first-order exact."""
    kinematics = HandKinematics(load_descriptor(write_mesh_hand(tmp_path)) if hand == "claw" else resolve_hand(hand))
    angles = kinematics.sample(1, 3)[0]
    pads, normals = kinematics.pads(angles)
    # A 2 cm cube whose face is 4 mm past finger 0's pad: the pad's link is inside it.
    cube = trimesh.creation.box(extents=(0.02, 0.02, 0.02))
    corners, faces = cube.vertices + pads[0] + (0.01 - 0.004) * normals[0], cube.faces
    variables = kinematics.independent
    rotation0, shift0 = Rotation.from_rotvec([0.2, -0.3, 0.1]).as_matrix(), np.zeros(3)
    # The palm is turned by rotation0 about the world origin: the cube turns with it.
    scene = FitScene(kinematics, [(corners @ rotation0.T, faces)])

    def depths(x):
        q = angles.copy()
        q[variables] = x[: len(variables)]
        rotation = Rotation.from_rotvec(x[len(variables) : len(variables) + 3]).as_matrix() @ rotation0
        scene.pose(kinematics.complete(q), rotation, shift0 + x[len(variables) + 3 :])
        into_object, into_hand = scene.depths()
        return np.maximum(into_object, into_hand)

    x = np.concatenate([angles[variables], [0.01, -0.02, 0.015], [0.0005, -0.0003, 0.0002]])
    deepest = depths(x)
    active = deepest - 0.5 * fit_module.LINK_TOLERANCE > 0
    assert active.any() and deepest.max() > 2e-3
    q = angles.copy()
    q[variables] = x[: len(variables)]
    palm = (x[len(variables) : len(variables) + 3], shift0 + x[len(variables) + 3 :])
    jac = fit_module.PoseJacobian(scene, kinematics.complete(q), variables, palm)
    analytic = fit_module._depth_rows(scene, jac)
    numeric = _central(depths, x, (), step=1e-7)
    assert np.abs(analytic[~active]).max(initial=0.0) == 0.0
    error = np.abs(analytic[active] - numeric[active]).max() / np.abs(numeric[active]).max()
    assert error < 1e-4
