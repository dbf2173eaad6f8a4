"""Tidy long tables of a suite run (``ogcp export RUN``), for pandas, R or a spreadsheet.

From the ``--out`` folder of ``ogcp suite`` (the latest record of each cell in
``results.jsonl``) this writes:

* ``grasps.csv``: one row per cell and simulated grasp (a cell without simulated grasps, or
  one that failed, gives one row with the grasp columns empty), with the cell's parameters,
  its plan (Q1, Q_OWS, bound, times) and the grasp's simulation (validity, minimum measured
  and predicted resistance, fidelity);
* ``directions.csv``: one row per cell, simulated grasp and disturbance direction, with the
  direction and its measured and predicted resistance;
* ``columns.md``: the column dictionary (unit and meaning of every column).

Records are read through :class:`ogcp.benchmarks.suite.record.CellRecord`,
:class:`ogcp.planner.records.plan.PlanView` and :class:`ogcp.sim_eval.result.SimRecord`; every file is
written atomically. ``fmt="parquet"`` writes ``.parquet`` tables instead, with pyarrow (not a
dependency of ogcp).
"""

from __future__ import annotations

import csv
import importlib
import io
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner.infra.atomic import write_bytes_atomic, write_text_atomic
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.sim_eval.result import SimGraspRecord, SimRecord

FORMATS = ("csv", "parquet")

_Q1 = "dimensionless"
#: How Q1 is measured, stated once in the column dictionary.
Q1_UNIT_NOTE = (
    "Q1, Q_OWS and the bound are dimensionless: wrenches are built from friction-cone edges of unit "
    "normal force, with torques divided by the torque scale rho [m], so Q1 is the wrench-space radius "
    "per unit grip force (times a grip force in N, a force in N). Resistances are loads in N along a "
    "direction of the same scaled wrench space: a force [N] and a torque [N·m] per unit load."
)

#: (column, unit, meaning) of the cell columns that lead both tables.
CELL_COLUMNS = (
    ("cell", "", "cell id (stable hash of the cell's parameters)"),
    ("object", "", "object spec (built-in name or fetched object)"),
    ("method", "", "planning method"),
    ("label", "", "method label of the suite (the table row of ogcp suite's summary)"),
    ("m", "", "fingers (contacts per grasp)"),
    ("contacts", "", "contacts sampled on the object, |C|"),
    ("contact_seed", "", "seed of the contact sampling"),
)
#: (column, unit, meaning) of ``grasps.csv`` after :data:`CELL_COLUMNS`.
GRASP_COLUMNS = (
    ("mu", "", "friction coefficient of the cones"),
    ("cone_edges", "", "edges per linearised friction cone, k"),
    ("contact_model", "", "hard (point contacts) or soft (with torsional friction)"),
    ("torsional_friction", "m", "torsional friction coefficient of soft fingers (0 for hard)"),
    ("groups", "", "suite groups listing the cell, ';'-separated"),
    ("status", "", "cell status: ok, error or stopped (search past its time limit)"),
    ("error", "", "error type of a failed cell"),
    ("q1", _Q1, "Q1 of the cell's best grasp"),
    ("q_ows", _Q1, "Q1 of the whole contact set, an upper bound of every grasp's Q1"),
    ("bound", _Q1, "certified upper bound on the optimum Q1 of the contact set and m"),
    ("plan_cpu_seconds", "s", "CPU time of the method (no sampling, caches or simulation)"),
    ("cell_wall_seconds", "s", "wall time of the whole cell"),
    ("cell_cpu_seconds", "s", "CPU time of the whole cell in its worker"),
    ("simulation_seconds", "s", "wall time of the cell's simulation"),
    ("grasp", "", "simulated grasp label (best, hfts-run-3, ...); empty: no simulated grasp"),
    ("grasp_contacts", "", "contact indices of the simulated grasp, space-separated"),
    ("grasp_q1", _Q1, "Q1 of the simulated grasp (planned contacts)"),
    ("realized_q1", _Q1, "Q1 at the contacts the fingertips reached"),
    ("q1_change", "", "relative change of Q1 from planned to realized contacts"),
    ("valid", "", "the preload passed every validity gate (true/false; empty: not recorded)"),
    ("sim_error", "", "why the grasp could not be simulated"),
    ("measured_min", "N", "smallest measured resistance over the directions (empty unless all measured)"),
    ("predicted_min", "N", "smallest predicted (analytic) resistance over the directions"),
    ("median_fidelity", "", "median over directions of |measured / predicted - 1|"),
    ("n_directions", "", "disturbance directions simulated (rows of directions.csv)"),
)
#: (column, unit, meaning) of ``directions.csv`` after :data:`CELL_COLUMNS`.
DIRECTION_COLUMNS = (
    ("grasp", "", "simulated grasp label"),
    ("valid", "", "the grasp passed every validity gate"),
    ("direction", "", "direction label"),
    *(
        (f"u_{axis}", "", f"direction component {axis} (unit vector in scaled wrench space)")
        for axis in ("fx", "fy", "fz", "tx", "ty", "tz")
    ),
    ("measured", "N", "measured resistance: load at which the grasp let go (empty: not measured)"),
    ("predicted", "N", "predicted (analytic) resistance at the realized contacts"),
    ("predicted_planned", "N", "predicted resistance at the planned contacts"),
    ("censored", "", "held to the end of the load ramp: measured is a lower bound"),
    ("fidelity", "", "|measured / predicted - 1|"),
)


def export_run(run_dir: str | Path, out_dir: str | Path | None = None, fmt: str = "csv") -> list[Path]:
    """Write the tidy tables and the column dictionary of a suite run.

    Args:
        run_dir: The ``--out`` folder of ``ogcp suite``.
        out_dir: Where the tables go (created; default: ``run_dir``).
        fmt: ``csv``, or ``parquet`` (needs pyarrow).

    Returns:
        The files written: the two tables, then ``columns.md``.

    Raises:
        OgcpError: For an unknown format, parquet without pyarrow, or a folder that is not a
            suite run.
    """
    if fmt not in FORMATS:
        raise choice_error("format", fmt, FORMATS)
    writer = _csv_bytes if fmt == "csv" else _parquet_writer()
    records = _records(run_dir)
    out = Path(run_dir if out_dir is None else out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OgcpError(f"cannot create --out {out}: {exc.strerror or exc}") from None
    tables = {
        "grasps": (CELL_COLUMNS + GRASP_COLUMNS, [row for r in records for row in grasp_rows(r)]),
        "directions": (CELL_COLUMNS + DIRECTION_COLUMNS, [row for r in records for row in direction_rows(r)]),
    }
    written = []
    for name, (columns, rows) in tables.items():
        path = out / f"{name}.{fmt}"
        write_bytes_atomic(path, writer([c[0] for c in columns], rows))
        written.append(path)
    path = out / "columns.md"
    write_text_atomic(path, column_dictionary())
    return [*written, path]


def grasp_rows(record: CellRecord) -> Iterator[dict[str, Any]]:
    """The ``grasps.csv`` rows of one cell: one per simulated grasp, or one without a grasp."""
    view = record.plan_view
    cell = {
        **_cell(record),
        "mu": _float(record.params.get("mu")),
        "cone_edges": record.params.get("cone_edges"),
        "contact_model": record.params.get("contact_model", "hard"),
        "torsional_friction": _float(record.params.get("torsional_friction", 0.0)),
        "groups": ";".join(record.groups),
        "status": record.status,
        "error": None if record.error is None else record.error.type,
        "q1": view.q1 if view else None,
        "q_ows": view.q_ows if view else None,
        "bound": view.bound if view else None,
        "plan_cpu_seconds": view.cpu_seconds if view else None,
        "cell_wall_seconds": record.wall_seconds,
        "cell_cpu_seconds": record.cpu_seconds,
        "simulation_seconds": record.simulation_seconds,
    }
    grasps: list[SimGraspRecord | None] = [*_grasps(record)]
    for grasp in grasps or [None]:
        yield {**cell, **_grasp(grasp)}


def direction_rows(record: CellRecord) -> Iterator[dict[str, Any]]:
    """The ``directions.csv`` rows of one cell: one per simulated grasp and direction."""
    cell = _cell(record)
    for grasp in _grasps(record):
        for i, label in enumerate(grasp.direction_labels):
            vector = grasp.directions[i] if i < len(grasp.directions) else [None] * 6
            yield {
                **cell,
                "grasp": grasp.label,
                "valid": grasp.valid,
                "direction": label,
                **{f"u_{a}": _float(v) for a, v in zip(("fx", "fy", "fz", "tx", "ty", "tz"), vector, strict=True)},
                "measured": _at(grasp.measured, i),
                "predicted": _at(grasp.predicted, i),
                "predicted_planned": _at(grasp.predicted_planned, i),
                "censored": bool(grasp.censored[i]) if i < len(grasp.censored) else None,
                "fidelity": _at(grasp.fidelity, i),
            }


def column_dictionary() -> str:
    """``columns.md``: every table's columns with unit and meaning (Markdown)."""
    lines = ["# Columns of the ogcp export tables", "", Q1_UNIT_NOTE, ""]
    for name, columns in (("grasps", CELL_COLUMNS + GRASP_COLUMNS), ("directions", CELL_COLUMNS + DIRECTION_COLUMNS)):
        lines += [f"## {name}", "", "| column | unit | meaning |", "| --- | --- | --- |"]
        # A pipe inside a cell (|C|, |measured / predicted - 1|) would end it: escape it.
        lines += [
            f"| {column} | {unit or '-'} | {meaning.replace('|', chr(92) + '|')} |" for column, unit, meaning in columns
        ]
        lines.append("")
    return "\n".join(lines)


def _records(run_dir: str | Path) -> list[CellRecord]:
    """The latest record of every cell of a run, sorted by object, label, contact set, m and id."""
    store = ResultStore(run_dir)
    if not store.results_path.is_file():
        raise OgcpError(f"{run_dir}: no results.jsonl (expected the --out folder of ogcp suite)")
    read = store.read()
    if not read.records and read.problems:
        raise OgcpError(f"{store.results_path}: no cell record this ogcp can read ({read.problems[0]})")
    latest: dict[str, CellRecord] = {}
    for line in read.records:
        try:
            record = CellRecord.from_dict(line)
        except OgcpError as exc:
            raise OgcpError(f"{store.results_path}: {exc}") from None
        latest[record.id] = record  # a rerun cell's newer record supersedes
    return sorted(
        latest.values(),
        key=lambda r: (r.object, r.label or "", r.contacts or 0, r.contact_seed or 0, r.m or 0, r.id),
    )


def _cell(record: CellRecord) -> dict[str, Any]:
    return {
        "cell": record.id,
        "object": record.object,
        "method": record.method,
        "label": record.label,
        "m": record.m,
        "contacts": record.contacts,
        "contact_seed": record.contact_seed,
    }


def _grasps(record: CellRecord) -> list[SimGraspRecord]:
    return [] if record.simulation is None else list(SimRecord.from_dict(record.simulation).grasps)


def _grasp(grasp: SimGraspRecord | None) -> dict[str, Any]:
    if grasp is None:
        return {}  # a missing key writes as an empty field
    return {
        "grasp": grasp.label,
        "grasp_contacts": None if grasp.grasp is None else " ".join(map(str, grasp.grasp)),
        "grasp_q1": grasp.q1,
        "realized_q1": grasp.q1_realized,
        "q1_change": grasp.q1_change,
        "valid": grasp.valid,
        "sim_error": grasp.error,
        "measured_min": grasp.measured_min,
        "predicted_min": grasp.predicted_min,
        "median_fidelity": grasp.median_fidelity,
        "n_directions": len(grasp.direction_labels),
    }


def _float(value: Any) -> float | None:
    """A finite number as float; anything else (None, NaN, text) as None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) + 0.0 if math.isfinite(value) else None  # + 0.0: -0.0 writes as 0.0


def _at(values: Any, i: int) -> float | None:
    return _float(float(values[i])) if i < len(values) else None


def _csv_bytes(columns: list[str], rows: list[dict[str, Any]]) -> bytes:
    """CSV with a header; None as an empty field, booleans as true/false, floats round-tripping."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_field(row.get(c)) for c in columns])
    return buffer.getvalue().encode("utf-8")


def _field(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def _parquet_writer() -> Callable[[list[str], list[dict[str, Any]]], bytes]:
    """A writer of parquet tables; raises OgcpError when pyarrow is not installed."""
    try:
        pa = importlib.import_module("pyarrow")
        pq = importlib.import_module("pyarrow.parquet")
    except ImportError:
        raise OgcpError(
            "--format parquet needs pyarrow, not installed: pip install pyarrow (or use --format csv)"
        ) from None

    def write(columns: list[str], rows: list[dict[str, Any]]) -> bytes:
        table = pa.Table.from_pydict({c: [row.get(c) for row in rows] for c in columns})
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        return bytes(sink.getvalue().to_pybytes())

    return write
