"""A hand's own links: overlaps the model was built with are not collisions; real ones still are."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner.hands import HandKinematics, load_descriptor
from ogcp.planner.hands.kinematics import HandModelWarning
from ogcp.planner.infra import OgcpError

#: Two three-link fingers. Each base link carries a bracket that the tip link, two joints further
#: on, swings into once the middle joint bends past about 0.1 rad: the way a convex hull of a
#: bracket mesh swallows the next links over most of their range. Straight (the reference), the
#: tip clears the bracket by 3 mm.
HULL_HAND = """<mujoco model="hulls">
  <compiler angle="radian"/>
  <worldbody>
    <body name="palm">
      <geom type="box" size="0.08 0.03 0.005"/>
      {fingers}
    </body>
  </worldbody>
</mujoco>
"""
FINGER = """<body name="f{k}_base" pos="{x} 0 0.01" euler="0 0 {yaw}">
        <joint name="f{k}_a" axis="1 0 0" range="-0.5 0.5"/>
        <geom type="capsule" size="0.005" fromto="0 0 0.006 0 0 0.034"/>
        <geom name="f{k}_bracket" type="box" size="0.016 0.01 0.03" pos="0.024 0 0.075"/>
        <body name="f{k}_mid" pos="0 0 0.04">
          <joint name="f{k}_b" axis="0 1 0" range="0 1.2"/>
          <geom type="capsule" size="0.005" fromto="0 0 0.006 0 0 0.024"/>
          <body name="f{k}_tip" pos="0 0 0.03">
            <joint name="f{k}_c" axis="0 1 0" range="0 1.2"/>
            <geom type="capsule" size="0.005" fromto="0 0 0 0 0 0.02"/>
          </body>
        </body>
      </body>"""
DESCRIPTOR = """schema = "ogcp.hand/1"
name = "hulls"
mjcf = "hulls.xml"
palm = "palm"
{extra}
[[fingers]]
name = "f0"
tip_body = "f0_tip"
tip_offset = [0.005, 0.0, 0.02]
pad_normal = [1.0, 0.0, 0.0]
tip_radius = 0.005

[[fingers]]
name = "f1"
tip_body = "f1_tip"
tip_offset = [0.005, 0.0, 0.02]
pad_normal = [1.0, 0.0, 0.0]
tip_radius = 0.005
"""


def write_hull_hand(folder, extra: str = ""):
    folder.mkdir(parents=True, exist_ok=True)
    fingers = "\n      ".join(
        FINGER.format(k=k, x=x, yaw=yaw) for k, (x, yaw) in enumerate(((-0.06, 0.0), (0.06, 3.14159)))
    )
    (folder / "hulls.xml").write_text(HULL_HAND.format(fingers=fingers))
    path = folder / "hulls.toml"
    path.write_text(DESCRIPTOR.format(extra=extra))
    return path


def _bent(kinematics: HandKinematics, bend: float) -> np.ndarray:
    """Both fingers' middle joints at ``bend`` [rad], everything else straight."""
    q = kinematics.reference()
    for k in range(2):
        q[kinematics.joint_names.index(f"f{k}_b")] = bend
    return q


def test_links_of_one_chain_that_overlap_in_most_poses_are_not_collisions(tmp_path):
    with pytest.warns(
        HandModelWarning, match=r"f0_base and f0_tip \(\d+%\), f1_base and f1_tip \(\d+%\); their contacts are ignored"
    ):
        kinematics = HandKinematics(load_descriptor(write_hull_hand(tmp_path)))
    bent = _bent(kinematics, 0.8)
    assert not kinematics.collisions(bent).any()
    assert {name for pair in kinematics.designed_pairs() for name in pair} >= {"f0_bracket", "f1_bracket"}
    assert len(kinematics.overlaps.on_chain) == 2 and min(kinematics.overlaps.on_chain.values()) > 0.9
    assert "ignored_collisions" in kinematics.describe()


def test_the_same_overlap_is_a_collision_when_the_share_rule_is_off(tmp_path, monkeypatch, recwarn):
    from ogcp.planner.hands import self_collision

    monkeypatch.setattr(self_collision, "OVERLAP_SHARE", 1.0)
    kinematics = HandKinematics(load_descriptor(write_hull_hand(tmp_path)))
    assert not [w for w in recwarn if issubclass(w.category, HandModelWarning)]
    hits = kinematics.collisions(np.vstack([_bent(kinematics, 0.0), _bent(kinematics, 0.8)]))
    assert not hits[0].any()  # straight: the tip clears the bracket
    assert hits[1, 0, 0] and hits[1, 1, 1]  # bent: each finger's tip inside its own bracket


def test_body_pairs_a_descriptor_lists_are_never_collisions(tmp_path, monkeypatch):
    from ogcp.planner.hands import self_collision

    monkeypatch.setattr(self_collision, "OVERLAP_SHARE", 1.0)
    extra = 'ignore_collisions = [["f0_base", "f0_tip"]]'
    kinematics = HandKinematics(load_descriptor(write_hull_hand(tmp_path, extra)))
    hits = kinematics.collisions(_bent(kinematics, 0.8))
    assert not hits[0, 0, 0] and hits[0, 1, 1]  # the listed finger only


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ('"f0_base"', r"ignore_collisions must be a list of \[body, body\] name pairs, got 'f0_base'"),
        ('[["f0_base"]]', r"ignore_collisions must be a list of \[body, body\] name pairs"),
        ('[["f0_base", 3]]', r"ignore_collisions must be a list of \[body, body\] name pairs"),
        ('[["palm", "palm"]]', r"ignore_collisions: \['palm', 'palm'\] pairs a body with itself"),
    ],
)
def test_a_malformed_ignore_list_is_one_line_naming_the_field(tmp_path, value, message):
    path = write_hull_hand(tmp_path, f"ignore_collisions = {value}")
    with pytest.raises(OgcpError, match=message) as info:
        load_descriptor(path)
    assert "\n" not in str(info.value)


def test_an_unknown_body_in_the_ignore_list_names_the_models_bodies(tmp_path):
    path = write_hull_hand(tmp_path, 'ignore_collisions = [["f0_base", "thumb"]]')
    with pytest.raises(
        OgcpError, match=r"ignore_collisions = 'thumb' is not a body of hulls.xml; its bodies are palm, f0_base"
    ):
        HandKinematics(load_descriptor(path))


def test_a_geom_outside_the_hand_is_no_part_of_it(tmp_path):
    """Geoms outside the hand's subtree (a table in the file the descriptor names) collide with nothing:
    finger 0's tip, bent 0.8 rad, passes through a small box on the world body."""
    path = write_hull_hand(tmp_path)
    model = tmp_path / "hulls.xml"
    table = '<geom name="table" type="box" size="0.004 0.004 0.004" pos="-0.03 0 0.08"/>'
    model.write_text(model.read_text().replace("<worldbody>", "<worldbody>" + table))
    with pytest.warns(HandModelWarning):  # the hull pairs, as without the box
        kinematics = HandKinematics(load_descriptor(path))
    assert not kinematics.collisions(_bent(kinematics, 0.8))[0, :, -1].any()  # nothing hits the palm group
