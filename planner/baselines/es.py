"""Exhaustive search (ES): the exact Q1 of every m-grasp of distinct contacts.

All C(|C|, m) grasps are split into chunks of consecutive lexicographic ranks, so the split
depends only on (|C|, m, chunk size), never on the number of workers. Each chunk takes the
batched path: support-function upper bounds for all its grasps at once (a bound at or
below the force-closure tolerance *proves* Q1 = 0), then the exact engine for the rest.
Every grasp's exact Q1 lands in the histogram, so ``es`` evaluates every grasp; the
``es-pruned`` variant also skips grasps whose bound cannot beat the chunk's best and
reports no histogram. The two are separate methods and never mixed.

The argmax is the largest Q1, ties broken by the lexicographically smallest indices.
With a checkpoint directory every finished chunk is written atomically as it completes,
and a rerun with the same parameters resumes from them with the identical answer; each
chunk is checked before it is reused (:mod:`ogcp.planner.baselines.es_checkpoint`).
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ogcp.planner.config.methods import ESConfig, ESPrunedConfig
from ogcp.planner.config.options import TIME_LIMIT, check_values
from ogcp.planner.grasp.constraints import Constraint, accepts_many
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel import FALLBACK, OK, default_directions, support_table
from ogcp.planner.grasp.kernel.geometry import CUT_MARGIN
from ogcp.planner.grasp.quality import exact_q1_batch, q1_certificate
from ogcp.planner.infra.errors import NoGraspError, OgcpError, SearchTimeout
from ogcp.planner.infra.heartbeat import Heartbeat
from ogcp.planner.infra.parallel import DEFAULT_BACKEND, DEFAULT_JOBS, run_tasks, validate_backend
from ogcp.planner.infra.provenance import provenance
from ogcp.planner.records.plan import check_result, histogram_record, plan_record

from . import combinations
from .es_checkpoint import ChunkResult, ChunkSpace, ChunkStore

ES_METHODS = (ESConfig.method, ESPrunedConfig.method)
#: What an exhaustive search's result certifies: the optimum, or (past its time limit) the best of
#: the grasps it covered.
ES_STATUSES = ("optimal", "stopped")
#: Grasps handed to the compiled kernel in one call inside a chunk.
BOUND_BLOCK = 50_000
#: es-pruned: grasps per kernel call between updates of the cut.
PRUNE_BATCH = 32
#: Grasps in a chunk's first block when it has a deadline; blocks double while they are quick.
FIRST_TIMED_BLOCK = 64
#: [s] Longest a block of a chunk with a deadline should take: how late a chunk may stop.
TIMED_BLOCK_SECONDS = 0.25
#: [s] How long past its deadline a chunk may look for a first admissible grasp (a stopped run
#: then has one to return, as a stopped search has its dive).
FIRST_GRASP_GRACE = 0.5


@dataclass(frozen=True, eq=False)
class ESResult:
    """Result of exhaustive search.

    Attributes:
        method: ``es`` or ``es-pruned``.
        grasp: Sorted indices of the best grasp (lexicographically smallest among ties).
        positions: Its contact points, shape (m, 3) [m].
        normals: Its inward normals, shape (m, 3).
        q1: Its Q1 [-].
        q_ows: Q1 of all contacts [-]; the histogram spans [0, q_ows].
        grasps: Number of grasps C(|C|, m).
        bin_edges: Histogram bin edges over (0, q_ows], shape (bins + 1,).
        counts: Force-closure grasps per bin (``es`` only).
        zero: Grasps with Q1 = 0 (``es`` only).
        excluded: Grasps that fail a constraint (not in the histogram or the argmax).
        exact_evaluations: Grasps whose Q1 needed an exact hull (the compiled expanding
            polytope, or qhull where it could not certify); the rest were settled by the
            support table or, for es-pruned, by a bound below the cut.
        chunks: Number of chunks; ``resumed`` of them came from the checkpoint.
        resumed: Chunks read back from the checkpoint.
        cpu_seconds: CPU time summed over workers, resumed chunks included [s].
        wall_seconds: Wall time of this run [s].
        config: Parameters of the run.
        evaluated: Grasps covered (evaluated or excluded); fewer than ``grasps`` when the run
            stopped at its time limit.
        status: ``optimal``, or ``stopped`` at the time limit: then ``grasp`` is the best of
            the grasps covered and the optimum is only known to be at most Q_OWS (``bound``).
    """

    method: str
    grasp: tuple[int, ...]
    positions: NDArray[np.float64]
    normals: NDArray[np.float64]
    q1: float
    q_ows: float
    grasps: int
    bin_edges: NDArray[np.float64]
    counts: NDArray[np.int64] | None
    zero: int | None
    excluded: int
    exact_evaluations: int
    chunks: int
    resumed: int
    cpu_seconds: float
    wall_seconds: float
    config: dict[str, Any]
    evaluated: int | None = None
    status: str = "optimal"

    def __post_init__(self) -> None:
        """Refuse impossible values: OgcpError unless 0 <= q1 <= bound <= q_ows (``check_result``)."""
        if self.status not in ES_STATUSES:
            raise OgcpError(f"ES status must be one of {', '.join(ES_STATUSES)}, got {self.status!r}")
        check_result(self.method, self.q1, self.q_ows, self.bound)

    @property
    def bound(self) -> float:
        """Certified upper bound on the optimal Q1 [-]: Q1 itself once every grasp is evaluated,
        else Q_OWS (no grasp's hull reaches past the hull of all contacts)."""
        return self.q1 if self.status == "optimal" else self.q_ows

    @property
    def force_closure_fraction(self) -> float | None:
        """Fraction of the admissible grasps covered that are in force closure (``es`` only)."""
        admissible = (self.grasps if self.evaluated is None else self.evaluated) - self.excluded
        return None if self.zero is None or admissible == 0 else 1.0 - self.zero / admissible

    def to_dict(self, contact_set: dict[str, Any] | None = None) -> dict[str, Any]:
        """JSON form, schema ``ogcp.plan/1`` (with ES statistics and the histogram)."""
        histogram = None
        if self.counts is not None:
            histogram = histogram_record(self.bin_edges, self.counts, self.zero, self.force_closure_fraction)
        stats = {
            "grasps": self.grasps,
            "excluded_by_constraints": self.excluded,
            "exact_evaluations": self.exact_evaluations,
            "chunks": self.chunks,
            "resumed_chunks": self.resumed,
            "cpu_seconds": self.cpu_seconds,
            "wall_seconds": self.wall_seconds,
            "evaluated_grasps": self.grasps if self.evaluated is None else self.evaluated,
        }
        return plan_record(
            self.method,
            self.grasp,
            self.q1,
            self.q_ows,
            self.bound,
            self.positions,
            self.normals,
            stats=stats,
            config=self.config,
            contact_set=contact_set,
            eps=0.0,
            histogram=histogram,
            status=self.status,
            gap=self.bound - self.q1,
        )


def _chunk_task(
    contacts: ContactSet,
    m: int,
    index: int,
    chunk: int,
    edges: NDArray[np.float64],
    pruned: bool,
    constraints: Sequence[Constraint] = (),
    deadline: float | None = None,
) -> ChunkResult:
    """Evaluate one chunk (runs in a worker process).

    With a ``deadline`` (a ``time.time()`` reading) the chunk goes in blocks that grow from
    :data:`FIRST_TIMED_BLOCK` grasps while each takes under :data:`TIMED_BLOCK_SECONDS`, and it
    stops at the first block boundary past the deadline once it has an admissible grasp (or
    :data:`FIRST_GRASP_GRACE` later): its result then covers fewer grasps than the chunk
    (``evaluated``), and the caller keeps it out of the checkpoint.
    """
    cpu0 = time.process_time()
    wrenches = np.asarray(contacts.wrenches)
    n = len(contacts)
    start = index * chunk
    stop = min(start + chunk, combinations.count(n, m))
    counts = np.zeros(len(edges) - 1, dtype=np.int64)
    zero = exact = excluded = 0
    best_q, best_g = 0.0, None
    first: tuple[int, ...] | None = None  # the chunk's first admissible grasp
    table = support_table(wrenches, default_directions())

    def evaluate(batch: NDArray[np.int64], cut: float) -> NDArray[np.float64]:
        """Q1 of the grasps (exact at or above ``cut``, an upper bound below it)."""
        nonlocal exact
        values, status = exact_q1_batch(wrenches, batch, table, cut)
        exact += int(np.count_nonzero((status == OK) | (status == FALLBACK)))
        return values

    size = BOUND_BLOCK if deadline is None else FIRST_TIMED_BLOCK
    rank = start
    while rank < stop:
        # A chunk past the deadline still evaluates one block, and goes on for a short grace
        # while none of its grasps was admissible, so that a stopped run has a grasp to return.
        late = -1.0 if deadline is None or rank == start else time.time() - deadline
        if late > 0 and (first is not None or late > FIRST_GRASP_GRACE):
            break
        began = time.perf_counter()
        end = min(rank + size, stop)
        block = combinations.combinations_range(n, m, rank, end)
        for constraint in constraints:  # P(g) filters the grasps before any quality is computed
            block = block[accepts_many(constraint, block, contacts)]
        excluded += end - rank - len(block)
        rank = end
        if len(block) and first is None:
            first = tuple(int(c) for c in block[0])
        if pruned:
            # Branch and bound: highest support bound first, the running best as the cut.
            upper = table[block].max(axis=1).min(axis=1)
            order = np.argsort(-upper, kind="stable")
            for at in range(0, len(order), PRUNE_BATCH):
                batch = np.sort(order[at : at + PRUNE_BATCH])
                # The margin keeps a grasp whose canonical Q1 ties the best (a rounding
                # error above its true value) in play for the lexicographic tie-break.
                if upper[order[at]] < best_q - CUT_MARGIN:
                    break
                values = evaluate(block[batch], best_q)
                best_q, best_g = _better(values, block[batch], best_q, best_g)
        elif len(block):
            values = evaluate(block, 0.0)
            zero += int(np.sum(values <= 0))
            positive = values[values > 0]
            bins = np.minimum(np.searchsorted(edges, positive, side="right") - 1, len(counts) - 1)
            counts += np.bincount(bins, minlength=len(counts))
            best_q, best_g = _better(values, block, best_q, best_g)
        if deadline is not None and time.perf_counter() - began < TIMED_BLOCK_SECONDS / 2:
            size = min(2 * size, BOUND_BLOCK)
    if best_g is None:
        # No grasp of the chunk is in force closure: all tie at 0, and the first admissible
        # one is the lexicographically smallest.
        best_g = first
    return ChunkResult(
        index, best_q, best_g, counts.tolist(), zero, excluded, rank - start, exact, time.process_time() - cpu0
    )


def _better(
    values: NDArray[np.float64], grasps: NDArray[np.int64], best_q: float, best_g: tuple[int, ...] | None
) -> tuple[float, tuple[int, ...] | None]:
    """The incumbent after ``grasps`` (in lexicographic order): ties go to the smaller grasp."""
    if not np.any(values > 0):
        return best_q, best_g
    top = float(values.max())
    grasp = tuple(int(c) for c in grasps[int(np.flatnonzero(values == top)[0])])
    if top > best_q or (top == best_q and (best_g is None or grasp < best_g)):
        return top, grasp
    return best_q, best_g


class ExhaustiveSearch:
    """Exhaustive search over all m-grasps, in parallel, resumable.

    Args:
        pruned: Skip grasps whose bound cannot beat the best (method ``es-pruned``; no
            histogram).
        jobs: Worker processes.
        backend: ``loky`` or ``dask``.
        address: Dask scheduler ``HOST:PORT``.
        checkpoint: Directory for finished chunks (resume); None keeps nothing on disk.
        chunk: Grasps per chunk.
        bins: Histogram bins over (0, Q_OWS].
        progress: Show a progress bar with an ETA on stderr.
        constraints: Grasp constraints P(g); grasps that fail are excluded (the count is
            reported) from the argmax and the histogram.
        time_limit: Wall-clock budget [s]: chunks stop within a block of it (a quarter of a
            second) and no chunk starts after it; the result is then the best grasp covered,
            status ``stopped``. None: unlimited.
        lines: Where a progress line goes every 30 s (a log, off a terminal); None: none.
    """

    def __init__(
        self,
        pruned: bool = False,
        jobs: int = DEFAULT_JOBS,
        backend: str = DEFAULT_BACKEND,
        address: str | None = None,
        checkpoint: str | Path | None = None,
        chunk: int = ESConfig.chunk,
        bins: int = ESConfig.bins,
        progress: bool = False,
        constraints: Sequence[Constraint] = (),
        time_limit: float | None = None,
        lines: Callable[[str], None] | None = None,
    ) -> None:
        self.time_limit = time_limit
        self.lines = lines
        self.pruned = pruned
        self.constraints = constraints
        self.jobs = jobs
        self.backend = backend
        self.address = address
        self.checkpoint = checkpoint
        self.chunk = chunk
        self.bins = bins
        self.progress = progress

    def run(self, contacts: ContactSet, m: int) -> ESResult:
        """Evaluate every grasp (or those the time limit allows) and return the best with the histogram.

        Raises:
            OgcpError: For invalid parameters, a checkpoint of a different run, or one whose
                chunks fail their checksum or consistency checks.
            SearchTimeout: When the time limit ends the run before any admissible grasp was
                evaluated.
        """
        provenance()  # recorded now: the commit and versions of the code that runs
        validate_backend(self.backend, self.address, self.jobs)
        n = len(contacts)
        if not isinstance(m, (int, np.integer)) or m < 2 or m > n:
            raise OgcpError(f"m must be an integer with 2 <= m <= |C| = {n}, got {m!r}")
        check_values(ESConfig, chunk=self.chunk, bins=self.bins)
        if self.time_limit is not None:
            TIME_LIMIT.check("time_limit", self.time_limit)
        wall0 = time.perf_counter()
        deadline = None if self.time_limit is None else time.time() + self.time_limit
        q_ows = q1_certificate(contacts.wrenches.reshape(-1, 6)).q1
        edges = np.linspace(0.0, q_ows, self.bins + 1) if q_ows > 0 else np.linspace(0.0, 1.0, self.bins + 1)
        total = combinations.count(n, int(m))
        n_chunks = -(-total // self.chunk)
        config = {
            "method": ESPrunedConfig.method if self.pruned else ESConfig.method,
            "m": int(m),
            "chunk": self.chunk,
            "bins": self.bins,
            "jobs": self.jobs,
            "backend": self.backend,
            "contact_set_digest": _digest(contacts),
            "constraints": [c.describe() for c in self.constraints],
        }
        space = ChunkSpace(contacts, int(m), self.chunk, edges, q_ows, self.pruned, tuple(self.constraints))
        store = ChunkStore(
            self.checkpoint,
            {k: config[k] for k in ("method", "m", "chunk", "bins", "contact_set_digest", "constraints")},
        )
        done = store.load(space)
        constraints = tuple(self.constraints)

        def tasks() -> Iterator[tuple[Any, ...]]:
            """The chunks still to do, listed as workers take them; after the deadline none but a first."""
            started = False
            for index in range(n_chunks):
                if started and deadline is not None and time.time() > deadline:
                    return
                if index not in done:
                    started = True
                    yield (contacts, int(m), index, self.chunk, edges, self.pruned, constraints, deadline)

        covered = sum(r.evaluated for r in done.values())
        bar = tqdm(total=total, unit="grasp", unit_scale=True, disable=not self.progress, desc=config["method"])
        bar.update(covered)
        results, partial = dict(done), []

        def line() -> str:
            best = max((r.best_q1 for r in list(results.values())), default=0.0)  # a copy: the work adds to it
            return (
                f"{config['method']}: {covered:.4g} of {total:.4g} grasps ({100 * covered / total:.2g} %), "
                f"best Q1 {best:.6f}, {time.perf_counter() - wall0:.0f} s elapsed"
            )

        try:
            with Heartbeat(self.lines, line):
                for result in run_tasks(_chunk_task, tasks(), self.jobs, self.backend, self.address):
                    if result.evaluated == space.size(result.index):
                        store.save(result)
                        results[result.index] = result
                    else:  # cut short by the deadline: its best counts, its grasps are not all done
                        partial.append(result)
                    covered += result.evaluated
                    bar.update(result.evaluated)
        finally:
            bar.close()
        return self._merge(contacts, int(m), space, results, partial, len(done), config, wall0)

    def _merge(
        self,
        contacts: ContactSet,
        m: int,
        space: ChunkSpace,
        results: dict[int, ChunkResult],
        partial: list[ChunkResult],
        resumed: int,
        config: dict[str, Any],
        wall0: float,
    ) -> ESResult:
        every = [*(results[index] for index in sorted(results)), *partial]
        best_q, best_g = -1.0, None
        for r in every:
            if r.best_grasp is not None and (
                best_g is None or r.best_q1 > best_q or (r.best_q1 == best_q and r.best_grasp < best_g)
            ):
                best_q, best_g = r.best_q1, r.best_grasp
        evaluated = sum(r.evaluated for r in every)
        finished = evaluated == space.total
        if best_g is None and not finished:
            raise SearchTimeout(config["method"], self.time_limit, 0, None, space.q_ows)
        if best_g is None:
            raise NoGraspError("no grasp satisfies the constraints")
        idx = np.array(best_g, dtype=np.intp)
        counts = np.sum([r.counts for r in every], axis=0).astype(np.int64)
        return ESResult(
            method=config["method"],
            grasp=best_g,
            positions=contacts.positions[idx].copy(),
            normals=contacts.normals[idx].copy(),
            q1=best_q,
            q_ows=space.q_ows,
            grasps=space.total,
            bin_edges=space.edges,
            counts=None if self.pruned else counts,
            zero=None if self.pruned else int(sum(r.zero for r in every)),
            excluded=int(sum(r.excluded for r in every)),
            exact_evaluations=int(sum(r.exact_evaluations for r in every)),
            chunks=len(results),
            resumed=resumed,
            cpu_seconds=float(sum(r.cpu_seconds for r in every)),
            wall_seconds=time.perf_counter() - wall0,
            config=config,
            evaluated=evaluated,
            status="optimal" if finished else "stopped",
        )


def _digest(contacts: ContactSet) -> str:
    h = hashlib.sha256()
    for array in (contacts.positions, contacts.normals, contacts.com):
        h.update(np.ascontiguousarray(array).tobytes())
    h.update(repr((contacts.torque_scale, contacts.mu, contacts.cone_edges)).encode())
    if contacts.torsional_friction:  # hard sets keep the digests their checkpoints were written with
        h.update(repr(contacts.torsional_friction).encode())
    return h.hexdigest()[:16]
