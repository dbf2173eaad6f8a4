"""External grasps beside the planners: which planner problem an external cell is drawn with.

An external cell (suite ``method = "external"``, :data:`ogcp.benchmarks.suite.config.EXTERNAL_METHOD`)
brings its own contacts, so its problem (|C|, no contact seed, the file's m) is never a planner
cell's. Figures that compare methods per problem would draw it alone; these helpers put it with
the planner problem of the same object at the same size and friction instead (its *host*): the
one with the same m, else the first, preferring one with an A* cell. An external cell without a
host keeps its own problem.
"""

from __future__ import annotations

from ogcp.benchmarks.suite.config import EXTERNAL_METHOD
from ogcp.benchmarks.suite.record import PROBLEM_FIELDS, Problem

from .data import CellData, RunData

#: The problem fields a host shares with an external cell: the same object, size and friction
#: (mu and contact model: a hard cell leaves ``torsional_friction`` out, so both read None).
SHARED = tuple(PROBLEM_FIELDS.index(name) for name in ("object", "diagonal", "mu", "torsional_friction"))
_M = PROBLEM_FIELDS.index("m")


def is_external(cell: CellData) -> bool:
    """Whether the cell is another planner's grasps (``method = "external"``)."""
    return cell.method == EXTERNAL_METHOD


def host_problems(data: RunData) -> dict[str, Problem]:
    """For each external cell with a host, by cell id, the planner problem it is drawn with.

    Args:
        data: The run.

    Returns:
        Cell id -> host problem; external cells without a host are not keys.
    """
    planned = data.by_problem([c for c in data.cells if not is_external(c)])
    hosts = {}
    for cell in data.cells:
        if not is_external(cell):
            continue
        shared = [p for p in planned if all(p[i] == cell.problem[i] for i in SHARED)]
        if shared:
            # Same m first, then a problem with an A* cell, then the first (sorted is stable).
            ranked = sorted(
                shared,
                key=lambda p: (p[_M] != cell.problem[_M], not any(c.method == "astar" for c in planned[p])),
            )
            hosts[cell.id] = ranked[0]
    return hosts


def by_problem_with_external(data: RunData) -> dict[Problem, list[CellData]]:
    """:meth:`RunData.by_problem`, with each external cell after the cells of its host problem.

    Args:
        data: The run.

    Returns:
        Problem -> cells, problems in order of first appearance (external cells without a host
        under their own problem).
    """
    hosts = host_problems(data)
    groups: dict[Problem, list[CellData]] = {}
    for cell in data.cells:
        if cell.id not in hosts:
            groups.setdefault(cell.problem, []).append(cell)
    for cell in data.cells:
        if cell.id in hosts:
            groups[hosts[cell.id]].append(cell)
    return groups
