"""Selecting a subset of a suite's cells (``ogcp suite --only KEY=VALUE[,VALUE...]``).

A long suite (the ``paper`` suite is hours of exhaustive search) can be run in slices: each
slice appends to the same results folder, the suite hash stays the same, and ``--resume``
never reruns a recorded cell, so the slices add up to the full run in any order.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

from ogcp.benchmarks.suite.config import Cell
from ogcp.planner.infra.errors import OgcpError, choice_error

#: What a selection can name, and how each key reads a cell's values.
SELECTORS: dict[str, Callable[[Cell], tuple[str, ...]]] = {
    "object": lambda cell: (cell.object.spec,),
    "method": lambda cell: (cell.method,),
    "group": lambda cell: cell.groups,
    "label": lambda cell: (cell.label,),
    "m": lambda cell: (str(cell.m),),
    "contacts": lambda cell: (str(cell.contacts),),
    # As a suite writes it: mu = 0.5 is selected by --only mu=0.5.
    "mu": lambda cell: (f"{cell.mu:g}",),
    "contact_model": lambda cell: ("soft" if cell.torsional_friction > 0 else "hard",),
}

Selection = dict[str, frozenset[str]]


def parse_selection(items: Sequence[str], cells: Iterable[Cell]) -> Selection:
    """Parse ``KEY=VALUE[,VALUE...]`` items against the suite's cells.

    Items with the same key add values; different keys must all match (AND).

    Args:
        items: The ``--only`` arguments.
        cells: The suite's cells; every value must select at least one of them.

    Raises:
        OgcpError: For a malformed item, an unknown key (listing the keys) or a value that no
            cell has (listing the values the suite has for that key).
    """
    cells = list(cells)
    selection: dict[str, set[str]] = {}
    for item in items:
        key, sep, values = item.partition("=")
        key = key.strip()
        if not sep or not values.strip():
            raise OgcpError(f"--only takes KEY=VALUE[,VALUE...], got {item!r} (keys: {', '.join(SELECTORS)})")
        if key not in SELECTORS:
            raise choice_error("--only key", key, tuple(SELECTORS))
        known = sorted({value for cell in cells for value in SELECTORS[key](cell)})
        for value in (v.strip() for v in values.split(",")):
            if value not in known:
                raise OgcpError(
                    f"--only {key}={value}: no cell of this suite has it; the suite has "
                    f"{key} = {', '.join(known) or '(none)'}"
                )
            selection.setdefault(key, set()).add(value)
    return {key: frozenset(values) for key, values in selection.items()}


def is_selected(cell: Cell, selection: Selection) -> bool:
    """Whether ``cell`` matches every key of ``selection`` (an empty selection matches all)."""
    return all(set(SELECTORS[key](cell)) & values for key, values in selection.items())
