"""Simulation study: rollout throughput, ramp-rate independence, and Q1 against measured resistance.

Run ``python -m ogcp.benchmarks.studies.sim_study --out DIR`` (default objects: the four built-ins). For each
object it simulates a set of grasps spanning the quality range: the A* optimum, the best of a
seeded random sample ("top"), random force-closure grasps and HFTS runs; then writes
``sim_study.json`` and ``sim_study.md`` with the set-level correlations, and prints the
throughput of ``mujoco.rollout`` against a serial ``mj_step`` loop measured in the same run.

The second table is about generalisation: per object and size (``--diagonals``), with the
default (reach-aware) contacts, the share of valid grasps (all, and A* with HFTS), the deepest
initial penetration, the median fidelity, the median planned-to-realized Q1 change, the
collision surface's offset from the mesh at the contacts, and the decomposition's parts and
time. For meshes the project was never tuned on::

    ogcp assets fetch all
    python -m ogcp.benchmarks.studies.sim_study --objects bunny homer plane cow bone cheetah dragon dog \
        --diagonals 0.05 0.2 2 --top 0 --random-fc 0 --hfts-runs 8 --rate-grasps 0 --no-throughput
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.baselines.hfts import HFTS
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.quality import q1
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.provenance import provenance
from ogcp.sim_eval.decomposition.decompose import decompose
from ogcp.sim_eval.evaluate import GraspEvaluator, object_diagonal
from ogcp.sim_eval.protocols.directions import direction_set
from ogcp.sim_eval.protocols.phases import ramp_trials, serial_trials, settle
from ogcp.sim_eval.protocols.predict import predicted_resistance
from ogcp.sim_eval.result import SimRecord
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.grasp_scene import build_scene
from ogcp.sim_eval.settings import SimSettings


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
    for run in HFTS(runs=hfts_runs, seed=seed).run(contacts, m).runs if hfts_runs else ():
        found.setdefault(tuple(run.grasp), "hfts")
    return list(found), list(found.values())


def throughput(contacts: ContactSet, mesh: Any, grasp: tuple[int, ...], settings: SimSettings) -> dict[str, float]:
    """Direction-trials per second: rollout over threads vs a serial mj_step loop, same trials."""
    parts = decompose(mesh)
    com, inertia = object_inertia(mesh, settings.body_mass)
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
        "threads": float(settings.threads or os.cpu_count() or 1),
        "rollout_trials_per_s": len(dirs) / (t1 - t0),
        "serial_trials_per_s": len(dirs) / (t2 - t1),
        "speedup": (t2 - t1) / (t1 - t0),
        "max_abs_difference": agree,
    }


def study_object(
    name: str, n: int, m: int, seed: int, settings: SimSettings, args: argparse.Namespace, diagonal: float | None = None
) -> dict[str, Any]:
    mesh, source = resolve_object(name, diagonal)
    contacts = sample_contacts(mesh, n, seed, source=source, tip_radius=default_tip_radius(mesh))
    grasps, labels = grasp_pool(contacts, m, seed, args.top, args.random_fc, args.hfts_runs)
    evaluator = GraspEvaluator(settings, progress=True)
    result = evaluator.evaluate(mesh, contacts, grasps, labels)
    changes = []
    slow_grasps = 0
    if args.rate_grasps:
        slow = GraspEvaluator(settings.with_updates(ramp_time=2 * settings.ramp_time)).evaluate(
            mesh, contacts, grasps[: args.rate_grasps], labels[: args.rate_grasps]
        )
        slow_grasps = len(slow.grasps)
        for fast, half in zip(result.grasps, slow.grasps, strict=False):
            ok = ~fast.censored & ~half.censored & np.isfinite(fast.measured) & np.isfinite(half.measured)
            changes.extend(np.abs(half.measured[ok] / fast.measured[ok] - 1).tolist())
    record = SimRecord.from_dict(result.to_dict())
    rate = {
        "grasps": slow_grasps,
        "directions": len(changes),
        "median_change": float(np.median(changes)) if changes else None,
        "p90_change": float(np.percentile(changes, 90)) if changes else None,
        "within_2pct": float(np.mean(np.array(changes) <= 0.02)) if changes else None,
    }
    summary = {
        "object": name,
        "diagonal": object_diagonal(mesh),
        "generalisation": generalisation(record, labels),
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
                "q1_change": g.q1_change,
                "collision_offsets": g.collision.get("offsets"),
                "invalid_reasons": list(g.invalid_reasons),
                "error": g.error,
            }
            for g in record.grasps
        ],
        "wall_seconds": record.wall_seconds,
    }
    if args.throughput:
        summary["throughput"] = throughput(contacts, mesh, grasps[0], settings)
    return summary


def generalisation(record: SimRecord, labels: list[str]) -> dict[str, Any]:
    """Valid share, penetration, fidelity, Q1 change and collision-surface offsets of one object's grasps."""
    diagonal = float(record.settings.get("object_diagonal") or math.nan)
    planned = [g for g, label in zip(record.grasps, labels, strict=True) if label in ("astar", "hfts")]
    offsets = [abs(o) for g in record.grasps for o in g.collision.get("offsets", []) if o is not None]
    within = [g.collision["within_tolerance"] for g in record.grasps if "within_tolerance" in g.collision]
    decomposition = record.decomposition
    levels = [decomposition, *decomposition.get("refined", [])]
    m = record.set_metrics
    return {
        "valid": sum(bool(g.valid) for g in record.grasps) / max(1, len(record.grasps)),
        "valid_astar_hfts": sum(bool(g.valid) for g in planned) / max(1, len(planned)),
        "valid_force_closure": _share([bool(g.valid) for g in record.grasps if (g.q1 or 0.0) > 0]),
        "max_penetration_ratio": m.get("max_initial_penetration_ratio"),
        "median_fidelity": m.get("median_fidelity"),
        "median_q1_change": m.get("median_q1_change"),
        "median_abs_q1_change": _median([abs(g.q1_change) for g in record.grasps if g.q1_change is not None]),
        "median_offset_ratio": float(np.median(offsets)) / diagonal if offsets else None,
        "max_offset_ratio": max(offsets) / diagonal if offsets else None,
        "within_tolerance": sum(within) / len(within) if within else None,
        "hull_counts": [level.get("hull_count") for level in levels],
        "decomposition_seconds": sum(float(level.get("compute_seconds") or 0.0) for level in levels),
    }


def _share(flags: list[bool]) -> float | None:
    return sum(flags) / len(flags) if flags else None


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def generalisation_markdown(rows: list[dict[str, Any]]) -> str:
    """The generalisation table: one row per object and size."""

    def pct(v: Any, digits: int = 0) -> str:
        return "-" if v is None else f"{100 * v:.{digits}f} %"

    header = (
        "| object | diagonal [m] | grasps | valid | valid A*+HFTS | valid, Q1 > 0 | max penetration / diag | "
        "median fidelity | median Q1 change | median / max offset / diag | within tolerance | parts | "
        "decomposition [s] |"
    )
    lines = [header, "|" + "---|" * 13]
    for r in rows:
        g = r["generalisation"]
        fid = "-" if g["median_fidelity"] is None else f"{g['median_fidelity']:.3f}"
        lines.append(
            f"| {r['object']} | {r['diagonal']:.3g} | {r['grasps']} | {pct(g['valid'])} | "
            f"{pct(g['valid_astar_hfts'])} | {pct(g['valid_force_closure'])} | {pct(g['max_penetration_ratio'], 3)} | "
            f"{fid} | "
            f"{pct(g['median_q1_change'], 1)} | {pct(g['median_offset_ratio'], 3)} / {pct(g['max_offset_ratio'], 2)} | "
            f"{pct(g['within_tolerance'])} | {'/'.join(str(c) for c in g['hull_counts'])} | "
            f"{g['decomposition_seconds']:.0f} |"
        )
    return "\n".join(lines) + "\n"


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
    parser.add_argument(
        "--diagonals", type=float, nargs="+", default=None, help="sizes [m] to scale each object to (default: its own)"
    )
    parser.add_argument("--out", type=Path, default=Path("results/sim_study"))
    args = parser.parse_args(argv)
    settings = SimSettings(directions=args.directions, holding_load=args.holding_load)
    rows = []
    for name in args.objects:
        for diagonal in args.diagonals or [None]:
            rows.append(study_object(name, args.contacts, args.fingers, args.seed, settings, args, diagonal))
            print(markdown(rows[-1:]), generalisation_markdown(rows[-1:]), sep="\n", flush=True)
            if "throughput" in rows[-1]:
                print("throughput:", json.dumps(rows[-1]["throughput"]), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(
        args.out / "sim_study.json", {"rows": rows, "settings": settings.to_dict(), "provenance": provenance()}
    )
    (args.out / "sim_study.md").write_text(markdown(rows) + "\n" + generalisation_markdown(rows))
    print(markdown(rows), generalisation_markdown(rows), sep="\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
