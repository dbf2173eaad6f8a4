"""The pads' gate measures how far a pad's contact patch lies from its contact, not where its force happens to sit."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ogcp.sim_eval.hand.pads import distance_to_hull, pad_off_contact, surface_gap

SQUARE = np.array([[0.0, 0.0, 0.0], [0.02, 0.0, 0.0], [0.02, 0.07, 0.0], [0.0, 0.07, 0.0]])


@pytest.mark.parametrize(
    ("target", "expected"),
    [
        ([0.01, 0.03, 0.0], 0.0),  # inside the patch
        ([0.01, 0.03, 0.004], 0.004),  # above it, along its normal
        ([0.03, 0.03, 0.0], 0.01),  # beside an edge
        ([0.023, 0.074, 0.0], 0.005),  # beyond a corner (3-4-5)
    ],
)
def test_the_distance_to_a_flat_patch(target, expected):
    assert distance_to_hull(SQUARE, np.array(target)) == pytest.approx(expected, abs=1e-6)


def test_a_patch_of_two_corners_is_their_segment_and_one_point_is_itself():
    edge = np.array([[0.0148, 0.0226, 0.0], [0.0459, 0.0102, 0.0]])
    middle = edge.mean(axis=0) + np.array([0.0, 0.0, 0.003])
    assert distance_to_hull(edge, middle) == pytest.approx(0.003, abs=1e-7)
    along = (edge[1] - edge[0]) / np.linalg.norm(edge[1] - edge[0])
    assert distance_to_hull(edge, edge[0] - 0.004 * along) == pytest.approx(0.004, abs=1e-7)  # past its end
    point = np.array([[0.01, 0.02, 0.03]])
    assert distance_to_hull(point, np.array([0.01, 0.02, 0.035])) == pytest.approx(0.005, abs=1e-7)


def test_a_pad_that_settled_off_its_contact_is_a_reason_in_one_line():
    off = pad_off_contact(1, 0.0174, 0.012)
    assert off.to_dict()["gate"] == "pad" and off.finger == 1 and off.unit == "m"
    assert off.message.startswith("finger 1's pad settled 17.40 mm from its contact (limit 12.00 mm): the hand settled")
    nothing = pad_off_contact(0, float("inf"), 0.012)
    assert np.isnan(nothing.value) and nothing.message.startswith("finger 0's pad presses nothing (limit 12.00 mm)")
    assert "\n" not in off.message + nothing.message


def test_a_flat_pads_surface_gap_is_measured_along_its_normal():
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body pos="0 0 0.1" euler="0 0 0.3"><geom name="jaw" type="box" size="0.01 0.004 0.025"/>'
        "</body></worldbody></mujoco>"
    )
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    jaw = np.array([0], dtype=np.intp)
    face = data.geom_xpos[0] + data.geom_xmat[0].reshape(3, 3) @ [0.0, -0.004, 0.02]  # on the face, near its end
    out = data.geom_xmat[0].reshape(3, 3) @ [0.0, -1.0, 0.0]  # the face's outward normal: the pad's normal
    assert surface_gap(model, data, jaw, face, out) == pytest.approx(0.0, abs=1e-9)
    assert surface_gap(model, data, jaw, face + 0.0006 * out, out) == pytest.approx(0.0006, abs=1e-9)  # hovering
    assert surface_gap(model, data, jaw, face - 0.0004 * out, out) == pytest.approx(0.0004, abs=1e-9)  # sunk in
    beside = face + data.geom_xmat[0].reshape(3, 3) @ [0.0, 0.0, 0.01]  # past the jaw's end
    assert surface_gap(model, data, jaw, beside, out) == np.inf
