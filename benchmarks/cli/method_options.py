"""``ogcp plan``'s method flags, generated from the methods' declared options.

Every method parameter (:mod:`ogcp.planner.config.methods`) becomes one flag: ``branching``
is ``--branching``, with the option's type, help and default. Flags default to None
("not given"), so the configuration fills in its own defaults and a flag given to a method
that does not take it is an error instead of being silently ignored.
"""

from __future__ import annotations

import argparse
from collections import Counter
from collections.abc import Callable
from typing import Any

from ogcp.benchmarks.cli.options import integer, number, valid
from ogcp.planner.config.options import MethodConfig, Option
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import METHODS, MethodSpec

#: Parameters that the contact options already provide (``--seed`` seeds the contacts and the method).
SHARED_FIELDS = ("seed",)
#: Argument groups of ``ogcp plan --help``: title and the methods whose own flags it holds.
GROUPS = (
    ("exhaustive search (--method es / es-pruned)", ("es", "es-pruned")),
    ("HFTS baseline (--method hfts)", ("hfts",)),
)
_TYPES: dict[str, Callable[[str], Any]] = {"int": integer, "float": number, "choice": str, "text": str, "names": str}


def flag(field: str) -> str:
    """The flag of a parameter: ``heuristic_branching`` -> ``--heuristic-branching``."""
    return "--" + field.replace("_", "-")


def declared_options() -> dict[str, dict[str, Option]]:
    """Parameter name -> {method: its option}, in registry and field order (shared fields left out)."""
    found: dict[str, dict[str, Option]] = {}
    for name, spec in METHODS.items():
        for field, declared in spec.options().items():
            if field not in SHARED_FIELDS:
                found.setdefault(field, {})[name] = declared
    return found


def group_of(methods: list[str]) -> str | None:
    """Title of the argument group for flags of these methods (None: the main options)."""
    return next((title for title, members in GROUPS if set(methods) <= set(members)), None)


def add_method_options(parser: argparse.ArgumentParser, groups: dict[str, Any]) -> None:
    """Add one flag per method parameter to ``parser`` or to its group in ``groups`` (title -> group)."""
    for field, declared in declared_options().items():
        title = group_of(list(declared))
        target = parser if title is None else groups[title]
        first = next(iter(declared.values()))
        choices = list(dict.fromkeys(c for d in declared.values() for c in d.choices))
        text = first.help.format(choices=", ".join(choices))
        if first.kind in ("int", "float") and first.bounds():
            text += f"; {valid(first)}"  # the range the configuration checks, upper end included
        text += _default_text(declared, title is not None)
        if first.kind == "bool":
            if any(d.default is not False for d in declared.values()):
                raise AssertionError(f"{field}: a flag can only switch on an option that defaults to false")
            target.add_argument(flag(field), action="store_true", help=text)
        else:
            target.add_argument(flag(field), type=_TYPES[first.kind], default=None, metavar=first.metavar, help=text)


def _default_text(declared: dict[str, Option], grouped: bool) -> str:
    """`` (default X)``; ``X for METHOD`` where only some methods have it; nothing for unset or false."""
    by_default: dict[Any, list[str]] = {}
    for method, declared_option in declared.items():
        if declared_option.default is not None and declared_option.default is not False:
            by_default.setdefault(declared_option.default, []).append(method)
    if not by_default:
        return ""
    # The default most methods share is stated plainly; the others name their methods.
    counts = Counter({value: len(methods) for value, methods in by_default.items()})
    parts = []
    for i, (value, _) in enumerate(counts.most_common()):
        methods = by_default[value]
        named = i > 0 or (len(declared) == 1 and not grouped)
        parts.append(_short(value) + (f" for {', '.join(methods)}" if named else ""))
    return f" (default {'; '.join(parts)})"


def _short(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def not_applicable(option_flag: str, methods: list[str], method: str, value: Any) -> OgcpError:
    """The error for a flag given to a method that does not take it."""
    which = f"method {methods[0]!r}" if len(methods) == 1 else "methods " + ", ".join(methods)
    given = option_flag if value is True else f"{option_flag} {_short(value)}"
    return OgcpError(f"{option_flag} applies to {which} only (method {method!r} got {given})")


def config_from_args(spec: MethodSpec, args: argparse.Namespace) -> MethodConfig:
    """The method's configuration from the flags given; the rest are its defaults.

    Raises:
        OgcpError: For an invalid value, or a flag of another method.
    """
    values: dict[str, Any] = {}
    for field, declared in declared_options().items():
        value = getattr(args, field)
        if value is None or value is False:
            continue  # not given
        if spec.name in declared:
            values[field] = value
            continue
        # An invalid value says so first, wherever it would apply.
        next(iter(declared.values())).check(field, value)
        raise not_applicable(flag(field), list(declared), spec.name, value)
    values.update({field: getattr(args, field) for field in SHARED_FIELDS if field in spec.options()})
    return spec.config(**values)
