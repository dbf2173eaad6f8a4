"""Grasps planned with a hand: how many the fit realises, and how many of those hold when the hand closes.

Run: ``python -m ogcp.benchmarks.studies.hand_fit [--cases sdh:box:3,sdh:donut:3,parallel_gripper:box:2]
[--contacts 100] [--seeds 6] [--diagonal 0.2] [--directions 16]``.

Per case (hand, object, m) and contact seed: sample the contacts, plan the A* optimum under the hand
(``--hand``), fit the hand to it against the object's convex parts (the CoACD decomposition,
cached; one hull for the box and the sphere) from its nearest samples until a fit is realised, and
close the hand on the realised ones and test them (:mod:`ogcp.sim_eval.hand.trial`, ``--directions``
random directions plus the axes). Printed per case: the share of the model's accepted grasps
among all (seed 0), fits realised, the median worst pad residual, grasps valid after closing, the
median fidelity of the valid ones, the most frequent reason of the invalid ones, seconds per grasp.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import statistics
import time

import numpy as np

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.hands import HandKinematics, HandReachability
from ogcp.sim_eval.decomposition import DecompositionSettings, decompose
from ogcp.sim_eval.evaluate import GraspEvaluator
from ogcp.sim_eval.hand.trial import HandSetup
from ogcp.sim_eval.settings import SimSettings

CONVEX = ("box", "sphere")


def run_case(hand: str, name: str, m: int, args: argparse.Namespace) -> str:
    mesh, _ = resolve_object(name, args.diagonal)
    model = HandReachability(hand)
    setup = HandSetup(HandKinematics(model.descriptor), model)
    method = "convex_hull" if name in CONVEX else "coacd"
    parts = decompose(mesh, DecompositionSettings(method=method), name=name)
    evaluator = GraspEvaluator(
        SimSettings(directions=args.directions), DecompositionSettings(method=method), hand=setup
    )
    first = sample_contacts(mesh, n=args.contacts, seed=0)
    grasps = np.array(list(itertools.combinations(range(args.contacts), m)))
    accepted = float(model.accepts_many(grasps, first).mean()) if len(grasps) <= 2_000_000 else float("nan")
    realised, residuals, valid, fidelities, seconds = 0, [], 0, [], []
    reasons: collections.Counter[str] = collections.Counter()
    for seed in range(args.seeds):
        contacts = sample_contacts(mesh, n=args.contacts, seed=seed)
        optimum = GraspPlanner(constraints=[model]).plan(contacts, m)
        started = time.perf_counter()
        (result,) = evaluator.evaluate(mesh, contacts, [tuple(optimum.grasp)], parts=parts).grasps
        seconds.append(time.perf_counter() - started)
        fit = result.hand.get("fit", {})
        if fit.get("realised"):
            realised += 1
            residuals.append(max(result.hand["fit_residuals"]))
        if result.valid:
            valid += 1
            if np.isfinite(result.median_fidelity):
                fidelities.append(result.median_fidelity)
        elif fit.get("realised"):
            gate = [r["gate"] for r in result.invalid_reasons] or (["pads"] if result.error is None else ["error"])
            reasons[gate[0]] += 1
    residual = f"{statistics.median(residuals) * 1e3:.3f}" if residuals else "-"
    fidelity = f"{statistics.median(fidelities):.2f}" if fidelities else "-"
    common = ", ".join(f"{gate} {count}" for gate, count in reasons.most_common(2)) or "-"
    return (
        f"| {hand}, {name}, {m} | {accepted:.2%} | {realised} of {args.seeds} | {residual} | {valid} of {realised} "
        f"| {fidelity} | {common} | {statistics.median(seconds):.1f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default="sdh:box:3,sdh:sphere:3,sdh:donut:3,parallel_gripper:box:2")
    parser.add_argument("--contacts", type=int, default=100)
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--diagonal", type=float, default=0.2)
    parser.add_argument("--directions", type=int, default=16)
    args = parser.parse_args()
    print(
        "| hand, object, m | accepted (seed 0) | A* optima realised | median worst residual [mm] | valid when closed "
        "| median fidelity | invalid because | s per grasp |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for case in args.cases.split(","):
        hand, name, m = case.split(":")
        print(run_case(hand, name, int(m), args), flush=True)


if __name__ == "__main__":
    main()
