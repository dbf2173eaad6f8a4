"""Why a settled grasp is invalid: each failed validity gate as a finger, an amount and a remedy.

:func:`~ogcp.sim_eval.protocols.phases.settle` records the gates as numbers (``initial_penetration``,
``tip_penetration``, ``tips_in_contact``, ``creep``, ``diverged``); this module turns the failed
ones into :class:`GateFailure` values that say which gate failed, on which finger, by how much
against which limit, and what the user can change. They are written into each grasp's
``ogcp.sim/1`` record (``invalid_reasons``) and printed by ``ogcp evaluate``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ogcp.sim_eval.protocols.phases import CONTACT_FRACTION
from ogcp.sim_eval.settings import SimSettings


@dataclass(frozen=True)
class GateFailure:
    """One failed validity gate of a settled grasp.

    Attributes:
        gate: ``penetration``, ``contact``, ``creep``, ``diverged`` or (a hand's) ``pad``; ``force_closure`` explains
            the others when the grasp the tips realize is not in force closure.
        finger: Position of the finger in the grasp, None for a gate of the whole grasp.
        value: What was measured (unit in ``unit``).
        limit: The gate's limit (same unit).
        unit: ``m`` or ``N``; empty for ``diverged``.
        advice: What the user can change.
    """

    gate: str
    finger: int | None
    value: float
    limit: float
    unit: str
    advice: str

    @property
    def message(self) -> str:
        """The failure in one line: which finger, how much, against what, and what to try."""
        who = f"finger {self.finger}" if self.finger is not None else "the grasp"
        if self.gate == "penetration":
            what = f"{who} starts {_mm(self.value)} inside the collision parts (limit {_mm(self.limit)})"
        elif self.gate == "contact":
            what = f"{who} does not press on the object after settling ({self.value:.2g} N, needs > {self.limit:.2g} N)"
        elif self.gate == "creep":
            what = f"the object drifts {_um(self.value)} at the end of settling (limit {_um(self.limit)})"
        elif self.gate == "pad":
            where = "presses nothing" if not np.isfinite(self.value) else f"settled {_mm(self.value)} from its contact"
            what = f"{who}'s pad {where} (limit {_mm(self.limit)})"
        elif self.gate == "force_closure":
            what = f"the realized contacts are not in force closure (Q1 {self.value:.2g})"
        else:
            what = "the simulation diverged while settling"
        return f"{what}: {self.advice}"

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the ``invalid_reasons`` entries of ``ogcp.sim/2``)."""
        return {
            "gate": self.gate,
            "finger": self.finger,
            "value": self.value,
            "limit": self.limit,
            "unit": self.unit,
            "message": self.message,
        }


def not_in_force_closure(q1: float) -> GateFailure:
    """Why an invalid grasp could not hold, when its realized contacts are not in force closure."""
    advice = (
        "no preload can hold it, so it slips or loses a finger; plan with a method that guarantees force "
        "closure (astar, es) or with more contacts"
    )
    return GateFailure("force_closure", None, q1, 0.0, "N", advice)


def gate_failures(gates: Mapping[str, Any], normal_forces: ArrayLike, settings: SimSettings) -> tuple[GateFailure, ...]:
    """The failed gates of one settled grasp, whole-grasp failures first, then by finger.

    Args:
        gates: The gates :func:`~ogcp.sim_eval.protocols.phases.settle` recorded.
        normal_forces: Tip normal forces after settling, shape (m,) [N].
        settings: The settings the grasp was simulated with (their limits are the gates').

    Returns:
        Empty when every gate passed.
    """
    if gates.get("diverged"):
        advice = 'try a smaller physics step, e.g. --settings with {"timestep": 0.001}'
        return (GateFailure("diverged", None, 1.0, 0.0, "", advice),)
    found: list[GateFailure] = []
    creep = float(gates.get("creep", 0.0))
    if creep > settings.creep_tolerance:
        advice = "the grasp slips under its own preload; a grasp with higher Q1 or a larger mu holds better"
        found.append(GateFailure("creep", None, creep, settings.creep_tolerance, "m", advice))
    depths = np.asarray(gates.get("tip_penetration", ()), dtype=float)
    for finger, depth in enumerate(depths):
        if depth > settings.penetration_tolerance:
            advice = (
                "the convex parts stand proud of the mesh or the tip does not fit there; "
                "try a smaller CoACD --threshold (tighter parts) or a smaller --tip-radius"
            )
            found.append(GateFailure("penetration", finger, float(depth), settings.penetration_tolerance, "m", advice))
    needed = CONTACT_FRACTION * settings.max_normal_force
    for finger, force in enumerate(np.asarray(normal_forces, dtype=float)):
        if not force > needed:
            advice = (
                "the tip lost the object: its contact may lie on a thin or sharp feature the tip slides off "
                "(plan with a larger --tip-radius), or the object slid away (see creep)"
            )
            found.append(GateFailure("contact", finger, float(force), needed, "N", advice))
    return tuple(found)


def _mm(metres: float) -> str:
    return f"{metres * 1e3:.2f} mm"


def _um(metres: float) -> str:
    return f"{metres * 1e6:.0f} um" if metres < 1e-3 else _mm(metres)
