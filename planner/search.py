"""Best-first search over super-contact grasps: A*, weighted A* and Dijkstra (paper Sec. III-IV).

A state is a tuple of m super-contacts, each a node of the :class:`PartitionTree` that the
expansion successor function Γ induces on C. With q(s) = Q1 of the union of the
super-contacts (Eq. 9) and arc cost d(s, s') = q(s) - q(s') (Eq. 10), the path cost is
g(s) = q(s0) - q(s) whatever the path, and the heuristic of Eq. 11 gives
f(s) = g(s) + (1 + eps) h(s) with h(s) = q(s) - max_{s' in Γh(s)} q(s').

Design points:

* Finger order is irrelevant to Q1 and to every constraint, so states are kept as
  sorted tuples (exact; disable with ``ordered=True`` to reproduce the paper's raw tree).
  Every sorted state then has exactly one parent, so no closed list is needed.
* Exact values are computed lazily. A successor enters the open list keyed by
  q(s0) - U(s'), where U is a cheap support-function upper bound of q
  (:mod:`planner.bounds`), hence a lower bound of its f. Only when it reaches the front
  is its exact heuristic computed, by branch and bound over Γh(s'): children are tried
  in order of decreasing U and the loop stops once no remaining U can beat the best
  exact value, so max q over Γh(s') is exact while most children never need a hull.
  Refinement is staged: a state popped with its bound key is re-inserted with its exact
  g (one Q1 evaluation; still a lower bound of f), and only when popped again is its
  heuristic computed and the state re-inserted with its exact key. Terminal states are always
  evaluated exactly before they can be returned, so A* stays optimal and the WA*
  guarantee holds (keys are never above the exact ones).
* The open list also yields the certificate: when the search stops, every unexplored
  grasp lies below an open state, so q(s0) minus the smallest unweighted f on the list is
  an upper bound on the optimum.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from tqdm import tqdm

from planner.bounds import Vector
from planner.constraints import Constraint, DistinctContacts
from planner.contacts import ContactSet
from planner.errors import OgcpError, choice_error
from planner.oracle import GraspQuality, PackedMask
from planner.provenance import provenance
from planner.result import SearchResult, SearchStats, effective_branching_factor
from planner.successors import SUCCESSORS, Indices, PartitionTree, make_partitioner
from planner.symmetry import SymmetryFilter

METHODS = ("astar", "dijkstra", "wastar")
HEURISTICS = (*SUCCESSORS, "none")
DEFAULT_WASTAR_EPS = 0.4

State = tuple[int, ...]
BOUND, EXACT_G, EXACT = 0, 1, 2


class GraspPlanner:
    """Optimal and bounded-suboptimal m-contact grasp planner.

    The constructor only stores parameters; :meth:`plan` validates them and searches.

    Args:
        method: ``astar`` (optimal), ``wastar`` (cost within 1 + eps of optimal) or
            ``dijkstra`` (uniform cost, h = 0).
        eps: WA* inflation; default 0.4 for ``wastar`` and 0 otherwise.
        branching: Branching factor b of the expansion successor function.
        successor: Expansion successor function Γ: ``fc`` (k-means) or ``ru`` (random).
        heuristic: Γh for the heuristic: ``fc``, ``ru`` or ``none``; default ``fc``
            (``none`` for Dijkstra).
        heuristic_branching: b of Γh; default ``branching``.
        symmetry: Approximate geometric symmetry removal (Sec. IV-D); may lose optimality.
        ordered: Keep finger order (the paper's raw tree) instead of sorted states.
        seed: Seed of every random choice (k-means init, random splits).
        kmeans_iterations: t for Γ^fc.
        position_weight: Weight of positions against normals in Γ^fc features.
        constraints: Extra grasp constraints; distinct contacts is always enforced.
    """

    def __init__(
        self,
        method: str = "astar",
        eps: float | None = None,
        branching: int = 2,
        successor: str = "fc",
        heuristic: str | None = None,
        heuristic_branching: int | None = None,
        symmetry: bool = False,
        ordered: bool = False,
        seed: int = 0,
        kmeans_iterations: int = 10,
        position_weight: float = 1.0,
        constraints: Sequence[Constraint] = (),
    ) -> None:
        self.method = method
        self.eps = eps
        self.branching = branching
        self.successor = successor
        self.heuristic = heuristic
        self.heuristic_branching = heuristic_branching
        self.symmetry = symmetry
        self.ordered = ordered
        self.seed = seed
        self.kmeans_iterations = kmeans_iterations
        self.position_weight = position_weight
        self.constraints = constraints

    def resolved_config(self) -> dict[str, Any]:
        """Validate the parameters and fill in method-dependent defaults.

        Raises:
            OgcpError: For any invalid parameter, naming the valid values.
        """
        if self.method not in METHODS:
            raise choice_error("method", self.method, METHODS)
        eps = self.eps
        if eps is None:
            eps = DEFAULT_WASTAR_EPS if self.method == "wastar" else 0.0
        if not (isinstance(eps, (int, float)) and math.isfinite(eps) and eps >= 0):
            raise OgcpError(f"eps must be a number >= 0, got {eps!r}")
        if self.method != "wastar" and eps != 0:
            raise OgcpError(f"eps applies to method 'wastar' only (method {self.method!r} got eps={eps})")
        heuristic = self.heuristic or ("none" if self.method == "dijkstra" else "fc")
        if heuristic not in HEURISTICS:
            raise choice_error("heuristic", heuristic, HEURISTICS)
        if self.method == "dijkstra" and heuristic != "none":
            raise OgcpError(f"method 'dijkstra' uses no heuristic (got heuristic {heuristic!r})")
        if self.successor not in SUCCESSORS:
            raise choice_error("successor function", self.successor, SUCCESSORS)
        for name, value in (("branching", self.branching), ("heuristic_branching", self.heuristic_branching)):
            if value is not None and (not isinstance(value, (int, np.integer)) or value < 2):
                raise OgcpError(f"{name} b must be an integer >= 2, got {value!r}")
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise OgcpError(f"seed must be a non-negative integer, got {self.seed!r}")
        return {
            "method": self.method,
            "eps": float(eps),
            "branching": int(self.branching),
            "successor": self.successor,
            "heuristic": heuristic,
            "heuristic_branching": int(self.heuristic_branching or self.branching),
            "symmetry": bool(self.symmetry),
            "ordered": bool(self.ordered),
            "seed": int(self.seed),
            "kmeans_iterations": int(self.kmeans_iterations),
            "position_weight": float(self.position_weight),
            "constraints": [c.describe() for c in self.constraints],
        }

    def plan(self, contacts: ContactSet, m: int, progress: bool = False) -> SearchResult:
        """Find the best m-contact grasp (or one within the WA* bound).

        Args:
            contacts: The contact set C.
            m: Number of contacts (fingers), 2 <= m <= |C|.
            progress: Show expansions and the current f on stderr (tqdm).

        Returns:
            The :class:`SearchResult`.

        Raises:
            OgcpError: For invalid parameters, or when no grasp satisfies the constraints.
        """
        provenance()  # recorded now: the commit and versions of the code that runs
        config = self.resolved_config()
        if not isinstance(m, (int, np.integer)) or m < 2:
            raise OgcpError(f"number of contacts m must be an integer >= 2, got {m!r}")
        if m > len(contacts):
            raise OgcpError(f"m = {m} exceeds the number of contacts |C| = {len(contacts)}")
        config["m"] = int(m)
        search = _Search(contacts, int(m), config, [DistinctContacts(), *self.constraints])
        with tqdm(desc=config["method"], unit=" expansions", disable=not progress, leave=False) as bar:
            search.on_expand = lambda f: (bar.update(), bar.set_postfix(f=f"{f:.6f}", refresh=False))
            return search.run()


class _Search:
    """One search run: the tree, the oracle, the open list and the statistics."""

    def __init__(self, contacts: ContactSet, m: int, config: dict[str, Any], constraints: list[Constraint]) -> None:
        self.contacts = contacts
        self.m = m
        self.config = config
        self.constraints = constraints
        self.eps = config["eps"]
        self.oracle = GraspQuality(contacts, config["seed"])

        def partitioner(kind: str, branching: int) -> Any:
            return make_partitioner(
                kind, contacts, branching, config["seed"], config["kmeans_iterations"], config["position_weight"]
            )

        self.tree = PartitionTree(len(contacts), partitioner(config["successor"], config["branching"]))
        self.heuristic_kind = config["heuristic"]
        self.heuristic_shares_tree = (
            self.heuristic_kind == config["successor"] and config["heuristic_branching"] == config["branching"]
        )
        self.heuristic_partitioner = (
            None
            if self.heuristic_kind == "none" or self.heuristic_shares_tree
            else partitioner(self.heuristic_kind, config["heuristic_branching"])
        )
        self._heuristic_parts: dict[int, list[tuple[Indices, PackedMask]]] = {}
        self._vectors: dict[Any, Vector] = {}
        self.symmetry = SymmetryFilter(contacts) if config["symmetry"] else None
        self.pruned = 0
        self.bound_evaluations = 0
        self.on_expand: Callable[[float], object] = lambda f: None

    # -- states -----------------------------------------------------------------------

    def members(self, state: State) -> list[Indices]:
        return [self.tree.members[node] for node in state]

    def depth(self, state: State) -> int:
        return max(self.tree.depth[node] for node in state)

    def is_terminal(self, state: State) -> bool:
        return all(self.tree.size(node) == 1 for node in state)

    def valid(self, parts: Sequence[Indices], terminal: bool) -> bool:
        if terminal:
            grasp = [int(p[0]) for p in parts]
            return all(c.accepts(grasp, self.contacts) for c in self.constraints)
        return all(c.admits(parts, self.contacts) for c in self.constraints)

    def successors(self, state: State) -> list[State]:
        """Γ restricted to valid states (Eq. 15), sorted unless finger order is kept."""
        combos = itertools.product(*(self.tree.children(node) for node in state))
        unique = dict.fromkeys(combos if self.config["ordered"] else (tuple(sorted(c)) for c in combos))
        result = []
        for child in unique:
            if not self.valid(self.members(child), self.is_terminal(child)):
                self.pruned += 1
                continue
            if self.symmetry is not None and not self.symmetry.is_new(self.depth(child), self.members(child)):
                continue
            result.append(child)
        return result

    # -- quality: exact values and cheap upper bounds ---------------------------------

    def vector(self, key: Any, members: Indices) -> Vector:
        vec = self.oracle.bounds.vector(members, self._vectors.get(key))
        self._vectors[key] = vec
        return vec

    def node_vectors(self, state: State) -> list[Vector]:
        return [self.vector(node, self.tree.members[node]) for node in state]

    def upper(self, vectors: Sequence[Vector]) -> float:
        self.bound_evaluations += 1
        return self.oracle.bounds.bound(vectors)

    def exact(self, state: State) -> float:
        return self.oracle.of_masks([self.tree.masks[node] for node in state], self.node_vectors(state))

    def heuristic_children(self, state: State) -> list[tuple[list[PackedMask], list[Vector]]]:
        """Valid Γh children as (masks, support vectors); never symmetry-filtered (admissibility)."""
        children = []
        if self.heuristic_shares_tree:
            combos = dict.fromkeys(tuple(sorted(c)) for c in itertools.product(*(self.tree.children(n) for n in state)))
            for child in combos:
                if self.valid(self.members(child), self.is_terminal(child)):
                    children.append(([self.tree.masks[n] for n in child], self.node_vectors(child)))
            return children
        options = []
        for node in state:
            parts = self._heuristic_parts.get(node)
            if parts is None:
                assert self.heuristic_partitioner is not None
                split = self.heuristic_partitioner.split(self.tree.members[node])
                parts = [(p, self.oracle.mask_of(p)) for p in split]
                self._heuristic_parts[node] = parts
            options.append([(p, mask, ("h", node, i)) for i, (p, mask) in enumerate(parts)])
        for combo in itertools.product(*options):
            parts = [p for p, _, _ in combo]
            if self.valid(parts, all(len(p) == 1 for p in parts)):
                children.append(([mask for _, mask, _ in combo], [self.vector(key, p) for p, _, key in combo]))
        return children

    def best_child_quality(self, state: State) -> float:
        """max q over valid Γh(s), exact, by branch and bound on the support bounds; -inf if none."""
        children = self.heuristic_children(state)
        ranked = sorted(((self.upper(vectors), masks, vectors) for masks, vectors in children), key=lambda c: -c[0])
        best = -math.inf
        for bound, masks, vectors in ranked:
            if bound <= best:
                break
            best = max(best, self.oracle.of_masks(masks, vectors))
        return best

    # -- the loop ---------------------------------------------------------------------

    def run(self) -> SearchResult:
        wall0, cpu0 = time.perf_counter(), time.process_time()
        root: State = (0,) * self.m
        q0 = self.exact(root)
        counter = itertools.count()
        created: dict[int, int] = {0: 1}
        visited: dict[int, int] = {}
        trace: list[tuple[int, float]] = []
        # Entries: (key, -depth, tie, state, lower bound of the unweighted f, stage), where
        # stage is BOUND (key from U), EXACT_G (key = exact g) or EXACT (exact key).
        open_list: list[tuple[float, int, int, State, float, int]] = [(0.0, 0, next(counter), root, 0.0, EXACT_G)]
        while open_list:
            key, neg_depth, _, state, _, stage = heapq.heappop(open_list)
            if stage == BOUND:
                g = q0 - self.exact(state)
                terminal = self.is_terminal(state) or self.heuristic_kind == "none"
                heapq.heappush(open_list, (g, neg_depth, next(counter), state, g, EXACT if terminal else EXACT_G))
                continue
            if stage == EXACT_G:
                scored = self.score(state, q0, q0 - key)
                if scored is not None:
                    heapq.heappush(open_list, (scored[0], neg_depth, next(counter), state, scored[1], EXACT))
                continue
            depth = -neg_depth
            visited[depth] = visited.get(depth, 0) + 1
            trace.append((len(trace), key))
            self.on_expand(key)
            if self.is_terminal(state):
                # The cached exact value: q0 - (q0 - q) need not equal q in floating point.
                return self.result(state, self.exact(state), q0, key, open_list, created, visited, trace, wall0, cpu0)
            for child in self.successors(state):
                child_depth = self.depth(child)
                created[child_depth] = created.get(child_depth, 0) + 1
                # U may be negative (then q = 0): clip so the key never exceeds the true f.
                lower = q0 - min(q0, max(0.0, self.upper(self.node_vectors(child))))
                heapq.heappush(open_list, (lower, -child_depth, next(counter), child, lower, BOUND))
        raise OgcpError("no grasp satisfies the constraints")

    def score(self, state: State, q0: float, q: float) -> tuple[float, float] | None:
        """Exact (key, unweighted f) of a state of exact quality q; None when no valid
        grasp lies below it."""
        if self.is_terminal(state) or self.heuristic_kind == "none":
            return q0 - q, q0 - q
        best = self.best_child_quality(state)
        if best == -math.inf:
            return None
        f = q0 - best
        g = q0 - q
        return g + (1.0 + self.eps) * (f - g), f

    def result(
        self,
        state: State,
        q: float,
        q0: float,
        g: float,
        open_list: list[tuple[float, int, int, State, float, int]],
        created: dict[int, int],
        visited: dict[int, int],
        trace: list[tuple[int, float]],
        wall0: float,
        cpu0: float,
    ) -> SearchResult:
        # Every unexplored grasp lies below an open state, whose stored value bounds its cost.
        lowest_f = min([g] + [entry[4] for entry in open_list])
        bound = max(q, q0 - lowest_f)
        eps_bound = q0 - (q0 - q) / (1.0 + self.eps)
        grasp = tuple(sorted(int(self.tree.members[node][0]) for node in state))
        levels = max(max(created), max(visited)) + 1
        solution_depth = self.depth(state)
        stats = SearchStats(
            created=sum(created.values()),
            visited=sum(visited.values()),
            created_per_level=tuple(created.get(i, 0) for i in range(levels)),
            visited_per_level=tuple(visited.get(i, 0) for i in range(levels)),
            q1_evaluations=self.oracle.evaluations,
            q1_cache_hits=self.oracle.cache_hits,
            bound_evaluations=self.bound_evaluations,
            bound_rejections=self.oracle.bound_rejections,
            hull_calls=self.oracle.hull_calls,
            pruned=self.pruned,
            symmetric_removed=self.symmetry.removed if self.symmetry else 0,
            effective_branching_factor=effective_branching_factor(sum(created.values()) - 1, solution_depth),
            solution_depth=solution_depth,
            trace=tuple(trace),
            wall_seconds=time.perf_counter() - wall0,
            cpu_seconds=time.process_time() - cpu0,
        )
        idx = np.array(grasp, dtype=np.intp)
        return SearchResult(
            method=self.config["method"],
            grasp=grasp,
            positions=self.contacts.positions[idx].copy(),
            normals=self.contacts.normals[idx].copy(),
            q1=q,
            q_ows=q0,
            bound=bound,
            eps=self.eps,
            eps_bound=eps_bound,
            stats=stats,
            config=self.config,
            contact_source=self.contacts.source,
        )
