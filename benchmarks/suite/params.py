"""Method parameters a suite may set, their types, ranges and defaults.

Every parameter of every method is spelled out here so that a suite file is checked
against one table: unknown keys, wrong types and out-of-range values are rejected with
the key's path and the valid values, and every variant is completed with the defaults
(its canonical form, hashed into the cell id).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from planner.baselines.es import DEFAULT_BINS, DEFAULT_CHUNK
from planner.infra.errors import OgcpError, choice_error
from planner.search.grasp_planner import DEFAULT_WASTAR_EPS, HEURISTICS
from planner.search.partitions import SUCCESSORS

HANDS = ("sdh",)
DEFAULT_HAND_THRESHOLD = 0.3


@dataclass(frozen=True)
class Param:
    """One method parameter.

    Attributes:
        kind: ``int``, ``float``, ``bool`` or ``choice``.
        default: Value when the suite does not set it (None: unset/optional).
        minimum: Smallest valid value (numbers only).
        exclusive: Whether ``minimum`` itself is invalid.
        choices: Valid values of a ``choice``.
        sweep: Whether a list of values (one variant each) is allowed.
    """

    kind: str
    default: Any
    minimum: float | None = None
    exclusive: bool = False
    choices: tuple[str, ...] = ()
    sweep: bool = True

    def describe(self) -> str:
        """The valid values in words, for error messages."""
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "bool":
            return "true or false"
        what = "an integer" if self.kind == "int" else "a number"
        if self.minimum is None:
            return what
        return f"{what} {'>' if self.exclusive else '>='} {self.minimum:g}"

    def check(self, where: str, value: Any) -> Any:
        """Validate one (scalar) value and return it in canonical form.

        Raises:
            OgcpError: Naming ``where`` and the valid values.
        """
        if self.kind == "choice":
            if not isinstance(value, str) or value not in self.choices:
                raise choice_error(where, value, self.choices)
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise OgcpError(f"{where}: expected true or false, got {value!r}")
            return value
        # TOML booleans are Python ints; a flag is never a valid count or size.
        numeric = isinstance(value, int) if self.kind == "int" else isinstance(value, (int, float))
        if isinstance(value, bool) or not numeric or not math.isfinite(value):
            raise OgcpError(f"{where}: expected {self.describe()}, got {value!r}")
        if self.minimum is not None and (value < self.minimum or (self.exclusive and value == self.minimum)):
            raise OgcpError(f"{where}: expected {self.describe()}, got {value!r}")
        return int(value) if self.kind == "int" else float(value)


def _search_params(method: str) -> dict[str, Param]:
    params = {
        "branching": Param("int", 2, minimum=2),
        "successor": Param("choice", "fc", choices=SUCCESSORS),
        "heuristic": Param(
            "choice",
            "none" if method == "dijkstra" else "fc",
            choices=("none",) if method == "dijkstra" else HEURISTICS,
        ),
        "heuristic_branching": Param("int", None, minimum=2),
        "symmetry": Param("bool", False),
        "ordered": Param("bool", False),
        "seed": Param("int", 0, minimum=0),
        "kmeans_iterations": Param("int", 10, minimum=1),
        "position_weight": Param("float", 1.0, minimum=0, exclusive=True),
        "record_tree": Param("bool", False, sweep=False),
        "max_spread": Param("float", None, minimum=0, exclusive=True),
        "hand": Param("choice", None, choices=HANDS),
        "hand_threshold": Param("float", None, minimum=0, exclusive=True),
    }
    if method == "wastar":
        params["eps"] = Param("float", DEFAULT_WASTAR_EPS, minimum=0)
    return params


def _es_params(method: str) -> dict[str, Param]:
    params = {
        "chunk": Param("int", DEFAULT_CHUNK, minimum=1),
        "max_spread": Param("float", None, minimum=0, exclusive=True),
        "hand": Param("choice", None, choices=HANDS),
        "hand_threshold": Param("float", None, minimum=0, exclusive=True),
    }
    if method == "es":
        params["bins"] = Param("int", DEFAULT_BINS, minimum=1)
    return params


HFTS_PARAMS = {
    "runs": Param("int", 20, minimum=1),
    "iterations": Param("int", 40, minimum=1),
    "seed": Param("int", 0, minimum=0),
    "position_weight": Param("float", 1.0, minimum=0, exclusive=True),
    "hand": Param("choice", None, choices=HANDS),
    "hand_threshold": Param("float", None, minimum=0, exclusive=True),
}

#: method -> its parameters (``method`` and ``label`` are keys of every method table).
METHOD_PARAMS: dict[str, dict[str, Param]] = {
    "astar": _search_params("astar"),
    "wastar": _search_params("wastar"),
    "dijkstra": _search_params("dijkstra"),
    "es": _es_params("es"),
    "es-pruned": _es_params("es-pruned"),
    "hfts": HFTS_PARAMS,
}
SEARCH_METHODS = ("astar", "wastar", "dijkstra")
#: Methods whose answer is the optimum (unless approximate symmetry removal is on).
OPTIMAL_METHODS = ("astar", "dijkstra", "es", "es-pruned")
EXHAUSTIVE_METHODS = ("es", "es-pruned")
TITLES = {
    "astar": "A*",
    "wastar": "WA*",
    "dijkstra": "Dijkstra",
    "es": "ES",
    "es-pruned": "ES (pruned)",
    "hfts": "HFTS",
}
#: Parameters left out of default labels: they vary within one plotted series.
UNLABELLED = ("seed", "record_tree")


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
        start = Param("int", 0, minimum=0).check(f"{where}.start", value["start"])
        count = Param("int", 1, minimum=1).check(f"{where}.count", value["count"])
        return list(range(start, start + count))
    return values_of(where, value, Param("int", 0, minimum=0))


def values_of(where: str, value: Any, param: Param) -> list[Any]:
    """A scalar or a non-empty list of scalars, each checked against ``param``.

    Raises:
        OgcpError: For an empty list, a list where none is allowed, or an invalid value.
    """
    if isinstance(value, list):
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
        OgcpError: For parameters that contradict each other.
    """
    spec = METHOD_PARAMS[method]
    params = {key: given.get(key, param.default) for key, param in sorted(spec.items())}
    if "heuristic_branching" in params and params["heuristic_branching"] is None:
        params["heuristic_branching"] = params["branching"]
    if params.get("hand") is None and given.get("hand_threshold") is not None:
        raise OgcpError(f"{where}.hand_threshold: applies only with hand = 'sdh'")
    if params.get("hand") is not None and params["hand_threshold"] is None:
        params["hand_threshold"] = DEFAULT_HAND_THRESHOLD
    return params


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
