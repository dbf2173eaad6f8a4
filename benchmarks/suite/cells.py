"""Running one suite cell: contact set, method, optional simulation, one result record.

:func:`run_cell` is what worker processes execute. It never raises for a failing method
or simulation: the failure is recorded in the cell (``status = "error"``, the message and
the traceback's tail) and the suite goes on. Contact sets and hand models are cached per
process, so a worker that runs many cells on one object samples its contacts once.

An external cell (``method = "external"``) plans nothing: its grasps come from an
``ogcp.grasps/1`` file, scored with ogcp's Q1 and simulated by ``ogcp.sim_eval.evaluate_grasps``,
and its plan record (:func:`external_plan`) reports the best of them, so every reader of
plan records takes it as it takes a planner's.
"""

from __future__ import annotations

import datetime
import time
from functools import lru_cache
from pathlib import Path
from typing import Any

from ogcp.benchmarks.suite.config import EXTERNAL_METHOD, Cell, best_grasp
from ogcp.benchmarks.suite.record import CellError, CellRecord
from ogcp.planner.config.options import MEMORY_LIMIT
from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.grasp.quality import q1_certificate
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import method_spec
from ogcp.planner.methods.runners import RunOptions
from ogcp.planner.objects import file_sha256, resolve_object
from ogcp.planner.records.grasps import ExternalGrasps, load_grasps
from ogcp.planner.records.plan import contact_set_record
from ogcp.planner.records.plan import plan_record as build_plan_record
from ogcp.planner.search.result import UNFINISHED

#: Keys of the [simulation] table that are arguments of evaluate_plan, not simulation settings.
SIMULATION_ARGUMENTS = ("decomposition", "max_grasps")
#: ``status`` of an external cell's plan: grasps given, not searched (nothing is certified).
EXTERNAL_STATUS = "external"


def run_cell(
    cell: Cell,
    simulation: dict[str, Any] | None = None,
    time_limit: float | None = None,
    memory_limit: float | None = MEMORY_LIMIT.default,
) -> dict[str, Any]:
    """Run one cell and return its JSON-ready record.

    Args:
        cell: The cell.
        simulation: Settings passed to ``ogcp.sim_eval.evaluate_plan`` (the suite's
            ``[simulation]`` table without ``enabled``); None skips the simulation.
        time_limit: Wall-clock budget of a planning cell (any method) [s]; past it the cell is
            recorded with status ``stopped`` and the best grasp found, its certified bound
            and gap (a ``SearchTimeout`` error when it had found none).
            None: unlimited.
        memory_limit: Most memory of a search cell, all its processes [GiB]; past it the
            cell is recorded like one past its time limit, with status ``memory``
            (:mod:`ogcp.planner.search.memory`). None: unlimited.

    Returns:
        The JSON form of its :class:`~ogcp.benchmarks.suite.record.CellRecord` (schema ``ogcp.cell/1``).
    """
    wall0, cpu0 = time.perf_counter(), time.process_time()
    plan = sim = sim_seconds = error = None
    try:
        if cell.method == EXTERNAL_METHOD:
            plan, sim, sim_seconds = run_external(cell, simulation)
        else:
            plan = plan_record(cell, contact_set(cell), time_limit, memory_limit)
        if simulation is not None and sim is None:
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
        cell.torsional_friction,
    )


@lru_cache(maxsize=8)
def _contacts(
    spec: str,
    diagonal: float | None,
    n: int,
    seed: int,
    mu: float,
    cone_edges: int,
    tip_radius: float | None,
    torsion: float = 0.0,
) -> ContactSet:
    """Sample a cell's contacts; ``tip_radius`` None is the object's default fingertip, 0 plain sampling [m]."""
    mesh, source = resolve_object(spec, diagonal)
    radius = default_tip_radius(mesh) if tip_radius is None else tip_radius
    return sample_contacts(mesh, n, seed, mu, cone_edges, source, tip_radius=radius, torsional_friction=torsion)


def plan_record(
    cell: Cell,
    contacts: ContactSet,
    time_limit: float | None = None,
    memory_limit: float | None = MEMORY_LIMIT.default,
) -> dict[str, Any]:
    """Run the cell's method and return its ``ogcp.plan/1`` record (the same record ``ogcp plan`` writes).

    Raises:
        OgcpError: For parameters the installed planner does not support.
    """
    spec = method_spec(cell.method)
    options = RunOptions(time_limit=time_limit, memory_limit=memory_limit, contact_seed=cell.contact_seed)
    config = spec.config(**dict(cell.variant))
    attempts = getattr(config, "realise", None)
    if attempts is None:
        return spec.run(config, contacts, cell.m, options).record
    from ogcp.sim_eval.realise import realise  # the hand's fit: MuJoCo, only for such cells

    return realise(attempts, options, lambda given: spec.run(config, contacts, cell.m, given)).record


def external_grasps(cell: Cell) -> ExternalGrasps:
    """The grasps file of an external cell, as the suite read it.

    Raises:
        OgcpError: For a cell of a planner, or a file that changed since the suite was read (its
            results would be recorded under the old content's id).
    """
    if cell.grasps_path is None:
        raise OgcpError(f"cell {cell.id} ({cell.method}) has no grasps file; only method {EXTERNAL_METHOD!r} has one")
    sha = dict(cell.variant)["grasps"]
    if file_sha256(Path(cell.grasps_path)) != sha:
        raise OgcpError(f"grasps file {cell.grasps_path} changed since the suite was read; run the suite again")
    return load_grasps(cell.grasps_path)


def run_external(
    cell: Cell, simulation: dict[str, Any] | None
) -> tuple[dict[str, Any], dict[str, Any] | None, float | None]:
    """An external cell's plan record, and its simulation unless ``simulation`` is None.

    Returns:
        The plan record, the ``ogcp.sim/2`` record of every grasp (None unsimulated) and its
        wall time [s] (None unsimulated).

    Raises:
        OgcpError: For a changed or invalid file, or contacts off the object's surface.
    """
    # Lazy: MuJoCo loads only when a suite has external grasps (their Q1 needs the surface checks).
    from ogcp.sim_eval.evaluate import object_diagonal, tip_radius
    from ogcp.sim_eval.external import evaluate_grasps, external_input
    from ogcp.sim_eval.settings import SimSettings

    grasps = external_grasps(cell)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    options = dict(simulation or {})
    extra = {key: options.pop(key) for key in SIMULATION_ARGUMENTS if key in options}
    mesh, source = grasps.load_object()
    # The same fingertip and surface tolerance as the simulation, so the plan's contacts are the simulated ones.
    radius = tip_radius(mesh, SimSettings.from_dict(options).scaled(object_diagonal(mesh)))
    given = external_input(mesh, grasps, radius, source=source)
    plan = external_plan(cell, grasps, given.contacts, given.grasps, given.q1)
    plan["stats"] = {"wall_seconds": time.perf_counter() - wall0, "cpu_seconds": time.process_time() - cpu0}
    if simulation is None:
        return plan, None, None
    sim0 = time.perf_counter()
    sim = evaluate_grasps(None, grasps, options, extra.get("decomposition"), max_grasps=extra.get("max_grasps"))
    return plan, sim.to_dict(), time.perf_counter() - sim0


def external_plan(
    cell: Cell,
    grasps: ExternalGrasps,
    contacts: ContactSet,
    indices: tuple[tuple[int, ...], ...],
    q1: tuple[float, ...],
) -> dict[str, Any]:
    """The ``ogcp.plan/1`` record of external grasps: the best one (by score, else the first) as the grasp.

    Its ``bound`` is Q_OWS, the Q1 of every given contact together: nothing is certified.

    Args:
        cell: The external cell.
        grasps: Its grasps file.
        contacts: Every grasp's contacts in one set (``ogcp.sim_eval.external.external_input``).
        indices: Each grasp's indices into ``contacts``.
        q1: ogcp's Q1 of each grasp [-].
    """
    best = best_grasp(grasps)
    grasp = indices[best]
    q_ows = q1_certificate(contacts.wrenches.reshape(-1, 6)).q1
    rows = list(grasp)
    top = [
        {"grasp": list(g), "q1": q, "label": given.label, "method": grasps.method_of(given), "score": given.score}
        for g, q, given in zip(indices, q1, grasps.grasps, strict=True)
    ]
    return build_plan_record(
        EXTERNAL_METHOD,
        grasp,
        q1[best],
        q_ows,
        q_ows,
        contacts.positions[rows],
        contacts.normals[rows],
        {},
        {"grasps": dict(cell.variant)["grasps"], "file": cell.grasps_path, "index": best},
        contact_set_record(contacts),
        status=EXTERNAL_STATUS,
        label=grasps.grasps[best].label,
        external=top,
    )


def simulate(plan: dict[str, Any], settings: dict[str, Any]) -> dict[str, Any]:
    """The ``ogcp.sim/1`` record of a plan, from ``ogcp.sim_eval.evaluate_plan``.

    Args:
        plan: The ``ogcp.plan/1`` record.
        settings: Simulation settings; ``decomposition`` (a table) and ``max_grasps`` go to
            ``evaluate_plan`` as their own arguments.
    """
    from ogcp.sim_eval import evaluate_plan  # lazy: MuJoCo loads only when a suite simulates

    options = dict(settings)
    extra = {key: options.pop(key) for key in SIMULATION_ARGUMENTS if key in options}
    return evaluate_plan(plan, options, **extra).to_dict()
