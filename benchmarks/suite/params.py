"""The method parameters a suite may set: a thin adapter over :mod:`ogcp.planner.methods`.

Each method's parameters, types, ranges and defaults are its configuration's declared
options (:mod:`ogcp.planner.config.methods`); here they are read as a suite file's keys. A
variant is completed by the configuration itself, and its canonical form (every
parameter, sorted by name) is what is hashed into the cell id.
"""

from __future__ import annotations

from typing import Any

from ogcp.planner.config.methods import DEFAULT_HAND_THRESHOLD
from ogcp.planner.config.options import ConfigError, Option
from ogcp.planner.grasp.contact_model import torsion_of
from ogcp.planner.grasp.defaults import CONTACT_MODEL, CONTACT_SEED, TORSIONAL_FRICTION
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import EXHAUSTIVE_METHODS, METHODS, OPTIMAL_METHODS

__all__ = [
    "EXHAUSTIVE_METHODS",
    "METHOD_PARAMS",
    "OPTIMAL_METHODS",
    "TITLES",
    "complete",
    "contact_models",
    "default_label",
    "seed_values",
    "values_of",
]

#: method -> its parameters (``method`` and ``label`` are keys of every method table).
METHOD_PARAMS: dict[str, dict[str, Option]] = {name: spec.options() for name, spec in METHODS.items()}
TITLES = {name: spec.title for name, spec in METHODS.items()}
#: Parameters left out of default labels: they vary within one plotted series.
UNLABELLED = ("seed", "record_tree")
#: Options added after cell ids were first recorded: left out of a variant while unset.
ADDED_UNSET = ("hand_fingers", "realise")
#: Most seeds of one ``{start, count}`` range: repeats for statistics, where 10^4 is plenty;
#: 10^12 asked for terabytes before the suite's size was known.
MAX_SEED_COUNT = 10_000
#: Seeds of a suite: the contacts' and the methods' have the same range.
SEED = CONTACT_SEED


def seed_values(where: str, value: Any) -> list[int]:
    """Seeds from an integer, a list of integers or a table ``{start = S, count = N}``.

    Raises:
        OgcpError: For anything else, naming ``where``.
    """
    if isinstance(value, dict):
        if set(value) != {"start", "count"}:
            raise OgcpError(
                f"{where}: a seed range needs exactly the keys count, start; got {', '.join(sorted(value))}"
            )
        start = SEED.check(f"{where}.start", value["start"])
        count = Option("int", 1, minimum=1, maximum=MAX_SEED_COUNT).check(f"{where}.count", value["count"])
        if SEED.maximum is not None and start + count - 1 > SEED.maximum:
            SEED.check(f"{where}.start + count - 1", start + count - 1)
        return list(range(start, start + count))
    return values_of(where, value, SEED)


def values_of(where: str, value: Any, param: Option) -> list[Any]:
    """A scalar or a non-empty list of scalars, each checked against ``param``.

    Raises:
        OgcpError: For an empty list, a list where none is allowed, or an invalid value.
    """
    if isinstance(value, list) and param.kind != "names":  # a names value is itself a list
        if not param.sweep:
            raise OgcpError(f"{where}: expected {param.describe()}, got a list")
        if not value:
            raise OgcpError(f"{where}: empty list; give at least one value ({param.describe()})")
        checked = [param.check(f"{where}[{i}]", v) for i, v in enumerate(value)]
        if len(set(map(repr, checked))) != len(checked):
            raise OgcpError(f"{where}: repeated values in {value!r}")
        return checked
    return [param.check(where, value)]


def complete(method: str, where: str, given: dict[str, Any]) -> dict[str, Any]:
    """Defaults filled in and dependent values resolved: the canonical variant parameters.

    Args:
        method: Method name.
        where: Key path of the method table, for errors.
        given: Scalar parameter values the suite set.

    Raises:
        OgcpError: For parameters that contradict each other, naming the key path.
    """
    try:
        config = METHODS[method].config(**given)
    except ConfigError as exc:
        raise OgcpError(f"{where}.{exc}") from exc
    canonical = config.canonical()
    for name in ADDED_UNSET:  # cells keep the ids they had before these options existed
        if canonical.get(name) is None:
            canonical.pop(name, None)
    return canonical


def default_label(method: str, params: dict[str, Any]) -> str:
    """A readable label: the method's title and every parameter that differs from its default."""
    defaults = complete(method, "", {})
    parts = [
        f"{key}={_short(value)}"
        for key, value in params.items()
        if key not in UNLABELLED
        and (key == "eps" or value != defaults.get(key))
        and value is not None
        and not (key == "hand_threshold" and value == DEFAULT_HAND_THRESHOLD)
    ]
    return " ".join([TITLES[method], *parts])


def _short(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value:g}" if isinstance(value, float) else str(value)


def contact_models(where: str, table: dict[str, Any]) -> list[float]:
    """A group's contact models as torsional friction coefficients [m] (0 = hard), in the order given.

    ``contact_model`` (one name or a list) and ``torsional_friction`` (one value or a list) sweep
    like ``mu``: ``contact_model = ["hard", "soft"]`` with ``torsional_friction = [0.01, 0.02]``
    gives hard fingers and soft ones at both coefficients; a coefficient alone implies soft.

    Raises:
        OgcpError: For an unknown model, a coefficient out of range, one given with only the hard
            model, or soft fingers with a zero coefficient.
    """
    given = table.get("contact_model")
    names: list[str | None] = values_of(f"{where}.contact_model", given, CONTACT_MODEL) if given is not None else [None]
    torsions: list[float | None] = (
        values_of(f"{where}.torsional_friction", table["torsional_friction"], TORSIONAL_FRICTION)
        if "torsional_friction" in table
        else [None]
    )
    found: list[float] = []
    for name in names:
        # Beside soft fingers, the hard model takes none of the listed coefficients.
        for torsion in [None] if name == "hard" and len(names) > 1 else torsions:
            value = torsion_of(name, torsion, f"{where}.contact_model", f"{where}.torsional_friction")
            if value not in found:
                found.append(value)
    return found
