"""The pads' gate measures how far a pad's contact patch lies from its contact, not where its force happens to sit."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.sim_eval.hand.pads import distance_to_hull

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
