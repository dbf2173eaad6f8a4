"""Arrays that grow in place (ogcp.planner.infra.arrays)."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner.infra.arrays import GROWTH, grow_rows


@pytest.mark.parametrize(("dtype", "width"), [(np.float64, 3), (np.int64, 3), (np.int32, 6)])
def test_grown_rows_keep_their_values_and_new_rows_are_zero(dtype, width):
    rng = np.random.default_rng(0)
    array = np.empty((0, width), dtype=dtype)
    expected = np.empty((0, width), dtype=dtype)
    for _ in range(40):  # from empty through many growths
        rows = (rng.integers(-1000, 1000, size=(7, width))).astype(dtype)
        used = len(expected)
        if used + len(rows) > len(array):
            before = len(array)
            grow_rows(array, used + len(rows))
            assert len(array) >= max(used + len(rows), int(before * GROWTH))
            assert not array[used:].any()  # new rows are zeros, old ones unchanged below
        array[used : used + len(rows)] = rows
        expected = np.concatenate([expected, rows])
        assert np.array_equal(array[: len(expected)], expected)
    assert array.dtype == dtype and array.shape[1] == width
