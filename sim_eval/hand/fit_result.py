"""What a hand fit found: its pose, per-finger residuals, penetrations, and whether it is realised.

A fit is *realised* when every chosen finger's residual is within :data:`RESIDUAL_TOLERANCE` and
no link is inside the object or another link beyond :data:`LINK_TOLERANCE`; otherwise
:attr:`HandFit.reason` names the finger and its residual, or the link and its depth. Both
tolerances grow with objects larger than the simulation's reference (:func:`tolerance_scale`), as
the simulation's gates do: a 1.35 m gripper's jaw tilted by 1.4 degrees to contacts that are not
exactly opposite is left 2.5-4 mm off them on a 1.2 m box.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.sim_eval.settings import REFERENCE_DIAGONAL

#: Largest pad residual of a realised fit [m], for objects up to the simulation's reference size.
RESIDUAL_TOLERANCE = 1e-3
#: Deepest a link may be inside the object or another link [m].
LINK_TOLERANCE = 1e-3
#: Widest a closed loop (a four-bar's connect) may stay open in a realised fit [m].
LOOP_TOLERANCE = 1e-4


@dataclass(frozen=True, eq=False)
class HandFit:
    """The hand's configuration and palm placement that best realise a grasp.

    Attributes:
        joint_angles: The hand's finger joints (kinematics order), within limits, shape (J,).
        rotation: Palm frame to world (object) frame, shape (3, 3).
        translation: Palm origin in the world frame, shape (3,) [m].
        fingers: The chosen fingers' indices; finger ``fingers[k]`` takes contact k.
        residuals: Each chosen finger's pad-centre distance from its target, shape (m,) [m].
        normal_angles: Angle between each pad normal and its contact's inward normal, shape (m,) [rad].
        penetration: Deepest any link is inside the object [m] (0 when none is).
        self_penetration: Deepest any link is inside another [m], the hand's designed overlaps apart.
        worst_link: The link (geom name) of the deepest penetration, or None.
        finger_names: The chosen fingers' names.
        loop_gap: Widest gap of the hand's closed loops [m] (0 for an open-chain hand).
        length_scale: The factor on :data:`RESIDUAL_TOLERANCE` and :data:`LINK_TOLERANCE`.
    """

    joint_angles: NDArray[np.float64]
    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]
    fingers: tuple[int, ...]
    residuals: NDArray[np.float64]
    normal_angles: NDArray[np.float64]
    penetration: float
    self_penetration: float
    worst_link: str | None
    finger_names: tuple[str, ...]
    loop_gap: float = 0.0
    length_scale: float = 1.0

    @property
    def tolerance(self) -> float:
        """The largest pad residual of a realised fit [m]."""
        return RESIDUAL_TOLERANCE * self.length_scale

    @property
    def link_tolerance(self) -> float:
        """The deepest a link of a realised fit may be inside the object or another link [m]."""
        return LINK_TOLERANCE * self.length_scale

    @property
    def realised(self) -> bool:
        """Every pad within :attr:`tolerance`, no link beyond :attr:`link_tolerance`, every loop closed."""
        deepest = max(self.penetration, self.self_penetration)
        closed = self.loop_gap <= LOOP_TOLERANCE
        return bool(self.residuals.max() <= self.tolerance and deepest <= self.link_tolerance and closed)

    @property
    def reason(self) -> str | None:
        """Why the fit is not realised (one line), or None."""
        worst = int(np.argmax(self.residuals))
        if self.residuals[worst] > self.tolerance:
            return (
                f"finger {self.finger_names[worst]} cannot reach its contact: {self.residuals[worst] * 1e3:.2f} mm off "
                f"(tolerance {self.tolerance * 1e3:.3g} mm)"
            )
        if self.penetration > self.link_tolerance:
            return f"link {self.worst_link} is {self.penetration * 1e3:.2f} mm inside the object"
        if self.self_penetration > self.link_tolerance:
            return f"link {self.worst_link} is {self.self_penetration * 1e3:.2f} mm inside another link"
        if self.loop_gap > LOOP_TOLERANCE:
            return f"a closed loop of the hand stays {self.loop_gap * 1e3:.2f} mm open (tolerance {LOOP_TOLERANCE * 1e3:g} mm)"
        return None

    def to_dict(self, joint_names: Sequence[str]) -> dict[str, Any]:
        """JSON-ready record: residuals [m] per finger, joint angles by name, palm pose, collisions."""
        return {
            "realised": self.realised,
            "reason": self.reason,
            "fingers": list(self.finger_names),
            "fit_residuals": self.residuals.tolist(),
            "normal_angles": self.normal_angles.tolist(),
            "joint_names": list(joint_names),
            "joint_angles": self.joint_angles.tolist(),
            "palm_rotation": self.rotation.tolist(),
            "palm_position": self.translation.tolist(),
            "penetration": self.penetration,
            "self_penetration": self.self_penetration,
            "worst_link": self.worst_link,
            "loop_gap": self.loop_gap,
            "tolerance": self.tolerance,
        }


def tolerance_scale(diagonal: float) -> float:
    """The factor on the fit's tolerances for an object of this bounding-box diagonal [m]: 1 up to
    the simulation's reference diagonal, then in proportion, as its length settings."""
    return max(1.0, float(diagonal) / REFERENCE_DIAGONAL)


def better_fit(a: HandFit, b: HandFit) -> bool:
    """Whether fit a is preferable: realised first, then the smaller worst violation."""
    if a.realised != b.realised:
        return a.realised
    return violation(a) < violation(b)


def violation(fit: HandFit) -> float:
    """How far the fit's worst pad or link is beyond its tolerance [m] (0 when within both)."""
    excess = (
        fit.residuals.max() - fit.tolerance,
        fit.penetration - fit.link_tolerance,
        fit.self_penetration - fit.link_tolerance,
    )
    return float(max(*excess, 0.0))
