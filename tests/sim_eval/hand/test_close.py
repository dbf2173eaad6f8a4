"""A hand closed on the object in MuJoCo: the pinch against its closed form, the protocol on a hand."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import trimesh

from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.planner.hands.servos import HandActuatorWarning
from ogcp.sim_eval.hand.fit import fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.scene import PREGRASP_RADII, build_hand_scene, close_hand
from ogcp.sim_eval.protocols.phases import ramp_trials, settle
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.settings import SimSettings
from tests.planner.hands.hand_files import write_gripper_variant, write_urdf_gripper

MU = 0.5
#: [N] A URDF slide's effort limit below the descriptor's force range.
EFFORT = 12.0
BOX = trimesh.creation.box(extents=(0.04, 0.03, 0.04))
POINTS = np.array([[0.0, 0.015, 0.0], [0.0, -0.015, 0.0]])
NORMALS = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])


def _closed(kinematics: HandKinematics, settings: SimSettings):
    parts = [(BOX.vertices, BOX.faces)]
    fit = fit_hand(FitScene(kinematics, parts), [0, 1], POINTS, NORMALS)
    assert fit.realised
    com, inertia = object_inertia(BOX)
    opened = build_hand_scene(kinematics, fit, POINTS, NORMALS, parts, com, inertia, settings, MU, 0.05)
    return opened, close_hand(opened)


#: The gripper's own servos written as a gripper's driver often is: a general affine actuator whose
#: command runs 0-255 over the jaw's 0-40 mm (the Robotiq 2F-85's form), kp 20000 N/m as the
#: descriptor's servos: force = 3.137 ctrl - 20000 length - 30 velocity.
AFFINE_SERVOS = "".join(
    f'<general name="{side}" joint="{side}" gainprm="{20000 * 0.04 / 255}" biastype="affine" '
    f'biasprm="0 -20000 -30" ctrlrange="0 255" forcerange="-20 20"/>'
    for side in ("left", "right")
)


def tendon_servo(stiffness: float = 40000.0, limit: float = 40.0) -> str:
    """The jaws driven as the Franka hand's are: one general affine actuator (``stiffness`` [N/m],
    ``limit`` [N], command 0-255 over 0-40 mm) on a tendon that averages the two slides
    (coefficients 0.5), the slides tied equal by a joint equality. The tendon's force splits half to
    each jaw: by default 20 N and 20000 N/m a jaw, as the descriptor's own servos."""
    return (
        '<tendon><fixed name="split"><joint joint="left" coef="0.5"/><joint joint="right" coef="0.5"/></fixed></tendon>'
        '<equality><joint joint1="left" joint2="right" solref="0.004 1" solimp="0.95 0.99 0.001"/></equality>'
        f'<actuator><general name="split" tendon="split" gainprm="{stiffness * 0.04 / 255}" biastype="affine" '
        f'biasprm="0 -{stiffness:g} -{stiffness * 0.0015:g}" ctrlrange="0 255" forcerange="-{limit:g} {limit:g}"/>'
        "</actuator>"
    )


def _pinching_hand(hand: str, folder) -> HandKinematics:
    if hand == "urdf":
        return HandKinematics(load_descriptor(write_urdf_gripper(folder)))
    if hand == "urdf_effort":  # MuJoCo clamps each slide's actuator force at the URDF's effort limit
        path = write_urdf_gripper(folder)
        urdf = folder / "urdf_gripper.urdf"
        urdf.write_text(urdf.read_text().replace('effort="20"', f'effort="{EFFORT:g}"'))
        kinematics = HandKinematics(load_descriptor(path))
        assert EFFORT < kinematics.descriptor.actuation.force_range
        return kinematics
    if hand == "affine":
        actuated = write_gripper_variant(
            folder, lambda text: text.replace("</worldbody>", f"</worldbody><actuator>{AFFINE_SERVOS}</actuator>")
        )
        kinematics = HandKinematics(load_descriptor(actuated))
        assert kinematics.servos == ()  # its own actuators drive it
        return kinematics
    if hand == "filtered":  # position servos whose force follows the command through a 5 ms filter
        servos = "".join(
            f'<position name="{s}" joint="{s}" kp="20000" kv="30" timeconst="0.005" forcerange="-20 20"/>'
            for s in ("left", "right")
        )
        filtered = write_gripper_variant(
            folder, lambda text: text.replace("</worldbody>", f"</worldbody><actuator>{servos}</actuator>")
        )
        kinematics = HandKinematics(load_descriptor(filtered))
        assert kinematics.servos == () and kinematics.replaced_actuators == ()
        return kinematics
    if hand == "motor":  # force-controlled: closed by ogcp's position servos within the motors' 20 N
        motors = "".join(f'<motor name="{s}" joint="{s}" gear="2" ctrlrange="-10 10"/>' for s in ("left", "right"))
        driven = write_gripper_variant(
            folder, lambda text: text.replace("</worldbody>", f"</worldbody><actuator>{motors}</actuator>")
        )
        with pytest.warns(HandActuatorWarning, match=r"actuators left, right hold no pose"):
            kinematics = HandKinematics(load_descriptor(driven))
        assert kinematics.replaced_actuators == ("left", "right") and kinematics.servos == ("left", "right")
        return kinematics
    if hand == "tendon":
        split = write_gripper_variant(
            folder, lambda text: text.replace("</worldbody>", f"</worldbody>{tendon_servo()}")
        )
        return HandKinematics(load_descriptor(split))
    return HandKinematics(resolve_hand(hand))


@pytest.mark.parametrize("hand", ["parallel_gripper", "urdf", "urdf_effort", "affine", "tendon", "motor", "filtered"])
def test_a_pinch_resists_slip_as_two_mu_f(hand, tmp_path):
    """Along the jaws, a pinch holds until 2 mu F, F each jaw's force: its servo's limit over a lever of
    1 (slides), or the joint's own clamp on it where that is lower (a URDF's effort limit)."""
    kinematics = _pinching_hand(hand, tmp_path)
    limit = EFFORT if hand == "urdf_effort" else kinematics.descriptor.actuation.force_range
    settings = SimSettings()
    opened, closed = _closed(kinematics, settings)
    assert opened.scene.start_qpos is not None and closed.scene.start_qpos is not None
    assert (opened.grasp > opened.pregrasp).all()
    np.testing.assert_allclose(opened.squeeze_forces, limit)  # the balanced squeeze presses at the limit
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"] and settled.gates["tips_in_contact"] == 2
    np.testing.assert_allclose(settled.normal_forces, limit, rtol=0.01)  # the squeeze saturates both servos
    closed_form = 2 * MU * limit
    directions = np.array([[0, 0, 1, 0, 0, 0], [0, 0, -1, 0, 0, 0]], dtype=float)
    rate = np.full(2, 2 * closed_form / settings.ramp_time)
    trials = ramp_trials(
        closed.scene, settled, directions, rate, settings.ramp_extent * settings.ramp_time, 1.0, settings
    )
    assert trials.failed.all() and not trials.diverged.any()
    np.testing.assert_allclose(trials.failure_load, closed_form, rtol=0.05)


def test_the_hand_starts_in_the_pregrasp_touching_nothing_with_pads_backed_off():
    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    opened, closed = _closed(kinematics, SimSettings())
    model = opened.scene.model
    data = mujoco.MjData(model)
    data.qpos[:] = opened.scene.start()
    mujoco.mj_forward(model, data)
    assert data.ncon == 0
    pads, _ = opened.hand.pads_world(data)
    gaps = np.linalg.norm(pads - POINTS, axis=1)
    np.testing.assert_allclose(gaps, PREGRASP_RADII * kinematics.fingers[0].radius, rtol=1e-3)
    data.qpos[:] = closed.scene.start()
    mujoco.mj_forward(model, data)
    assert data.ncon >= 2  # the closed hand touches the box


def test_a_wrist_between_root_and_palm_is_welded_at_its_reference(tmp_path):
    descriptor = write_gripper_variant(
        tmp_path,
        lambda text: text.replace(
            '<body name="palm">',
            '<body name="arm"><joint name="wrist" axis="1 0 0"/><geom size="0.01"/><body name="palm">',
        ).replace("    </body>\n  </worldbody>", "    </body>\n    </body>\n  </worldbody>"),
    )
    kinematics = HandKinematics(load_descriptor(descriptor))
    assert kinematics.idle_joints() == ("wrist",)
    settings = SimSettings()
    _, closed = _closed(kinematics, settings)
    assert mujoco.mj_name2id(closed.scene.model, mujoco.mjtObj.mjOBJ_JOINT, "hand/wrist") == -1
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"] and settled.gates["tips_in_contact"] == 2


def test_a_driven_wrist_is_welded_too_with_its_actuator(tmp_path):
    """The Shadow hand's wrist and a floating base's joints carry servos: the palm is still held rigidly."""
    descriptor = write_gripper_variant(
        tmp_path,
        lambda text: (
            text.replace(
                '<body name="palm">',
                '<body name="base"><joint name="lift" type="slide" axis="0 0 1" range="-1 1"/><geom size="0.01"/>'
                '<body name="arm"><joint name="wrist" axis="1 0 0" range="-1 1"/><geom size="0.01"/><body name="palm">',
            )
            .replace("    </body>\n  </worldbody>", "    </body>\n    </body>\n    </body>\n  </worldbody>")
            .replace(
                "</worldbody>",
                '</worldbody><actuator><position name="lift_servo" joint="lift" kp="100"/>'
                '<position name="wrist_servo" joint="wrist" kp="10"/></actuator>'
                '<sensor><jointpos name="wrist_angle" joint="wrist"/></sensor>',
            )
        ),
    )
    kinematics = HandKinematics(load_descriptor(descriptor))
    assert set(kinematics.idle_joints()) == {"lift", "wrist"}
    settings = SimSettings()
    _, closed = _closed(kinematics, settings)
    scene = closed.scene.model
    for kind, name in ((mujoco.mjtObj.mjOBJ_JOINT, "hand/wrist"), (mujoco.mjtObj.mjOBJ_ACTUATOR, "hand/wrist_servo")):
        assert mujoco.mj_name2id(scene, kind, name) == -1
    assert mujoco.mj_name2id(scene, mujoco.mjtObj.mjOBJ_JOINT, "hand/lift") == -1
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"] and settled.gates["tips_in_contact"] == 2


@pytest.mark.parametrize("travel", [None, 2e-4, 1e-3, 1.0])
def test_a_servo_resists_along_its_jaw_what_it_builds_within_the_failure_distance(travel):
    """Pushed along y, the pinch sheds one jaw's force: F when the servos are stiff, kp h within the travel."""
    from ogcp.sim_eval.hand.predict import hand_resistance, realised_contacts
    from ogcp.sim_eval.hand.trial import _settled_data

    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    limit, kp = kinematics.descriptor.actuation.force_range, kinematics.descriptor.actuation.kp
    settings = SimSettings()
    _, closed = _closed(kinematics, settings)
    data = _settled_data(closed, settle(closed.scene, settings))
    model = closed.scene.model
    contacts = realised_contacts(model, data, closed.hand, closed.scene.object_geoms)
    com = np.zeros(3)
    along = np.array([[0, 1, 0, 0, 0, 0], [0, -1, 0, 0, 0, 0]], dtype=float)
    resisted = hand_resistance(model, data, closed.hand, contacts, com, 0.05, MU, 8, along, travel=travel)
    # Half-width travel / sqrt(3): the largest box of motions inside the failure sphere.
    expected = limit if travel is None else min(limit, kp * travel / np.sqrt(3.0))
    np.testing.assert_allclose(resisted, expected, rtol=0.02)


@pytest.mark.parametrize("torsion", [0.0, 0.01])
def test_soft_pads_resist_a_twist_about_their_line_as_two_gamma_f(torsion):
    """Two single-point pads resist a twist about the line between them only by torsional friction: 2 gamma F."""
    from ogcp.sim_eval.hand.predict import RealisedContacts, hand_resistance, realised_contacts
    from ogcp.sim_eval.hand.trial import _settled_data

    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    limit = kinematics.descriptor.actuation.force_range
    settings = SimSettings()
    _, closed = _closed(kinematics, settings)
    data = _settled_data(closed, settle(closed.scene, settings))
    model = closed.scene.model
    patch = realised_contacts(model, data, closed.hand, closed.scene.object_geoms)
    # One point per jaw, at its patch's centre: round pads, which no patch helps against a twist.
    pads = [patch.bodies == body for body in np.unique(patch.bodies)]
    point = RealisedContacts(
        np.array([patch.points[on].mean(axis=0) for on in pads]),
        np.array([patch.normals[on][0] for on in pads]),
        np.array([patch.bodies[on][0] for on in pads]),
        np.array([patch.geoms[on][0] for on in pads]),
        np.array([patch.forces[on].sum() for on in pads]),
    )
    line = point.points[1] - point.points[0]
    twist = np.concatenate([np.zeros(3), line / np.linalg.norm(line)])[None, :]
    rho = 0.05
    com = point.points.mean(axis=0)
    resisted = hand_resistance(model, data, closed.hand, point, com, rho, MU, 8, twist, torsion=torsion)
    # Each jaw presses at most its servo's limit F; each soft contact twists up to gamma F.
    np.testing.assert_allclose(resisted, 2.0 * torsion * limit / rho, rtol=1e-3, atol=1e-9)


@pytest.mark.parametrize("steady", [True, False])
def test_the_object_is_damped_while_the_hand_closes_and_free_after(steady, monkeypatch):
    from ogcp.sim_eval.hand import scene as hand_scene_module

    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    opened, _ = _closed(kinematics, SimSettings())
    model = opened.scene.model
    first = int(model.jnt_dofadr[model.body_jntadr[opened.scene.object_body]])
    seen = []
    real = hand_scene_module._close
    monkeypatch.setattr(
        hand_scene_module, "_close", lambda h, d: (seen.append(model.dof_damping[first : first + 6].copy()), real(h, d))
    )
    before = model.dof_damping.copy()
    closed = close_hand(opened, steady_object=steady)
    (during,) = seen
    mass = model.body_mass[opened.scene.object_body]
    assert during[:3] == pytest.approx([mass / hand_scene_module.CLOSING_DRAG_TIME] * 3 if steady else [0.0] * 3)
    assert np.array_equal(model.dof_damping, before)  # settling and the protocol see the free object
    assert closed.scene.start_qpos is not None


@pytest.mark.parametrize("travel", [None, 2e-4, 1e-3])
def test_a_tendon_servo_resists_within_the_travel_what_its_stiffness_builds(travel, tmp_path):
    """The Franka-style jaws pushed along y: the equality hands the far jaw's share to the near one, so the pinch
    holds the tendon's whole force, which grows by its stiffness s times the jaws' travel (h / sqrt(3)) up to its limit.
    """
    from ogcp.sim_eval.hand.predict import hand_resistance, realised_contacts
    from ogcp.sim_eval.hand.trial import _settled_data

    stiffness, limit = 400.0, 100.0  # [N/m], [N]: a soft servo; its command's range leaves it far from its limit
    servo = tendon_servo(stiffness, limit)
    kinematics = HandKinematics(
        load_descriptor(
            write_gripper_variant(tmp_path, lambda text: text.replace("</worldbody>", f"</worldbody>{servo}"))
        )
    )
    settings = SimSettings()
    _, closed = _closed(kinematics, settings)
    data = _settled_data(closed, settle(closed.scene, settings))
    model = closed.scene.model
    contacts = realised_contacts(model, data, closed.hand, closed.scene.object_geoms)
    along = np.array([[0, 1, 0, 0, 0, 0], [0, -1, 0, 0, 0, 0]], dtype=float)
    resisted = hand_resistance(model, data, closed.hand, contacts, np.zeros(3), 0.05, MU, 8, along, travel=travel)
    settled = float(data.actuator_force[0])
    assert 0 < settled < limit / 10
    expected = limit if travel is None else settled + stiffness * travel / np.sqrt(3.0)
    np.testing.assert_allclose(resisted, expected, rtol=0.02)


@pytest.mark.parametrize("take_up", [True, False])
def test_a_saturated_jaw_gives_no_slack_along_the_line_between_the_jaws(take_up):
    """Pushed along y, the trailing jaw unloads as soon as the object moves once its slack is taken up.

    The squeeze asks a jaw at its limit for twice that force: 1 mm of travel (F / kp) over which it
    follows the object at F. With a failure distance of 1.5 mm the pinch then resists only half of F
    along the line between the jaws; with the slack taken up after settling (1.1 F asked) it resists F.
    The loads run on the protocol's scene, the palm welded.
    """
    import dataclasses

    from ogcp.sim_eval.hand.lean import failure_reach, lean_scene
    from ogcp.sim_eval.hand.squeeze import SLACK_SHARE, take_up_slack
    from ogcp.sim_eval.hand.trial import _settled_data

    kinematics = HandKinematics(resolve_hand("parallel_gripper"))
    limit, kp = kinematics.descriptor.actuation.force_range, kinematics.descriptor.actuation.kp
    settings = SimSettings(move_threshold=1.5e-3)
    _, closed = _closed(kinematics, settings)
    settled = settle(closed.scene, settings)
    assert settled.gates["valid"]
    data = _settled_data(closed, settled)
    model = closed.scene.model
    scene = closed.scene
    if take_up:
        ctrl = take_up_slack(model, data, scene.preload_ctrl)
        asked = kp * (ctrl - data.actuator_length)
        np.testing.assert_allclose(asked, (1 + SLACK_SHARE) * limit, rtol=1e-9)
        unsaturated = take_up_slack(model, data, data.actuator_length + 0.5 * limit / kp)
        np.testing.assert_allclose(unsaturated, data.actuator_length + 0.5 * limit / kp)  # below the limit: kept
        closed = dataclasses.replace(closed, scene=dataclasses.replace(scene, preload_ctrl=ctrl))
    reach = failure_reach(settings.move_threshold, settings.rotation_threshold, float(np.linalg.norm(BOX.extents)))
    lean = lean_scene(closed, settled, reach, settings.creep_tolerance)
    assert lean.summary["lean"]
    directions = np.array([[0, 1, 0, 0, 0, 0], [0, -1, 0, 0, 0, 0]], dtype=float)
    rate = np.full(2, 2 * limit / settings.ramp_time)
    extent = settings.ramp_extent * settings.ramp_time
    trials = ramp_trials(lean.scene, lean.settled, directions, rate, extent, 1.0, settings)
    assert trials.failed.all() and not trials.diverged.any()
    if take_up:  # F, and a little more while the object, no longer held along y, gathers speed
        np.testing.assert_allclose(trials.failure_load, limit, rtol=0.1)
    else:
        assert (trials.failure_load < 0.7 * limit).all()
