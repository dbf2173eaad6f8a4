"""Closed loops of a hand model: found in each MJCF form, their gaps zero where the model was built, their Jacobians MuJoCo's."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ogcp.planner.hands.loops import LOOP_LEVER, find_loops, loop_gap, loop_system

CHAIN = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="palm">
      <body name="a" pos="0 0.02 0">
        <joint name="a" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.004"/>
        <site name="a_end" pos="0 0 0.05" euler="0.3 0 0"/>
        <body name="b" pos="0 0 0.05">
          <joint name="b" axis="1 0 0"/>
          <joint name="b_twist" axis="0 0 1"/>
          <geom type="box" size="0.01 0.01 0.02" pos="0 0.01 0.02"/>
          <site name="b_end" pos="0 0.015 0" euler="0 0.2 0"/>
        </body>
      </body>
      <body name="c" pos="0 0.035 0">
        <joint name="c" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.003"/>
        <site name="c_end" pos="0 0 0.05"/>
      </body>
    </body>
  </worldbody>
  <equality>{equality}</equality>
</mujoco>"""
EQUALITIES = {
    "connect": '<connect body1="c" body2="b" anchor="0 0 0.05"/>',
    "connect sites": '<connect site1="c_end" site2="b_end"/>',
    "weld": '<weld body1="c" body2="b" anchor="0 0.01 0.02"/>',
    "weld sites": '<weld site1="a_end" site2="b_end"/>',
}


def _model(kind: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(CHAIN.format(equality=EQUALITIES[kind]))


@pytest.mark.parametrize("kind", sorted(EQUALITIES))
def test_a_loops_gap_is_mujocos_own_violation_and_body_forms_close_where_built(kind):
    model = _model(kind)
    (loop,) = find_loops(model, range(1, model.nbody))
    assert loop.rows == (3 if kind.startswith("connect") else 6)
    names = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in loop.joints}
    assert names == ({"b", "b_twist"} if kind == "weld sites" else {"a", "b", "b_twist", "c"})
    data = mujoco.MjData(model)
    if not kind.endswith("sites"):  # MuJoCo's compiler puts the second anchor where the first is
        mujoco.mj_kinematics(model, data)
        gap, first, second = loop_gap(model, data, loop)
        np.testing.assert_allclose(gap, 0.0, atol=1e-12)
        np.testing.assert_allclose(first, second, atol=1e-12)
    data.qpos[:] = np.random.default_rng(5).uniform(-0.4, 0.4, model.nq)
    mujoco.mj_fwdPosition(model, data)
    gap, _, _ = loop_gap(model, data, loop)
    rows = np.flatnonzero(data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    assert np.linalg.norm(gap[:3]) > 1e-3
    np.testing.assert_allclose(gap[:3], data.efc_pos[rows[:3]], atol=1e-12)  # the point gap, as MuJoCo holds it


@pytest.mark.parametrize("kind", sorted(EQUALITIES))
def test_a_loops_jacobian_is_the_derivative_of_its_gap(kind):
    model = _model(kind)
    loops = find_loops(model, range(1, model.nbody))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    data.qpos[:] = rng.uniform(-0.3, 0.3, model.nq)

    def gaps(qpos: np.ndarray) -> np.ndarray:
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        return loop_system(model, data, loops)[0]

    base = data.qpos.copy()
    gaps(base)
    _, jacobian = loop_system(model, data, loops)
    step = 1e-6
    numeric = np.array([(gaps(base + step * e) - gaps(base - step * e)) / (2 * step) for e in np.eye(model.nq)]).T
    np.testing.assert_allclose(jacobian, numeric, atol=1e-6 * max(1.0, LOOP_LEVER))


def test_equalities_that_do_not_close_a_loop_of_the_hand_are_not_loops():
    model = mujoco.MjModel.from_xml_string(
        CHAIN.format(equality='<connect body1="c" anchor="0 0 0.05"/><joint joint1="a" joint2="c"/>')
    )
    assert find_loops(model, range(1, model.nbody)) == ()  # one to the world, one between joints
    inactive = mujoco.MjModel.from_xml_string(
        CHAIN.format(equality='<connect body1="c" body2="b" anchor="0 0 0.05" active="false"/>')
    )
    assert find_loops(inactive, range(1, inactive.nbody)) == ()
