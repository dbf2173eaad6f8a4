"""Any hand's kinematics from MuJoCo: the SDH against its old closed form, a user's MJCF and URDF, the checks."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
import trimesh

from ogcp.planner.hands import HandKinematics, load_descriptor, resolve_hand
from ogcp.planner.hands.kinematics import HandModelWarning
from ogcp.planner.hands.loading import one_object_obj
from ogcp.planner.infra import OgcpError

from .hand_files import (
    write_fourbar_gripper,
    write_gripper_variant,
    write_light_hand,
    write_mesh_hand,
    write_urdf_gripper,
)

# The SDH's fingertip points and pad normals from the closed-form numpy model ogcp had before
# MuJoCo became the one kinematic truth (its forward_kinematics), for configurations in its
# order (base, prox_1, dist_1, prox_2, dist_2, prox_3, dist_3) [rad]: the end of each distal link
# (MJCF site tip_k) and the distal link's +x, in the palm frame [m].
OLD_CONFIGURATIONS = [
    [0, 0, 0, 0, 0, 0, 0],
    [0.3, 0.2, 0.5, -0.4, 0.9, 0.7, -0.3],
    [1.5, 1.2, -1.1, 0.1, 0.2, -1.5, 1.5],
    [0.8, -0.6, 0.4, 0.6, -0.2, 0.3, 0.3],
]
OLD_TIPS = [
    [[0.01905, 0.033, 0.246], [0.01905, -0.033, 0.246], [-0.03811, 0.0, 0.246]],
    [
        [0.0054577386, -0.0267882394, 0.2281674488],
        [0.0192371091, -0.0338230364, 0.2307861815],
        [0.0442899864, 0.0, 0.2202515273],
    ],
    [
        [0.0915123313, -0.015974043, 0.1905017311],
        [0.0429766, -0.0168290831, 0.2425084098],
        [-0.1243933163, 0.0, 0.1656187679],
    ],
    [
        [0.0020040824, 0.0930790483, 0.2295260913],
        [0.0396623817, 0.0396492002, 0.2254842088],
        [0.0261305073, 0.0, 0.2301720959],
    ],
]
OLD_NORMALS = [
    [[-0.4999496325, -0.8660544815, 0.0], [-0.4999496325, 0.8660544815, 0.0], [1.0, 0.0, 0.0]],
    [
        [-0.1695529139, -0.7458118937, -0.6442176872],
        [-0.1945455978, 0.8557471375, -0.4794255386],
        [0.921060994, 0.0, -0.3894183423],
    ],
    [[0.8243808166, -0.5571620573, -0.0998334166], [0.791515355, 0.5349497643, -0.2955202067], [1.0, 0.0, 0.0]],
    [
        [0.2675103427, -0.9428513741, 0.1986693308],
        [0.2514046981, 0.8860863572, -0.3894183423],
        [0.8253356149, 0.0, -0.5646424734],
    ],
]


@pytest.fixture(scope="module")
def sdh():
    return HandKinematics(resolve_hand("sdh"))


def test_mujoco_forward_kinematics_equals_the_old_sdh_figures(tmp_path):
    # The tip sites of the old model: the descriptor's pad put at the end of each distal link.
    text = (
        resolve_hand("sdh").path.read_text().replace("tip_offset = [0.009, 0.0, 0.0595]", "tip_offset = [0, 0, 0.0685]")
    )
    (tmp_path / "old.toml").write_text(text.replace('mjcf = "sdh.xml"', f'mjcf = "{resolve_hand("sdh").model_path}"'))
    with pytest.warns(
        HandModelWarning, match=r"finger_1 \(9.00 mm inside distal_1; tip_offset = \[0.009, 0, 0.0685\] is on it\)"
    ):  # the end, not the pad
        kinematics = HandKinematics(load_descriptor(tmp_path / "old.toml"))
    assert kinematics.joint_names == ("base_1", "prox_1", "dist_1", "base_2", "prox_2", "dist_2", "prox_3", "dist_3")
    for old, tips, normals in zip(OLD_CONFIGURATIONS, OLD_TIPS, OLD_NORMALS, strict=True):
        base, *flexions = old
        angles = kinematics.complete([base, *flexions[:2], 0.0, *flexions[2:]])  # base_2 follows base_1
        assert angles[3] == base
        points, pads = kinematics.pads(angles)
        np.testing.assert_allclose(points, tips, atol=1e-9)
        np.testing.assert_allclose(pads, normals, atol=1e-9)


def test_the_sdh_is_closed_by_its_own_actuators_and_keeps_its_base_coupling(sdh):
    assert sdh.servos == ()  # its MJCF has a servo per motor
    assert sdh.model.nu == 7 and [sdh.joint_names[k] for k in sdh.independent] == [
        "base_1", "prox_1", "dist_1", "prox_2", "dist_2", "prox_3", "dist_3"
    ]  # fmt: skip
    samples = sdh.sample(200, seed=4)
    assert np.array_equal(samples[:, 0], samples[:, 3])
    assert ((samples >= sdh.limits[:, 0]) & (samples <= sdh.limits[:, 1])).all()
    assert np.array_equal(samples, sdh.sample(200, seed=4)) and not np.array_equal(samples, sdh.sample(200, seed=5))


def test_batched_pads_equal_one_by_one_and_are_in_the_palm_frame(sdh):
    q = sdh.sample(20, seed=1)
    points, normals = sdh.pads_many(q)
    for k in (0, 7, 19):
        one = sdh.pads(q[k])
        np.testing.assert_array_equal(points[k], one[0])
        np.testing.assert_array_equal(normals[k], one[1])
    np.testing.assert_allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-12)


def test_collisions_find_fingers_curled_into_each_other(sdh):
    straight = sdh.reference()
    curled = sdh.complete(np.array([0.0, 1.5, 1.5, 0.0, 1.5, 1.5, 1.5, 1.5]))
    hits = sdh.collisions(np.vstack([straight, curled]))
    assert not hits[0].any()
    assert hits[1, 0, 1] and hits[1, 1, 0] and hits[1, 0, 2]  # every finger pair meets at the centre


def test_a_users_mesh_hand_without_actuators_gets_servos_and_a_palm_off_the_origin(tmp_path):
    kinematics = HandKinematics(load_descriptor(write_mesh_hand(tmp_path)))
    assert kinematics.servos == ("f0_a", "f0_b", "f1_a", "f1_b", "f2_a", "f2_b")
    assert kinematics.model.nu == 6 and kinematics.model.actuator_forcerange[:, 1].tolist() == [1.5] * 6
    # The palm sits turned and shifted in the world; pads are reported in its own frame.
    points, normals = kinematics.pads(kinematics.reference())
    np.testing.assert_allclose(points[0], [0.035 - 0.008, 0.0, 0.08], atol=1e-6)
    np.testing.assert_allclose(normals[0], [-1.0, 0.0, 0.0], atol=1e-5)  # finger 0 turned by pi: faces the centre


def test_a_urdf_hand_compiles_with_mesh_paths_and_pads_on_fixed_links(tmp_path):
    kinematics = HandKinematics(load_descriptor(write_urdf_gripper(tmp_path)))
    assert kinematics.joint_names == ("left", "right") and kinematics.servos == ("left", "right")
    points, normals = kinematics.pads([0.03, 0.03])
    np.testing.assert_allclose(points, [[0.0, 0.011, 0.07], [0.0, -0.011, 0.07]], atol=1e-9)
    np.testing.assert_allclose(normals, [[0, -1, 0], [0, 1, 0]], atol=1e-12)


def _descriptor(tmp_path, model: str, **finger: str) -> object:
    (tmp_path / "m.xml").write_text(model)
    entry = {
        "name": '"f"',
        "tip_body": '"tip"',
        "tip_offset": "[0, 0, 0]",
        "pad_normal": "[1, 0, 0]",
        "tip_radius": "0.01",
    }
    entry.update(finger)
    lines = "\n".join(f"{k} = {v}" for k, v in entry.items())
    palm = finger.pop("palm", '"palm"') if "palm" in finger else '"palm"'
    text = f'schema = "ogcp.hand/1"\nname = "t"\nmjcf = "m.xml"\npalm = {palm}\n[[fingers]]\n{lines}\n'
    (tmp_path / "t.toml").write_text(text)
    return load_descriptor(tmp_path / "t.toml")


MODEL = """<mujoco><worldbody><body name="palm"><geom size="0.01"/>
  <body name="link"><joint name="hinge" axis="0 1 0" range="-1 1"/><geom size="0.01"/>
    <body name="tip" pos="0 0 0.05"><geom size="0.01"/></body></body>
  <body name="fixed" pos="0.05 0 0"><geom size="0.01"/></body>
  <body name="balled" pos="-0.05 0 0"><joint name="ball" type="ball"/><geom size="0.01"/></body>
</body><body name="elsewhere" pos="1 0 0"><freejoint/><geom size="0.01"/>
  <body name="beyond"><joint name="other" axis="0 0 1"/><geom size="0.01"/></body></body></worldbody></mujoco>"""


@pytest.mark.parametrize(
    "finger,message",
    [
        ({"tip_body": '"nail"'}, "fingers[0].tip_body = 'nail' is not a body of m.xml; its bodies are palm, link, tip"),
        ({"tip_body": '"elsewhere"'}, "tip_body 'elsewhere' is not below the palm 'palm'"),
        ({"tip_body": '"fixed"'}, "no joint moves 'fixed' relative to the palm 'palm'"),
        ({"joints": '["knuckle"]'}, "joint 'knuckle' is not a joint of m.xml"),
        ({"joints": '["other"]'}, "joint 'other' is not on the chain from the palm to 'tip'"),
        ({"tip_body": '"balled"'}, "joint 'ball' must be a hinge or a slide"),
    ],
)
def test_what_the_model_must_have_is_checked_in_one_line(tmp_path, finger, message):
    descriptor = _descriptor(tmp_path, MODEL, **finger)
    with pytest.raises(OgcpError) as info:
        HandKinematics(descriptor)
    assert message in str(info.value) and str(info.value).startswith(str(tmp_path / "t.toml"))


def test_an_unknown_palm_and_a_model_mujoco_refuses_are_one_line(tmp_path):
    descriptor = _descriptor(tmp_path, MODEL.replace('name="palm"', 'name="hand"'))
    with pytest.raises(OgcpError, match="palm = 'palm' is not a body of m.xml"):
        HandKinematics(descriptor)
    descriptor = _descriptor(tmp_path, MODEL.replace("<geom size", '<geom type="mesh" mesh="gone" size', 1))
    with pytest.raises(OgcpError, match="mjcf = m.xml: MuJoCo cannot compile it") as info:
        HandKinematics(descriptor)
    assert "\n" not in str(info.value)


def test_a_urdf_whose_mesh_is_missing_names_it(tmp_path):
    path = write_urdf_gripper(tmp_path)
    (tmp_path / "meshes" / "palm.stl").unlink()
    with pytest.raises(OgcpError, match="mesh file 'package://urdf_gripper/meshes/palm.stl' not found"):
        HandKinematics(load_descriptor(path))


def test_a_urdf_is_read_without_its_visuals_and_names_a_mesh_mujoco_cannot_read(tmp_path):
    """ROS packages often ship COLLADA visuals, or leave them out: ogcp simulates collision geometry only."""
    path = write_urdf_gripper(tmp_path)
    urdf = tmp_path / "urdf_gripper.urdf"
    collision = '<collision><geometry><mesh filename="package://urdf_gripper/meshes/palm.stl"/></geometry></collision>'
    visuals = (
        '<visual><geometry><mesh filename="package://urdf_gripper/meshes/palm.dae"/></geometry></visual>'
        '<visual><geometry><mesh filename="package://urdf_gripper/meshes/gone.dae"/></geometry></visual>'
    )
    (tmp_path / "meshes" / "palm.dae").write_text("<COLLADA/>")
    urdf.write_text(urdf.read_text().replace(collision, visuals + collision))
    kinematics = HandKinematics(load_descriptor(path))
    assert kinematics.model.nmesh == 1  # the collision mesh alone
    urdf.write_text(urdf.read_text().replace("meshes/palm.stl", "meshes/palm.dae"))
    with pytest.raises(OgcpError) as info:
        HandKinematics(load_descriptor(path))
    text = str(info.value)
    assert "palm.dae" in text and "MuJoCo reads STL, OBJ, MSH meshes" in text and "\n" not in text
    assert text.count("MuJoCo cannot compile it") == 1


def test_configurations_out_of_range_name_the_joint(sdh):
    with pytest.raises(OgcpError, match="joint prox_1 = 2 is outside its range"):
        sdh.check([0, 2, 0, 0, 0, 0, 0, 0])
    with pytest.raises(OgcpError, match="has 8 joints"):
        sdh.check([0.0] * 7)


def test_a_urdf_mujoco_cannot_compile_is_one_line_naming_the_file(tmp_path):
    path = write_urdf_gripper(tmp_path)
    urdf = tmp_path / "urdf_gripper.urdf"
    urdf.write_text(urdf.read_text().replace('<child link="left_pad"/>', '<child link="nowhere"/>'))
    with pytest.raises(OgcpError) as info:
        HandKinematics(load_descriptor(path))
    text = str(info.value)
    assert text.startswith(f"{path}: mjcf = urdf_gripper.urdf: MuJoCo cannot compile it") and "\n" not in text
    urdf.write_text("<robot name='x'><link name='palm'>")  # cut short
    with pytest.raises(OgcpError, match="urdf_gripper.urdf is not a readable URDF"):
        HandKinematics(load_descriptor(path))


def test_a_hand_whose_hinges_hardly_move_gets_a_warning_about_degrees(tmp_path, recwarn):
    from ogcp.planner.hands.kinematics import HandModelWarning

    descriptor = write_mesh_hand(tmp_path / "radians")
    HandKinematics(load_descriptor(descriptor))
    assert not [w for w in recwarn if issubclass(w.category, HandModelWarning)]
    model = tmp_path / "radians" / "claw.xml"
    # The same ranges read as degrees: the fingers move 1.7 degrees at most.
    model.write_text(model.read_text().replace('angle="radian" ', ""))
    with pytest.warns(HandModelWarning, match=r"moves more than 1\.7 degrees; MJCF reads angles in degrees unless"):
        HandKinematics(load_descriptor(descriptor))


def test_a_four_bar_loop_joins_its_finger_and_its_passive_joints_get_no_servo(tmp_path, recwarn):
    from ogcp.planner.hands.kinematics import HandModelWarning

    kinematics = HandKinematics(load_descriptor(write_fourbar_gripper(tmp_path)))
    assert [loop.name for loop in kinematics.loops] == ["l_follower-l_pad", "r_follower-r_pad"]
    names = [
        [kinematics.joint_names[list(kinematics.joint_ids).index(j)] for j in f.joints] for f in kinematics.fingers
    ]
    assert names == [["l_driver", "l_pad", "l_follower"], ["r_driver", "r_pad", "r_follower"]]
    # The drivers' servos move the jaws through the loops: none is added, none is idle, no warning.
    assert kinematics.servos == () and kinematics.idle_joints() == ()
    assert not [w for w in recwarn if issubclass(w.category, HandModelWarning)]
    # Sampled configurations have their loops closed: a parallelogram, the follower turned with the
    # driver and the jaw back by as much, so the sampled jaws stay upright.
    angles = dict(zip(kinematics.joint_names, kinematics.sample(300, seed=2).T, strict=True))
    for side in "lr":
        np.testing.assert_allclose(angles[f"{side}_follower"], angles[f"{side}_driver"], atol=1e-5)
        np.testing.assert_allclose(angles[f"{side}_pad"], -angles[f"{side}_driver"], atol=1e-5)
    assert np.ptp(angles["l_driver"]) > 1.0  # and spread over the driver's range


def test_a_loop_no_actuator_drives_gets_the_descriptors_servos(tmp_path):
    strut = '<body name="strut" pos="0 0.03 0.01"><joint name="strut" axis="1 0 0"/><geom size="0.003"/></body>'
    loop = '</worldbody><equality><connect body1="strut" body2="left" anchor="0 0 0"/></equality>'
    descriptor = write_gripper_variant(
        tmp_path,
        lambda text: text.replace('<body name="left"', strut + '<body name="left"').replace("</worldbody>", loop),
    )
    kinematics = HandKinematics(load_descriptor(descriptor))
    assert [loop.name for loop in kinematics.loops] == ["strut-left"]
    assert "strut" in kinematics.joint_names and set(kinematics.servos) == {"left", "right", "strut"}


def test_a_finger_whose_joints_share_one_servo_gets_a_one_line_warning(tmp_path, recwarn):
    from ogcp.planner.hands.kinematics import HandModelWarning

    path = write_light_hand(tmp_path / "light", tendons=True)  # a tendon servo per distal joint: fully actuated
    HandKinematics(load_descriptor(path))
    assert not [w for w in recwarn if issubclass(w.category, HandModelWarning)]
    model = path.parent / "light.xml"
    shared = "".join(
        f'<fixed name="t{k}"><joint joint="f{k}_a" coef="1"/><joint joint="f{k}_b" coef="1"/></fixed>' for k in range(3)
    )
    servos = "".join(f'<position tendon="t{k}" ctrlrange="-0.3 2.8"/>' for k in range(3))
    text = re.sub(
        r"<tendon>.*</actuator>",
        f"<tendon>{shared}</tendon><actuator>{servos}</actuator>",
        model.read_text(),
        flags=re.DOTALL,
    )
    model.write_text(text)
    with pytest.warns(
        HandModelWarning, match=r"f0 \(2 joints, f0_a, f0_b; 2 directions of motion, 1 servo direction\)"
    ):
        HandKinematics(load_descriptor(path))


@pytest.mark.parametrize(
    ("offset", "said"),
    [
        (
            "[0.0, -0.0025, 0.06]",
            r"left \(1.50 mm inside left; tip_offset = \[0, -0.004, 0.06\] is on it\)",
        ),  # 1.5 mm into the jaw, as the Franka hand's pad box is behind its bumps
        ("[0.0, -0.005, 0.06]", r"left \(1.00 mm off left's surface; tip_offset = \[0, -0.004, 0.06\] is on it\)"),
        ("[0.0, -0.004, 0.5]", r"left \(no geometry of left under it\)"),
    ],
)
def test_a_pad_point_off_its_tips_surface_is_named(tmp_path, offset, said, recwarn):
    path = write_gripper_variant(
        tmp_path,
        lambda text: text,
        lambda text: text.replace("tip_offset = [0.0, -0.004, 0.06]", f"tip_offset = {offset}"),
    )
    with pytest.warns(HandModelWarning, match=said):
        HandKinematics(load_descriptor(path))


def test_pads_on_their_surfaces_load_without_a_word(recwarn):
    for hand in ("sdh", "shadow_hand", "parallel_gripper"):
        try:
            descriptor = resolve_hand(hand)
        except OgcpError:  # the Shadow hand, where it was not fetched
            continue
        HandKinematics(descriptor)
    assert not [w for w in recwarn if "pad points" in str(w.message)]


def _two_object_obj(path) -> int:
    """Two boxes in one OBJ file, each its own object (as Blender and CoACD write them); the face count."""
    lines = []
    for k, (extents, centre) in enumerate((((0.02, 0.11, 0.01), (0, 0, 0)), ((0.02, 0.02, 0.01), (0, 0, -0.01)))):
        box = trimesh.creation.box(extents=extents)
        box.apply_translation(centre)
        lines.append(f"o part{k}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in box.vertices]
        base = 8 * k + 1
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in box.faces]
    path.write_text("\n".join(lines) + "\n")
    return 24


def test_an_obj_mesh_of_several_objects_reaches_mujoco_whole(tmp_path):
    """MuJoCo reads the first object's faces only; the loader gives it every face, MJCF and URDF alike."""
    (tmp_path / "meshes").mkdir()
    faces = _two_object_obj(tmp_path / "meshes" / "palm.obj")
    assert one_object_obj(b"o a\nv 0 0 0\nf 1 1 1\n") is None  # one object: left as it is
    assert one_object_obj((tmp_path / "meshes" / "palm.obj").read_bytes()).count(b"\nf ") == faces
    mjcf = write_gripper_variant(
        tmp_path,
        lambda text: text.replace(
            '<geom name="palm" type="box" size="0.02 0.055 0.01"',
            '<geom name="palm" type="mesh" mesh="palm"',
        ).replace(
            "<worldbody>", '<compiler meshdir="meshes"/><asset><mesh name="palm" file="palm.obj"/></asset><worldbody>'
        ),
    )
    kinematics = HandKinematics(load_descriptor(mjcf))
    assert kinematics.model.mesh_facenum.tolist() == [faces]
    urdf = write_urdf_gripper(tmp_path / "urdf")
    (tmp_path / "urdf" / "meshes" / "palm.stl").unlink()
    _two_object_obj(tmp_path / "urdf" / "meshes" / "palm.obj")
    text = (tmp_path / "urdf" / "urdf_gripper.urdf").read_text()
    (tmp_path / "urdf" / "urdf_gripper.urdf").write_text(text.replace("meshes/palm.stl", "meshes/palm.obj"))
    assert HandKinematics(load_descriptor(urdf)).model.mesh_facenum.tolist() == [faces]


def test_a_urdf_link_whose_inertia_breaks_the_triangle_inequality_is_balanced_with_a_warning(tmp_path):
    """CAD exports often do (dex-urdf's Schunk SVH): MuJoCo refuses them unless told to balance."""
    from ogcp.planner.hands.loading import HandLoadWarning
    from ogcp.sim_eval.hand.fit_scene import FitScene

    path = write_urdf_gripper(tmp_path)
    urdf = tmp_path / "urdf_gripper.urdf"
    unbalanced = '<inertia ixx="1e-6" iyy="1e-6" izz="5e-6" ixy="0" ixz="0" iyz="0"/>'
    text = urdf.read_text()
    first = text.index('<link name="left">')
    start = text.index("<inertia ", first)
    end = text.index("/>", start) + 2
    urdf.write_text(text[:start] + unbalanced + text[end:])
    with pytest.warns(HandLoadWarning, match=r"the inertia of left breaks the triangle inequality") as caught:
        kinematics = HandKinematics(load_descriptor(path))
    assert all("\n" not in str(w.message) for w in caught)
    left = kinematics.model.body("left").id
    np.testing.assert_allclose(kinematics.model.body_inertia[left], [7e-6 / 3] * 3, rtol=1e-9)  # their mean
    assert kinematics.model.body_inertia[kinematics.model.body("right").id] == pytest.approx([1e-6] * 3)
    FitScene(kinematics)  # a scene the hand is copied into compiles too
    # The file's own MuJoCo compiler settings are kept (its folders aside: the meshes come in memory).
    own = '<mujoco><compiler balanceinertia="true" meshdir="nowhere/"/></mujoco></robot>'
    urdf.write_text(urdf.read_text().replace("</robot>", own))
    with warnings.catch_warnings():
        warnings.simplefilter("error", HandLoadWarning)
        balanced = HandKinematics(load_descriptor(path))
    np.testing.assert_allclose(balanced.model.body_inertia[left], [7e-6 / 3] * 3, rtol=1e-9)
    FitScene(balanced)


COUPLED = """<mujoco><compiler angle="radian"/><worldbody><body name="palm"><geom size="0.01"/>
  <body name="link"><joint name="driver" axis="0 1 0" range="0 1.5"/><geom size="0.01"/>
    <body name="distal" pos="0 0 0.05"><joint name="follower" axis="0 1 0" range="RANGE"/><geom size="0.01"/>
      <body name="tip" pos="0 0 0.03"><geom size="0.01"/></body></body></body>
</body></worldbody>
<equality><joint joint1="follower" joint2="driver" polycoef="0 1.2 0 0 0"/></equality></mujoco>"""


def test_a_coupled_joints_driver_is_narrowed_to_keep_the_coupled_joint_in_its_range(tmp_path):
    """A mimic joint whose range is narrower than its driver's times the ratio (the Schunk SVH's distal
    joints, 1.045 x the driver with the same range): samples and fits stay where MuJoCo's limits allow."""
    kinematics = HandKinematics(_descriptor(tmp_path, COUPLED.replace("RANGE", "0 1.2"), tip_offset="[0.01, 0, 0]"))
    driver, follower = kinematics.joint_names.index("driver"), kinematics.joint_names.index("follower")
    assert kinematics.limits[driver] == pytest.approx([0.0, 1.0], abs=1e-8)  # bisected to the limit
    assert 1.2 * kinematics.limits[driver][1] <= 1.2 + 1e-9  # on the allowed side of the boundary
    samples = kinematics.sample(500, 0)
    assert samples[:, follower] == pytest.approx(1.2 * samples[:, driver])
    for q in samples:
        kinematics.check(q)
    assert samples[:, driver].max() > 0.95
    with pytest.raises(OgcpError, match="joint 'follower' follows 'driver' outside its range") as info:
        HandKinematics(_descriptor(tmp_path, COUPLED.replace("RANGE", "2 3"), tip_offset="[0.01, 0, 0]"))
    assert "\n" not in str(info.value)
