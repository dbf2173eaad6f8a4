"""The result record of one suite cell (schema ``ogcp.cell/1``), written and read here.

:func:`ogcp.benchmarks.suite.cells.run_cell` builds a :class:`CellRecord` and the runner appends its
:meth:`~CellRecord.to_dict` to ``results.jsonl``; the runner, ``ogcp compare`` and ``ogcp plot``
read lines back with :meth:`CellRecord.from_dict`. The record holds the cell's ``params`` block
(built by :class:`CellParams`, read through :class:`CellRecord`'s accessors), its ``ogcp.plan/1``
record (owned by :mod:`ogcp.planner.records.plan`, read through :attr:`CellRecord.plan_view`) and its
``ogcp.sim/1`` record (owned by :mod:`ogcp.sim_eval.result`) as they were written.
"""

from __future__ import annotations

import traceback
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from ogcp.benchmarks.suite.store import CELL_SCHEMA, jsonable
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.plan import PlanView

#: Lines of a failing cell's traceback kept in its record.
TRACEBACK_LINES = 15
#: Params that make two cells plan on the same contact set: object, |C|, contact seed, m, mu, k, diagonal
#: and the fingertip radius the contacts were kept for (absent, so None, for plain sampling).
PROBLEM_FIELDS = (
    "object",
    "contacts",
    "contact_seed",
    "m",
    "mu",
    "cone_edges",
    "diagonal",
    "tip_radius",
    "torsional_friction",
)

Problem = tuple[Any, ...]


@dataclass(frozen=True)
class CellParams:
    """The ``params`` block of a cell record: what the cell ran. Its keys are these field names.

    Attributes:
        object: The object as the suite names it (name or mesh path).
        contacts: Number of contacts n.
        contact_seed: Seed of the contact sampling (None for external grasps: nothing is sampled).
        m: Number of fingers.
        mu: Friction coefficient.
        cone_edges: Friction-cone edges k.
        diagonal: Bounding-box diagonal [m] (None for a mesh file at its own size).
        method: Method name.
        variant: The method's canonical parameters.
        label: Label for tables and plots.
        tip_radius: Fingertip radius the contacts were kept for: ``"default"`` (the
            simulation's default fingertip of the object), a radius [m], or None for the
            paper's plain sampling (then the key is left out, as in records made before it).
        torsional_friction: Torsional friction coefficient of soft fingers [m]; None for hard
            fingers (the key is left out, and so is ``contact_model``, as in records made before it).
    """

    object: str
    contacts: int
    contact_seed: int | None
    m: int
    mu: float
    cone_edges: int
    diagonal: float | None
    method: str
    variant: Mapping[str, Any]
    label: str
    tip_radius: float | str | None = None
    torsional_friction: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the record's ``params`` object): the :data:`PROBLEM_FIELDS` first, then the rest in field order."""
        values = {f.name: dict(self.variant) if f.name == "variant" else getattr(self, f.name) for f in fields(self)}
        if self.tip_radius is None:
            del values["tip_radius"]  # plain sampling: the params of plain cells are unchanged
        if self.torsional_friction is None:
            del values["torsional_friction"]  # hard fingers: the params of hard cells are unchanged
        else:
            values["contact_model"] = "soft"
        order = [name for name in PROBLEM_FIELDS if name in values]
        return {name: values[name] for name in [*order, *(k for k in values if k not in order)]}


@dataclass(frozen=True)
class CellError:
    """Why a cell failed.

    Attributes:
        type: The exception's class name.
        message: The first line of its message.
        traceback: The last :data:`TRACEBACK_LINES` lines of its traceback.
    """

    type: str
    message: str
    traceback: str

    @classmethod
    def from_exception(cls, exc: BaseException) -> CellError:
        """The record of an exception, with the traceback it carries."""
        lines = "".join(traceback.format_exception(exc)).rstrip().splitlines()
        return cls(type(exc).__name__, (str(exc).strip().splitlines() or [""])[0], "\n".join(lines[-TRACEBACK_LINES:]))

    def to_dict(self) -> dict[str, str]:
        """JSON form (the record's ``error`` object)."""
        return {"type": self.type, "message": self.message, "traceback": self.traceback}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CellError:
        """Read an ``error`` object; a missing key reads as ``""`` (``"error"`` for the type)."""
        return cls(str(data.get("type", "error")), str(data.get("message", "")), str(data.get("traceback", "")))


@dataclass(frozen=True)
class CellRecord:
    """The record of one cell: what ran, how it ended, the plan and the simulation.

    Attributes:
        id: The cell id (stable hash of its parameters).
        params: The cell's ``params`` block (:meth:`CellParams.to_dict`).
        groups: Names of the suite groups that list the cell.
        status: ``"ok"``, ``"error"``, or ``"stopped"`` (a search cell past the time limit:
            its plan is the best grasp found, with a certified bound and gap).
        error: Why it failed (``status`` error), else None.
        plan: The ``ogcp.plan/1`` record, None when planning failed.
        simulation: The ``ogcp.sim/1`` record, None without simulation or when it failed.
        simulation_seconds: Wall time of the simulation [s].
        wall_seconds: Wall time of the whole cell [s].
        cpu_seconds: CPU time of the whole cell in its worker [s].
        finished_at: UTC time the cell finished (ISO 8601, seconds).
    """

    id: str
    params: dict[str, Any]
    groups: tuple[str, ...] = ()
    status: str = "ok"
    error: CellError | None = None
    plan: dict[str, Any] | None = None
    simulation: dict[str, Any] | None = None
    simulation_seconds: float | None = None
    wall_seconds: float | None = None
    cpu_seconds: float | None = None
    finished_at: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form, schema ``ogcp.cell/1`` (numpy values as Python values, NaN as None)."""
        return jsonable(
            {
                "schema": CELL_SCHEMA,
                "id": self.id,
                "params": self.params,
                "groups": list(self.groups),
                "status": self.status,
                "error": None if self.error is None else self.error.to_dict(),
                "plan": self.plan,
                "simulation": self.simulation,
                "simulation_seconds": self.simulation_seconds,
                "wall_seconds": self.wall_seconds,
                "cpu_seconds": self.cpu_seconds,
                "finished_at": self.finished_at,
            }
        )

    @classmethod
    def from_dict(cls, data: Any) -> CellRecord:
        """Read one line of ``results.jsonl``.

        Only what every reader needs is checked: an id, a ``params`` object and a status.
        Other keys that are missing or of the wrong type read as None or empty.

        Raises:
            OgcpError: For anything but a JSON object with those three.
        """
        if not isinstance(data, dict) or not isinstance(data.get("id"), str):
            raise OgcpError("not a cell record with an id")
        params, status = data.get("params"), data.get("status")
        if not isinstance(params, dict) or not isinstance(status, str):
            raise OgcpError(f"record {data['id']} has no params/status: not a cell record")
        error, plan, simulation, groups = (
            data.get("error"),
            data.get("plan"),
            data.get("simulation"),
            data.get("groups"),
        )
        return cls(
            id=data["id"],
            params=params,
            groups=tuple(str(g) for g in groups) if isinstance(groups, list) else (),
            status=status,
            error=CellError.from_dict(error) if isinstance(error, dict) else None,
            plan=plan if isinstance(plan, dict) else None,
            simulation=simulation if isinstance(simulation, dict) else None,
            simulation_seconds=_seconds(data.get("simulation_seconds")),
            wall_seconds=_seconds(data.get("wall_seconds")),
            cpu_seconds=_seconds(data.get("cpu_seconds")),
            finished_at=str(data["finished_at"]) if data.get("finished_at") is not None else None,
        )

    @property
    def ok(self) -> bool:
        """The cell finished without error."""
        return self.status == "ok"

    @property
    def method(self) -> str | None:
        """The planning method of ``params`` (None when absent)."""
        method = self.params.get("method")
        return None if method is None else str(method)

    @property
    def object(self) -> str:
        """The object spec of ``params``."""
        return str(self.params.get("object"))

    @property
    def contacts(self) -> int | None:
        """The number of contacts of ``params`` (None when absent)."""
        return _integer(self.params.get("contacts"))

    @property
    def contact_seed(self) -> int | None:
        """The contact seed of ``params`` (None when absent)."""
        return _integer(self.params.get("contact_seed"))

    @property
    def m(self) -> int | None:
        """The number of fingers of ``params`` (None when absent)."""
        return _integer(self.params.get("m"))

    @property
    def label(self) -> str | None:
        """The method label of ``params`` (None when absent or empty)."""
        return str(self.params["label"]) if self.params.get("label") else None

    @property
    def variant(self) -> dict[str, Any]:
        """The method's parameters (``params.variant``; empty when absent)."""
        variant = self.params.get("variant")
        return variant if isinstance(variant, dict) else {}

    @property
    def problem(self) -> Problem:
        """The :data:`PROBLEM_FIELDS` of ``params``: the contact set and m the cell plans on."""
        return tuple(self.params.get(name) for name in PROBLEM_FIELDS)

    @property
    def plan_view(self) -> PlanView | None:
        """Typed read access to the plan, None when planning failed."""
        return None if self.plan is None else PlanView(self.plan)

    def describe(self) -> str:
        """``object n=|C| seed=s m=m label``, for one-line messages."""
        return f"{self.object} n={self.contacts} seed={self.contact_seed} m={self.m} {self.label}"


def _integer(value: Any) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _seconds(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None
