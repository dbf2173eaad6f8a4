"""``--render`` of a plan made with a hand draws that hand as it settled, not fingertip spheres."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
import pytest

from ogcp.planner.hands import HandKinematics, resolve_hand
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval import render
from ogcp.sim_eval.decomposition import DecompositionSettings
from ogcp.sim_eval.evaluate import evaluate_plan
from ogcp.sim_eval.hand.mount import PREFIX
from ogcp.sim_eval.protocols.phases import FULL_STATE
from ogcp.sim_eval.settings import SimSettings

HULL = DecompositionSettings(method="convex_hull")


def _drawn(monkeypatch: pytest.MonkeyPatch) -> list[dict[str, Any]]:
    """What :func:`render.render_grasp` is asked to draw, instead of drawing it (no OpenGL needed)."""
    calls: list[dict[str, Any]] = []

    def record(scene: Any, settled: Any, width: int, height: int, **kwargs: Any) -> np.ndarray:
        calls.append({"scene": scene, "settled": settled, **kwargs})
        return np.zeros((height, width, 3), dtype=np.uint8)

    monkeypatch.setattr(render, "render_grasp", record)
    return calls


def test_a_hand_plan_is_drawn_with_the_hand_as_evaluate_settled_it(sdh_plan, monkeypatch):
    calls = _drawn(monkeypatch)
    render.render_plan(sdh_plan, SimSettings(directions=4), HULL)
    (call,) = calls
    scene, model = call["scene"], call["scene"].model
    assert scene.finger_geoms is not None and len(call["framed"]) > len(scene.finger_geoms)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, call["settled"].state, FULL_STATE)
    joints = HandKinematics(resolve_hand("sdh")).joint_names
    address = [model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, PREFIX + j)] for j in joints]
    drawn = data.qpos[address]
    (grasp,) = evaluate_plan(sdh_plan, {"directions": 4}, HULL).grasps
    assert drawn == pytest.approx(grasp.hand["settled_joint_angles"], abs=1e-9)


def test_the_camera_looks_across_the_line_from_the_palm_to_the_object(sdh_plan, monkeypatch):
    calls = _drawn(monkeypatch)
    render.render_plan(sdh_plan, SimSettings(directions=4), HULL)
    (call,) = calls
    scene, model = call["scene"], call["scene"].model
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, call["settled"].state, FULL_STATE)
    mujoco.mj_kinematics(model, data)
    palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, PREFIX + resolve_hand("sdh").palm)
    line = (data.xipos[scene.object_body] - data.xpos[palm])[:2]
    view = np.array([np.cos(np.radians(call["azimuth"])), np.sin(np.radians(call["azimuth"]))])
    assert np.linalg.norm(line) > 1e-3 and abs(view @ line) < 1e-9  # the view is perpendicular to the line


def test_tips_draw_the_same_plan_with_fingertip_spheres(sdh_plan, monkeypatch):
    calls = _drawn(monkeypatch)
    render.render_plan(sdh_plan, SimSettings(directions=4), HULL, tips=True)
    (call,) = calls
    assert call["scene"].finger_geoms is None and call.get("framed") is None


def test_a_grasp_the_hand_cannot_realise_is_not_drawn(sdh_plan, monkeypatch):
    from ogcp.sim_eval.hand import trial

    def unreachable(contacts: Any, grasp: Any, label: str, *args: Any, **kwargs: Any) -> Any:
        return trial.failed_result(contacts, grasp, label, "unreachable for the sdh hand: finger 1 is 4.0 mm off", "")

    monkeypatch.setattr(trial, "close_on_grasp", unreachable)
    with pytest.raises(OgcpError) as caught:
        render.render_plan(sdh_plan, SimSettings(directions=4), HULL)
    message = str(caught.value)
    assert message.startswith("nothing to draw for grasp 0: unreachable for the sdh hand") and "--tips" in message
    assert "\n" not in message


def test_the_frame_keeps_the_palm_and_fingers_and_leaves_the_forearm_out():
    model = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody>
        <geom name="floor" type="plane" size="1 1 .1"/>
        <body name="forearm"><geom name="arm" type="capsule" size=".05" fromto="0 0 0 0 0 .3"/>
          <body name="palm" pos="0 0 .3"><geom name="palm" type="box" size=".04 .04 .01"/>
            <body name="finger" pos="0 0 .02"><joint type="hinge"/><geom name="finger" type="capsule" size=".01" fromto="0 0 0 0 0 .05"/>
            </body></body></body></worldbody></mujoco>"""
    )
    names = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in render.palm_and_fingers(model, "palm")}
    assert names == {"palm", "finger"}
    assert len(render.palm_and_fingers(model, "no such body")) == 0


def test_a_hand_is_drawn_where_offscreen_rendering_works(sdh_plan):
    try:
        render.check_offscreen_rendering()
    except OgcpError:
        pytest.skip("no OpenGL context here (set MUJOCO_GL=egl to run this)")
    hand = render.render_plan(sdh_plan, SimSettings(directions=4), HULL, width=160, height=120)
    tips = render.render_plan(sdh_plan, SimSettings(directions=4), HULL, width=160, height=120, tips=True)
    assert hand.shape == tips.shape == (120, 160, 3)
    # The hand's links cover far more of the picture than three small spheres do.
    lit = [int((image.sum(axis=2) > 30).sum()) for image in (hand, tips)]
    assert lit[0] > 1.2 * lit[1]
