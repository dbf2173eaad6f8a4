"""Arrays that grow in place: the open list and the state rows of a search at m >= 5.

``np.concatenate`` (or a new array and a copy) holds the old rows and the new array at once,
three to four times the rows in use at the moment of growth, and at m >= 5 that moment is the
peak (gigabytes of rows). :func:`grow_rows` resizes in place instead: ``realloc``, which for
arrays this large moves pages (``mremap``) rather than copying them.
"""

from __future__ import annotations

import numpy as np

#: Factor by which an array's rows grow: each growth zero-fills the new rows, which then count
#: in the resident memory, so less room sits unused than with doubling.
GROWTH = 1.5


def grow_rows(array: np.ndarray, rows: int) -> None:
    """Resize ``array`` in place to at least ``rows`` rows (and at least :data:`GROWTH` times
    its rows); the rows it held keep their values, the new ones are zeros.

    Args:
        array: An array that owns its contiguous data, and of which no view is alive: a view
            would go on reading the memory it had before.
        rows: Rows needed.
    """
    size = max(rows, int(len(array) * GROWTH) + 1)
    array.resize((size, *array.shape[1:]), refcheck=False)
