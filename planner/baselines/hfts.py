"""HFTS baseline: hierarchical fingertip space optimisation (Hang et al.), reimplemented.

On the same :class:`ContactSet` and the same Q1 as every other method in ogcp:

* Hierarchy: recursive k-means on ``[w * (p - com) / rho, n]`` with 12 clusters at the top
  and 4 below, ``depth = int(log4(N / 3)) - 1`` cluster levels (at least 1). A node's
  representative is the mean position and the normalised mean inward normal of its
  contacts. Below the last cluster level are the real contacts, so the search always
  ends on real contacts and reports their exact Q1.
* One run: a random top-level node per finger; at every level ``iterations`` moves, each
  moving *all* fingers at once to random siblings, accepted only if the objective
  improves; then a random child per finger, taken even if worse; no backtracking.
* Objective: the signed Q1 of the representatives (the offset of the facet nearest the
  origin, negative outside force closure; -inf for degenerate or repeated contacts),
  minus ``residual_weight`` (1.0) times the hand's reachability residual when a hand is
  modelled. The residual penalises; it does not forbid (the run reports whether its
  final grasp is within the hand's threshold).

HFTS is randomised and anytime: :class:`HFTS` runs seeds ``seed .. seed + runs - 1``
independently (in parallel) and reports each run and their spread.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.config.methods import HFTSConfig
from ogcp.planner.config.options import TIME_LIMIT, check_values
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.quality import q1, q1_certificate, signed_q1
from ogcp.planner.grasp.wrench import contact_wrenches
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.heartbeat import Heartbeat
from ogcp.planner.infra.parallel import DEFAULT_BACKEND, DEFAULT_JOBS, run_tasks, validate_backend
from ogcp.planner.infra.provenance import provenance
from ogcp.planner.records.plan import check_result, plan_record
from ogcp.planner.search.partitions import KMeansPartitioner

TOP_CLUSTERS = 12
CHILD_CLUSTERS = 4


@dataclass(frozen=True)
class HFTSRun:
    """One seeded HFTS run: its grasp, exact Q1 and, per level, the objective after the
    descent into it (start), after its moves, and how many moves were accepted.

    A run that meets its deadline (``stopped``) makes no more moves: it descends at random to
    real contacts, and its per-level lists end at the level it stopped in.
    """

    seed: int
    grasp: tuple[int, ...]
    q1: float
    start_per_level: tuple[float, ...]
    objective_per_level: tuple[float, ...]
    accepted_per_level: tuple[int, ...]
    evaluations: int
    cpu_seconds: float
    residual: float | None = None
    stopped: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {**self.__dict__, "grasp": list(self.grasp)}


@dataclass(frozen=True, eq=False)
class HFTSResult:
    """All runs of an HFTS invocation; ``grasp`` and ``q1`` are the best run's."""

    grasp: tuple[int, ...]
    q1: float
    q_ows: float
    positions: NDArray[np.float64]
    normals: NDArray[np.float64]
    runs: tuple[HFTSRun, ...]
    wall_seconds: float
    config: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Refuse impossible values: OgcpError unless 0 <= q1 <= q_ows (``check_result``)."""
        check_result(HFTSConfig.method, self.q1, self.q_ows, self.q_ows)

    @property
    def values(self) -> NDArray[np.float64]:
        """Q1 of every run [-]."""
        return np.array([r.q1 for r in self.runs])

    def summary(self) -> dict[str, float]:
        """Mean, std, max, force-closure fraction, evaluations and CPU time over the runs."""
        v = self.values
        return {
            "runs": len(v),
            "mean": float(v.mean()),
            "std": float(v.std()),
            "max": float(v.max()),
            "force_closure_fraction": float(np.mean(v > 0)),
            "q1_evaluations": int(sum(r.evaluations for r in self.runs)),
            "cpu_seconds": float(sum(r.cpu_seconds for r in self.runs)),
            "wall_seconds": self.wall_seconds,
        }

    @property
    def status(self) -> str:
        """``heuristic``, or ``stopped`` when the time limit cut a run short."""
        return "stopped" if any(r.stopped for r in self.runs) else "heuristic"

    def to_dict(self, contact_set: dict[str, Any] | None = None) -> dict[str, Any]:
        """JSON form, schema ``ogcp.plan/1``, with ``runs`` listing every run."""
        return plan_record(
            HFTSConfig.method,
            self.grasp,
            self.q1,
            self.q_ows,
            self.q_ows,  # a heuristic certifies nothing: the optimum is only known to be <= Q_OWS
            self.positions,
            self.normals,
            stats=self.summary(),
            config=self.config,
            contact_set=contact_set,
            runs=[r.to_dict() for r in self.runs],
            status=self.status,
            gap=self.q_ows - self.q1,
        )


class Hierarchy:
    """The HFTS hierarchy: nodes are contact-index arrays, level 0 = top clusters."""

    def __init__(self, contacts: ContactSet, position_weight: float, seed: int) -> None:
        n = len(contacts)
        self.depth = max(1, int(math.log(n / 3.0, 4)) - 1) if n >= 3 else 1
        top = KMeansPartitioner(contacts, TOP_CLUSTERS, 10, position_weight, seed)
        below = KMeansPartitioner(contacts, CHILD_CLUSTERS, 10, position_weight, seed)
        self.members: list[NDArray[np.intp]] = []
        self.children: list[list[int]] = []
        self.parent: list[int] = []
        self.levels: list[list[int]] = [[]]
        for part in top.split(np.arange(n, dtype=np.intp)):
            self._add(part, -1, 0)
        for level in range(1, self.depth):
            self.levels.append([])
            for node in self.levels[level - 1]:
                for part in below.split(self.members[node]):
                    self._add(part, node, level)
        positions = np.array([contacts.positions[m].mean(axis=0) for m in self.members])
        normals = np.array([contacts.normals[m].mean(axis=0) for m in self.members])
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        self.positions = positions
        self.normals = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 1e-12)

    def _add(self, members: NDArray[np.intp], parent: int, level: int) -> None:
        node = len(self.members)
        self.members.append(members)
        self.children.append([])
        self.parent.append(parent)
        self.levels[level].append(node)
        if parent >= 0:
            self.children[parent].append(node)

    def siblings(self, node: int, level: int) -> list[int]:
        """Nodes sharing the parent (the whole top level for level 0)."""
        return self.levels[0] if level == 0 else self.children[self.parent[node]]


def _signed_q1(contacts: ContactSet, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> float:
    if np.any(np.linalg.norm(normals, axis=1) < 1e-12):
        return -math.inf
    w = contact_wrenches(
        positions,
        normals,
        contacts.com,
        contacts.torque_scale,
        contacts.mu,
        contacts.cone_edges,
        contacts.torsional_friction,
    )
    return signed_q1(w.reshape(-1, 6))


def _one_run(
    contacts: ContactSet,
    tree: Hierarchy,
    m: int,
    seed: int,
    iterations: int,
    hand: Any = None,
    weight: float = 1.0,
    deadline: float | None = None,
) -> HFTSRun:
    """One HFTS run (module-level so worker processes can run it); ``deadline`` is a
    ``time.time()`` reading after which it makes no more moves."""
    cpu0 = time.process_time()
    stopped = False
    rng = np.random.default_rng(seed)
    evaluations = 0

    def objective(level: int, choice: list[int]) -> float:
        nonlocal evaluations
        if len(set(choice)) < m:
            return -math.inf
        evaluations += 1
        source = (tree.positions, tree.normals) if level < tree.depth else (contacts.positions, contacts.normals)
        positions, normals = source[0][choice], source[1][choice]
        value = _signed_q1(contacts, positions, normals)
        if hand is not None and math.isfinite(value):
            value -= weight * float(hand.residuals(positions[None], normals[None])[0])
        return value

    def other(options: list[int] | NDArray[np.intp], current: int) -> int:
        """A random option other than the current one (the current one if it is alone)."""
        pick = int(rng.choice(options))
        while pick == current and len(options) > 1:
            pick = int(rng.choice(options))
        return pick

    choice = [int(rng.choice(tree.levels[0])) for _ in range(m)]
    leaves: list[int] = []
    start_per_level: list[float] = []
    per_level: list[float] = []
    accepted_per_level: list[int] = []
    for level in range(tree.depth + 1):
        stopped = stopped or (deadline is not None and time.time() > deadline)
        if not stopped:
            value = objective(level, choice)
            start_per_level.append(value)
        accepted = 0
        for _ in range(0 if stopped else iterations):
            if deadline is not None and time.time() > deadline:
                stopped = True
                break
            if level < tree.depth:
                candidate = [other(tree.siblings(node, level), node) for node in choice]
            else:  # the real contacts of each finger's leaf cluster
                candidate = [other(tree.members[leaf], c) for leaf, c in zip(leaves, choice)]
            candidate_value = objective(level, candidate)
            if candidate_value > value:
                choice, value, accepted = candidate, candidate_value, accepted + 1
        if len(per_level) < len(start_per_level):
            per_level.append(value)
            accepted_per_level.append(accepted)
        if level + 1 < tree.depth:  # descend: a random child per finger, kept even if worse
            choice = [int(rng.choice(tree.children[node])) for node in choice]
        elif level + 1 == tree.depth:
            leaves = choice
            choice = _distinct([int(rng.choice(tree.members[node])) for node in leaves], leaves, tree, rng)
    grasp = tuple(sorted(choice))
    # The reported quality is the exact Q1 of the real contacts, in canonical order.
    final = q1(contacts.subset_wrenches(np.array(grasp))) if len(set(grasp)) == m else 0.0
    residual = None
    if hand is not None:
        residual = float(hand.residuals(contacts.positions[None, list(grasp)], contacts.normals[None, list(grasp)])[0])
    return HFTSRun(
        seed,
        grasp,
        final,
        tuple(start_per_level),
        tuple(per_level),
        tuple(accepted_per_level),
        evaluations,
        time.process_time() - cpu0,
        residual,
        stopped,
    )


def _distinct(choice: list[int], leaves: list[int], tree: Hierarchy, rng: np.random.Generator) -> list[int]:
    """``choice`` with each repeated contact replaced by another of its finger's leaf cluster, or
    of any cluster when that one is used up: m fingers never share a contact, even where m
    exceeds the clusters (HFTS itself was made for m <= 5). Unchanged, and no draw spent,
    when the contacts are already distinct."""
    if len(set(choice)) == len(choice):
        return choice
    taken: set[int] = set()
    everything = np.concatenate([tree.members[node] for node in tree.levels[-1]])
    for finger, contact in enumerate(choice):
        if contact in taken:
            free = [int(c) for c in tree.members[leaves[finger]] if int(c) not in taken]
            free = free or [int(c) for c in everything if int(c) not in taken]
            contact = int(rng.choice(free))
            choice[finger] = contact
        taken.add(contact)
    return choice


class HFTS:
    """HFTS over R independent seeded runs.

    Args:
        runs: Number of runs R; run r uses seed ``seed + r``.
        seed: First seed.
        iterations: Moves per level.
        position_weight: Weight of positions (scaled by rho) against normals in the features.
        hierarchy_seed: Seed of the k-means hierarchy (shared by all runs).
        jobs: Worker processes; ``backend`` / ``address`` as for exhaustive search.
        hand: A hand model with ``residuals(positions, normals)`` (e.g.
            :class:`ogcp.planner.hands.reachability.SDHReachability`); its residual is
            subtracted from the objective with weight ``residual_weight``.
        time_limit: Wall-clock budget of all runs [s]: past it every run stops moving and
            descends at random to real contacts (status ``stopped``). None: unlimited.
        lines: Where a progress line goes every 30 s (a log, off a terminal); None: none.
    """

    def __init__(
        self,
        runs: int = HFTSConfig.runs,
        seed: int = HFTSConfig.seed,
        iterations: int = HFTSConfig.iterations,
        position_weight: float = HFTSConfig.position_weight,
        hierarchy_seed: int = 0,
        jobs: int = DEFAULT_JOBS,
        backend: str = DEFAULT_BACKEND,
        address: str | None = None,
        hand: Any = None,
        residual_weight: float = 1.0,
        time_limit: float | None = None,
        lines: Callable[[str], None] | None = None,
    ) -> None:
        self.time_limit = time_limit
        self.lines = lines
        self.hand = hand
        self.residual_weight = residual_weight
        self.runs = runs
        self.seed = seed
        self.iterations = iterations
        self.position_weight = position_weight
        self.hierarchy_seed = hierarchy_seed
        self.jobs = jobs
        self.backend = backend
        self.address = address

    def run(self, contacts: ContactSet, m: int) -> HFTSResult:
        """Run HFTS R times and collect the runs (best first in ``grasp``/``q1``)."""
        provenance()  # recorded now: the commit and versions of the code that runs
        validate_backend(self.backend, self.address, self.jobs)
        check_values(
            HFTSConfig,
            runs=self.runs,
            iterations=self.iterations,
            seed=self.seed,
            position_weight=self.position_weight,
        )
        if not isinstance(m, (int, np.integer)) or m < 2 or m > len(contacts):
            raise OgcpError(f"m must be an integer with 2 <= m <= |C| = {len(contacts)}, got {m!r}")
        if self.time_limit is not None:
            TIME_LIMIT.check("time_limit", self.time_limit)
        wall0 = time.perf_counter()
        deadline = None if self.time_limit is None else time.time() + self.time_limit
        tree = Hierarchy(contacts, self.position_weight, self.hierarchy_seed)
        if self.hand is not None:
            self.hand.chosen(int(m))  # its fingers take the m contacts: as many, and no more than it has
        # Runs that start past the deadline still end on real contacts (one exact Q1 each), so
        # every run has a grasp and the seeds stay comparable.
        tasks = [
            (contacts, tree, int(m), self.seed + r, self.iterations, self.hand, self.residual_weight, deadline)
            for r in range(self.runs)
        ]
        runs: list[HFTSRun] = []

        def line() -> str:
            best = max((r.q1 for r in runs), default=0.0)
            return f"hfts: {len(runs)} of {self.runs} runs, best Q1 {best:.6f}, {time.perf_counter() - wall0:.0f} s elapsed"

        with Heartbeat(self.lines, line):
            runs.extend(run_tasks(_one_run, tasks, self.jobs, self.backend, self.address))
        runs.sort(key=lambda r: r.seed)
        best = max(runs, key=lambda r: (r.q1, [-i for i in r.grasp]))
        idx = np.array(best.grasp, dtype=np.intp)
        config = {
            "method": HFTSConfig.method,
            "m": int(m),
            "runs": self.runs,
            "seed": self.seed,
            "iterations": self.iterations,
            "position_weight": self.position_weight,
            "hierarchy_seed": self.hierarchy_seed,
            "top_clusters": TOP_CLUSTERS,
            "child_clusters": CHILD_CLUSTERS,
            "levels": tree.depth,
            "hand": None if self.hand is None else self.hand.describe(),
            "residual_weight": self.residual_weight,
        }
        return HFTSResult(
            grasp=best.grasp,
            q1=best.q1,
            q_ows=q1_certificate(contacts.wrenches.reshape(-1, 6)).q1,
            positions=contacts.positions[idx].copy(),
            normals=contacts.normals[idx].copy(),
            runs=tuple(runs),
            wall_seconds=time.perf_counter() - wall0,
            config=config,
        )
