"""A joint stop is a spring in MuJoCo: the prediction's stiffness for it is the one MuJoCo holds a steady load with."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ogcp.sim_eval.hand.travel import stop_reach, stop_stiffness

SLIDER = """<mujoco>
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <body name="slider">
      <joint name="slide" type="slide" axis="1 0 0" range="0 0.1" damping="5" {limit}/>
      <geom type="box" size="0.01 0.01 0.01" mass="{mass}"/>
    </body>
  </worldbody>
</mujoco>"""


@pytest.mark.parametrize(
    ("mass", "limit"),
    [
        (0.05, ""),
        (0.2, ""),
        (0.05, 'solreflimit="0.01 1"'),
        (0.05, 'solreflimit="-2000 -50" solimplimit="0.9 0.95 0.001"'),
    ],
)
def test_a_stop_holds_a_steady_push_at_the_stiffness_predicted(mass, limit):
    model = mujoco.MjModel.from_xml_string(SLIDER.format(mass=mass, limit=limit))
    data = mujoco.MjData(model)
    stiffness = stop_stiffness(model, 0)
    push = 4e-3 * stiffness  # 4 mm past the limit: past solimp's 1 mm width, at its full impedance
    data.xfrc_applied[1, 0] = -push
    for _ in range(5000):
        mujoco.mj_step(model, data)
    passed = -float(data.qpos[0])
    assert abs(float(data.qvel[0])) < 1e-6
    assert push / passed == pytest.approx(stiffness, rel=0.02)


def test_a_stop_pushes_what_its_softness_allows_within_the_travel():
    model = mujoco.MjModel.from_xml_string(SLIDER.format(mass=0.05, limit=""))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    points, bodies = np.array([[0.01, 0.0, 0.0]]), np.array([1])
    reach = stop_reach(model, data, points, bodies, 0.002, 0)
    assert reach == pytest.approx(stop_stiffness(model, 0) * 0.002 / np.sqrt(3.0), rel=1e-9)
    assert stop_reach(model, data, points, np.array([0]), 0.002, 0) == np.inf  # it moves no contact
