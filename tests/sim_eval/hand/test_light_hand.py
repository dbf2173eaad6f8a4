"""A light hand with stiff servos and no force limits (an Allegro hand's model is one) closes and holds."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.sim_eval.evaluate import evaluate_plan
from ogcp.sim_eval.hand import servo_step
from ogcp.sim_eval.hand.servo_step import MAX_OMEGA_DT, steady_servos
from ogcp.sim_eval.settings import SimSettings
from tests.planner.hands.hand_files import write_light_hand


@pytest.fixture(scope="module")
def light_plan(tmp_path_factory):
    folder = tmp_path_factory.mktemp("light")
    descriptor = write_light_hand(folder / "hand")
    path = folder / "plan.json"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OGCP_CACHE", str(folder / "cache"))
        argv = ["plan", "box", "-n", "60", "-m", "3", "--diagonal", "0.06", "--hand", str(descriptor), "-o", str(path)]
        assert main(argv) == 0
    return json.loads(path.read_text())


def test_a_light_stiffly_servoed_hand_holds_and_grips_as_fingertips_do(light_plan):
    (grasp,) = evaluate_plan(light_plan, {"directions": 8}).grasps
    assert grasp.valid and grasp.gates["tips_in_contact"] == 3, grasp.invalid_reasons
    # No actuator limits the grip: its weakest pad presses F_max, as a fingertip does, and none
    # presses more than the balance needs (not the tens of newtons the control range would allow).
    share, forces = grasp.hand["squeeze_share"], np.array(grasp.hand["squeeze_forces"])
    assert forces.min() == pytest.approx(share * SimSettings().max_normal_force, rel=1e-6)
    assert forces.max() < 4 * forces.min()


def test_a_servo_that_drives_its_joint_through_a_tendon_is_steadied_too(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    descriptor = write_light_hand(tmp_path / "hand", tendons=True)
    path = tmp_path / "plan.json"
    argv = ["plan", "box", "-n", "60", "-m", "3", "--diagonal", "0.06", "--hand", str(descriptor), "-o", str(path)]
    assert main(argv) == 0
    (grasp,) = evaluate_plan(json.loads(path.read_text()), {"directions": 8}).grasps
    assert grasp.valid and grasp.gates["tips_in_contact"] == 3, grasp.invalid_reasons


def test_without_the_armature_the_same_hand_flings_the_object(light_plan, monkeypatch):
    monkeypatch.setattr(servo_step, "MAX_OMEGA_DT", 1e9)
    (grasp,) = evaluate_plan(light_plan, {"directions": 8}).grasps
    assert not grasp.valid


HINGE = """<mujoco><option timestep="0.002"/><worldbody><body>
  <joint name="j" axis="0 1 0" damping="{damping}"/>
  <geom type="capsule" size="0.008" fromto="0 0 0 0 0 0.03" density="{density}"/>
</body></worldbody><actuator><position joint="j" kp="{kp}" kv="{kv}"/></actuator></mujoco>"""


def _hinge(density: float = 800.0, kp: float = 10.0, damping: float = 0.0, kv: float = 0.0):
    model = mujoco.MjModel.from_xml_string(HINGE.format(density=density, kp=kp, damping=damping, kv=kv))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    inertia = float(model.body_inertia[1, 1] + model.body_mass[1] * model.body_ipos[1, 2] ** 2)
    return model, inertia


def test_steady_servos_bring_omega_dt_down_and_keep_the_damping_ratio():
    model, inertia = _hinge(kv=2.0 * np.sqrt(10.0 * _hinge()[1]))  # critically damped, light
    assert np.sqrt(10.0 / inertia) * model.opt.timestep > 1.0
    steady_servos(model, model.qpos0.copy())
    total = inertia + model.dof_armature[0]
    assert np.sqrt(10.0 / total) * model.opt.timestep == pytest.approx(MAX_OMEGA_DT, rel=1e-6)
    damping = model.dof_damping[0] + model.actuator_biasprm[0, 2] * -1.0
    assert damping / (2.0 * np.sqrt(10.0 * total)) == pytest.approx(1.0, rel=1e-6)


def test_steady_servos_leave_a_heavy_or_overdamped_joint_as_it_is():
    heavy, _ = _hinge(density=1e7)
    steady_servos(heavy, heavy.qpos0.copy())
    assert heavy.dof_armature[0] == 0.0 and heavy.dof_damping[0] == 0.0
    overdamped, _ = _hinge(damping=1.0)
    steady_servos(overdamped, overdamped.qpos0.copy())
    assert overdamped.dof_armature[0] > 0.0 and overdamped.dof_damping[0] == 1.0
