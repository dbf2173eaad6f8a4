"""``ogcp contacts`` and ``ogcp plan``: sample contact sets and plan grasps with any method."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.cli.options import integer, number, positive_int
from planner.baselines.es import DEFAULT_BINS, DEFAULT_CHUNK, ES_METHODS, ESResult, ExhaustiveSearch
from planner.baselines.hfts import HFTS, HFTSResult
from planner.grasp.constraints import Constraint, MaxFingerSpread
from planner.grasp.contact_set import DEFAULT_CONE_EDGES, DEFAULT_MU, ContactSet, sample_contacts
from planner.hands.reachability import SDHReachability
from planner.infra.atomic import write_json_atomic
from planner.infra.errors import OgcpError, choice_error
from planner.infra.parallel import BACKENDS
from planner.objects import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, resolve_object
from planner.records.plan import contact_set_record, hand_record
from planner.search.grasp_planner import HEURISTICS, METHODS, GraspPlanner
from planner.search.partitions import SUCCESSORS
from planner.search.result import SearchResult

DEFAULT_CONTACTS = 100
HANDS = ("sdh",)


def _add_contact_options(parser: argparse.ArgumentParser, n_default: int | None) -> None:
    parser.add_argument(
        "-n",
        "--contacts",
        type=positive_int,
        default=n_default,
        metavar="N",
        help=f"number of contacts sampled from the surface (default {n_default or DEFAULT_CONTACTS})",
    )
    parser.add_argument("--seed", type=integer, default=0, help="seed of every random choice (default 0)")
    parser.add_argument("--mu", type=number, default=DEFAULT_MU, help=f"friction coefficient (default {DEFAULT_MU})")
    parser.add_argument(
        "--cone-edges",
        type=integer,
        default=DEFAULT_CONE_EDGES,
        help=f"friction-cone edges k (default {DEFAULT_CONE_EDGES})",
    )
    parser.add_argument(
        "--diagonal",
        type=number,
        default=DEFAULT_DIAGONAL,
        help=f"bounding-box diagonal of built-in objects [m] (default {DEFAULT_DIAGONAL})",
    )


def register(commands: Any) -> None:
    """Add ``contacts`` and ``plan`` to the ``ogcp`` sub-commands."""
    objects = ", ".join(sorted(BUILTIN_OBJECTS))

    contacts = commands.add_parser("contacts", help="sample a contact set from a mesh and write it as JSON")
    contacts.add_argument("object", metavar="MESH_OR_NAME", help=f"mesh file or built-in object ({objects})")
    _add_contact_options(contacts, DEFAULT_CONTACTS)
    contacts.add_argument("-o", "--output", required=True, type=Path, help="output JSON file")
    contacts.set_defaults(handler=run_contacts)

    plan = commands.add_parser("plan", help="plan an optimal or bounded-suboptimal m-contact grasp")
    plan.add_argument(
        "object",
        metavar="MESH_OR_NAME_OR_CONTACTS",
        help=f"mesh file, built-in object ({objects}) or contact JSON file",
    )
    plan.add_argument("-m", "--fingers", type=integer, default=3, help="number of contacts m (default 3)")
    plan.add_argument(
        "--method", default="astar", help=f"method: {', '.join(METHODS + ES_METHODS + ('hfts',))} (default astar)"
    )
    plan.add_argument("--eps", type=number, default=None, help="WA* inflation eps >= 0 (default 0.4 for wastar)")
    plan.add_argument("--branching", type=integer, default=2, help="branching factor b >= 2 (default 2)")
    plan.add_argument("--successor", default="fc", help=f"expansion successors: {', '.join(SUCCESSORS)} (default fc)")
    plan.add_argument(
        "--heuristic",
        default=None,
        help=f"heuristic successors: {', '.join(HEURISTICS)} (default fc; none for dijkstra)",
    )
    plan.add_argument(
        "--heuristic-branching", type=integer, default=None, help="b of the heuristic (default: --branching)"
    )
    plan.add_argument(
        "--symmetry", action="store_true", help="approximate geometric symmetry removal (may lose optimality)"
    )
    plan.add_argument("--ordered", action="store_true", help="keep finger order (the paper's raw search tree)")
    plan.add_argument(
        "--time-limit",
        type=number,
        default=None,
        metavar="SECONDS",
        help="stop A*/WA*/Dijkstra after this many seconds with the best grasp so far and a "
        "certified bound on the optimum (exit status 2)",
    )
    plan.add_argument(
        "--record-tree",
        action="store_true",
        help="keep the search tree (parent, level, f, visited per state) in the JSON result",
    )
    plan.add_argument("--kmeans-iterations", type=integer, default=10, help="k-means iterations t for fc (default 10)")
    plan.add_argument("--position-weight", type=number, default=1.0, help="position weight in fc features (default 1)")
    plan.add_argument(
        "--max-spread",
        type=number,
        default=None,
        metavar="METRES",
        help="constraint: maximum distance between any two contacts [m]",
    )
    plan.add_argument("--hand", default=None, help="constraint: fingertips reachable by this hand (sdh); needs m = 3")
    plan.add_argument("--hand-threshold", type=number, default=0.3, help="largest reachability residual (default 0.3)")
    _add_contact_options(plan, None)
    es = plan.add_argument_group("exhaustive search (--method es / es-pruned)")
    es.add_argument("--jobs", type=positive_int, default=1, help="worker processes (default 1)")
    es.add_argument("--backend", default="loky", help=f"parallel backend: {', '.join(BACKENDS)} (default loky)")
    es.add_argument("--address", default=None, metavar="HOST:PORT", help="Dask scheduler address (backend dask)")
    es.add_argument(
        "--checkpoint",
        type=Path,
        default=None,
        metavar="DIR",
        help="keep finished chunks here; a rerun resumes from them",
    )
    es.add_argument(
        "--chunk", type=positive_int, default=DEFAULT_CHUNK, help=f"grasps per chunk (default {DEFAULT_CHUNK})"
    )
    es.add_argument("--bins", type=positive_int, default=DEFAULT_BINS, help=f"histogram bins (default {DEFAULT_BINS})")
    hfts = plan.add_argument_group("HFTS baseline (--method hfts)")
    hfts.add_argument("--runs", type=positive_int, default=20, help="independent runs, seeds S..S+R-1 (default 20)")
    hfts.add_argument("--iterations", type=positive_int, default=40, help="moves per level (default 40)")
    hfts.add_argument(
        "--no-optimum", action="store_true", help="skip the A* run that reports the optimum next to the HFTS spread"
    )
    plan.add_argument("--json", action="store_true", help="print one JSON object (schema ogcp.plan/1)")
    plan.add_argument("-o", "--output", type=Path, default=None, help="also write the JSON result to this file")
    plan.set_defaults(handler=run_plan)


def load_contact_set(spec: str, args: argparse.Namespace) -> ContactSet:
    """Contact set from a contact JSON file, or sampled from a mesh or built-in object."""
    if spec.lower().endswith(".json"):
        if args.contacts is not None:
            raise OgcpError("-n/--contacts does not apply to a contact file (its contacts are fixed)")
        return ContactSet.load(spec)
    mesh, source = resolve_object(spec, args.diagonal)
    n = args.contacts if args.contacts is not None else DEFAULT_CONTACTS
    return sample_contacts(mesh, n, args.seed, args.mu, args.cone_edges, source)


def summary(result: SearchResult, contacts: ContactSet) -> str:
    """Readable multi-line summary of a plan."""
    s, c = result.stats, result.config
    source = contacts.source
    what = source.get("name") or source.get("path") or "contact file"
    heuristic = f"Γh={c['heuristic']} b={c['heuristic_branching']}" if c["heuristic"] != "none" else "no heuristic"
    method = {"astar": "A*", "wastar": f"WA* (eps={result.eps:g})", "dijkstra": "Dijkstra"}[result.method]
    if result.method == "wastar":
        certificate = f"within bound: optimum <= {result.bound:.6f} (guarantee: <= {result.eps_bound:.6f})"
    elif c["symmetry"]:
        certificate = "optimal up to approximate symmetry removal"
    else:
        certificate = "optimal (certified)"
    lines = [
        f"object: {what}   |C| = {len(contacts)}   mu = {contacts.mu:g}   k = {contacts.cone_edges}   seed = {c['seed']}",
        f"search: {method}, m = {c['m']}, Γ={c['successor']} b={c['branching']}, {heuristic}"
        + (", symmetry removal" if c["symmetry"] else ""),
        f"grasp: {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
        f"certificate: {certificate}",
        (
            f"states: created {s.created}, visited {s.visited}, b* = {s.effective_branching_factor:.2f}, "
            f"solution depth {s.solution_depth}"
        ),
        f"created per level: {list(s.created_per_level)}",
        f"visited per level: {list(s.visited_per_level)}",
        (
            f"Q1 evaluations: {s.q1_evaluations} (cache hits {s.q1_cache_hits}, rejected by bound {s.bound_rejections}), "
            f"hull calls {s.hull_calls}"
        ),
        f"time: {s.wall_seconds:.2f} s wall, {s.cpu_seconds:.2f} s CPU",
        "contacts (index: position [m] / inward normal):",
    ]
    for i, p, n in zip(result.grasp, result.positions, result.normals):
        lines.append(f"  {i:5d}: [{p[0]:+.4f} {p[1]:+.4f} {p[2]:+.4f}] / [{n[0]:+.3f} {n[1]:+.3f} {n[2]:+.3f}]")
    return "\n".join(lines)


def build_constraints(args: argparse.Namespace) -> tuple[list[Constraint], SDHReachability | None]:
    """Constraints from --max-spread and --hand; the hand model is also returned."""
    constraints: list[Constraint] = []
    if args.max_spread is not None:
        constraints.append(MaxFingerSpread(args.max_spread))
    hand = None
    if args.hand is not None:
        if args.hand not in HANDS:
            raise choice_error("hand", args.hand, HANDS)
        if args.fingers != 3:
            raise OgcpError(f"the {args.hand} hand has 3 fingers; got -m {args.fingers}")
        hand = SDHReachability(threshold=args.hand_threshold)
        constraints.append(hand)
    return constraints, hand


def run_contacts(args: argparse.Namespace) -> int:
    mesh, source = resolve_object(args.object, args.diagonal)
    contacts = sample_contacts(mesh, args.contacts, args.seed, args.mu, args.cone_edges, source)
    write_json_atomic(args.output, contacts.to_dict())
    print(f"wrote {len(contacts)} contacts to {args.output}", file=sys.stderr)
    return 0


def es_summary(result: ESResult, contacts: ContactSet) -> str:
    """Readable summary of an exhaustive search."""
    lines = [
        f"object: {contacts.source.get('name') or contacts.source.get('path') or 'contact file'}   |C| = {len(contacts)}",
        (
            f"search: {result.method}, m = {result.config['m']}, {result.grasps} grasps in {result.chunks} chunks "
            f"({result.resumed} resumed), backend {result.config['backend']}"
        ),
        f"grasp: {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
    ]
    admissible = result.grasps - result.excluded
    if result.excluded:
        lines.append(f"constraints: {result.excluded} grasps excluded, {admissible} admissible")
    if result.counts is not None and admissible:
        lines.append(
            f"force closure: {admissible - result.zero} of {admissible} "
            f"({100 * result.force_closure_fraction:.2f} %); histogram over (0, Q_OWS]: {result.counts.tolist()}"
        )
    lines.append(
        f"exact evaluations: {result.exact_evaluations}; time: {result.wall_seconds:.2f} s wall, "
        f"{result.cpu_seconds:.2f} s CPU (all workers)"
    )
    return "\n".join(lines)


def run_es(args: argparse.Namespace, contacts: ContactSet) -> int:
    if args.eps is not None:
        raise OgcpError(f"eps applies to method 'wastar' only (method {args.method!r} got eps={args.eps})")
    constraints, hand = build_constraints(args)
    search = ExhaustiveSearch(
        pruned=args.method == "es-pruned",
        jobs=args.jobs,
        backend=args.backend,
        address=args.address,
        checkpoint=args.checkpoint,
        chunk=args.chunk,
        bins=args.bins,
        progress=sys.stderr.isatty(),
        constraints=constraints,
    )
    result = search.run(contacts, args.fingers)
    record = result.to_dict(contact_set_record(contacts))
    record["config"]["seed"] = args.seed
    if hand is not None:
        record["hand"] = hand_record(hand, result.grasp, contacts)
    if args.output is not None:
        write_json_atomic(args.output, record)
    print(json.dumps(record) if args.json else es_summary(result, contacts))
    return 0


def hfts_summary(result: HFTSResult, contacts: ContactSet) -> str:
    """Readable summary of the HFTS runs."""
    s = result.summary()
    lines = [
        f"object: {contacts.source.get('name') or contacts.source.get('path') or 'contact file'}   |C| = {len(contacts)}",
        (
            f"search: HFTS, m = {result.config['m']}, {s['runs']} runs (seeds {result.config['seed']}.."
            f"{result.config['seed'] + s['runs'] - 1}), {result.config['levels']} cluster levels"
        ),
        f"best run: grasp {list(result.grasp)}   Q1 = {result.q1:.6f}   Q_OWS = {result.q_ows:.6f}",
        (
            f"spread: mean {s['mean']:.6f}  std {s['std']:.6f}  max {s['max']:.6f}  "
            f"force closure {100 * s['force_closure_fraction']:.0f} %"
        ),
        f"Q1 evaluations: {s['q1_evaluations']}; time: {s['wall_seconds']:.2f} s wall, {s['cpu_seconds']:.2f} s CPU",
        "runs (seed: Q1):  " + "  ".join(f"{r.seed}: {r.q1:.4f}" for r in result.runs),
    ]
    return "\n".join(lines)


def run_hfts(args: argparse.Namespace, contacts: ContactSet) -> int:
    if args.eps is not None:
        raise OgcpError(f"eps applies to method 'wastar' only (method 'hfts' got eps={args.eps})")
    if args.max_spread is not None:
        raise OgcpError("HFTS models a hand by its residual (--hand), not by --max-spread")
    hand = build_constraints(args)[1]
    search = HFTS(
        runs=args.runs,
        seed=args.seed,
        iterations=args.iterations,
        position_weight=args.position_weight,
        jobs=args.jobs,
        backend=args.backend,
        address=args.address,
        hand=hand,
    )
    result = search.run(contacts, args.fingers)
    if not args.no_optimum:
        optimum = GraspPlanner(seed=args.seed, constraints=[hand] if hand else ()).plan(contacts, args.fingers)
        record_optimum = {"method": "astar", "grasp": list(optimum.grasp), "q1": optimum.q1}
    else:
        record_optimum = None
    record = result.to_dict(contact_set_record(contacts))
    if hand is not None:
        record["hand"] = hand_record(hand, result.grasp, contacts)
    text = hfts_summary(result, contacts)
    if record_optimum is not None:
        record["optimum"] = record_optimum
        gaps = record_optimum["q1"] - result.values
        text += (
            f"\nA* optimum: grasp {record_optimum['grasp']}   Q1 = {record_optimum['q1']:.6f}   "
            f"HFTS gap: best {gaps.min():.6f}, mean {gaps.mean():.6f}, "
            f"runs reaching it {int(np.sum(gaps <= 0))} of {len(gaps)}"
        )
    if args.output is not None:
        write_json_atomic(args.output, record)
    print(json.dumps(record) if args.json else text)
    return 0


def run_plan(args: argparse.Namespace) -> int:
    for flag, given in (("--record-tree", args.record_tree), ("--time-limit", args.time_limit is not None)):
        if given and args.method in (*ES_METHODS, "hfts"):
            raise OgcpError(f"{flag} applies to methods astar, dijkstra, wastar (got {args.method!r})")
    contacts = load_contact_set(args.object, args)
    if args.method in ES_METHODS:
        return run_es(args, contacts)
    if args.method == "hfts":
        return run_hfts(args, contacts)
    constraints, hand = build_constraints(args)
    planner = GraspPlanner(
        method=args.method,
        eps=args.eps,
        branching=args.branching,
        successor=args.successor,
        heuristic=args.heuristic,
        heuristic_branching=args.heuristic_branching,
        symmetry=args.symmetry,
        ordered=args.ordered,
        seed=args.seed,
        kmeans_iterations=args.kmeans_iterations,
        position_weight=args.position_weight,
        constraints=constraints,
        record_tree=args.record_tree,
        time_limit=args.time_limit,
    )
    result = planner.plan(contacts, args.fingers, progress=sys.stderr.isatty())
    record = result.to_dict(contact_set_record(contacts))
    if hand is not None:
        record["hand"] = hand_record(hand, result.grasp, contacts)
    if args.output is not None:
        write_json_atomic(args.output, record)
    text = summary(result, contacts)
    if hand is not None:
        h = record["hand"]
        text += (
            f"\nhand: {h['name']}, residual {h['residual']:.3f}, fingers on contacts {h['finger_contacts']}, "
            f"joint angles [rad] {[round(a, 3) for a in h['joint_angles']]}"
        )
    print(json.dumps(record) if args.json else text)
    return 0
