"""One best-first search on several cores: the grasps dealt to parts, a process each.

:mod:`ogcp.planner.search.deal` splits the grasps into disjoint parts. Part 0 runs in the calling
process and the others in child interpreters (``python -m ogcp.planner.search.part_child``: no copy
of the caller's threads or locks, and no re-import of the caller's script), each a whole search
from the root that keeps only its own states. A part ends at its own goal, at the time limit or
stop request, or once nothing left in it can beat the best grasp of any part. The result is the
best part's grasp with the largest of the parts' certified bounds: proven optimal (A*) when
every part finished or was beaten. Children ignore Ctrl-C (the caller's stop request reaches
them through the shared board) and end with their parent.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import pickle
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ogcp.planner.grasp.constraints import Constraint
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import NoGraspError, OgcpError, SearchTimeout
from ogcp.planner.infra.lifetime import owned_tempdir
from ogcp.planner.search.best_first import Search
from ogcp.planner.search.deal import Board, Part, PartDone
from ogcp.planner.search.result import UNFINISHED, SearchResult, SearchStats, effective_branching_factor

#: [s] How often the caller looks at its children and its stop request while it waits.
POLL_S = 0.2
#: [s] How long a child may take to return its result once asked to stop, before it is killed.
STOP_GRACE_S = 30.0
#: Prefix of the folders that hold a run's board and arguments (see :func:`ogcp.planner.infra.lifetime.owned_tempdir`).
TEMP_PREFIX = "ogcp-search-"


@dataclass(frozen=True)
class PartOutcome:
    """How one part ended.

    Attributes:
        result: Its best grasp's result; None when it evaluated no grasp of its own.
        bound: Certified upper bound on the Q1 of its grasps [-].
        status: ``finished`` (its goal, or beaten by another part's grasp), ``stopped``,
            ``memory`` or ``interrupted``.
        stats: Its statistics.
    """

    result: SearchResult | None
    bound: float
    status: str
    stats: SearchStats


@dataclass(frozen=True)
class PartTask:
    """What a child needs to run its part (pickled to a file it reads).

    Attributes:
        contacts: The contact set C.
        m: Number of fingers.
        config: Resolved configuration.
        constraints: Grasp constraints, distinct contacts included.
        parts: Number of parts.
        deadline: Wall-clock time (``time.time()``) at which every part stops; None: none.
        memory_limit: Most bytes the part's open states may take; None: unlimited.
    """

    contacts: ContactSet
    m: int
    config: dict[str, Any]
    constraints: list[Constraint]
    parts: int
    deadline: float | None
    memory_limit: float | None = None


def run_part(search: Search) -> PartOutcome:
    """Run one part's search to its end (see the module docstring)."""
    try:
        result = search.run()
    except PartDone as done:
        return PartOutcome(None, max(0.0, min(search.q0, done.bound)), "finished", search.statistics(0))
    except SearchTimeout as timeout:
        status = "interrupted" if search.stop is not None and search.stop.is_set() else "stopped"
        return PartOutcome(None, timeout.upper_bound, "memory" if timeout.memory else status, search.statistics(0))
    status = result.status if result.status in UNFINISHED else "finished"
    return PartOutcome(result, result.bound, status, result.stats)


def search_in_parts(
    contacts: ContactSet,
    m: int,
    config: dict[str, Any],
    constraints: list[Constraint],
    jobs: int,
    time_limit: float | None = None,
    stop: threading.Event | None = None,
    on_expand: Callable[[float], object] = lambda f: None,
    on_progress: Callable[[float | None, float], object] = lambda best, bound: None,
    memory_limit: float | None = None,
) -> SearchResult:
    """One search over ``jobs`` processes (see the module docstring).

    Args:
        contacts: The contact set C.
        m: Number of fingers.
        config: Resolved configuration (:meth:`ogcp.planner.search.grasp_planner.GraspPlanner.resolved_config`).
        constraints: Grasp constraints, distinct contacts included.
        jobs: Number of parts (processes), >= 2.
        time_limit: Wall-clock budget [s]; None: unlimited.
        stop: Set to stop every part; the result then has status ``interrupted``.
        on_expand: Called with f at each expansion of part 0.
        on_progress: Called about every 0.5 s with the best Q1 of all parts (None before the
            first) and their certified bound [-].
        memory_limit: Most bytes the open states of each part may take
            (:func:`ogcp.planner.search.memory.states_budget`); None: unlimited.

    Raises:
        OgcpError: When no grasp satisfies the constraints, or a part failed.
        SearchTimeout: When stopped before any part found a valid grasp.
    """
    wall0 = time.perf_counter()
    deadline = None if time_limit is None else time.time() + time_limit
    with owned_tempdir(TEMP_PREFIX) as folder:
        board = Board.create(folder / "board", jobs)
        with open(folder / "task.pickle", "wb") as handle:
            pickle.dump(PartTask(contacts, m, config, constraints, jobs, deadline, memory_limit), handle)
        children: list[subprocess.Popen[bytes]] = []
        outcomes: list[PartOutcome] = []
        try:
            # The child imports this very planner, wherever it was imported from here.
            root = str(Path(__file__).resolve().parents[2])
            env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
            for rank in range(1, jobs):
                command = [
                    sys.executable,
                    "-m",
                    "ogcp.planner.search.part_child",
                    str(folder),
                    str(rank),
                    str(os.getpid()),
                ]
                children.append(subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, env=env))
            own_part = Part(0, board)
            search = Search(contacts, m, config, constraints, False, time_limit, stop, own_part, memory_limit)
            search.on_expand, search.on_progress = on_expand, on_progress
            own = run_part(search)
            own_part.report(own.bound)
            if own.status == "interrupted":
                board.set()  # the request ends the others (each part keeps the deadline itself)
            outcomes.append(own)
            for rank, child in enumerate(children, start=1):
                report = functools.partial(_report, own_part, search.q0, on_progress)
                outcomes.append(_wait(rank, child, board, stop, deadline, report))
        finally:
            board.set()
            for child in children:
                if child.poll() is None:
                    child.kill()  # only after a failure: every child has ended once its outcome is read
                child.wait()
                if child.stdout is not None:
                    child.stdout.close()
    return merge(outcomes, config, search.q0, time.perf_counter() - wall0, time_limit)


def _wait(
    rank: int,
    child: subprocess.Popen[bytes],
    board: Board,
    stop: threading.Event | None,
    deadline: float | None,
    report: Callable[[], object],
) -> PartOutcome:
    """A child's outcome, passing on the caller's stop request meanwhile (the child keeps the
    deadline itself)."""
    asked: float | None = None
    while True:
        try:
            output, _ = child.communicate(timeout=POLL_S)
            break
        except subprocess.TimeoutExpired:
            pass
        if stop is not None and stop.is_set():
            board.set()
            asked = time.time() if asked is None else asked
        due = min(math.inf if deadline is None else deadline, math.inf if asked is None else asked)
        if time.time() > due + STOP_GRACE_S:
            raise OgcpError(f"search part {rank} did not stop within {STOP_GRACE_S:g} s of its time limit or request")
        report()
    try:
        outcome = pickle.loads(output)
    except Exception:  # noqa: BLE001 - a child killed mid-write leaves anything behind
        raise OgcpError(f"search part {rank} ended without a result (exit code {child.returncode})") from None
    if isinstance(outcome, str):
        raise OgcpError(outcome)
    if not isinstance(outcome, PartOutcome):
        raise OgcpError(f"search part {rank} returned a {type(outcome).__name__}, not its outcome")
    board.bounds[rank] = outcome.bound
    return outcome


def _report(part: Part, q0: float, on_progress: Callable[[float | None, float], object]) -> None:
    best, bound = part.overall()
    on_progress(best, min(q0, bound))  # inf until every part has reported


def child_main(folder: Path, rank: int) -> bytes:
    """A child's part, run from ``folder`` (the board and the task); returns its pickled outcome
    or a one-line error (:mod:`ogcp.planner.search.part_child` writes it to stdout)."""
    try:
        with open(folder / "task.pickle", "rb") as handle:
            task = pickle.load(handle)
        board = Board(folder / "board", task.parts)
        limit = None if task.deadline is None else max(1e-3, task.deadline - time.time())
        part = Part(rank, board)
        search = Search(
            task.contacts, task.m, task.config, task.constraints, False, limit, board, part, task.memory_limit
        )
        return pickle.dumps(run_part(search))
    except Exception as error:  # noqa: BLE001 - every failure must reach the caller as one line
        return pickle.dumps(f"search part {rank}: {type(error).__name__}: {error}")


def merge(
    outcomes: list[PartOutcome], config: dict[str, Any], q0: float, wall_seconds: float, time_limit: float | None
) -> SearchResult:
    """The best part's result, certified by every part's bound, with the parts' statistics summed.

    Raises:
        OgcpError: When no part holds a valid grasp.
        SearchTimeout: When parts stopped before any found a valid grasp.
    """
    stopped = [o for o in outcomes if o.status in UNFINISHED]
    interrupted = any(o.status == "interrupted" for o in stopped)
    # The time limit or a request ended the run; a part past its memory limit ended only itself.
    why = "interrupted" if interrupted else "stopped" if any(o.status == "stopped" for o in stopped) else "memory"
    bound = max(o.bound for o in outcomes)
    found = [o.result for o in outcomes if o.result is not None]
    if not found:
        if stopped:
            visited = sum(o.stats.visited for o in outcomes)
            seconds = time_limit if why == "stopped" else None
            raise SearchTimeout(config["method"], seconds, visited, None, min(q0, bound), why == "memory")
        raise NoGraspError("no grasp satisfies the constraints")
    winner = max(found, key=lambda r: r.q1)  # the first of equals: the lowest part
    bound = min(q0, max(winner.q1, bound))
    if bound > winner.q1 and stopped:
        status = why
    elif config["symmetry"]:
        status = "approximate"
    else:
        status = "optimal" if bound <= winner.q1 else "bounded"
    stats = merged_stats([o.stats for o in outcomes], winner, wall_seconds)
    return dataclasses.replace(winner, bound=bound, status=status, stats=stats)


def merged_stats(parts: list[SearchStats], winner: SearchResult, wall_seconds: float) -> SearchStats:
    """The parts' statistics summed (states above the dealt depth count once per part); the
    trace is the winning part's, the wall time the whole run's."""

    def total(name: str) -> int:
        return int(sum(getattr(s, name) for s in parts))

    def per_level(name: str) -> tuple[int, ...]:
        rows = [getattr(s, name) for s in parts]
        levels = max(len(r) for r in rows)
        return tuple(sum(r[i] for r in rows if i < len(r)) for i in range(levels))

    created = total("created")
    return dataclasses.replace(
        winner.stats,
        created=created,
        visited=total("visited"),
        created_per_level=per_level("created_per_level"),
        visited_per_level=per_level("visited_per_level"),
        q1_evaluations=total("q1_evaluations"),
        q1_cache_hits=total("q1_cache_hits"),
        bound_evaluations=total("bound_evaluations"),
        bound_rejections=total("bound_rejections"),
        hull_calls=total("hull_calls"),
        pruned=total("pruned"),
        symmetric_removed=total("symmetric_removed"),
        effective_branching_factor=effective_branching_factor(created - 1, winner.stats.solution_depth),
        wall_seconds=wall_seconds,
        cpu_seconds=float(sum(s.cpu_seconds for s in parts)),
        peak_rss_bytes=total("peak_rss_bytes"),
        facet_bounds=total("facet_bounds"),
        dropped=total("dropped"),
        local_search_evaluations=total("local_search_evaluations"),
        local_search_seconds=float(sum(s.local_search_seconds for s in parts)),
        forgotten=total("forgotten"),
    )
