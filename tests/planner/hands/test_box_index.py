"""The leaf index answers "is any point within r of a box?" exactly as comparing every point does."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner.hands.box_index import LEAF_SIZE, BoxIndex


def _brute(points, low, high, radius):
    gap = np.maximum(low[:, None, :] - points[None], 0.0) + np.maximum(points[None] - high[:, None, :], 0.0)
    return bool((np.einsum("bnd,bnd->bn", gap, gap) <= radius**2).any())


@pytest.mark.parametrize("count", [1, LEAF_SIZE, 5 * LEAF_SIZE + 7, 3000])
def test_the_answer_is_the_brute_force_one(count):
    rng = np.random.default_rng(count)
    points = rng.normal(size=(count, 12))
    index = BoxIndex(points)
    answers = []
    for _ in range(400):
        centre = rng.normal(scale=1.5, size=(6, 12))
        half = rng.uniform(0.0, 1.0, size=(6, 12)) * rng.choice([0.05, 0.5, 2.0])
        radius = float(rng.choice([0.0, 0.3, 1.5]))
        expected = _brute(points, centre - half, centre + half, radius)
        assert index.any_within(centre - half, centre + half, radius) == expected
        answers.append(expected)
    assert 0 < sum(answers) < len(answers)  # both answers were exercised


def test_a_box_around_a_point_admits_it_at_radius_zero():
    points = np.random.default_rng(0).uniform(size=(500, 4))
    index = BoxIndex(points)
    assert index.any_within(points[123:124], points[123:124], 0.0)
    assert not index.any_within(np.full((1, 4), 5.0), np.full((1, 4), 6.0), 1.0)
