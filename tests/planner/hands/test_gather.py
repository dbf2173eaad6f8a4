"""A hand whose palm and fingers sit on the world side by side, or on a common base beside the palm."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner.hands import HandKinematics, load_descriptor
from ogcp.planner.hands.gather import ROOT
from ogcp.planner.infra.errors import OgcpError

from .hand_files import LEFT_JAW, ON_A_BASE, SIDE_BY_SIDE, write_gripper_variant


def _side_by_side(text: str) -> str:
    return SIDE_BY_SIDE


def _hand(folder, edit) -> HandKinematics:
    folder.mkdir()
    return HandKinematics(load_descriptor(write_gripper_variant(folder, edit)))


def test_a_palm_and_fingers_on_the_world_side_by_side_are_one_hand(tmp_path):
    """Gathered below one body, poses unchanged: the same pads in the palm frame as the built-in gripper's."""
    builtin = _hand(tmp_path / "nested", lambda text: text)
    beside = _hand(tmp_path / "beside", _side_by_side)
    assert beside.model.body(beside.root).name == ROOT and beside.joint_names == builtin.joint_names
    for q in ([0.0, 0.0], [0.01, 0.035], [0.04, 0.02]):
        for got, want in zip(beside.pads(q), builtin.pads(q), strict=True):
            np.testing.assert_allclose(got, want, atol=1e-12)
    rotation, position = beside.palm_pose
    np.testing.assert_allclose(position, [0.1, 0.0, 0.2], atol=1e-12)
    np.testing.assert_allclose(rotation, np.eye(3), atol=1e-12)


def test_fingers_on_a_base_the_palm_is_fixed_to_need_no_gathering(tmp_path):
    """A URDF's usual tree: a base link, the palm fixed below it, the fingers beside the palm."""

    builtin = _hand(tmp_path / "nested", lambda text: text)
    based = _hand(tmp_path / "based", lambda text: ON_A_BASE)
    assert based.model.body(based.root).name == "base"
    for got, want in zip(based.pads([0.02, 0.01]), builtin.pads([0.02, 0.01]), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-12)


@pytest.mark.parametrize(
    "palm",
    ['<body name="palm" pos="0.1 0 0.2"><freejoint/>', '<body name="palm" pos="0.1 0 0.2"><joint type="slide"/>'],
    ids=["a floating palm", "a palm on a slide"],
)
def test_fingers_beside_a_palm_that_moves_are_not_its_fingers(tmp_path, palm):
    """They would not follow it: one line naming the finger."""
    with pytest.raises(
        OgcpError, match="tip_body 'left' is not below the palm 'palm', nor on a body the palm is fixed to"
    ):
        _hand(tmp_path / "moving", lambda text: _side_by_side(text).replace('<body name="palm" pos="0.1 0 0.2">', palm))


def test_a_finger_on_a_floating_body_stays_out(tmp_path):
    """MuJoCo allows free joints on the world's children only: such a body is not gathered."""
    floating = SIDE_BY_SIDE.replace(
        f'<body name="left" pos="0.1 0.045 0.21">{LEFT_JAW}</body>',
        f'<body name="float" pos="0.1 0.045 0.21"><freejoint/><geom size="0.01"/><body name="left">{LEFT_JAW}</body></body>',
    )
    assert floating != SIDE_BY_SIDE
    with pytest.raises(OgcpError, match="tip_body 'left' is not below the palm 'palm'"):
        _hand(tmp_path / "floating", lambda text: floating)
