"""``ogcp plan --realise N``: plan again without the grasps the hand cannot realise.

The reachability model is a sample of the hand's poses, and the search favours wide grasps, at
the edge of what it accepts; there the fit (the one ``ogcp evaluate`` runs before it closes the
hand) may leave a pad short. With ``--realise N`` each planned grasp is fitted against the object's
convex parts (:meth:`ogcp.sim_eval.evaluate.GraspEvaluator.fit_hand`, nothing simulated); a grasp
the hand cannot realise is excluded (:class:`~ogcp.planner.grasp.constraints.ExcludedGrasps`)
and the method runs again, up to N plans. The record keeps every rejected grasp with the fit's
reason (``realise``), and the last plan is the result whether realised or not.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ogcp.benchmarks.cli.options import positive_int
from ogcp.planner.infra.errors import OgcpError

if TYPE_CHECKING:
    from ogcp.planner.methods.runners import MethodRun, RunOptions

#: Methods that take grasp constraints, so that a grasp can be excluded.
REALISING_METHODS = ("astar", "wastar", "dijkstra", "es", "es-pruned")
#: Most plans ``--realise`` may ask for: each is a full search and a fit.
MAX_REALISE = 50


def add_realise_option(parser: argparse.ArgumentParser) -> None:
    """``--realise N`` on ``ogcp plan``."""
    parser.add_argument(
        "--realise",
        type=positive_int,
        default=None,
        metavar="N",
        help="with --hand: fit the hand to the planned grasp (as ogcp evaluate does, against the object's "
        "convex parts) and, where it cannot realise it, plan again without it, up to N plans "
        f"(at most {MAX_REALISE}; A*, WA*, Dijkstra, ES); the record lists the grasps rejected and why",
    )


def realise(
    method: str,
    hand: str | None,
    options: RunOptions,
    attempts: int,
    run_once: Callable[[RunOptions], MethodRun],
) -> MethodRun:
    """Plan, fit and plan again without the grasps the hand cannot realise.

    Args:
        method: The method's name.
        hand: The hand the method plans for (its ``--hand``); None: refused.
        options: The run options (:class:`ogcp.planner.methods.runners.RunOptions`).
        attempts: Most plans.
        run_once: Runs the method with given options; returns its :class:`MethodRun`.

    Returns:
        The last run, its record with a ``realise`` block.

    Raises:
        OgcpError: Without a hand, for a method without constraints, with a checkpoint, or for
            more than :data:`MAX_REALISE` plans.
    """
    if hand is None:
        raise OgcpError("--realise needs --hand: it fits that hand to each planned grasp")
    if method not in REALISING_METHODS:
        raise OgcpError(f"--realise applies to {', '.join(REALISING_METHODS)}, not {method}")
    if options.checkpoint is not None:
        raise OgcpError("--realise plans again with other constraints; a checkpoint holds one run's chunks: drop one")
    if attempts > MAX_REALISE:
        raise OgcpError(f"--realise takes at most {MAX_REALISE} plans, got {attempts}")
    from ogcp.sim_eval.evaluate import GraspEvaluator, plan_hand
    from ogcp.sim_eval.inputs.plan_input import plan_input

    rejected: list[dict[str, Any]] = []
    evaluator: GraspEvaluator | None = None
    for attempt in range(1, attempts + 1):
        run = run_once(dataclasses.replace(options, exclude=tuple(tuple(r["grasp"]) for r in rejected)))
        record = run.record
        planned = plan_input(record)
        if evaluator is None:
            evaluator = GraspEvaluator(hand=plan_hand(record))
        fit = evaluator.fit_hand(planned.mesh, planned.contacts, planned.grasps[0])
        block = {"attempts": attempt, "realised": bool(fit.realised), "rejected": list(rejected)}
        if fit.realised or attempt == attempts or record.get("status") in ("stopped", "memory", "interrupted"):
            record["realise"] = block
            return run
        rejected.append({"grasp": sorted(int(i) for i in planned.grasps[0]), "reason": str(fit.reason)})
        print(
            f"ogcp: plan {attempt} of {attempts}: the hand cannot realise grasp {rejected[-1]['grasp']} "
            f"({fit.reason}); planning again without it",
            file=sys.stderr,
            flush=True,
        )
    raise AssertionError("unreachable")  # the loop returns on its last attempt
