"""Declared options: one declaration gives a method parameter its default, type, range and help.

A method's configuration is a frozen dataclass (:class:`MethodConfig`) whose fields are
declared with :func:`option`. The field's :class:`Option` (kept in its metadata) validates
the value when the configuration is made, and it is what the command line's flags and the
benchmark suites' parameter tables are generated from, so nothing is written twice.

Every number has a finite valid range. The upper ends of the method parameters are in
:data:`UPPER_LIMITS` (by parameter name; see there why each is where it is), and the run-time
options that ``ogcp plan`` and ``ogcp suite`` share (:data:`TIME_LIMIT`, :data:`JOBS`) are
declared here too.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any, ClassVar

from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.infra.parallel import max_jobs

KINDS = ("int", "float", "bool", "choice", "text", "names")
#: Longest ``text`` value (a file path) and most entries of a ``names`` list.
MAX_TEXT = 4096
MAX_NAMES = 64
#: Key of a dataclass field's metadata that holds its Option.
METADATA_KEY = "ogcp.option"
#: Largest seed: an unsigned 32-bit integer, the range CoACD's seed and most random-number
#: libraries take, so a seed recorded by ogcp can be passed on anywhere unchanged.
MAX_SEED = 2**32 - 1
#: Upper ends of the method parameters (:mod:`ogcp.planner.config.methods`), by parameter name.
#: :func:`options_of` gives them to every configuration's options, so the configurations,
#: ``ogcp plan``'s flags and the suites' tables check them alike. Each keeps a parameter where
#: its run stays finite in time and memory:
UPPER_LIMITS: dict[str, float] = {
    # Expanding a state creates up to b^m successors (b = 1000 with m = 3 is 10^9 of them;
    # b = 64 already spends 30 s on one expansion of 1000 contacts). The paper uses 2 and 4.
    "branching": 64,
    "heuristic_branching": 64,
    # k-means runs at every node of the partition tree; Lloyd's iterations converge in tens.
    "kmeans_iterations": 1000,
    # Positions enter the features as w (p - com) / rho, of length <= w: at w = 1000 the unit
    # normals weigh ~10^-6 as much, already ignored; at 10^308 k-means met NaN and failed.
    "position_weight": 1000.0,
    # Metres, like the largest object diagonal (ogcp.planner.grasp.defaults.DIAGONAL): a larger
    # spread constrains nothing.
    "max_spread": 100.0,
    # Residuals are distances between codes whose dimensions (4 per finger pair) are normalised by
    # their sampled spread (the default accepts 1): 10 is 10x that; at 10^308 squaring it overflowed.
    "hand_threshold": 10.0,
    # WA*'s Q1 >= Q_OWS - (1 + eps) (Q_OWS - Q1*) says nothing at eps = 100 unless the
    # optimum holds 99 % of Q_OWS; larger eps only inflates the priorities towards overflow.
    "eps": 100.0,
    # Grasps per chunk of exhaustive search: 10^7 3-contact grasps are 240 MB of indices per
    # worker (50x the default); 10^12 would ask for terabytes at once.
    "chunk": 10_000_000,
    # Histogram bins: one count each, drawn in a figure; 10^12 would allocate 8 TB.
    "bins": 10_000,
    # HFTS runs and moves per level: each move evaluates a grasp, so 10^4 of each is 10^8
    # evaluations per level (the paper: 20 runs of 40 moves); 10^9 never ended.
    "runs": 10_000,
    "iterations": 10_000,
    "seed": MAX_SEED,
}
#: Longest wall-clock budget of a search [s] (about four months): a longer one is no limit
#: at all; leave the option out instead.
MAX_TIME_LIMIT = 1e7


class ConfigError(OgcpError):
    """A configuration value is invalid.

    The message is ``"<field>: <problem>"``, so a caller that knows where the value came
    from (a suite's key path) can prefix it.

    Attributes:
        field: Name (or key path) of the invalid value.
        problem: What is wrong, with the valid values.
    """

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field}: {problem}")
        self.field = field
        self.problem = problem


@dataclasses.dataclass(frozen=True)
class Option:
    """The declaration of one parameter.

    Attributes:
        kind: ``int``, ``float``, ``bool``, ``choice``, ``text`` (a non-empty string such as a
            file path) or ``names`` (a list of distinct non-empty names; comma-separated on the
            command line).
        default: Value when none is given; None means unset (then None is also valid).
        help: One line for ``--help``; ``{choices}`` is replaced by the valid choices.
        minimum: Smallest valid value (numbers only).
        exclusive: Whether ``minimum`` itself is invalid.
        maximum: Largest valid value (numbers only; valid itself).
        choices: Valid values of a ``choice``.
        sweep: Whether a suite may list several values (one variant each).
        metavar: Placeholder of the value in ``--help`` (default: the flag's name).
    """

    kind: str
    default: Any
    help: str = ""
    minimum: float | None = None
    exclusive: bool = False
    maximum: float | None = None
    choices: tuple[str, ...] = ()
    sweep: bool = True
    metavar: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise choice_error("option kind", self.kind, KINDS)

    def describe(self) -> str:
        """The valid values in words, for error messages: ``an integer from 3 to 64``."""
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "bool":
            return "true or false"
        if self.kind == "text":
            return "a non-empty string"
        if self.kind == "names":
            return "a list of distinct names"
        what = "an integer" if self.kind == "int" else "a number"
        bounds = self.bounds()
        if bounds.startswith(("<", ">")):
            return f"{what} {bounds}"
        return f"{what} {'from ' if bounds else ''}{bounds}".rstrip()

    def bounds(self) -> str:
        """The valid range of a number, for ``--help`` and messages: ``3 to 64``, ``> 0 and <= 10``, ``>= 0``."""
        low = None if self.minimum is None else _number(self.minimum)
        high = None if self.maximum is None else _number(self.maximum)
        if low is not None and high is not None:
            return f"> {low} and <= {high}" if self.exclusive else f"{low} to {high}"
        if low is not None:
            return f"{'>' if self.exclusive else '>='} {low}"
        return "" if high is None else f"<= {high}"

    def check(self, where: str, value: Any) -> Any:
        """Validate one value and return it in canonical form (ints as int, numbers as float).

        Args:
            where: Name or key path of the value, for the error message.
            value: The value.

        Raises:
            OgcpError: Naming ``where`` and the valid values (:class:`ConfigError`, or the
                :func:`~ogcp.planner.infra.errors.choice_error` of a choice).
        """
        if self.kind == "choice":
            if not isinstance(value, str) or value not in self.choices:
                raise choice_error(where, value, self.choices)
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise ConfigError(where, f"expected true or false, got {value!r}")
            return value
        if self.kind == "text":
            if not isinstance(value, str) or not value.strip() or len(value) > MAX_TEXT:
                raise ConfigError(where, f"expected a non-empty string of at most {MAX_TEXT} characters, got {value!r}")
            return value
        if self.kind == "names":
            return _names(where, value)
        # TOML booleans are Python ints; a flag is never a valid count or size.
        numeric = isinstance(value, numbers.Integral if self.kind == "int" else numbers.Real)
        below = (
            isinstance(value, bool)
            or not numeric
            or not math.isfinite(value)
            or (self.minimum is not None and (value < self.minimum or (self.exclusive and value == self.minimum)))
        )
        if below or (self.maximum is not None and value > self.maximum):
            raise ConfigError(where, self._problem(value, below))
        return int(value) if self.kind == "int" else float(value)

    def _problem(self, value: Any, below: bool) -> str:
        """``expected an integer >= 3, got 2 (valid: 3 to 64)``: the side that failed, then the range."""
        what = "an integer" if self.kind == "int" else "a number"
        if self.maximum is None:
            return f"expected {self.describe()}, got {value!r}"
        if below and self.minimum is not None:
            side = f"{'>' if self.exclusive else '>='} {_number(self.minimum)}"
        else:
            side = "" if below else f"<= {_number(self.maximum)}"
        return f"expected {what}{' ' + side if side else ''}, got {value!r} (valid: {self.bounds()})"


def _names(where: str, value: Any) -> tuple[str, ...]:
    """A ``names`` value as a tuple: a list or tuple of strings, or one comma-separated string."""
    if isinstance(value, str):
        value = [part.strip() for part in value.split(",")]
    ok = isinstance(value, list | tuple) and 0 < len(value) <= MAX_NAMES
    if not ok or not all(isinstance(v, str) and v.strip() for v in value):
        raise ConfigError(where, f"expected a list of 1 to {MAX_NAMES} non-empty names, got {value!r}")
    if len(set(value)) != len(value):
        raise ConfigError(where, f"names a value twice: {', '.join(value)}")
    return tuple(value)


def _number(value: float) -> str:
    """A bound as written: integers in full (a seed's 4294967295), other numbers short (1e-05)."""
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return f"{value:g}"


def option(kind: str, default: Any, help: str, **details: Any) -> Any:
    """A dataclass field declared by an :class:`Option` (same arguments)."""
    return field_of(Option(kind, default, help, **details))


def field_of(declared: Option) -> Any:
    """A dataclass field for an existing :class:`Option` (to share one between configurations)."""
    return dataclasses.field(default=declared.default, metadata={METADATA_KEY: declared})


def options_of(config: type[MethodConfig] | MethodConfig) -> dict[str, Option]:
    """Field name -> Option of a configuration class or instance, in field order.

    An option declared without a maximum gets the one :data:`UPPER_LIMITS` gives its name.
    """
    found = {f.name: f.metadata[METADATA_KEY] for f in dataclasses.fields(config) if METADATA_KEY in f.metadata}
    return {name: _limited(name, declared) for name, declared in found.items()}


def _limited(name: str, declared: Option) -> Option:
    limit = UPPER_LIMITS.get(name)
    if limit is None or declared.maximum is not None or declared.kind not in ("int", "float"):
        return declared
    return dataclasses.replace(declared, maximum=limit)


def check_values(config: type[MethodConfig], **values: Any) -> None:
    """Validate some values against a configuration's options (for engines that take them one by one).

    Raises:
        OgcpError: For the first invalid value, naming it and the valid values.
    """
    declared = options_of(config)
    for name, value in values.items():
        declared[name].check(name, value)


@dataclasses.dataclass(frozen=True, kw_only=True)
class MethodConfig:
    """Base of every method's configuration: validates and canonicalises its declared fields.

    Subclasses that resolve dependent defaults or check combinations extend
    ``__post_init__`` (calling this one first) and set resolved values with
    :func:`object.__setattr__` (the dataclass is frozen).

    Attributes:
        method: The method's name (a class constant).
    """

    method: ClassVar[str]

    def __post_init__(self) -> None:
        for name, declared in options_of(self).items():
            value = getattr(self, name)
            if value is None and declared.default is None:
                continue  # unset
            object.__setattr__(self, name, declared.check(name, value))

    def canonical(self) -> dict[str, Any]:
        """Every parameter, sorted by name (what a suite hashes into a cell id)."""
        return {name: getattr(self, name) for name in sorted(options_of(self))}


#: Wall-clock budget of a search cell or ``ogcp plan``'s search [s]; None: unlimited.
TIME_LIMIT = Option("float", None, "wall-clock budget [s]", minimum=0, exclusive=True, maximum=MAX_TIME_LIMIT)
#: Most memory of one search, all its processes together [GiB]: past it the search forgets its
#: least promising open states (:mod:`ogcp.planner.search.memory`).
MEMORY_LIMIT = Option("float", 4.0, "memory of one search, all its processes [GiB]", minimum=0, exclusive=True)
#: Local worker processes (a Dask cluster decides its own).
JOBS = Option("int", 1, "worker processes", minimum=1, maximum=max_jobs())
