"""Plan again without the grasps the hand cannot realise (a method's ``realise = N``).

The reachability model is a sample of the hand's poses, and the search favours wide grasps, at
the edge of what it accepts; there the fit (the one :meth:`ogcp.sim_eval.evaluate.GraspEvaluator.evaluate`
runs before it closes the hand) may leave a pad short. With ``realise = N`` (``ogcp plan
--realise N``, or a suite's method table) each planned grasp is fitted against the object's
convex parts (:meth:`~ogcp.sim_eval.evaluate.GraspEvaluator.fit_hand`, nothing simulated); a grasp
the hand cannot realise is excluded (:class:`~ogcp.planner.grasp.constraints.ExcludedGrasps`) and
the method runs again, up to N plans. The record keeps every rejected grasp with the fit's reason
(``realise``); the last plan is the result, realised or not, and a plan that stopped (a time or
memory limit, Ctrl-C) ends the loop as it is.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.runners import MethodRun, RunOptions

#: Statuses of a plan that did not finish: the loop ends with it.
UNFINISHED = ("stopped", "memory", "interrupted")


def realise(
    attempts: int,
    options: RunOptions,
    run_once: Callable[[RunOptions], MethodRun],
    tell: Callable[[str], None] | None = None,
) -> MethodRun:
    """Plan, fit and plan again without the grasps the hand cannot realise, up to ``attempts`` plans.

    Args:
        attempts: Most plans.
        options: The run options; their ``exclude`` grows with each rejected grasp.
        run_once: Runs the method (with a hand) under given options.
        tell: Where a line goes for each rejected grasp; None: nowhere.

    Returns:
        The last run, its record with a ``realise`` block: ``attempts`` (plans made), ``realised``
        (the last one's fit) and ``rejected`` (each grasp, sorted, and the fit's reason).

    Raises:
        OgcpError: With a checkpoint (it holds one run's chunks), or for a plan without a hand.
    """
    if options.checkpoint is not None:
        raise OgcpError("realise plans again with other constraints; a checkpoint holds one run's chunks: drop one")
    from ogcp.sim_eval.decomposition.decompose import Decomposition, decompose
    from ogcp.sim_eval.evaluate import GraspEvaluator, plan_hand
    from ogcp.sim_eval.inputs.plan_input import plan_input

    rejected: list[dict[str, Any]] = []
    problem: tuple[GraspEvaluator, Any, Any, Decomposition] | None = None  # the same every plan
    for attempt in range(1, attempts + 1):
        run = run_once(dataclasses.replace(options, exclude=tuple(tuple(r["grasp"]) for r in rejected)))
        record = run.record
        if problem is None:
            hand = plan_hand(record)
            if hand is None:
                raise OgcpError("realise needs a hand: it fits that hand to each planned grasp")
            planned = plan_input(record)
            problem = (GraspEvaluator(hand=hand), planned.mesh, planned.contacts, decompose(planned.mesh))
        evaluator, mesh, contacts, parts = problem
        grasp = tuple(int(i) for i in record["grasp"])
        fit = evaluator.fit_hand(mesh, contacts, grasp, parts=parts)
        if fit.realised or attempt == attempts or record.get("status") in UNFINISHED:
            record["realise"] = {"attempts": attempt, "realised": bool(fit.realised), "rejected": rejected}
            return run
        rejected.append({"grasp": sorted(grasp), "reason": str(fit.reason)})
        if tell is not None:
            tell(
                f"plan {attempt} of {attempts}: the hand cannot realise grasp {rejected[-1]['grasp']} "
                f"({fit.reason}); planning again without it"
            )
    raise AssertionError("the loop returns on its last plan")
