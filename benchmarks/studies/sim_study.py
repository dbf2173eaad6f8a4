"""Simulation study: rollout throughput, ramp-rate independence, and Q1 against measured resistance.

Run ``python -m benchmarks.studies.sim_study --out DIR`` (default objects: the four built-ins). For each
object it simulates a set of grasps spanning the quality range: the A* optimum, the best of a
seeded random sample ("top"), random force-closure grasps and HFTS runs; then writes
``sim_study.json`` and ``sim_study.md`` with the set-level correlations, and prints the
throughput of ``mujoco.rollout`` against a serial ``mj_step`` loop measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from planner import GraspPlanner, resolve_object, sample_contacts
from planner.baselines.hfts import HFTS
from planner.grasp.contact_set import ContactSet
from planner.grasp.quality import q1
from planner.infra.atomic import write_json_atomic
from planner.infra.provenance import provenance
from sim_eval.body import object_inertia
from sim_eval.decomposition.decompose import decompose
from sim_eval.directions import direction_set
from sim_eval.evaluate import GraspEvaluator
from sim_eval.predict import predicted_resistance
from sim_eval.protocol import ramp_trials, serial_trials, settle
from sim_eval.result import SimRecord
from sim_eval.scene import build_scene
from sim_eval.settings import SimSettings


def grasp_pool(
    contacts: ContactSet, m: int, seed: int, top: int, random_fc: int, hfts_runs: int
) -> tuple[list[tuple[int, ...]], list[str]]:
    """Grasps spanning the quality range: optimum, best sampled, random force-closure, HFTS."""
    rng = np.random.default_rng(seed)
    found: dict[tuple[int, ...], str] = {}
    found[tuple(GraspPlanner().plan(contacts, m).grasp)] = "astar"
    sample = {tuple(sorted(rng.choice(len(contacts), m, replace=False).tolist())) for _ in range(4000)}
    scored = sorted(((q1(contacts.subset_wrenches(np.array(g))), g) for g in sample), reverse=True)
    for _, g in scored[:top]:
        found.setdefault(g, "top")
    fc = [g for value, g in scored if value > 0]
    for k in rng.permutation(len(fc))[:random_fc]:
        found.setdefault(fc[k], "random-fc")
    for run in HFTS(runs=hfts_runs, seed=seed).run(contacts, m).runs:
        found.setdefault(tuple(run.grasp), "hfts")
    return list(found), list(found.values())


def throughput(contacts: ContactSet, mesh: Any, grasp: tuple[int, ...], settings: SimSettings) -> dict[str, float]:
    """Direction-trials per second: rollout over threads vs a serial mj_step loop, same trials."""
    parts = decompose(mesh)
    com, inertia = object_inertia(mesh, settings.object_mass)
    idx = np.asarray(grasp)
    radius = settings.tip_radius_ratio * float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    scene = build_scene(
        parts.parts, com, inertia, contacts.positions[idx], contacts.normals[idx], settings, contacts.mu, radius
    )
    settled = settle(scene, settings)
    dirs = direction_set(settings.directions, settings.direction_seed).vectors
    pred = predicted_resistance(
        contacts.positions[idx],
        contacts.normals[idx],
        contacts.com,
        contacts.torque_scale,
        contacts.mu,
        settings.prediction_cone_edges,
        settings.max_normal_force,
        dirs,
    ).resistance
    rates = np.maximum(pred, 0.1 * pred.max()) / settings.ramp_time
    duration = settings.ramp_extent * settings.ramp_time
    t0 = time.perf_counter()
    batched = ramp_trials(scene, settled, dirs, rates, duration, contacts.torque_scale, settings)
    t1 = time.perf_counter()
    serial = serial_trials(scene, settled, dirs, rates, duration, contacts.torque_scale, settings)
    t2 = time.perf_counter()
    agree = float(np.max(np.abs(batched.failure_load - serial.failure_load)))
    return {
        "trials": len(dirs),
        "steps_per_trial": batched.steps,
        "threads": settings.threads or os.cpu_count(),
        "rollout_trials_per_s": len(dirs) / (t1 - t0),
        "serial_trials_per_s": len(dirs) / (t2 - t1),
        "speedup": (t2 - t1) / (t1 - t0),
        "max_abs_difference": agree,
    }


def study_object(
    name: str, n: int, m: int, seed: int, settings: SimSettings, args: argparse.Namespace
) -> dict[str, Any]:
    mesh, source = resolve_object(name)
    contacts = sample_contacts(mesh, n, seed, source=source)
    grasps, labels = grasp_pool(contacts, m, seed, args.top, args.random_fc, args.hfts_runs)
    evaluator = GraspEvaluator(settings, progress=True)
    result = evaluator.evaluate(mesh, contacts, grasps, labels)
    slow = GraspEvaluator(settings.with_updates(ramp_time=2 * settings.ramp_time)).evaluate(
        mesh, contacts, grasps[: args.rate_grasps], labels[: args.rate_grasps]
    )
    changes = []
    for fast, half in zip(result.grasps, slow.grasps, strict=False):
        ok = ~fast.censored & ~half.censored & np.isfinite(fast.measured) & np.isfinite(half.measured)
        changes.extend(np.abs(half.measured[ok] / fast.measured[ok] - 1).tolist())
    record = SimRecord.from_dict(result.to_dict())
    rate = {
        "grasps": len(slow.grasps),
        "directions": len(changes),
        "median_change": float(np.median(changes)) if changes else None,
        "p90_change": float(np.percentile(changes, 90)) if changes else None,
        "within_2pct": float(np.mean(np.array(changes) <= 0.02)) if changes else None,
    }
    summary = {
        "object": name,
        "contacts": n,
        "grasps": len(grasps),
        "labels": labels,
        "set_metrics": record.set_metrics,
        "rate_halving": rate,
        "per_grasp": [
            {
                "label": g.label,
                "grasp": list(g.grasp or ()),
                "q1": g.q1,
                "valid": g.valid,
                "predicted_min": g.predicted_min,
                "measured_min": g.measured_min,
                "median_fidelity": g.median_fidelity,
            }
            for g in record.grasps
        ],
        "wall_seconds": record.wall_seconds,
    }
    if args.throughput:
        summary["throughput"] = throughput(contacts, mesh, grasps[0], settings)
    return summary


def markdown(rows: list[dict[str, Any]]) -> str:
    def f(v: Any) -> str:
        return "-" if v is None else f"{v:.3f}"

    header = (
        "| object | grasps | valid | Spearman Q1 | Kendall Q1 | Spearman pred | Kendall pred | AUC Q1 | "
        "median fidelity | rate x0.5: median change |"
    )
    lines = [header, "|" + "---|" * 10]
    for r in rows:
        s = r["set_metrics"]
        q, p = s.get("q1_vs_measured", {}), s.get("predicted_vs_measured", {})
        lines.append(
            f"| {r['object']} | {r['grasps']} | {s['n_valid']} | {f(q.get('spearman'))} | "
            f"{f(q.get('kendall'))} | {f(p.get('spearman'))} | {f(p.get('kendall'))} | "
            f"{f(s.get('auc_q1_holds'))} | {f(s.get('median_fidelity'))} | "
            f"{f(r['rate_halving']['median_change'])} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", nargs="+", default=["box", "sphere", "donut", "amphora"])
    parser.add_argument("-n", "--contacts", type=int, default=200)
    parser.add_argument("-m", "--fingers", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--top", type=int, default=8)
    parser.add_argument("--random-fc", type=int, default=14)
    parser.add_argument("--hfts-runs", type=int, default=6)
    parser.add_argument("--rate-grasps", type=int, default=4, help="grasps re-run at half the ramp rate")
    parser.add_argument("--directions", type=int, default=64)
    parser.add_argument("--holding-load", type=float, default=3.0)
    parser.add_argument("--no-throughput", dest="throughput", action="store_false")
    parser.add_argument("--out", type=Path, default=Path("results/sim_study"))
    args = parser.parse_args(argv)
    settings = SimSettings(directions=args.directions, holding_load=args.holding_load)
    rows = []
    for name in args.objects:
        rows.append(study_object(name, args.contacts, args.fingers, args.seed, settings, args))
        print(markdown(rows[-1:]), flush=True)
        if "throughput" in rows[-1]:
            print("throughput:", json.dumps(rows[-1]["throughput"]), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(
        args.out / "sim_study.json", {"rows": rows, "settings": settings.to_dict(), "provenance": provenance()}
    )
    (args.out / "sim_study.md").write_text(markdown(rows))
    print(markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
