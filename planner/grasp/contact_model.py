"""The contact model of a contact set from what a user gives: hard fingers, or soft with torsion.

One rule for the command line, the suites and the Python API: ``hard`` (the default) takes no
torsional coefficient; ``soft`` takes one > 0 [m] and defaults to
:data:`~ogcp.planner.grasp.defaults.DEFAULT_TORSIONAL_FRICTION`. A contact set stores only the
coefficient (0 = hard), so nothing can record one model and compute with the other.
Imports nothing heavy: ``--help`` and suite validation use it.
"""

from __future__ import annotations

from ogcp.planner.grasp.defaults import CONTACT_MODEL, DEFAULT_TORSIONAL_FRICTION, TORSIONAL_FRICTION
from ogcp.planner.infra.errors import OgcpError


def torsion_of(
    model: str | None,
    torsion: float | None,
    model_name: str = "contact_model",
    torsion_name: str = "torsional_friction [m]",
) -> float:
    """The torsional friction coefficient [m] of a contact model and an optional coefficient.

    Args:
        model: ``"hard"`` or ``"soft"``; None = soft when ``torsion`` is given, else hard.
        torsion: Torsional friction coefficient [m]; None = the soft default.
        model_name: The model's name in error messages (a flag, a suite key or a file's field).
        torsion_name: The coefficient's name in error messages, e.g. ``"--torsional-friction"``.

    Returns:
        0.0 for hard fingers, the coefficient (> 0) for soft ones.

    Raises:
        OgcpError: For an unknown model, a coefficient outside its range, a coefficient given
            with the hard model, or a zero coefficient with the soft one.
    """
    prefix = f"{torsion_name}: "
    if model is not None:
        CONTACT_MODEL.check(model_name, model)
    if torsion is not None:
        torsion = TORSIONAL_FRICTION.check(torsion_name, torsion)
    resolved = model or ("soft" if torsion is not None else "hard")
    if resolved == "hard":
        if torsion:
            raise OgcpError(
                f"{prefix}a torsional friction coefficient ({torsion:g} m) needs the soft contact model; "
                "hard fingers are point contacts without torsion"
            )
        return 0.0
    if torsion is None:
        return DEFAULT_TORSIONAL_FRICTION
    if torsion <= 0:
        raise OgcpError(f"{prefix}soft fingers need a torsional friction coefficient > 0 [m], got {torsion:g}")
    return float(torsion)
