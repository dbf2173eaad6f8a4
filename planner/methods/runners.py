"""Running a configured method on a contact set: the engine's result and its complete plan record.

Everything a record holds beyond what the engine writes (the ``hand`` block, HFTS's A*
``optimum``, the seed of exhaustive search) is added here, in one place, so that
``ogcp plan`` and the suite cells write the same ``ogcp.plan/1`` records.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from functools import lru_cache
from pathlib import Path
from typing import Any, TypeVar

from ogcp.planner.baselines.es import ESResult, ExhaustiveSearch
from ogcp.planner.baselines.hfts import HFTS, HFTSResult
from ogcp.planner.config.methods import (
    AStarConfig,
    ConstraintOptions,
    ESConfig,
    ESPrunedConfig,
    HandOptions,
    HFTSConfig,
)
from ogcp.planner.config.options import MEMORY_LIMIT, MethodConfig, options_of
from ogcp.planner.grasp.constraints import Constraint, ExcludedGrasps, MaxFingerSpread
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.hands.reachability import HandReachability
from ogcp.planner.infra.errors import NoGraspError, SearchTimeout
from ogcp.planner.infra.parallel import DEFAULT_BACKEND, DEFAULT_JOBS
from ogcp.planner.records.plan import add_hand, add_optimum, contact_set_record
from ogcp.planner.search.grasp_planner import GraspPlanner
from ogcp.planner.search.result import SearchResult

#: [s] Budget of the A* that finds the optimum next to HFTS's runs when no time limit is set: A*
#: proves m = 3 on every built-in object in about 10 s, and at large m it may never finish.
OPTIMUM_SECONDS = 60.0

R = TypeVar("R")


@dataclass(frozen=True)
class RunOptions:
    """How to run a method, as opposed to what it computes (never part of a suite cell's id).

    Attributes:
        time_limit: Wall-clock budget of any method [s] (HFTS's A* optimum included); None:
            unlimited.
        memory_limit: Most memory of one A*, WA* or Dijkstra search, all its processes [GiB]
            (:mod:`ogcp.planner.search.memory`); None: unlimited.
        progress: Show a progress bar on stderr (search, exhaustive search).
        jobs: Worker processes (exhaustive search, HFTS); for A*, WA* and Dijkstra the
            processes one search is dealt to (:mod:`ogcp.planner.search.parts`).
        backend: Parallel backend ``loky`` or ``dask`` (exhaustive search, HFTS).
        address: Dask scheduler ``HOST:PORT`` (backend ``dask``).
        checkpoint: Directory of finished chunks, so a rerun resumes (exhaustive search).
        optimum: Also run A* and record its optimum next to HFTS's runs.
        contact_seed: Seed the contacts were sampled with; exhaustive search, which has no
            seed of its own, records it as ``config.seed``. None: not recorded.
        stop: An event that stops A*, WA* and Dijkstra when set; they return their best
            grasp with status ``interrupted``.
        lines: Where a method sends a progress line at least every 30 s (off a terminal, where
            no bar shows); None: none.
        exclude: Grasps (sets of contact indices) A*, WA*, Dijkstra and exhaustive search may not
            return: those a hand could not realise (``ogcp plan --realise``).
    """

    time_limit: float | None = None
    memory_limit: float | None = MEMORY_LIMIT.default
    progress: bool = False
    jobs: int = DEFAULT_JOBS
    backend: str = DEFAULT_BACKEND
    address: str | None = None
    checkpoint: str | Path | None = None
    optimum: bool = False
    contact_seed: int | None = None
    stop: threading.Event | None = None
    lines: Callable[[str], None] | None = None
    exclude: tuple[tuple[int, ...], ...] = ()


@dataclass(frozen=True, eq=False)
class MethodRun:
    """A finished run.

    Attributes:
        result: The engine's result.
        record: Its complete ``ogcp.plan/1`` record.
    """

    result: SearchResult | ESResult | HFTSResult
    record: dict[str, Any]


@lru_cache(maxsize=4)
def hand_model(hand: str, fingers: tuple[str, ...] | None, threshold: float) -> HandReachability:
    """The hand model of a built-in name or descriptor path (cached: a worker runs many cells)."""
    return HandReachability(hand, fingers, threshold=threshold)


def constraints_of(config: HandOptions, m: int) -> tuple[list[Constraint], HandReachability | None]:
    """The grasp constraints a configuration asks for; the hand model is also returned.

    Raises:
        OgcpError: For a bad hand, or m more than its fingers or other than the fingers named.
    """
    constraints: list[Constraint] = []
    if isinstance(config, ConstraintOptions) and config.max_spread is not None:
        constraints.append(MaxFingerSpread(config.max_spread))
    if config.hand is None:
        return constraints, None
    assert config.hand_threshold is not None  # resolved with the hand
    hand = hand_model(config.hand, config.hand_fingers, config.hand_threshold)
    hand.chosen(m)
    return [*constraints, hand], hand


def _constraints(config: HandOptions, m: int, options: RunOptions) -> tuple[list[Constraint], HandReachability | None]:
    """:func:`constraints_of`, and the grasps ``options`` exclude."""
    constraints, hand = constraints_of(config, m)
    if options.exclude:
        constraints.append(ExcludedGrasps(options.exclude))
    return constraints, hand


def _under_denser_hands(
    search: Callable[[list[Constraint], float | None], R],
    contacts: ContactSet,
    m: int,
    constraints: list[Constraint],
    hand: HandReachability | None,
    time_limit: float | None,
    retry: bool = True,
) -> tuple[R, HandReachability | None]:
    """Run a search; one that finds no grasp under a hand runs again under denser models of it.

    Each retry's model has :data:`~ogcp.planner.hands.reachability.DENSER_FACTOR` times the
    samples (:meth:`HandReachability.denser`: where some grasp of the m-contact ``contacts`` came
    near). Sampling a denser model takes seconds to minutes that no time limit can bound, so a
    search with a ``time_limit`` [s] runs once, as does one without ``retry`` (a checkpointed
    exhaustive search, whose finished chunks belong to the first model). The search is called
    with the constraints and the time it may take.

    Returns:
        The result and the hand model it was found under.

    Raises:
        NoGraspError: Once no denser model finds one, saying what about the hand may change that.
    """
    while True:
        try:
            return search(constraints, time_limit), hand
        except NoGraspError as exc:
            if hand is None:
                raise
            denser = hand.denser(contacts, m) if retry and time_limit is None else None
            if denser is None:
                raise NoGraspError(f"{exc}: {hand.why_none(m, contacts)}") from None
            constraints = [denser if c is hand else c for c in constraints]
            hand = denser


def engine_arguments(config: MethodConfig) -> dict[str, Any]:
    """The configuration's own parameters, named as the engine's constructor names them (constraints apart)."""
    constraint_fields = {f.name for f in fields(ConstraintOptions)}
    return {name: getattr(config, name) for name in options_of(config) if name not in constraint_fields}


def run_search(config: AStarConfig, contacts: ContactSet, m: int, options: RunOptions) -> MethodRun:
    """A*, WA* or Dijkstra (by ``config.method``).

    Raises:
        OgcpError: For invalid parameters, or when no grasp satisfies the constraints.
        SearchTimeout: When the search stops (time limit or ``options.stop``) before it
            found any valid grasp; with one, it is returned with status ``stopped``,
            ``memory`` or ``interrupted``.
    """

    def search(constraints: list[Constraint], time_limit: float | None) -> SearchResult:
        planner = GraspPlanner(
            method=config.method,
            constraints=constraints,
            time_limit=time_limit,
            jobs=options.jobs,
            memory_limit=options.memory_limit,
            **engine_arguments(config),
        )
        return planner.plan(contacts, m, progress=options.progress, stop=options.stop, lines=options.lines)

    result, hand = _under_denser_hands(search, contacts, m, *_constraints(config, m, options), options.time_limit)
    return MethodRun(result, add_hand(result.to_dict(contact_set_record(contacts)), hand, contacts))


def run_exhaustive(config: ESConfig | ESPrunedConfig, contacts: ContactSet, m: int, options: RunOptions) -> MethodRun:
    """Exhaustive search, with (``es``) or without (``es-pruned``) the histogram.

    Raises:
        OgcpError: For invalid parameters, a checkpoint of another run, or no admissible grasp.
        SearchTimeout: When the time limit ends it before any admissible grasp was evaluated.
    """

    def search(constraints: list[Constraint], time_limit: float | None) -> ESResult:
        return ExhaustiveSearch(
            pruned=config.method == ESPrunedConfig.method,
            jobs=options.jobs,
            backend=options.backend,
            address=options.address,
            checkpoint=options.checkpoint,
            progress=options.progress,
            constraints=constraints,
            time_limit=time_limit,
            lines=options.lines,
            **engine_arguments(config),
        ).run(contacts, m)

    retry = options.checkpoint is None  # a checkpoint's chunks belong to the first model
    result, hand = _under_denser_hands(
        search, contacts, m, *_constraints(config, m, options), options.time_limit, retry
    )
    record = result.to_dict(contact_set_record(contacts))
    if options.contact_seed is not None:
        record["config"]["seed"] = options.contact_seed
    return MethodRun(result, add_hand(record, hand, contacts))


def run_hfts(config: HFTSConfig, contacts: ContactSet, m: int, options: RunOptions) -> MethodRun:
    """HFTS's runs, and with ``options.optimum`` the A* optimum under the same hand.

    The optimum's A* gets what is left of the time limit, or :data:`OPTIMUM_SECONDS` without
    one; one that does not finish is recorded with its status and certified bound.

    Raises:
        OgcpError: For invalid parameters.
    """
    wall0 = time.perf_counter()
    hand = constraints_of(config, m)[1]
    search = HFTS(
        jobs=options.jobs,
        backend=options.backend,
        address=options.address,
        hand=hand,
        time_limit=options.time_limit,
        lines=options.lines,
        **engine_arguments(config),
    )
    result = search.run(contacts, m)
    record = add_hand(result.to_dict(contact_set_record(contacts)), hand, contacts)
    if options.optimum:
        budget = OPTIMUM_SECONDS if options.time_limit is None else options.time_limit - (time.perf_counter() - wall0)
        if budget > 0:
            planner = GraspPlanner(seed=config.seed, constraints=[hand] if hand else (), time_limit=budget)
            with contextlib.suppress(SearchTimeout):  # nothing found in the time left: no optimum to show
                optimum = planner.plan(contacts, m, stop=options.stop)
                add_optimum(record, optimum.method, optimum.grasp, optimum.q1, optimum.status, optimum.bound)
    return MethodRun(result, record)
