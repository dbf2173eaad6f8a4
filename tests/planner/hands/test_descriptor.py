"""The ogcp.hand/1 descriptor: every field checked, one line per fault naming the file and the field."""

from __future__ import annotations

import pytest

from ogcp.planner.hands import load_descriptor, resolve_hand
from ogcp.planner.hands.registry import BUILTIN_HANDS, is_descriptor_path
from ogcp.planner.infra import OgcpError

GOOD = """schema = "ogcp.hand/1"
name = "g"
mjcf = "g.xml"
palm = "palm"
[[fingers]]
name = "left"
tip_body = "left"
tip_offset = [0.0, -0.004, 0.06]
pad_normal = [0.0, -1.0, 0.0]
tip_radius = 0.004
[[fingers]]
name = "right"
tip_body = "right"
tip_offset = [0.0, 0.004, 0.06]
pad_normal = [0.0, 1.0, 0.0]
tip_radius = 0.004
[actuation]
kp = 100.0
force_range = 10.0
"""


def _write(tmp_path, text, model="g.xml"):
    (tmp_path / model).write_text("<mujoco/>")
    path = tmp_path / "hand.toml"
    path.write_text(text)
    return path


def test_a_good_descriptor_reads_with_its_paths_resolved_and_digests(tmp_path):
    hand = load_descriptor(_write(tmp_path, GOOD))
    assert hand.name == "g" and hand.model_path == (tmp_path / "g.xml").resolve()
    assert hand.finger_names == ("left", "right") and hand.actuation.kp == 100.0
    assert len(hand.sha256) == 64 and len(hand.model_sha256) == 64
    assert hand.choose_fingers(2) == (0, 1) and hand.choose_fingers(2, ["right", "left"]) == (1, 0)
    assert hand.choose_fingers(1, ["right"]) == (1,)


@pytest.mark.parametrize(
    "edit,message",
    [
        (lambda t: t.replace('"ogcp.hand/1"', '"ogcp.hand/2"'), "schema must be 'ogcp.hand/1', got 'ogcp.hand/2'"),
        (lambda t: "colour = 1\n" + t, "unknown key 'colour'; valid keys are schema, name, mjcf"),
        (lambda t: t.replace('name = "g"\n', ""), "name must be a non-empty string, got None"),
        (lambda t: t.replace('"g.xml"', '"missing.xml"'), "mjcf = 'missing.xml': no such file"),
        (lambda t: t.replace('"g.xml"', '"g.obj"'), "must be an MJCF (.xml) or URDF (.urdf) file"),
        (
            lambda t: t.replace('"g.xml"', '"g.urdf.xacro"'),
            "URDF (.urdf) file (expand it first: xacro g.urdf.xacro > g.urdf)",
        ),
        (
            lambda t: t.replace("[0.0, -1.0, 0.0]", "[0.0, -0.5, 0.0]"),
            "fingers[0]: pad_normal [0.0, -0.5, 0.0] is not a unit",
        ),
        (lambda t: t.replace("[0.0, -0.004, 0.06]", "[0.0, 0.06]"), "fingers[0]: tip_offset must be 3 finite numbers"),
        (
            lambda t: t.replace("[0.0, -0.004, 0.06]", "[0.0, nan, 0.06]"),
            "fingers[0]: tip_offset must be 3 finite numbers",
        ),
        (lambda t: t.replace("[0.0, -0.004, 0.06]", "[0.0, -4.0, 60.0]"), "is more than 2 m from tip_body (units?)"),
        (
            lambda t: t.replace("tip_radius = 0.004\n[[", "tip_radius = 0\n[["),
            "fingers[0]: tip_radius = 0 is outside (0, 0.5]",
        ),
        (
            lambda t: t.replace("tip_radius = 0.004\n[[", "tip_radius = 0.004\npad_width = -0.02\n[["),
            "fingers[0]: pad_width = -0.02 is outside (0, 0.5]",
        ),
        (
            lambda t: t.replace("tip_radius = 0.004\n[[", 'tip_radius = 0.004\npad_width = "wide"\n[['),
            "fingers[0]: pad_width must be a finite number, got 'wide'",
        ),
        (
            lambda t: t.replace('tip_body = "right"', 'tip_body = "left"'),
            "fingers[0] and fingers[1] have the same tip body 'left'",
        ),
        (lambda t: t.replace('name = "right"', 'name = "left"'), "fingers[0] and fingers[1] have the same name 'left'"),
        (lambda t: t.replace('name = "left"\n', 'name = "left"\nnails = 1\n'), "fingers[0]: unknown key 'nails'"),
        (lambda t: t.replace('name = "left"\n', 'name = "left"\njoints = []\n'), "joints must be a non-empty list"),
        (lambda t: t.replace('name = "left"\n', 'name = "left"\njoints = ["a", "a"]\n'), "name a joint twice"),
        (lambda t: t.replace("kp = 100.0", "kp = -1.0"), "[actuation]: kp = -1.0 is outside (0, 1e+06]"),
        (lambda t: t.replace("kp = 100.0", "stiffness = 1.0"), "[actuation]: unknown key 'stiffness'"),
        (
            lambda t: t + "[reachability]\nsamples = 50.5\n",
            "[reachability]: samples must be an integer in [1000, 2000000]",
        ),
        (
            lambda t: t + "[reachability]\nsamples = 999\n",
            "[reachability]: samples must be an integer in [1000, 2000000]",
        ),
        (lambda t: t + "[reachability]\nseed = 1\n", "[reachability]: unknown key 'seed'; valid keys are samples"),
        (lambda t: "reachability = 3\n" + t, "[reachability] must be a table, got 3"),
        (lambda t: t.split("[[fingers]]")[0], "[[fingers]] must list at least one finger"),
        (lambda t: t + "[[", "not a TOML hand descriptor"),
    ],
)
def test_every_fault_is_one_line_naming_the_file_and_the_field(tmp_path, edit, message):
    path = _write(tmp_path, edit(GOOD))
    with pytest.raises(OgcpError) as info:
        load_descriptor(path)
    text = str(info.value)
    assert message in text and text.startswith(str(path)) and "\n" not in text


def test_a_hand_asks_for_its_reachability_samples(tmp_path):
    import shutil

    from ogcp.planner.hands import HandReachability

    assert load_descriptor(_write(tmp_path, GOOD)).reach_samples is None  # grown until it recalls the hand
    gripper = resolve_hand("parallel_gripper")
    shutil.copy(gripper.model_path, tmp_path / gripper.model_path.name)
    path = tmp_path / "gripper.toml"
    path.write_text(gripper.path.read_text() + "\n[reachability]\nsamples = 1500\n")
    hand = load_descriptor(path)
    assert hand.reach_samples == 1500
    model = HandReachability(hand, cache_dir=tmp_path / "cache")
    assert model.samples == 1500 and len(model.sampled.angles) == 1500
    assert HandReachability(hand, samples=1200, cache_dir=tmp_path / "cache").samples == 1200


def test_a_missing_or_binary_descriptor_is_one_line(tmp_path):
    with pytest.raises(OgcpError, match="cannot read the hand descriptor"):
        load_descriptor(tmp_path / "none.toml")
    (tmp_path / "bin.toml").write_bytes(b"\x96\xff\x00")
    with pytest.raises(OgcpError, match="not a TOML hand descriptor"):
        load_descriptor(tmp_path / "bin.toml")


def test_m_and_named_fingers_are_checked_against_the_hand(tmp_path):
    hand = load_descriptor(_write(tmp_path, GOOD))
    with pytest.raises(OgcpError, match="the g hand has 2 fingers; a grasp of m = 3 contacts cannot use them"):
        hand.choose_fingers(3)
    with pytest.raises(OgcpError, match="has no finger 'thumb'; its fingers are left, right"):
        hand.choose_fingers(1, ["thumb"])
    with pytest.raises(OgcpError, match="1 hand fingers named \\(left\\) for a grasp of m = 2"):
        hand.choose_fingers(2, ["left"])


def test_built_in_names_and_paths_resolve(tmp_path):
    assert {resolve_hand(name).name for name in BUILTIN_HANDS} == set(BUILTIN_HANDS)
    assert resolve_hand(_write(tmp_path, GOOD)).name == "g"
    assert resolve_hand("hand.toml", relative_to=tmp_path).name == "g"
    assert is_descriptor_path("hands/x.toml") and not is_descriptor_path("sdh")
    with pytest.raises(OgcpError, match="unknown hand 'shadow'; built-in hands are parallel_gripper, sdh"):
        resolve_hand("shadow")
