"""``ogcp evaluate`` and ``ogcp decompose``: the simulation commands (MuJoCo is imported lazily)."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tomllib
from pathlib import Path
from typing import Any

# Only light modules at the top (the settings and their defaults): the parser is built for every
# command, ``--help`` included. numpy, the plan records and MuJoCo load in the handlers.
from ogcp.benchmarks.cli.options import (
    add_contact_model_options,
    add_diagonal_option,
    check_output,
    contact_model_given,
    finite_number,
    torsion_from_args,
    typed,
    valid,
)
from ogcp.planner.config.options import ConfigError, Option
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.builtin import DEFAULT_DIAGONAL
from ogcp.sim_eval.decomposition.settings import METHODS as DECOMPOSITION_METHODS
from ogcp.sim_eval.decomposition.settings import DecompositionSettings
from ogcp.sim_eval.settings import PROTOCOLS, RANGES, SimSettings

AXIS_LABELS = ("+fx", "-fx", "+fy", "-fy", "+fz", "-fz", "+tx", "-tx", "+ty", "-ty", "+tz", "-tz", "q1-weakest")

# Defaults are read from the settings themselves, so each is written once.
_SIM = SimSettings()
_DECOMPOSITION = DecompositionSettings()
#: Grasps of a plan simulated at most: at least one (0 would simulate nothing and succeed).
MAX_GRASPS = Option("int", None, "grasps simulated at most", minimum=1)


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
    evaluate.add_argument(
        "plan",
        type=Path,
        metavar="PLAN_OR_GRASPS.json",
        help="plan result (ogcp plan ... --json / -o) or grasps from any planner (schema ogcp.grasps/1, "
        "docs/external_grasps.md)",
    )
    evaluate.add_argument(
        "--directions",
        type=typed(RANGES["directions"]),
        default=_SIM.directions,
        help="quasi-uniform 6-D load directions besides the 12 axes and Q1's weakest; "
        f"{valid(RANGES['directions'])} (default {_SIM.directions})",
    )
    evaluate.add_argument(
        "--max-force",
        type=typed(RANGES["max_normal_force"]),
        default=_SIM.max_normal_force,
        help=f"per-finger normal-force cap F_max [N]; {valid(RANGES['max_normal_force'])} "
        f"(default {_SIM.max_normal_force:g})",
    )
    evaluate.add_argument(
        "--tip-radius",
        type=typed(RANGES["tip_radius"]),
        default=None,
        metavar="METRES",
        help=f"fingertip radius [m]; {valid(RANGES['tip_radius'])} "
        f"(default {100 * _SIM.tip_radius_ratio:g}%% of the object's diagonal)",
    )
    evaluate.add_argument(
        "--ramp-time",
        type=typed(RANGES["ramp_time"]),
        default=_SIM.ramp_time,
        metavar="SECONDS",
        help=f"seconds for a load to reach its prediction; {valid(RANGES['ramp_time'])} (default {_SIM.ramp_time:g})",
    )
    evaluate.add_argument(
        "--protocol",
        choices=PROTOCOLS,
        default=_SIM.protocol,
        help="ramp to failure (default) or DexGraspBench's fixed +-x,y,z load",
    )
    evaluate.add_argument("--weight-test", action="store_true", help="also hold m g along the six force axes")
    evaluate.add_argument(
        "--tips",
        action="store_true",
        help="test a plan made with a hand with fingertip spheres instead (default: the plan's hand, closed "
        "by its servos)",
    )
    model = evaluate.add_argument_group(
        "contact model of the simulation",
        "default: the plan's own (a grasps file's, else hard); given, it replaces it in the simulation and the "
        "prediction, while Q1 stays the plan's",
    )
    add_contact_model_options(model)
    evaluate.add_argument(
        "--on-surface",
        choices=("project", "refuse"),
        default="project",
        help="contacts of an ogcp.grasps/1 file off the mesh surface: project them onto it (with a warning) "
        "or refuse the file (default project)",
    )
    evaluate.add_argument(
        "--max-grasps",
        type=typed(MAX_GRASPS),
        default=None,
        metavar="N",
        help=f"simulate at most this many grasps, best first; {valid(MAX_GRASPS)} (default: all of the plan's)",
    )
    evaluate.add_argument(
        "--threads",
        type=typed(RANGES["threads"]),
        default=None,
        help=f"rollout threads; {valid(RANGES['threads'])} (default: all cores)",
    )
    evaluate.add_argument(
        "--settings",
        type=Path,
        default=None,
        metavar="FILE",
        help="JSON or TOML (.toml) file of further simulation settings, by name (lengths at a 0.2 m diagonal, "
        'scaled with the object; "scale_lengths": false makes them absolute)',
    )
    _add_decomposition_options(evaluate)
    evaluate.add_argument(
        "--render",
        type=Path,
        default=None,
        metavar="PNG",
        help="also save a picture of the best grasp after settling, with the plan's hand unless --tips "
        "(needs MUJOCO_GL=egl/osmesa)",
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


def settings_file(path: Path) -> dict[str, Any]:
    """The settings of a ``--settings`` file: a JSON object, or a TOML table for a ``.toml`` file.

    Raises:
        OgcpError: For a file that cannot be read, is not valid JSON (TOML), or is not a table
            of settings; one line naming the file and where it is wrong.
    """
    toml = path.suffix.lower() == ".toml"
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text) if toml else json.loads(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise OgcpError(f"{path}: cannot read simulation settings: {getattr(exc, 'strerror', None) or exc}") from exc
    except json.JSONDecodeError as exc:
        hint = "" if text.lstrip().startswith(("{", "[")) else "; a TOML file needs the suffix .toml"
        raise OgcpError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno}){hint}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise OgcpError(f"{path}: not valid TOML ({exc})") from exc
    if not isinstance(data, dict):
        raise OgcpError(
            f"{path}: simulation settings must be a JSON object of settings by name, got {type(data).__name__}"
        )
    return data


def _settings(args: argparse.Namespace) -> SimSettings:
    extra = settings_file(args.settings) if args.settings is not None else {}
    values = {
        "directions": args.directions,
        "max_normal_force": args.max_force,
        "tip_radius": args.tip_radius,
        "ramp_time": args.ramp_time,
        "protocol": args.protocol,
        "weight_test": args.weight_test,
        "threads": args.threads,
        **({"torsional_friction": torsion_from_args(args)} if contact_model_given(args) else {}),
        **extra,
    }
    try:
        return SimSettings.from_dict(values)
    except OgcpError as exc:
        # Name the file when the value came from it (the flags' own values were checked by argparse).
        flag = isinstance(exc, ConfigError) and exc.field.rsplit(" ", 1)[-1] not in extra
        if args.settings is None or flag:
            raise
        raise OgcpError(f"{args.settings}: {exc}") from exc


def _fmt(value: Any, digits: int = 3, scale: float = 1.0) -> str:
    """A number of a record for the table: ``-`` for what is not one (NaN is null in JSON, a
    diverged grasp's creep is infinite, a hand-edited record may hold anything)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "-"
    return f"{scale * value:.{digits}f}"


def _list(values: Any) -> list[Any]:
    return values if isinstance(values, list) else []


def _millimetres(values: Any) -> str:
    return "/".join(_fmt(v, 2, 1e3) for v in _list(values))


def _realized_lines(grasp: Any) -> list[str]:
    """Where the tips really started and how far the collision surface is from the mesh (sim/2 records)."""
    lines = []
    realized, collision = grasp.realized, grasp.collision
    if realized:
        change = grasp.q1_change
        lines.append(
            f"  realized contacts: {_millimetres(realized.get('offsets', []))} mm from the plan, normals "
            f"{'/'.join(_fmt(a, 1) for a in _list(realized.get('normal_angles')))} deg off; Q1 "
            f"{_fmt(grasp.q1, 4)} -> {_fmt(grasp.q1_realized, 4)}"
            + ("" if change is None else f" ({100 * change:+.1f} %)")
        )
    if collision:
        lines.append(
            f"  collision surface: {_millimetres(collision.get('offsets', []))} mm from the mesh along the normals "
            f"(tolerance {_fmt(collision.get('tolerance'), 2, 1e3)} mm, CoACD threshold "
            f"{collision.get('threshold')})"
        )
        if collision.get("note"):
            lines.append(f"  note: {collision['note']}")
    return lines


def _hand_lines(hand: dict[str, Any]) -> list[str]:
    """The hand's fit and the contacts of its other links, for a grasp tested with a hand."""
    if not hand:
        return []
    residuals = [f"{1e3 * r:.2f}" for r in _list(hand.get("fit_residuals")) if isinstance(r, int | float)]
    lines = [f"  hand {hand.get('name', '?')}: pad residuals [mm] {', '.join(residuals) or '-'}"]
    extra = [
        f"{e.get('link')} {_fmt(e.get('force'))} N" for e in _list(hand.get("extra_contacts")) if isinstance(e, dict)
    ]
    if extra:
        lines.append(f"  other links touching the object: {', '.join(extra)}")
    pads = (hand.get("fit") or {}).get("reason") if isinstance(hand.get("fit"), dict) else None
    if pads:
        lines.append(f"  fit: {pads}")
    return lines


def sim_summary(record: dict[str, Any]) -> str:
    """Human-readable table of an ``ogcp.sim/1`` or ``/2`` record."""
    import numpy as np

    from ogcp.sim_eval.result import SimRecord

    sim = SimRecord.from_dict(record)
    name = sim.object.get("name") or sim.object.get("path", "?")
    found = sim.object.get("torque_scale")
    rho = float(found) if isinstance(found, (int, float)) and not isinstance(found, bool) and found > 0 else None
    lines = [f"object: {name}, {len(sim.grasps)} grasp(s), {_fmt(sim.wall_seconds, 1)} s"]
    for g in sim.grasps:
        head = f"\n{g.label} {list(g.grasp or ())}: Q1 {_fmt(g.q1, 4)}"
        if g.error:
            lines.append(f"{head}  {'UNREACHABLE' if g.unreachable else 'ERROR'} {g.error}")
            continue
        gates = g.gates
        # A diverged grasp has no finite creep or measurements: its table shows "-" for them.
        diverged = " DIVERGED" if gates.get("diverged") is True else ""
        lines.append(
            f"{head}  valid {g.valid}{diverged} (penetration {_fmt(gates.get('initial_penetration'), 3, 1e3)} mm, "
            f"tips in contact {gates.get('tips_in_contact', '-')}, creep {_fmt(gates.get('creep'), 2, 1e6)} um)"
        )
        lines.extend(f"  invalid: {reason}" for reason in g.invalid_reasons)
        lines.extend(_hand_lines(g.hand))
        lines.extend(_realized_lines(g))
        for name, test in g.hold_tests.items():
            test = test if isinstance(test, dict) else {}
            passed = dict(zip(_list(test.get("axes")), _list(test.get("passed"))))
            lines.append(f"  {name} test: {'pass' if test.get('success') is True else 'FAIL'} {passed}")
            lines.extend(f"    {failure}" for failure in _list(test.get("failures")))
        if not np.isfinite(g.measured).any():
            continue
        lines.append("  direction      predicted     measured  unit   fidelity")
        for label, p, m, c, f in zip(g.direction_labels, g.predicted, g.measured, g.censored, g.fidelity):
            if label in AXIS_LABELS:
                scale, unit = _row_unit(label, rho)
                lines.append(
                    f"  {label:<11}  {_fmt(p, 3, scale):>11}  {_fmt(m, 3, scale):>11}{'+' if c else ' '} {unit:<6} {_fmt(f)}"
                )
        lines.append(
            f"  minimum      {_fmt(g.predicted_min):>11}  {_fmt(g.measured_min):>11}  {'N*':<6} "
            f"median fidelity over {len(g.direction_labels)} directions: {_fmt(g.median_fidelity)}"
        )
    m = sim.set_metrics
    unreachable = f" ({m['n_unreachable']} unreachable, not simulated)" if m.get("n_unreachable") else ""
    change = _fmt(m.get("median_q1_change"), 1, 100)
    lines.append(
        f"\nset: {m.get('n_valid', '-')} valid of {m.get('n_simulated', '-')}{unreachable}, "
        f"median fidelity {_fmt(m.get('median_fidelity'))}"
        + ("" if change == "-" else f", median Q1 change {'' if change.startswith('-') else '+'}{change} %")
    )
    q, p = m.get("q1_vs_measured"), m.get("predicted_vs_measured")
    if isinstance(q, dict) and isinstance(p, dict):
        lines.append(
            f"Q1 vs measured min: Spearman {_fmt(q.get('spearman'))}, Kendall {_fmt(q.get('kendall'))}; "
            f"predicted vs measured: Spearman {_fmt(p.get('spearman'))}, Kendall {_fmt(p.get('kendall'))}; "
            f"AUC(Q1, holds {m.get('holding_load', '-')} N) {_fmt(m.get('auc_q1_holds'))}"
        )
    lines.extend(_dexgraspbench_line(m.get("dexgraspbench")))
    lines.append(
        "(+ = held to the end of the ramp: a lower bound; Q1 is dimensionless; N* = the size of a scaled "
        f"wrench, forces in N and torques divided by rho{'' if rho is None else f' = {rho:.4g} m'})"
    )
    return "\n".join(lines)


def _row_unit(label: str, rho: float | None) -> tuple[float, str]:
    """Scale and unit of a table row: forces in N, torques in N·m (when the record gives rho), N* else."""
    if label.startswith(("+f", "-f")):
        return 1.0, "N"
    if label.startswith(("+t", "-t")) and rho is not None:
        return rho, "N·m"
    return 1.0, "N*"


def _dexgraspbench_line(summary: Any) -> list[str]:
    """The set's DexGraspBench success rate and ROC-AUCs of Q1 (``--protocol dexgraspbench``)."""
    if not isinstance(summary, dict):
        return []
    found = summary.get("auc_q1")
    auc: dict[str, Any] = found if isinstance(found, dict) else {}
    line = (
        f"DexGraspBench ({summary.get('source')}): success {summary.get('n_success', '-')} of "
        f"{summary.get('n_evaluated', '-')} ({_fmt(summary.get('success_rate'), 1, 100)} %); AUC(Q1, success) "
        f"Mann-Whitney {_fmt(auc.get('mann_whitney'))}, theirs ({auc.get('bins', '-')} bins) "
        f"{_fmt(auc.get('dexgraspbench'))}"
    )
    return [line]


def run_evaluate(args: argparse.Namespace) -> int:
    from ogcp.benchmarks.cli.external import is_external, run_external
    from ogcp.planner.records.plan import load_plan
    from ogcp.sim_eval.evaluate import evaluate_plan

    if is_external(args.plan):
        return run_external(args, _settings(args), _decomposition(args), sim_summary)

    # Before the simulation: an output with nowhere to go would waste it.
    check_output(args.output)
    check_output(args.render)
    if args.render is not None and args.render.suffix.lower() != ".png":
        raise OgcpError(f"--render {args.render}: the picture is a PNG; give a file name ending in .png")
    record = load_plan(args.plan)
    if args.render is not None:
        from ogcp.sim_eval.render import check_offscreen_rendering

        check_offscreen_rendering()
    result = evaluate_plan(
        record,
        _settings(args),
        _decomposition(args),
        progress=sys.stderr.isatty(),
        max_grasps=args.max_grasps,
        plan_file=args.plan,
        tips=args.tips,
    )
    data = result.to_dict()
    if args.output is not None:  # first: a picture that fails must not cost the results
        write_json_atomic(args.output, data)
    print(json.dumps(data) if args.json else sim_summary(data))
    if args.render is not None:
        try:
            _render(record, args)
        except OgcpError as exc:
            print(f"ogcp: error: {exc}", file=sys.stderr)
            return 1
    return 0


def _render(record: dict[str, Any], args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from ogcp.sim_eval.render import render_plan

    image = render_plan(record, _settings(args), _decomposition(args), tips=args.tips, plan_file=args.plan)
    try:
        plt.imsave(args.render, image)
    except OSError as exc:
        raise OgcpError(f"cannot write {args.render}: {exc.strerror or exc}") from exc
    print(f"picture of the best grasp: {args.render}", file=sys.stderr)


def run_decompose(args: argparse.Namespace) -> int:
    from ogcp.planner.objects import resolve_object
    from ogcp.sim_eval.decomposition.decompose import decompose

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
