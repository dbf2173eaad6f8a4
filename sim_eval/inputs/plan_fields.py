"""Type and range checks of the ``ogcp.plan/1`` fields the simulation reads (:func:`check_plan_fields`).

A plan is user input: every field ``ogcp.sim_eval.inputs.plan_input`` reads is checked here first, so a
malformed file ends in one line naming the field's key path, never in a traceback deeper in.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ogcp.planner.config.options import Option
from ogcp.planner.grasp.defaults import CONE_EDGES, CONTACT_SEED, CONTACTS, DIAGONAL, MU, TIP_RADIUS, TORSIONAL_FRICTION
from ogcp.planner.infra.errors import OgcpError

#: The plan's fields that the simulation reads, by key path, with their valid values (a
#: missing or null field is allowed where older plans or other methods lack it).
_NUMBERS: dict[str, Option] = {
    "q1": Option("float", None, minimum=0),
    "q_ows": Option("float", None, minimum=0),
    "contact_set.size": CONTACTS,
    "contact_set.torque_scale": Option("float", None, minimum=0, exclusive=True),
    "contact_set.mu": MU,
    "contact_set.cone_edges": CONE_EDGES,
    "contact_set.torsional_friction": TORSIONAL_FRICTION,
}
#: Keys of a contact source (either copy) and their valid values.
_SOURCE: dict[str, Option | type] = {
    "n": CONTACTS,
    "seed": CONTACT_SEED,
    "tip_radius": TIP_RADIUS,
    "reach_tolerance": Option("float", None, minimum=0),
    "diagonal": DIAGONAL,
    "sampling": str,
    "kind": str,
    "name": str,
    "path": str,
    "sha256": str,
}


def _field(record: dict[str, Any], path: str) -> Any:
    node: Any = record
    for key in path.split("."):
        node = node.get(key) if isinstance(node, dict) else None
    return node


def _present(record: dict[str, Any], path: str) -> bool:
    *parents, last = path.split(".")
    node = _field(record, ".".join(parents)) if parents else record
    return isinstance(node, dict) and last in node


def _block(record: dict[str, Any], path: str, kind: type) -> None:
    value = _field(record, path)
    if value is not None and not isinstance(value, kind):
        what = "an object" if kind is dict else "a list"
        raise OgcpError(f"plan field {path}: expected {what}, got {type(value).__name__} {_show_short(value)}")


def _show_short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _point(value: Any) -> bool:
    """Whether ``value`` is [x, y, z] of finite numbers."""
    numbers = isinstance(value, list) and len(value) == 3
    return numbers and all(isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in value)


def _rows(record: dict[str, Any], path: str) -> None:
    """A list of [x, y, z] rows of finite numbers (positions or normals), if present."""
    value = _field(record, path)
    if value is None:
        return
    if not (isinstance(value, list) and all(_point(row) for row in value)):
        raise OgcpError(
            f"plan field {path}: expected a list of [x, y, z] rows of finite numbers, got {_show_short(value)}"
        )


def check_plan_fields(record: dict[str, Any]) -> None:
    """Check the type and range of every field of an ``ogcp.plan/1`` record that the simulation reads.

    Fields it does not read (``method``, ``bound``, ``status``, ``stats``, ``config``,
    ``provenance``, ...) are left to their readers, which are lenient by design.

    Raises:
        OgcpError: ``plan field <key path>: expected ..., got ...`` for the first bad field.
    """
    for path in ("contact_set", "contact_set.source", "contact_set.mesh", "source", "contacts"):
        _block(record, path, dict)
    for path in ("grasp", "top", "runs"):
        _block(record, path, list)
    for i, run in enumerate(_field(record, "runs") or []):
        if not isinstance(run, dict):
            raise OgcpError(f"plan field runs[{i}]: expected an object with a grasp, got {_show_short(run)}")
    for path, declared in _NUMBERS.items():
        value = _field(record, path)
        # NaN is written as null, so a quality may be null; mu, k and the size never are.
        if value is not None or (path.startswith("contact_set.") and _present(record, path)):
            declared.check(f"plan field {path}", value)
    com = _field(record, "contact_set.com")
    if com is not None and not _point(com):
        raise OgcpError(f"plan field contact_set.com: expected [x, y, z] of finite numbers, got {_show_short(com)}")
    for path in ("contacts.positions", "contacts.normals", "contact_set.positions", "contact_set.normals"):
        _rows(record, path)
    for where in ("contact_set.source", "source"):
        source = _field(record, where) or {}
        for key, expected in _SOURCE.items():
            value = source.get(key)
            if value is None and (key not in source or key not in ("n", "seed", "sampling")):
                continue  # absent, or null where null means none (no tip, a mesh at its own size)
            if isinstance(expected, Option):
                expected.check(f"plan field {where}.{key}", value)
            elif not isinstance(value, expected):
                raise OgcpError(f"plan field {where}.{key}: expected a string, got {_show_short(value)}")
