"""Running one suite cell: contact set, method, optional simulation, one result record.

:func:`run_cell` is what worker processes execute. It never raises for a failing method
or simulation: the failure is recorded in the cell (``status = "error"``, the message and
the traceback's tail) and the suite goes on. Contact sets and hand models are cached per
process, so a worker that runs many cells on one object samples its contacts once.
"""

from __future__ import annotations

import datetime
import time
from functools import lru_cache
from typing import Any

from benchmarks.suite.config import Cell
from benchmarks.suite.record import CellError, CellRecord
from planner.grasp.contact_set import ContactSet, sample_contacts
from planner.grasp.reach import default_tip_radius
from planner.methods.registry import method_spec
from planner.methods.runners import RunOptions
from planner.objects import resolve_object
from planner.search.result import UNFINISHED

#: Keys of the [simulation] table that are arguments of evaluate_plan, not simulation settings.
SIMULATION_ARGUMENTS = ("decomposition", "max_grasps")


def run_cell(cell: Cell, simulation: dict[str, Any] | None = None, time_limit: float | None = None) -> dict[str, Any]:
    """Run one cell and return its JSON-ready record.

    Args:
        cell: The cell.
        simulation: Settings passed to ``sim_eval.evaluate_plan`` (the suite's
            ``[simulation]`` table without ``enabled``); None skips the simulation.
        time_limit: Wall-clock budget of a search cell (astar, wastar, dijkstra) [s]; past
            it the cell is recorded with status ``stopped`` and the best grasp found, its
            certified bound and gap (a ``SearchTimeout`` error when it had found none).
            None: unlimited.

    Returns:
        The JSON form of its :class:`~benchmarks.suite.record.CellRecord` (schema ``ogcp.cell/1``).
    """
    wall0, cpu0 = time.perf_counter(), time.process_time()
    plan = sim = sim_seconds = error = None
    try:
        plan = plan_record(cell, contact_set(cell), time_limit)
        if simulation is not None:
            sim0 = time.perf_counter()
            sim = simulate(plan, simulation)
            sim_seconds = time.perf_counter() - sim0
    except Exception as exc:  # noqa: BLE001 - a failing cell is data, never the end of the suite
        error = CellError.from_exception(exc)
    return CellRecord(
        id=cell.id,
        params=cell.params(),
        groups=tuple(cell.groups),
        status="error" if error is not None else cell_status(plan),
        error=error,
        plan=plan,
        simulation=sim,
        simulation_seconds=sim_seconds,
        wall_seconds=time.perf_counter() - wall0,
        cpu_seconds=time.process_time() - cpu0,
        finished_at=datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    ).to_dict()


def cell_status(plan: dict[str, Any] | None) -> str:
    """``stopped`` for the plan of a search that did not finish (time limit), else ``ok``."""
    return "stopped" if plan is not None and plan.get("status") in UNFINISHED else "ok"


def contact_set(cell: Cell) -> ContactSet:
    """The cell's contact set (cached per process)."""
    return _contacts(
        cell.object.path or cell.object.spec,
        cell.diagonal,
        cell.contacts,
        cell.contact_seed,
        cell.mu,
        cell.cone_edges,
        cell.tip_radius,
    )


@lru_cache(maxsize=8)
def _contacts(
    spec: str, diagonal: float | None, n: int, seed: int, mu: float, cone_edges: int, tip_radius: float | None
) -> ContactSet:
    """Sample a cell's contacts; ``tip_radius`` None is the object's default fingertip, 0 plain sampling [m]."""
    mesh, source = resolve_object(spec, diagonal)
    radius = default_tip_radius(mesh) if tip_radius is None else tip_radius
    return sample_contacts(mesh, n, seed, mu, cone_edges, source, tip_radius=radius)


def plan_record(cell: Cell, contacts: ContactSet, time_limit: float | None = None) -> dict[str, Any]:
    """Run the cell's method and return its ``ogcp.plan/1`` record (the same record ``ogcp plan`` writes).

    Raises:
        OgcpError: For parameters the installed planner does not support.
    """
    spec = method_spec(cell.method)
    options = RunOptions(time_limit=time_limit, contact_seed=cell.contact_seed)
    return spec.run(spec.config(**dict(cell.variant)), contacts, cell.m, options).record


def simulate(plan: dict[str, Any], settings: dict[str, Any]) -> dict[str, Any]:
    """The ``ogcp.sim/1`` record of a plan, from ``sim_eval.evaluate_plan``.

    Args:
        plan: The ``ogcp.plan/1`` record.
        settings: Simulation settings; ``decomposition`` (a table) and ``max_grasps`` go to
            ``evaluate_plan`` as their own arguments.
    """
    from sim_eval import evaluate_plan  # lazy: MuJoCo loads only when a suite simulates

    options = dict(settings)
    extra = {key: options.pop(key) for key in SIMULATION_ARGUMENTS if key in options}
    return evaluate_plan(plan, options, **extra).to_dict()
