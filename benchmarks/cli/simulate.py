"""``ogcp evaluate`` and ``ogcp decompose``: the simulation commands (MuJoCo is imported lazily)."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Any

# Only light modules at the top (the settings and their defaults): the parser is built for every
# command, ``--help`` included. numpy, the plan records and MuJoCo load in the handlers.
from benchmarks.cli.options import add_diagonal_option, finite_number, nonnegative_int
from planner.infra.atomic import write_json_atomic
from planner.infra.errors import OgcpError
from planner.objects.builtin import DEFAULT_DIAGONAL
from sim_eval.decomposition.settings import METHODS as DECOMPOSITION_METHODS
from sim_eval.decomposition.settings import DecompositionSettings
from sim_eval.settings import PROTOCOLS, SimSettings

AXIS_LABELS = ("+fx", "-fx", "+fy", "-fy", "+fz", "-fz", "+tx", "-tx", "+ty", "-ty", "+tz", "-tz", "q1-weakest")

# Defaults are read from the settings themselves, so each is written once.
_SIM = SimSettings()
_DECOMPOSITION = DecompositionSettings()


def _add_decomposition_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--decomposition",
        choices=DECOMPOSITION_METHODS,
        default=_DECOMPOSITION.method,
        help=f"convex decomposition of the object (default {_DECOMPOSITION.method})",
    )
    parser.add_argument(
        "--threshold",
        type=finite_number,
        default=_DECOMPOSITION.threshold,
        help=f"CoACD concavity threshold (default {_DECOMPOSITION.threshold:g})",
    )
    parser.add_argument(
        "--timeout",
        type=finite_number,
        default=_DECOMPOSITION.timeout_s,
        help=f"CoACD time limit [s] (default {_DECOMPOSITION.timeout_s:g})",
    )
    parser.add_argument(
        "--refine",
        type=finite_number,
        nargs="*",
        default=list(_DECOMPOSITION.refine_thresholds),
        metavar="THRESHOLD",
        help="finer CoACD thresholds tried in turn where the collision surface misses the mesh at a contact "
        f"(default {' '.join(f'{t:g}' for t in _DECOMPOSITION.refine_thresholds)}; none: never refine)",
    )
    parser.add_argument(
        "--contact-tolerance",
        type=finite_number,
        default=_DECOMPOSITION.contact_tolerance,
        help="largest offset of the collision surface from the mesh along a contact normal, as a fraction of "
        f"the object's diagonal (default {_DECOMPOSITION.contact_tolerance:g})",
    )


def register(commands: Any) -> None:
    """Add ``evaluate`` and ``decompose`` to the ``ogcp`` sub-commands."""
    evaluate = commands.add_parser("evaluate", help="simulate the grasps of a plan in MuJoCo: measured vs predicted")
    evaluate.add_argument("plan", type=Path, metavar="PLAN.json", help="plan result (ogcp plan ... --json / -o)")
    evaluate.add_argument(
        "--directions",
        type=nonnegative_int,
        default=_SIM.directions,
        help=f"quasi-uniform 6-D load directions besides the 12 axes and Q1's weakest (default {_SIM.directions})",
    )
    evaluate.add_argument(
        "--max-force",
        type=finite_number,
        default=_SIM.max_normal_force,
        help=f"per-finger normal-force cap F_max [N] (default {_SIM.max_normal_force:g})",
    )
    evaluate.add_argument(
        "--tip-radius",
        type=finite_number,
        default=None,
        help=f"fingertip radius [m] (default {100 * _SIM.tip_radius_ratio:g}%% of the object's diagonal)",
    )
    evaluate.add_argument(
        "--ramp-time",
        type=finite_number,
        default=_SIM.ramp_time,
        help=f"seconds for a load to reach its prediction (default {_SIM.ramp_time:g})",
    )
    evaluate.add_argument(
        "--protocol",
        choices=PROTOCOLS,
        default=_SIM.protocol,
        help="ramp to failure (default) or DexGraspBench's fixed +-x,y,z load",
    )
    evaluate.add_argument("--weight-test", action="store_true", help="also hold m g along the six force axes")
    evaluate.add_argument("--max-grasps", type=nonnegative_int, default=None, help="simulate at most this many grasps")
    evaluate.add_argument("--threads", type=nonnegative_int, default=None, help="rollout threads (default: all cores)")
    evaluate.add_argument(
        "--settings",
        type=Path,
        default=None,
        help="JSON file of further simulation settings (lengths at a 0.2 m diagonal, scaled with the object; "
        '"scale_lengths": false makes them absolute)',
    )
    _add_decomposition_options(evaluate)
    evaluate.add_argument(
        "--render",
        type=Path,
        default=None,
        metavar="PNG",
        help="also save a picture of the best grasp after settling (needs MUJOCO_GL=egl/osmesa)",
    )
    evaluate.add_argument("--json", action="store_true", help="print the ogcp.sim/2 record instead of a table")
    evaluate.add_argument("-o", "--output", type=Path, default=None, help="also write the ogcp.sim/2 record here")
    evaluate.set_defaults(handler=run_evaluate)

    decompose = commands.add_parser("decompose", help="fill the convex-decomposition cache for an object")
    decompose.add_argument("object", metavar="MESH_OR_NAME", help="mesh file or object name")
    add_diagonal_option(decompose, DEFAULT_DIAGONAL)
    _add_decomposition_options(decompose)
    decompose.add_argument("--json", action="store_true", help="print the decomposition metadata as JSON")
    decompose.set_defaults(handler=run_decompose)


def _decomposition(args: argparse.Namespace) -> DecompositionSettings:
    return DecompositionSettings(
        method=args.decomposition,
        threshold=args.threshold,
        timeout_s=args.timeout,
        refine_thresholds=tuple(args.refine),
        contact_tolerance=args.contact_tolerance,
    )


def _settings(args: argparse.Namespace) -> SimSettings:
    extra: dict[str, Any] = {}
    if args.settings is not None:
        try:
            extra = json.loads(args.settings.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise OgcpError(f"{args.settings}: cannot read simulation settings: {exc}") from exc
        if not isinstance(extra, dict):
            raise OgcpError(f"{args.settings}: simulation settings must be a JSON object")
    if args.threads == 0:
        raise OgcpError("--threads must be >= 1")
    values = {
        "directions": args.directions,
        "max_normal_force": args.max_force,
        "tip_radius": args.tip_radius,
        "ramp_time": args.ramp_time,
        "protocol": args.protocol,
        "weight_test": args.weight_test,
        "threads": args.threads,
        **extra,
    }
    return SimSettings.from_dict(values)


def _fmt(value: float | None, digits: int = 3) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _millimetres(values: Any) -> str:
    return "/".join("-" if v is None else f"{1e3 * v:.2f}" for v in values)


def _realized_lines(grasp: Any) -> list[str]:
    """Where the tips really started and how far the collision surface is from the mesh (sim/2 records)."""
    lines = []
    realized, collision = grasp.realized, grasp.collision
    if realized:
        change = grasp.q1_change
        lines.append(
            f"  realized contacts: {_millimetres(realized.get('offsets', []))} mm from the plan, normals "
            f"{'/'.join(f'{a:.1f}' for a in realized.get('normal_angles', []))} deg off; Q1 "
            f"{_fmt(grasp.q1, 4)} -> {_fmt(grasp.q1_realized, 4)} N"
            + ("" if change is None else f" ({100 * change:+.1f} %)")
        )
    if collision:
        lines.append(
            f"  collision surface: {_millimetres(collision.get('offsets', []))} mm from the mesh along the normals "
            f"(tolerance {_fmt(1e3 * collision.get('tolerance', math.nan), 2)} mm, CoACD threshold "
            f"{collision.get('threshold')})"
        )
        if collision.get("note"):
            lines.append(f"  note: {collision['note']}")
    return lines


def sim_summary(record: dict[str, Any]) -> str:
    """Human-readable table of an ``ogcp.sim/1`` or ``/2`` record."""
    import numpy as np

    from sim_eval.result import SimRecord

    sim = SimRecord.from_dict(record)
    name = sim.object.get("name") or sim.object.get("path", "?")
    lines = [f"object: {name}, {len(sim.grasps)} grasp(s), {sim.wall_seconds:.1f} s"]
    for g in sim.grasps:
        head = f"\n{g.label} {list(g.grasp or ())}: Q1 {_fmt(g.q1, 4)} N"
        if g.error:
            lines.append(f"{head}  {'UNREACHABLE' if g.unreachable else 'ERROR'} {g.error}")
            continue
        gates = g.gates
        lines.append(
            f"{head}  valid {g.valid} (penetration {gates['initial_penetration'] * 1e3:.3f} mm, "
            f"tips in contact {gates['tips_in_contact']}, creep {gates['creep'] * 1e6:.2f} um)"
        )
        lines.extend(f"  invalid: {reason}" for reason in g.invalid_reasons)
        lines.extend(_realized_lines(g))
        for name, test in g.hold_tests.items():
            lines.append(
                f"  {name} test: {'pass' if test['success'] else 'FAIL'} {dict(zip(test['axes'], test['passed']))}"
            )
        if not np.isfinite(g.measured).any():
            continue
        lines.append("  direction    predicted [N]  measured [N]  fidelity")
        for label, p, m, c, f in zip(g.direction_labels, g.predicted, g.measured, g.censored, g.fidelity):
            if label in AXIS_LABELS:
                lines.append(f"  {label:<11}  {_fmt(p):>13}  {_fmt(m):>12}{'+' if c else ' '} {_fmt(f)}")
        lines.append(
            f"  minimum      {_fmt(g.predicted_min):>13}  {_fmt(g.measured_min):>12}   "
            f"median fidelity over {len(g.direction_labels)} directions: {_fmt(g.median_fidelity)}"
        )
    m = sim.set_metrics
    unreachable = f" ({m['n_unreachable']} unreachable, not simulated)" if m.get("n_unreachable") else ""
    lines.append(
        f"\nset: {m['n_valid']} valid of {m['n_simulated']}{unreachable}, "
        f"median fidelity {_fmt(m.get('median_fidelity'))}"
        + ("" if m.get("median_q1_change") is None else f", median Q1 change {100 * m['median_q1_change']:+.1f} %")
    )
    if "q1_vs_measured" in m:
        q, p = m["q1_vs_measured"], m["predicted_vs_measured"]
        lines.append(
            f"Q1 vs measured min: Spearman {_fmt(q['spearman'])}, Kendall {_fmt(q['kendall'])}; "
            f"predicted vs measured: Spearman {_fmt(p['spearman'])}, Kendall {_fmt(p['kendall'])}; "
            f"AUC(Q1, holds {m['holding_load']} N) {_fmt(m['auc_q1_holds'])}"
        )
    lines.append("(+ = held to the end of the ramp: a lower bound)")
    return "\n".join(lines)


def run_evaluate(args: argparse.Namespace) -> int:
    from planner.records.plan import load_plan
    from sim_eval.evaluate import evaluate_plan

    record = load_plan(args.plan)
    result = evaluate_plan(
        record, _settings(args), _decomposition(args), progress=sys.stderr.isatty(), max_grasps=args.max_grasps
    )
    data = result.to_dict()
    if args.render is not None:
        _render(record, args)
    if args.output is not None:
        write_json_atomic(args.output, data)
    print(json.dumps(data) if args.json else sim_summary(data))
    return 0


def _render(record: dict[str, Any], args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from sim_eval.render import render_plan

    image = render_plan(record, _settings(args), _decomposition(args))
    try:
        plt.imsave(args.render, image)
    except OSError as exc:
        raise OgcpError(f"cannot write {args.render}: {exc.strerror or exc}") from exc
    print(f"picture of the best grasp: {args.render}", file=sys.stderr)


def run_decompose(args: argparse.Namespace) -> int:
    from planner.objects import resolve_object
    from sim_eval.decomposition.decompose import decompose

    mesh, _ = resolve_object(args.object, args.diagonal)
    settings = _decomposition(args)
    # Every level of the ladder, so that evaluate finds the finer ones cached too.
    for threshold in settings.ladder:
        level = dataclasses.replace(settings, threshold=threshold)
        result = decompose(mesh, level, progress=sys.stderr.isatty(), name=args.object)
        if args.json:
            print(json.dumps({**result.meta, "cache_path": str(result.cache_path)}))
        else:
            print(
                f"{args.object} at threshold {threshold:g}: {result.hull_count} convex parts, volume ratio "
                f"{result.volume_ratio}, {result.compute_seconds:.1f} s, cached at {result.cache_path}"
            )
    return 0
