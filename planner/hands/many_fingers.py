"""Grasps of more than three of a hand's fingers: every three of the fingers accept their contacts.

The code of m pads (:func:`~ogcp.planner.hands.sampled_model.pair_code`) has 4 C(m, 2) dimensions,
24 for m = 4, where uniform samples of the hand seldom come near a pose it takes: the Shadow hand's
10,000 samples recall none of its own 4-finger poses (the nearest sample lies a median 2.2
normalised units away, the threshold is 1), against 49 % of its 3-finger ones. Three fingers' codes
have 12 dimensions, and every three of the m fingers is a 3-finger hand of its own. So an m-grasp
(m > 3) is accepted when, under one assignment of its contacts to the chosen fingers, the model of
each three of those fingers accepts their three contacts within :data:`TRIPLE_SLACK` times the
threshold; its residual is the least, over assignments, of the largest of those residuals divided
by :data:`TRIPLE_SLACK`. Measured on the Shadow hand's own poses of thumb, index, middle and ring
(507 held out): each three recalled 46-73 % at the threshold; all four threes 14 % at it, 63 % at
1.25 times it and 90 % at 1.5. At 1.25 the test accepts 4.2 % of the random 4-grasps of a 12 cm box
(183,820 drawn), and the fit realised one of its six best-Q1 ones from four starts, with pads
within 1.2 mm on two more: a necessary test, not a sufficient one; the fit decides, and
``--realise`` plans again without what it cannot realise.

Pruning stays sound: a grasp accepted under an assignment has, for any three of its contacts, the
three fingers they are assigned to accepting them; so a super-contact state is pruned only where
some three of its super-contacts are admitted by no three fingers' model under any assignment.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.sampled_model import FingerModel, assignments, pair_code

__all__ = ["TRIPLE_SLACK", "ManyFingers"]

#: How far past the threshold each three fingers' residual may lie in a grasp of more than three
#: contacts: all four threes of the Shadow hand's own 4-finger poses lie within it for 63 % of
#: them, against 49 % of its 3-finger poses within the threshold itself.
TRIPLE_SLACK = 1.25


@dataclass(frozen=True, eq=False)
class TripleTable:
    """The residuals of a batch of m-grasps under every assignment, with each three's nearest sample.

    Attributes:
        residuals: Per grasp and assignment, the largest of the threes' residuals over
            :data:`TRIPLE_SLACK`, shape (B, m!).
        per_three: Per grasp, assignment and three of fingers, its residual, shape (B, m!, C(m, 3)).
        nearest: The nearest sample's row of the same, shape (B, m!, C(m, 3)).
    """

    residuals: NDArray[np.float64]
    per_three: NDArray[np.float64]
    nearest: NDArray[np.intp]


class ManyFingers:
    """The m > 3 chosen fingers of a hand, as the C(m, 3) 3-finger models of their threes.

    Args:
        chosen: The fingers (descriptor indices) that take the contacts, in order.
        model_of: The 3-finger model of three of them (descriptor indices, in order).
    """

    def __init__(self, chosen: tuple[int, ...], model_of: Callable[[tuple[int, ...]], FingerModel]) -> None:
        m = len(chosen)
        self.chosen = chosen
        self.threes = np.array(list(itertools.combinations(range(m), 3)), dtype=np.intp)  # finger positions
        self.models = [model_of(tuple(chosen[k] for k in three)) for three in self.threes]
        self.orders = assignments(m)[0]  # orders[a, k]: the grasp slot finger k takes
        self.slots = np.array(list(itertools.permutations(range(m), 3)), dtype=np.intp)  # ordered slot threes
        where = {tuple(int(v) for v in s): i for i, s in enumerate(self.slots)}
        self.gather = np.array(
            [[where[tuple(int(v) for v in order[three])] for three in self.threes] for order in self.orders]
        )

    def table(self, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> TripleTable:
        """Residuals of pad targets (B, m, 3) [m] with inward normals (B, m, 3) under every assignment."""
        batch = len(positions)
        codes = pair_code(positions[:, self.slots], normals[:, self.slots])  # (B, S, 12)
        distance = np.empty((batch, len(self.threes), len(self.slots)))
        nearest = np.empty((batch, len(self.threes), len(self.slots)), dtype=np.intp)
        for t, model in enumerate(self.models):
            d, rows = model.tree.query((codes / model.scale).reshape(-1, codes.shape[-1]), k=1)
            distance[:, t] = np.hypot(d.reshape(batch, -1), model.beyond(codes))
            nearest[:, t] = model.rows[rows].reshape(batch, -1)  # unbounded query: every row found
        threes = np.arange(len(self.threes))[None, :]
        per_three = distance[:, threes, self.gather]  # (B, m!, T)
        return TripleTable(per_three.max(axis=2) / TRIPLE_SLACK, per_three, nearest[:, threes, self.gather])

    def residuals(self, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
        """The least residual over assignments of each grasp, shape (B,)."""
        return np.asarray(self.table(positions, normals).residuals.min(axis=1), dtype=float)

    def ranked_starts(
        self, positions: NDArray[np.float64], normals: NDArray[np.float64]
    ) -> list[tuple[float, int, NDArray[np.int64]]]:
        """Starts for a fit of one grasp (positions, normals (m, 3)): (residual, sample row, assignment),
        the assignments by residual, and within one its threes' nearest samples by theirs."""
        table = self.table(positions[None], normals[None])
        found = []
        for a in np.argsort(table.residuals[0], kind="stable"):
            for t in np.argsort(table.per_three[0, a], kind="stable"):
                found.append((float(table.residuals[0, a]), int(table.nearest[0, a, t]), self.orders[a]))
        return found

    def admits(self, within: Callable[[FingerModel, NDArray[np.intp]], bool], m: int) -> bool:
        """Sound: False only if some three of the m super-contacts are admitted by no three fingers' model.

        ``within(model, three)`` is the 3-finger test of super-contacts ``three`` (indices, shape
        (3,)) at the widened threshold, under any assignment.
        """
        for three in itertools.combinations(range(m), 3):
            picked = np.array(three, dtype=np.intp)
            if not any(within(model, picked) for model in self.models):
                return False
        return True
