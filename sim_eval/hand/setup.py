"""The hand that simulates a set of grasps, and its fit to one grasp from the nearest samples.

:class:`HandSetup` holds the compiled hand and its reachability model, whose samples nearest a
grasp are where :func:`fit_grasp` starts the fit (:mod:`ogcp.sim_eval.hand.fit`) until one is
realised where the hand's servos can press a balanced grip (:class:`SqueezeCheck`).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.reachability import HandReachability
from ogcp.planner.hands.sampled_model import MAX_AUTO_SAMPLES
from ogcp.sim_eval.hand.fit import HandFit, fit_hand
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.squeeze import balanced_grip
from ogcp.sim_eval.protocols.phases import CONTACT_FRACTION

#: Samples a fit starts from, nearest first, until one fit is realised.
FIT_STARTS = 16
#: The weakest pad force of a grip a fit is taken for, as a fraction of F_max: twice what the contact
#: gate counts as touching (``CONTACT_FRACTION``), so that half the grip still touches.
PRESS_FRACTION = 2 * CONTACT_FRACTION


@dataclasses.dataclass(frozen=True, eq=False)
class HandSetup:
    """The hand that simulates a set of grasps.

    Attributes:
        kinematics: The hand, compiled.
        model: Its reachability model (the fit's starts); None: built on first use (grasps
            posed by another planner are not fitted and never need it).
        fingers: Names of the fingers that take the contacts; None: the first m.
        samples: The size of the model the plan was made under, where a search made it denser
            than the hand's own (:meth:`HandReachability.denser`); None: the hand's own.
    """

    kinematics: HandKinematics
    model: HandReachability | None = None
    fingers: tuple[str, ...] | None = None
    samples: int | None = None

    @functools.cached_property
    def reach(self) -> HandReachability:
        """The reachability model: the given one, else sampled (or read from its cache) now."""
        if self.model is not None:
            return self.model
        own = HandReachability(self.kinematics.descriptor, self.fingers)
        denser = self.samples is not None and len(own.q) < self.samples <= MAX_AUTO_SAMPLES  # not a damaged record's
        if own.growable and denser:
            return HandReachability(self.kinematics.descriptor, self.fingers, self.samples)  # the plan's, cached
        return own

    @classmethod
    def of(cls, hand: HandKinematics, fingers: Sequence[str] | None = None, samples: int | None = None) -> HandSetup:
        """A setup for a compiled hand (its reachability model is built on first use)."""
        return cls(hand, None, tuple(fingers) if fingers is not None else None, samples)


def fit_grasp(
    setup: HandSetup,
    scene: FitScene,
    contacts: ContactSet,
    grasp: tuple[int, ...],
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    squeeze: SqueezeCheck | None = None,
) -> tuple[HandFit, tuple[int, ...]]:
    """The best fit from the grasp's nearest samples, and the order in which the fingers take its contacts.

    ``points`` and ``normals`` (shape (m, 3)) are the targets of the grasp's contacts, in grasp order.
    With ``squeeze``, a realised fit is taken only where the hand's servos can press a balanced grip
    (a finger resting on a joint limit it would have to push past cannot press); the best realised
    fit where none can.
    """
    fingers = setup.reach.chosen(len(grasp))
    best: tuple[HandFit, tuple[int, ...]] | None = None
    pressing: tuple[HandFit, tuple[int, ...]] | None = None
    for start in setup.reach.starts(grasp, contacts, FIT_STARTS):
        order = tuple(start.fingers)
        fit = fit_hand(scene, fingers, points[list(order)], normals[list(order)], start.joint_angles)
        if best is None or _rank(fit) < _rank(best[0]):
            best = (fit, order)
        if fit.realised and (
            squeeze is None or squeeze.can_press(scene, fit, points[list(order)], normals[list(order)])
        ):
            pressing = (fit, order)
            break
    assert best is not None
    return pressing or best


@dataclasses.dataclass(frozen=True)
class SqueezeCheck:
    """What :func:`~ogcp.sim_eval.hand.squeeze.balanced_grip` needs besides the fit: the object and friction."""

    com: NDArray[np.float64]
    torque_scale: float
    mu: float
    max_normal_force: float

    def can_press(
        self, scene: FitScene, fit: HandFit, points: NDArray[np.float64], normals: NDArray[np.float64]
    ) -> bool:
        """Whether the servos can press a balanced grip at the fit's pose, every pad with at least :data:`PRESS_FRACTION` of F_max."""
        scene.pose(fit.joint_angles, fit.rotation, fit.translation)
        grip = balanced_grip(
            scene.model,
            scene.hand,
            scene.data.qpos.copy(),
            fit.fingers,
            points,
            normals,
            self.com,
            self.torque_scale,
            self.mu,
            self.max_normal_force,
        )
        return grip is not None and float(grip.pad_forces.min()) >= PRESS_FRACTION * self.max_normal_force


def _rank(fit: HandFit) -> tuple[bool, float]:
    deepest = max(fit.penetration, fit.self_penetration)
    return (not fit.realised, float(max(fit.residuals.max(), deepest)))
