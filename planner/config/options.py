"""Declared options: one declaration gives a method parameter its default, type, range and help.

A method's configuration is a frozen dataclass (:class:`MethodConfig`) whose fields are
declared with :func:`option`. The field's :class:`Option` (kept in its metadata) validates
the value when the configuration is made, and it is what the command line's flags and the
benchmark suites' parameter tables are generated from, so nothing is written twice.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any, ClassVar

from planner.infra.errors import OgcpError, choice_error

KINDS = ("int", "float", "bool", "choice")
#: Key of a dataclass field's metadata that holds its Option.
METADATA_KEY = "ogcp.option"


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
        kind: ``int``, ``float``, ``bool`` or ``choice``.
        default: Value when none is given; None means unset (then None is also valid).
        help: One line for ``--help``; ``{choices}`` is replaced by the valid choices.
        minimum: Smallest valid value (numbers only).
        exclusive: Whether ``minimum`` itself is invalid.
        choices: Valid values of a ``choice``.
        sweep: Whether a suite may list several values (one variant each).
        metavar: Placeholder of the value in ``--help`` (default: the flag's name).
    """

    kind: str
    default: Any
    help: str = ""
    minimum: float | None = None
    exclusive: bool = False
    choices: tuple[str, ...] = ()
    sweep: bool = True
    metavar: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise choice_error("option kind", self.kind, KINDS)

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
        """Validate one value and return it in canonical form (ints as int, numbers as float).

        Args:
            where: Name or key path of the value, for the error message.
            value: The value.

        Raises:
            OgcpError: Naming ``where`` and the valid values (:class:`ConfigError`, or the
                :func:`~planner.infra.errors.choice_error` of a choice).
        """
        if self.kind == "choice":
            if not isinstance(value, str) or value not in self.choices:
                raise choice_error(where, value, self.choices)
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise ConfigError(where, f"expected true or false, got {value!r}")
            return value
        # TOML booleans are Python ints; a flag is never a valid count or size.
        numeric = isinstance(value, numbers.Integral if self.kind == "int" else numbers.Real)
        if isinstance(value, bool) or not numeric or not math.isfinite(value):
            raise ConfigError(where, f"expected {self.describe()}, got {value!r}")
        if self.minimum is not None and (value < self.minimum or (self.exclusive and value == self.minimum)):
            raise ConfigError(where, f"expected {self.describe()}, got {value!r}")
        return int(value) if self.kind == "int" else float(value)


def option(kind: str, default: Any, help: str, **details: Any) -> Any:
    """A dataclass field declared by an :class:`Option` (same arguments)."""
    return field_of(Option(kind, default, help, **details))


def field_of(declared: Option) -> Any:
    """A dataclass field for an existing :class:`Option` (to share one between configurations)."""
    return dataclasses.field(default=declared.default, metadata={METADATA_KEY: declared})


def options_of(config: type[MethodConfig] | MethodConfig) -> dict[str, Option]:
    """Field name -> Option of a configuration class or instance, in field order."""
    return {f.name: f.metadata[METADATA_KEY] for f in dataclasses.fields(config) if METADATA_KEY in f.metadata}


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
