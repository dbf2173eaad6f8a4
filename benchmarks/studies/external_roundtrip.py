"""An ogcp plan evaluated as a plan and as exported ``ogcp.grasps/1`` grasps gives the same numbers.

Run: ``python -m ogcp.benchmarks.studies.external_roundtrip [--object box] [--grasps 100] [--contacts 100]
[--directions 8] [--decomposition coacd|convex_hull]``. Plans the A* optimum on the object's contacts
(sampled as ``ogcp plan`` samples them), adds random distinct grasps as the plan's ``top`` list up
to ``--grasps``, evaluates the plan (``ogcp.sim_eval.evaluate_plan``), exports it
(``ogcp.sim_eval.export_grasps``), evaluates the file (``ogcp.sim_eval.evaluate_grasps``), and prints the
largest differences of Q1, validity, the predicted and the measured resistance per direction.
Every one must be 0 (or within 1e-9 relative): the external path adds nothing of its own.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.records.plan import contact_set_record
from ogcp.sim_eval import SimResult, evaluate_grasps, evaluate_plan, export_grasps


def _difference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Largest absolute and relative difference of two arrays; NaN must sit at the same places."""
    if a.shape != b.shape or not np.array_equal(np.isnan(a), np.isnan(b)):
        return float("inf"), float("inf")
    finite = ~np.isnan(a)
    if not finite.any():
        return 0.0, 0.0
    gap = np.abs(a[finite] - b[finite])
    return float(gap.max()), float((gap / np.maximum(np.abs(a[finite]), 1e-300)).max())


def compare(plan: SimResult, external: SimResult) -> dict[str, float]:
    """Largest differences between the two evaluations, grasp by grasp (same order)."""
    worst = {"q1_abs": 0.0, "q1_rel": 0.0, "predicted_rel": 0.0, "measured_abs": 0.0, "measured_rel": 0.0}
    mismatched = 0
    for a, b in zip(plan.grasps, external.grasps, strict=True):
        mismatched += (a.label, a.valid, a.error is None) != (b.label, b.valid, b.error is None)
        q_abs, q_rel = _difference(np.array([a.q1]), np.array([b.q1]))
        p_rel = _difference(a.predicted, b.predicted)[1]
        m_abs, m_rel = _difference(a.measured, b.measured)
        for key, value in zip(worst, (q_abs, q_rel, p_rel, m_abs, m_rel), strict=True):
            worst[key] = max(worst[key], value)
    worst["mismatched_grasps"] = float(mismatched)
    worst["measured_values"] = float(sum(np.isfinite(g.measured).sum() for g in plan.grasps))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--object", default="box", help="built-in or fetched name, or mesh path")
    parser.add_argument("--contacts", type=int, default=100)
    parser.add_argument("--grasps", type=int, default=100)
    parser.add_argument("--m", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--directions", type=int, default=8)
    parser.add_argument("--decomposition", default="coacd", choices=("coacd", "convex_hull"))
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()

    mesh, source = resolve_object(args.object, None)
    contacts = sample_contacts(mesh, args.contacts, args.seed, source=source, tip_radius=default_tip_radius(mesh))
    best = GraspPlanner().plan(contacts, args.m)
    record = best.to_dict(contact_set_record(contacts))
    rng = np.random.default_rng(args.seed)
    chosen = [tuple(best.grasp)]
    while len(chosen) < args.grasps:
        grasp = tuple(sorted(int(i) for i in rng.choice(len(contacts), args.m, replace=False)))
        if grasp not in chosen:
            chosen.append(grasp)
    record["top"] = [{"grasp": list(g)} for g in chosen[1:]]
    settings = {"directions": args.directions, "threads": args.threads}
    decomposition = {"method": args.decomposition}

    start = time.perf_counter()
    planned = evaluate_plan(record, settings, decomposition)
    plan_seconds = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as folder:
        exported = export_grasps(record, Path(folder) / "grasps.json")
        start = time.perf_counter()
        external = evaluate_grasps(None, exported, settings, decomposition)
        external_seconds = time.perf_counter() - start
    worst = compare(planned, external)
    directions = len(planned.grasps[0].direction_labels)
    print(
        f"{args.object}: {len(planned.grasps)} grasps (A* optimum Q1 {best.q1:.6g} + random), "
        f"{directions} directions each, {planned.set_metrics['n_valid']} valid; "
        f"plan {plan_seconds:.1f} s, external {external_seconds:.1f} s"
    )
    print(
        "max |Q1 plan - Q1 external| = {q1_abs:.3g} (relative {q1_rel:.3g}); predicted: relative {predicted_rel:.3g}; "
        "measured ({measured_values:.0f} finite values): {measured_abs:.3g} N (relative {measured_rel:.3g}); grasps whose label, validity or error "
        "differ: {mismatched_grasps:.0f}".format(**worst)
    )


if __name__ == "__main__":
    main()
