"""Running a suite into an output folder, resumably, serially or in parallel.

Cells are independent: they run through :func:`ogcp.planner.infra.parallel.run_tasks` (serial,
local processes or a Dask cluster) and the main process appends each finished record
to ``results.jsonl``, so the folder is the same whatever ran the cells, apart from the
order of the lines and the timings. ``resume`` skips cells whose id is already recorded
and refuses a folder written by a different suite (another hash).

The suite's own process compiles (or loads) the numba kernels its methods call before any cell
starts, and every process that runs cells loads them before its first cell
(:func:`_run_warm_cell`), so no cell's times include numba's compilation; the seconds each
process spent on it go to the session's ``kernel_warmup_seconds`` in ``manifest.json``.
Progress goes to stderr: a bar on a terminal, else an opening line, one line per finished cell
at most every ``interval`` seconds (``lines="periodic"``) or one per cell (``lines="each"``),
and a line whenever 30 s pass without one (:mod:`ogcp.benchmarks.suite.progress`).
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from ogcp.benchmarks.suite.cells import run_cell
from ogcp.benchmarks.suite.config import Suite
from ogcp.benchmarks.suite.manifest import (
    ManifestSuite,
    first_commit,
    new_manifest,
    session_record,
    with_kernel_warmup,
    with_session,
)
from ogcp.benchmarks.suite.progress import Meter, number
from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.select import Selection, is_selected, parse_selection
from ogcp.benchmarks.suite.store import LOCK, ResultStore
from ogcp.planner.config.options import JOBS, MEMORY_LIMIT, TIME_LIMIT
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.parallel import run_tasks, validate_backend
from ogcp.planner.search.memory import states_budget

#: Progress line modes: none, one line per finished cell at most every ``interval`` s, every cell.
PROGRESS_LINES = ("none", "periodic", "each")

#: The kernel families this process has warmed; a lock because Dask runs cells in threads.
_WARM_LOCK = threading.Lock()
_WARMED: set[str] = set()


def _warm_up_once(methods: Sequence[str], announce: Callable[[str], None] | None = None) -> float | None:
    """Warm the kernels the methods call that this process has not warmed yet.

    The suite's own process warms up first, before any worker starts: on a cold cache it
    compiles (announcing it) and the workers then only load numba's cache. Only the families
    the suite's methods call (:func:`ogcp.planner.methods.warm_up.families_for`) are warmed.

    Returns:
        The seconds it took, None if this process had already warmed them.
    """
    # Lazy: the runner module stays importable without numba loaded.
    from ogcp.planner.methods.warm_up import families_for, warm_up

    with _WARM_LOCK:
        families = set(families_for(methods))
        if families <= _WARMED:
            return None
        seconds = warm_up(methods, announce=announce)
        _WARMED.update(families)
        return seconds


def _run_warm_cell(methods: Sequence[str], *task: Any) -> tuple[dict[str, Any], int, float | None]:
    """:func:`run_cell` after the kernel warm-up of this process for the suite's methods (first call only).

    Returns:
        The cell's record, this process's id and its warm-up seconds (None: done before).
    """
    warmup = _warm_up_once(methods)
    return run_cell(*task), os.getpid(), warmup


@dataclass(frozen=True)
class RunSummary:
    """Outcome of :meth:`SuiteRunner.run`.

    Attributes:
        cells: Cells in the suite.
        skipped: Cells already recorded (resume) and not rerun.
        ran: Cells run now.
        errors: Cells recorded as errors, over the whole folder.
        remaining: Cells still to run (``max_cells`` stopped the run).
        records: id -> latest record of every recorded cell of the suite.
    """

    cells: int
    skipped: int
    ran: int
    errors: int
    remaining: int
    records: dict[str, dict[str, Any]]


class SuiteRunner:
    """Runs a suite's cells into an output folder.

    Args:
        suite: The validated suite.
        out: Output folder; must be empty or absent unless ``resume``.
        jobs: Worker processes (1: serial in this process).
        backend: ``loky`` or ``dask``.
        address: Dask scheduler ``HOST:PORT``.
        resume: Continue the run recorded in ``out`` (same suite hash), skipping its finished cells.
        retry_errors: With ``resume``, also rerun cells recorded as errors (the new record supersedes).
        max_cells: Stop after running this many cells (the rest: a later ``resume``).
        time_limit: Wall-clock budget of each planning cell [s] (an execution policy, not part
            of the suite: a cell past it is recorded as stopped, to rerun with
            ``retry_errors`` and a larger limit). None: unlimited.
        memory_limit: Most memory of each search cell, all its processes [GiB]
            (:mod:`ogcp.planner.search.memory`); a cell past it is recorded like one past its time
            limit. None: unlimited.
        only: Run only the cells matching these ``KEY=VALUE[,VALUE...]`` items
            (:mod:`ogcp.benchmarks.suite.select`); the others stay for a later ``resume``.
        progress: Show a progress bar on stderr (for a terminal).
        lines: Progress lines on stderr, one of :data:`PROGRESS_LINES`: ``none``;
            ``periodic``: done/total, errors, elapsed and ETA after a finished cell, at most
            every ``interval`` seconds, and after the last; ``each``: one line per cell
            (its description, Q1 and wall seconds). Errors are reported in every mode.
        interval: Least seconds between two ``periodic`` lines.
        log: Where one-line notices go (default: stderr).
    """

    def __init__(
        self,
        suite: Suite,
        out: str | Path,
        jobs: int = 1,
        backend: str = "loky",
        address: str | None = None,
        resume: bool = False,
        retry_errors: bool = False,
        max_cells: int | None = None,
        only: Sequence[str] = (),
        time_limit: float | None = None,
        memory_limit: float | None = MEMORY_LIMIT.default,
        progress: bool = False,
        lines: str = "none",
        interval: float = 10.0,
        log: Callable[[str], None] | None = None,
    ) -> None:
        self.suite = suite
        self.out = Path(out)
        self.jobs = jobs
        self.backend = backend
        self.address = address
        self.resume = resume
        self.retry_errors = retry_errors
        self.max_cells = max_cells
        self.only = tuple(only)
        self.time_limit = time_limit
        self.memory_limit = memory_limit
        self.progress = progress
        self.lines = lines
        self.interval = interval
        self.log = log or (lambda text: print(text, file=sys.stderr))

    def run(self) -> RunSummary:
        """Run every cell not yet recorded and return the summary.

        Raises:
            OgcpError: For invalid options, a non-empty folder without ``resume``, a folder
                of another suite, or a folder in use.
        """
        validate_backend(self.backend, self.address, self.jobs)
        if self.backend != "dask":  # a Dask cluster decides its own workers
            JOBS.check("jobs", self.jobs)
        if self.lines not in PROGRESS_LINES:
            raise OgcpError(f"lines must be one of {', '.join(PROGRESS_LINES)}, got {self.lines!r}")
        if self.retry_errors and not self.resume:
            raise OgcpError("--retry-errors applies with --resume only")
        if self.max_cells is not None and (not isinstance(self.max_cells, int) or self.max_cells < 1):
            raise OgcpError(f"max_cells must be an integer >= 1, got {self.max_cells!r}")
        selection = parse_selection(self.only, self.suite.cells)
        if self.time_limit is not None:
            try:
                TIME_LIMIT.check("time_limit", self.time_limit)
            except OgcpError:
                raise OgcpError(
                    f"time_limit must be a number of seconds {TIME_LIMIT.bounds()}, got {self.time_limit!r}"
                ) from None
        if self.memory_limit is not None:  # each cell's search runs in one process
            states_budget(MEMORY_LIMIT.check("memory_limit", self.memory_limit), 1)
        store = ResultStore(self.out)
        fresh = _is_fresh(self.out)
        if not fresh and not self.resume:
            raise OgcpError(
                f"{self.out} is not empty; pass --resume to continue the run recorded there, or choose another --out"
            )
        if not fresh and not store.manifest_path.exists():
            raise OgcpError(f"{self.out} holds no manifest.json: not an ogcp suite folder; choose another --out")
        with store.lock():
            manifest = self._check_manifest(store, fresh)
            cut = store.cut_partial_tail()
            if cut:
                self.log(f"ogcp: removed an incomplete last line ({cut} bytes) from {store.results_path}")
            report = store.read()
            for problem in report.problems:
                self.log(f"ogcp: warning: {problem}")
            return self._run_cells(store, manifest, report.latest(), selection)

    def _check_manifest(self, store: ResultStore, fresh: bool) -> dict[str, Any]:
        manifest = None if fresh else store.read_manifest()
        session = session_record(
            self.jobs,
            self.backend,
            self.address,
            self.resume,
            self.retry_errors,
            self.max_cells,
            self.only,
            self.time_limit,
            self.memory_limit,
        )
        if manifest is None:
            manifest = new_manifest(self.suite, session)
        else:
            recorded = ManifestSuite.of(manifest)
            digest = recorded.hash if recorded else None
            if digest != self.suite.hash:
                held = f"{self.out} holds suite {recorded.name if recorded else None!r} with hash {digest}"
                if digest == self.suite.without_simulation().hash:
                    raise OgcpError(f"{held}, run with --no-simulation; resume with --no-simulation too")
                raise OgcpError(f"{held}; this suite's hash is {self.suite.hash}: the suite changed, use another --out")
            first = first_commit(manifest)
            if first != session["git_commit"]:
                self.log(
                    f"ogcp: warning: resuming with git commit {session['git_commit']}; the run started with {first}"
                )
            manifest = with_session(manifest, session)
        store.write_manifest(manifest)
        return manifest

    def _run_cells(
        self, store: ResultStore, manifest: dict[str, Any], done: dict[str, dict[str, Any]], selection: Selection
    ) -> RunSummary:
        ids = {c.id for c in self.suite.cells}
        stray = set(done) - ids
        if stray:
            self.log(f"ogcp: warning: {len(stray)} records in {store.results_path} are not cells of this suite")
        done = {k: v for k, v in done.items() if k in ids}
        todo = [c for c in self.suite.cells if c.id not in done or (self.retry_errors and _failed(done[c.id]))]
        skipped = len(self.suite.cells) - len(todo)
        todo = [c for c in todo if is_selected(c, selection)]
        if self.max_cells is not None:
            todo = todo[: self.max_cells]
        missing = [n for n in self.suite.unfetched_objects() if any(c.object.spec == n for c in todo)]
        if missing:
            self.log(
                f"ogcp: warning: objects not fetched yet: {', '.join(missing)}; their cells will be recorded "
                f"as errors (run `ogcp assets fetch {' '.join(missing)}`, then --resume --retry-errors)"
            )
        settings = {k: v for k, v in self.suite.simulation.items() if k != "enabled"} if self.suite.simulate else None
        records = dict(done)
        bar = tqdm(
            total=len(self.suite.cells), initial=skipped, unit="cell", desc=self.suite.name, disable=not self.progress
        )
        # On a terminal the lines go above the bar (tqdm.write), else through the log.
        say = (lambda text: tqdm.write(text, file=sys.stderr)) if self.progress else self.log
        meter = Meter(self.suite.name, len(self.suite.cells), skipped, len(todo), self.lines, self.interval, say)
        meter.started()
        warmups: dict[int, float] = {}
        try:
            with meter.heartbeat():
                limits = (self.time_limit, self.memory_limit)
                methods = tuple(sorted({cell.method for cell in todo}))
                tasks = [(methods, cell, settings if cell.simulate else None, *limits) for cell in todo]
                if tasks:
                    warmup = _warm_up_once(methods, say)
                    warmups[os.getpid()] = warmup if warmup is not None else warmups.get(os.getpid(), 0.0)
                finished = (
                    run_tasks(_run_warm_cell, tasks, self.jobs, self.backend, self.address) if tasks else iter(())
                )
                for line, pid, warmup in finished:
                    # A process already warm from an earlier run in it (loky reuses its workers) compiled nothing.
                    warmups[pid] = warmup if warmup is not None else warmups.get(pid, 0.0)
                    store.append(line)
                    records[line["id"]] = line
                    bar.update()
                    record = CellRecord.from_dict(line)
                    if record.error is not None:
                        say(
                            f"ogcp: cell {record.id} ({record.describe()}) failed: "
                            f"{record.error.type}: {record.error.message}"
                        )
                    elif record.status == "stopped" and record.plan_view is not None:
                        view = record.plan_view
                        say(
                            f"ogcp: cell {record.id} ({record.describe()}) stopped at its time limit: "
                            f"best Q1 {number(view.q1)}, optimum <= {number(view.bound)}"
                        )
                    meter.finished(record)
        finally:
            bar.close()
            if warmups:  # also after an interruption: the cells recorded so far ran warm
                store.write_manifest(with_kernel_warmup(manifest, list(warmups.values())))
        errors = sum(1 for r in records.values() if _failed(r))
        return RunSummary(
            len(self.suite.cells), skipped, len(todo), errors, len(self.suite.cells) - len(records), records
        )


def summary_table(suite: Suite, records: dict[str, dict[str, Any]]) -> str:
    """One line per object and label: cells done, errors, best Q1, summed wall seconds."""
    rows: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for cell in suite.cells:
        rows.setdefault((cell.object.spec, cell.label), [])
        if cell.id in records:
            rows[(cell.object.spec, cell.label)].append(records[cell.id])
    totals = {key: sum(1 for c in suite.cells if (c.object.spec, c.label) == key) for key in rows}
    width = max([len(label) for _, label in rows] + [6])
    lines = [f"{'object':<12} {'method':<{width}} {'done':>9} {'errors':>6} {'best Q1':>10} {'wall s':>9}"]
    for (obj, label), done in rows.items():
        found = [r for r in map(_parsed, done) if r is not None]
        views = [r.plan_view for r in found if r.ok]
        values = [q1 for v in views if v is not None and (q1 := v.q1) is not None]
        best = f"{max(values):10.6f}" if values else f"{'-':>10}"
        errors = sum(1 for r in found if r.status in ("error", "stopped"))
        wall = sum(r.wall_seconds or 0.0 for r in found)
        lines.append(
            f"{obj:<12} {label:<{width}} {f'{len(done)}/{totals[(obj, label)]}':>9} {errors:>6} {best} {wall:9.2f}"
        )
    return "\n".join(lines)


def _parsed(line: dict[str, Any]) -> CellRecord | None:
    """The cell record of a ``results.jsonl`` line, None for a line that is not one."""
    try:
        return CellRecord.from_dict(line)
    except OgcpError:
        return None


def _failed(line: dict[str, Any]) -> bool:
    """Whether a ``results.jsonl`` line records a cell to rerun: an error, or a search that stopped."""
    record = _parsed(line)
    return record is not None and record.status in ("error", "stopped")


def _is_fresh(directory: Path) -> bool:
    """Absent, or holding nothing but a lock file left by an earlier attempt."""
    if directory.exists() and not directory.is_dir():
        raise OgcpError(f"--out {directory} is a file, not a folder")
    try:
        return not directory.exists() or all(p.name == LOCK for p in directory.iterdir())
    except OSError as exc:  # a path through a file, or a folder that cannot be listed
        raise OgcpError(f"cannot use --out {directory}: {exc.strerror or exc}") from exc
