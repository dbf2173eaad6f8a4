"""Grasps planned with a hand: how many the fit realises, how many hold when the hand closes, and the same grasps with fingertips.

Run: ``python -m ogcp.benchmarks.studies.hand_fit [--cases sdh:box:3,sdh:donut:3,parallel_gripper:box:2]
[--contacts 100] [--seeds 6] [--diagonal 0.2] [--directions 16] [--plan-time-limit S]
[--torsional-friction METRES] [--realise N] [--out DIR]``.

Per case (hand, object, m) and contact seed: sample the contacts, plan the A* optimum under the hand
(``--hand``; with ``--plan-time-limit``, the best grasp A* finds within it; with ``--realise N``,
planned again without each grasp the hand's fit cannot realise, up to N plans, the rows
counting the grasps ``rejected``), fit the hand to it against the object's convex parts (the CoACD decomposition,
cached; one hull for the box and the sphere) from its nearest samples until a fit is realised, and
close the hand on the realised ones and test them (:mod:`ogcp.sim_eval.hand.trial`, ``--directions``
random directions plus the axes); the same grasp is also tested with fingertip spheres. Printed
per case: the share of the model's accepted grasps among all (seed 0), fits realised, the median
worst pad residual, grasps valid after closing, the median fidelity of the valid ones, the most
frequent reason of the invalid ones, seconds per hand grasp, and the tips' side: grasps valid
with fingertips, how many of those the hand realised and held, the tips' median fidelity, and the
median ratio of the hand trial (fit, close, protocol) to the fingertip trial of the grasps valid
with both, timed in the same run; after the table, each case's median seconds per phase, and the
median share of its valid grasps' ramps that held past their end (censored: left out of the fidelity).
With ``--out``, every grasp's row goes to ``DIR/hand_fit.json`` and the tips-versus-hand figure
(:func:`ogcp.benchmarks.plots.tips_hand.fig_tips_vs_hand`) to ``DIR/tips_vs_hand.{pdf,png}``.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import json
import math
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.grasp.constraints import ExcludedGrasps
from ogcp.planner.hands import HandKinematics, HandReachability
from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.decomposition import DecompositionSettings, decompose
from ogcp.sim_eval.evaluate import GraspEvaluator
from ogcp.sim_eval.hand.setup import HandSetup
from ogcp.sim_eval.settings import SimSettings

CONVEX = ("box", "sphere")


def _fidelity(result: Any) -> float | None:
    value = float(result.median_fidelity)
    return value if result.valid and np.isfinite(value) else None


def _censored(result: Any) -> float | None:
    """The share of a valid grasp's ramps that held past their end: left out of its fidelity."""
    censored = np.asarray(result.censored, dtype=bool)
    return float(censored.mean()) if result.valid and censored.size else None


def run_case(hand: str, name: str, m: int, args: argparse.Namespace) -> dict[str, Any]:
    """Every seed's grasp of one case, tested with the hand and with fingertips."""
    mesh, _ = resolve_object(name, args.diagonal)
    model = HandReachability(hand)
    setup = HandSetup(HandKinematics(model.descriptor), model)
    method = "convex_hull" if name in CONVEX else "coacd"
    parts = decompose(mesh, DecompositionSettings(method=method), name=name)
    settings = SimSettings(directions=args.directions)
    with_hand = GraspEvaluator(settings, DecompositionSettings(method=method), hand=setup)
    with_tips = GraspEvaluator(settings, DecompositionSettings(method=method))
    soft = args.torsional_friction  # a two-jaw grasp of hard contacts resists no twist about its line: Q1 = 0
    first = sample_contacts(mesh, n=args.contacts, seed=0, torsional_friction=soft)
    accepted = float("nan")  # past 2,000,000 grasps (4 of 100 contacts: 3.9 million) not counted
    if math.comb(args.contacts, m) <= 2_000_000:
        grasps = np.array(list(itertools.combinations(range(args.contacts), m)))
        accepted = float(model.accepts_many(grasps, first).mean())
    rows = []
    for seed in range(args.seeds):
        contacts = sample_contacts(mesh, n=args.contacts, seed=seed, torsional_friction=soft)
        rejected: list[tuple[int, ...]] = []
        try:
            for _ in range(args.realise or 1):  # with --realise: plan again without what the fit leaves short
                excluded = [ExcludedGrasps(rejected)] if rejected else []
                planner = GraspPlanner(constraints=[model, *excluded], time_limit=args.plan_time_limit)
                grasp = tuple(planner.plan(contacts, m).grasp)
                if not args.realise or with_hand.fit_hand(mesh, contacts, grasp, parts=parts).realised:
                    break
                rejected.append(grasp)
        except OgcpError as exc:  # no grasp the hand reaches: recorded, and the other seeds go on
            rows.append({"seed": seed, **_UNPLANNED, "error": str(exc)})
            continue
        started = time.perf_counter()
        (held,) = with_hand.evaluate(mesh, contacts, [grasp], parts=parts).grasps
        seconds = time.perf_counter() - started
        started = time.perf_counter()
        (tips,) = with_tips.evaluate(mesh, contacts, [grasp], parts=parts).grasps
        tips_seconds = time.perf_counter() - started
        fit = held.hand.get("fit", {})
        reason = None
        if fit.get("realised") and not held.valid:
            gates = [r["gate"] for r in held.invalid_reasons] or (["pads"] if held.error is None else ["error"])
            reason = gates[0]
        rows.append(
            {
                "seed": seed,
                "grasp": list(grasp),
                "q1": held.q1,
                "realised": bool(fit.get("realised")),
                "worst_residual": max(held.hand["fit_residuals"]) if fit.get("realised") else None,
                "unrealised_because": fit.get("reason"),  # the fit's one line where it is not realised
                "hand_valid": bool(held.valid),
                "hand_fidelity": _fidelity(held),
                "hand_censored": _censored(held),
                "invalid_because": reason,
                "hand_seconds": seconds,
                "tips_valid": bool(tips.valid),
                "tips_fidelity": _fidelity(tips),
                "tips_censored": _censored(tips),
                "tips_seconds": tips_seconds,
                "hand_phase_seconds": held.hand.get("seconds", {}),
                "rejected": len(rejected),
            }
        )
    return {"hand": hand, "object": name, "m": m, "accepted": accepted, "rows": rows}


#: The row of a seed whose plan found no grasp: nothing realised, held or timed.
_UNPLANNED: dict[str, Any] = {
    "planned": False,
    "grasp": None,
    "q1": None,
    "realised": False,
    "worst_residual": None,
    "unrealised_because": None,
    "hand_valid": False,
    "hand_fidelity": None,
    "hand_censored": None,
    "invalid_because": None,
    "hand_seconds": None,
    "tips_valid": False,
    "tips_fidelity": None,
    "tips_censored": None,
    "tips_seconds": None,
    "hand_phase_seconds": {},
    "rejected": 0,
}


def _share(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.2%}"


def _median(values: list[float], digits: int, scale: float = 1.0) -> str:
    return f"{statistics.median(values) * scale:.{digits}f}" if values else "-"


def table_row(case: dict[str, Any]) -> str:
    """One markdown row of a case (the columns of :data:`HEADER`)."""
    rows = case["rows"]
    realised = [r for r in rows if r["realised"]]
    valid = [r for r in realised if r["hand_valid"]]
    reasons = collections.Counter(r["invalid_because"] for r in realised if r["invalid_because"])
    common = ", ".join(f"{gate} {count}" for gate, count in reasons.most_common(2)) or "-"
    tips = [r for r in rows if r["tips_valid"]]
    unplanned = sum(not r.get("planned", True) for r in rows)
    planned = f"{len(realised)} of {len(rows)}" + (f" ({unplanned} without a grasp)" if unplanned else "")
    return (
        f"| {case['hand']}, {case['object']}, {case['m']} | {_share(case['accepted'])} | {planned} "
        f"| {_median([r['worst_residual'] for r in realised], 3, 1e3)} | {len(valid)} of {len(realised)} "
        f"| {_median([r['hand_fidelity'] for r in valid if r['hand_fidelity'] is not None], 2)} | {common} "
        f"| {_median([r['hand_seconds'] for r in rows if r['hand_seconds'] is not None], 1)} | {len(tips)} of {len(rows)} "
        f"| {sum(r['realised'] for r in tips)}, {sum(r['hand_valid'] for r in tips)} "
        f"| {_median([r['tips_fidelity'] for r in tips if r['tips_fidelity'] is not None], 2)} "
        f"| {_median([r['hand_seconds'] / r['tips_seconds'] for r in valid if r['tips_valid']], 1)} |"
    )


def phase_line(case: dict[str, Any]) -> str:
    """Where the hand trials of a case spent their time: median seconds of each phase, and of the tips' trial."""
    rows = [r for r in case["rows"] if r["hand_valid"] and r["tips_valid"]]
    phases = ("fit", "close", "protocol", "ramps")
    times = {
        p: [r["hand_phase_seconds"].get(p) for r in rows if r.get("hand_phase_seconds", {}).get(p) is not None]
        for p in phases
    }
    parts = ", ".join(f"{p} {_median(times[p], 1)}" for p in phases)
    # The hand's ramps alone against the whole fingertip trial: a floor under the hand / tips ratio
    # that no faster fit or closing lowers.
    floor = [
        r["hand_phase_seconds"]["ramps"] / r["tips_seconds"]
        for r in rows
        if r.get("hand_phase_seconds", {}).get("ramps") is not None and r["tips_seconds"]
    ]
    return (
        f"{case['hand']}, {case['object']}: median s of the grasps valid with both: {parts}; "
        f"tips {_median([r['tips_seconds'] for r in rows], 1)}; the hand's ramps alone / tips trial {_median(floor, 1)}"
    )


def censored_line(case: dict[str, Any]) -> str:
    """How much of the fidelity's ground its medians stand on: the share of ramps that held past their end.

    A direction that holds past ``ramp_extent`` times its prediction is censored and left out of
    the grasp's median fidelity, which then flatters a prediction that runs low.
    """
    shares = {}
    for side in ("hand", "tips"):
        values = [r.get(f"{side}_censored") for r in case["rows"] if r.get(f"{side}_valid")]
        share = _median([v for v in values if v is not None], 0, 100.0)
        shares[side] = share if share == "-" else f"{share} %"
    return (
        f"{case['hand']}, {case['object']}: censored ramps (held past their end, left out of the fidelity), "
        f"median share over the valid grasps: hand {shares['hand']}, tips {shares['tips']}"
    )


def unrealised_line(case: dict[str, Any]) -> str | None:
    """Why the fit left the case's planned grasps unrealised, one reason per grasp, or None when it
    realised every planned one."""
    reasons = [r["unrealised_because"] for r in case["rows"] if r.get("unrealised_because")]
    if not reasons:
        return None
    return f"{case['hand']}, {case['object']}: not realised: {'; '.join(reasons)}"


HEADER = (
    "| hand, object, m | accepted (seed 0) | planned grasps realised | median worst residual [mm] | valid when closed "
    "| median fidelity | invalid because | s per grasp | valid with tips | of those: realised, held "
    "| tips' median fidelity | hand / tips time (both valid) |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--cases", default="sdh:box:3,sdh:sphere:3,sdh:donut:3,parallel_gripper:box:2")
    parser.add_argument("--contacts", type=int, default=100)
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--diagonal", type=float, default=0.2)
    parser.add_argument("--directions", type=int, default=16)
    parser.add_argument(
        "--plan-time-limit",
        type=float,
        default=None,
        help="plan each grasp within this many seconds (its best grasp then); default: the A* optimum",
    )
    parser.add_argument(
        "--torsional-friction",
        type=float,
        default=0.0,
        metavar="METRES",
        help="soft-finger contacts with this torsional friction [m] (0: hard point contacts)",
    )
    parser.add_argument(
        "--realise",
        type=int,
        default=None,
        metavar="N",
        help="plan again without each grasp the hand's fit cannot realise, up to N plans (as ogcp plan --realise)",
    )
    parser.add_argument("--out", type=Path, default=None, help="write hand_fit.json and the tips-versus-hand figure")
    args = parser.parse_args(argv)
    print(HEADER)
    cases = []
    for spec in args.cases.split(","):
        hand, name, m = spec.rsplit(":", 2)
        cases.append(run_case(hand, name, int(m), args))
        print(table_row(cases[-1]), flush=True)
    for case in cases:
        print(phase_line(case))
    for case in cases:
        print(censored_line(case))
    for case in cases:
        if (line := unrealised_line(case)) is not None:
            print(line)
    if args.out is not None:
        from ogcp.benchmarks.plots.style import save_figure
        from ogcp.benchmarks.plots.tips_hand import fig_tips_vs_hand

        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "hand_fit.json").write_text(
            json.dumps({"args": vars(args) | {"out": str(args.out)}, "cases": cases})
        )
        for path in save_figure(fig_tips_vs_hand(cases), args.out, "tips_vs_hand"):
            print(f"wrote {path}")


if __name__ == "__main__":
    main()
