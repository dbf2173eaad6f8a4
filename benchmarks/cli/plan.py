"""``ogcp contacts`` and ``ogcp plan``: sample contact sets and plan grasps with any method.

The method flags come from the methods' declared options
(:mod:`ogcp.benchmarks.cli.method_options`); running and recording is the registry's
(:mod:`ogcp.planner.methods.registry`), the same for the command line and the suites.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

# Only light modules at the top: the parser is built for every command, ``--help`` included.
# The contact sampling, the engines and the summaries (numpy, trimesh, scipy, numba) are
# imported by the functions that use them.
from ogcp.benchmarks.cli.method_options import GROUPS, add_method_options, config_from_args, not_applicable
from ogcp.benchmarks.cli.options import (
    add_contact_model_options,
    add_diagonal_option,
    check_output,
    contact_model_given,
    integer,
    positive_int,
    torsion_from_args,
    typed,
    valid,
)
from ogcp.planner.config.methods import DEFAULT_FINGERS, DEFAULT_METHOD, DEFAULT_SEED
from ogcp.planner.config.options import JOBS, MEMORY_LIMIT, TIME_LIMIT
from ogcp.planner.grasp.defaults import (
    CONE_EDGES,
    CONTACT_SEED,
    DEFAULT_CONE_EDGES,
    DEFAULT_CONTACTS,
    DEFAULT_MU,
    DEFAULT_TIP_RADIUS_RATIO,
    MU,
    TIP_RADIUS,
)
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.parallel import BACKENDS, DEFAULT_BACKEND, DEFAULT_JOBS
from ogcp.planner.methods.registry import METHODS, SEARCH_METHODS, MethodSpec, method_spec
from ogcp.planner.objects.builtin import BUILTIN_OBJECTS, DEFAULT_DIAGONAL

if TYPE_CHECKING:
    import trimesh

    from ogcp.planner.grasp.contact_set import ContactSet
    from ogcp.planner.methods.runners import MethodRun, RunOptions

#: Run-time flags (destination -> flag); each applies to the methods whose spec lists it.
RUN_FLAGS = {
    "time_limit": "--time-limit",
    "memory_limit": "--memory-limit",
    "jobs": "--jobs",
    "backend": "--backend",
    "address": "--address",
    "checkpoint": "--checkpoint",
    "optimum": "--no-optimum",
}


def _add_contact_options(parser: argparse.ArgumentParser, n_default: int | None) -> None:
    parser.add_argument(
        "-n",
        "--contacts",
        type=positive_int,
        default=n_default,
        metavar="N",
        help=f"number of contacts sampled from the surface (default {DEFAULT_CONTACTS})",
    )
    parser.add_argument(
        "--seed",
        type=typed(CONTACT_SEED),
        default=DEFAULT_SEED,
        help=f"seed of every random choice (default {DEFAULT_SEED}; {valid(CONTACT_SEED)})",
    )
    # None, not the default, so that a contact file (whose mu and k are fixed) can refuse them.
    parser.add_argument(
        "--mu", type=typed(MU), default=None, help=f"friction coefficient (default {DEFAULT_MU}; {valid(MU)})"
    )
    parser.add_argument(
        "--cone-edges",
        type=typed(CONE_EDGES),
        default=None,
        help=f"friction-cone edges k (default {DEFAULT_CONE_EDGES}; {valid(CONE_EDGES)})",
    )
    add_contact_model_options(parser)
    parser.add_argument(
        "--tip-radius",
        type=tip_radius,
        default=None,
        metavar="METRES",
        help="fingertip radius r [m]: keep only contacts a sphere of radius r touches without cutting the object "
        f"(default: the simulation's fingertip, {100 * DEFAULT_TIP_RADIUS_RATIO:g}%% of the object's bounding-box "
        "diagonal; 0 = the paper's plain sampling of the whole surface)",
    )
    add_diagonal_option(parser, DEFAULT_DIAGONAL)


def tip_radius(text: str) -> float:
    """A fingertip radius [m]: a finite number in :data:`TIP_RADIUS`'s range (0 = plain sampling)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan  # reported below, with the valid values
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a finite number of metres >= 0 (0 = plain sampling), got {text!r}")
    return float(typed(TIP_RADIUS)(text))


def hand_tip_radius(args: argparse.Namespace) -> float | None:
    """``ogcp contacts --hand`` without ``--tip-radius``: the hand's largest pad rounding [m]."""
    hand = getattr(args, "hand", None) if args.command == "contacts" else None
    if hand is None or args.tip_radius is not None:
        return None
    from ogcp.planner.hands.registry import resolve_hand

    return max(finger.tip_radius for finger in resolve_hand(hand).fingers)


def sample_from_args(mesh: trimesh.Trimesh, source: dict[str, Any], n: int, args: argparse.Namespace) -> ContactSet:
    """Sample ``n`` contacts with the contact flags; no ``--tip-radius`` means the default fingertip."""
    from ogcp.planner.grasp.contact_set import sample_contacts
    from ogcp.planner.grasp.reach import default_tip_radius

    # ``ogcp contacts --hand``: its pads' rounding. ``ogcp plan --hand`` keeps the default fingertip,
    # as a suite's cells share one contact set across methods with and without hands.
    radius = args.tip_radius if args.tip_radius is not None else hand_tip_radius(args)
    radius = default_tip_radius(mesh) if radius is None else radius
    mu = DEFAULT_MU if args.mu is None else args.mu
    cone_edges = DEFAULT_CONE_EDGES if args.cone_edges is None else args.cone_edges
    torsion = torsion_from_args(args)
    return sample_contacts(mesh, n, args.seed, mu, cone_edges, source, tip_radius=radius, torsional_friction=torsion)


def register(commands: Any) -> None:
    """Add ``contacts`` and ``plan`` to the ``ogcp`` sub-commands."""
    objects = ", ".join(sorted(BUILTIN_OBJECTS))

    contacts = commands.add_parser("contacts", help="sample a contact set from a mesh and write it as JSON")
    contacts.add_argument("object", metavar="MESH_OR_NAME", help=f"mesh file or built-in object ({objects})")
    _add_contact_options(contacts, DEFAULT_CONTACTS)
    contacts.add_argument(
        "--hand",
        metavar="NAME|FILE.toml",
        default=None,
        help="sample contacts this hand's pads can touch: the tip radius is its largest pad rounding "
        "(unless --tip-radius is given)",
    )
    contacts.add_argument("-o", "--output", required=True, type=Path, help="output JSON file")
    contacts.set_defaults(handler=run_contacts)

    plan = commands.add_parser(
        "plan",
        help="plan an optimal or bounded-suboptimal m-contact grasp",
        epilog="exit status: 0 a finished search (status optimal, bounded or approximate; heuristic for HFTS); "
        "2 invalid input, or no valid grasp; 3 stopped at --time-limit and 130 stopped by Ctrl-C, both with the "
        "best grasp so far, its certified bound and gap printed (and written with -o). A second Ctrl-C aborts.",
    )
    plan.add_argument(
        "object",
        metavar="MESH_OR_NAME_OR_CONTACTS",
        help=f"mesh file, built-in object ({objects}) or contact JSON file",
    )
    plan.add_argument(
        "-m",
        "--fingers",
        type=integer,
        default=DEFAULT_FINGERS,
        help=f"number of contacts m (default {DEFAULT_FINGERS})",
    )
    plan.add_argument(
        "--method", default=DEFAULT_METHOD, help=f"method: {', '.join(METHODS)} (default {DEFAULT_METHOD})"
    )
    groups = {title: plan.add_argument_group(title) for title, _ in GROUPS}
    add_method_options(plan, groups)
    plan.add_argument(
        "--time-limit",
        type=typed(TIME_LIMIT),
        default=None,
        metavar="SECONDS",
        help="stop after this many seconds, any method; the result is the best grasp so far with its "
        "certified bound and gap (Q_OWS for ES and HFTS; status 'stopped', exit status 3)",
    )
    plan.add_argument(
        "--memory-limit",
        type=typed(MEMORY_LIMIT),
        default=None,
        metavar="GIB",
        help=f"most memory of an A*/WA*/Dijkstra search, all its processes (default {MEMORY_LIMIT.default:g}); "
        "past it the search forgets its least promising states and may end with its best grasp "
        "and certified bound (status 'memory', exit status 4)",
    )
    _add_contact_options(plan, None)
    es, hfts = groups.values()
    es.add_argument(
        "--jobs",
        type=typed(JOBS),
        default=None,
        help=f"worker processes; A*, WA* and Dijkstra deal one search to this many (default {DEFAULT_JOBS}; {valid(JOBS)})",
    )
    es.add_argument(
        "--backend", default=None, help=f"parallel backend: {', '.join(BACKENDS)} (default {DEFAULT_BACKEND})"
    )
    es.add_argument("--address", default=None, metavar="HOST:PORT", help="Dask scheduler address (backend dask)")
    es.add_argument(
        "--checkpoint",
        type=Path,
        default=None,
        metavar="DIR",
        help="keep finished chunks here; a rerun resumes from them",
    )
    hfts.add_argument(
        "--no-optimum", action="store_true", help="skip the A* run that reports the optimum next to the HFTS spread"
    )
    plan.add_argument("--json", action="store_true", help="print one JSON object (schema ogcp.plan/1)")
    plan.add_argument("-o", "--output", type=Path, default=None, help="also write the JSON result to this file")
    plan.set_defaults(handler=run_plan)


def load_contact_set(spec: str, args: argparse.Namespace) -> ContactSet:
    """Contact set from a contact JSON file, or sampled from a mesh or built-in object."""
    from ogcp.planner.grasp.contact_set import ContactSet

    if spec.lower().endswith(".json"):
        if args.contacts is not None:
            raise OgcpError("-n/--contacts does not apply to a contact file (its contacts are fixed)")
        if args.tip_radius is not None:
            raise OgcpError("--tip-radius does not apply to a contact file (its contacts are fixed)")
        if args.diagonal is not None:
            raise OgcpError("--diagonal does not apply to a contact file (its contacts are fixed)")
        if args.mu is not None:
            raise OgcpError("--mu does not apply to a contact file (its wrenches are fixed)")
        if args.cone_edges is not None:
            raise OgcpError("--cone-edges does not apply to a contact file (its wrenches are fixed)")
        if contact_model_given(args):
            raise OgcpError(
                "--contact-model and --torsional-friction do not apply to a contact file (its wrenches are fixed)"
            )
        return ContactSet.load(spec)
    from ogcp.planner.objects.contact_cache import ContactRequest, cached_contacts

    n = args.contacts if args.contacts is not None else DEFAULT_CONTACTS
    request = ContactRequest(
        spec=spec,
        diagonal=args.diagonal,
        n=n,
        seed=args.seed,
        mu=DEFAULT_MU if args.mu is None else args.mu,
        cone_edges=DEFAULT_CONE_EDGES if args.cone_edges is None else args.cone_edges,
        tip_radius=args.tip_radius,
        torsional_friction=torsion_from_args(args),
    )

    def sample() -> ContactSet:
        from ogcp.planner.objects.resolve import resolve_object  # trimesh: only when the cache has no entry

        mesh, source = resolve_object(spec, args.diagonal)
        return sample_from_args(mesh, source, n, args)

    return cached_contacts(request, sample)


def run_options_from_args(spec: MethodSpec, args: argparse.Namespace) -> RunOptions:
    """How to run the method, from the run-time flags given.

    Raises:
        OgcpError: For a run-time flag of another method.
    """
    from ogcp.planner.methods.runners import RunOptions

    given = {field: getattr(args, field) for field in RUN_FLAGS if field != "optimum"}
    given["optimum"] = False if args.no_optimum else None
    options: dict[str, Any] = {}
    for field, value in given.items():
        if value is None:
            continue
        if field not in spec.run_options:
            takers = [name for name, other in METHODS.items() if field in other.run_options]
            raise not_applicable(RUN_FLAGS[field], takers, spec.name, True if field == "optimum" else value)
        options[field] = value
    if "optimum" in spec.run_options:
        options.setdefault("optimum", True)  # ogcp plan shows HFTS's gap to the optimum unless told not to
    # The contacts' seed is recorded by methods without a seed of their own (exhaustive search).
    terminal = sys.stderr.isatty()
    lines = None if terminal else (lambda text: print(f"ogcp: {text}", file=sys.stderr, flush=True))
    return RunOptions(progress=terminal, lines=lines, contact_seed=args.seed, **options)


def run_contacts(args: argparse.Namespace) -> int:
    from ogcp.planner.objects.resolve import resolve_object

    mesh, source = resolve_object(args.object, args.diagonal)
    contacts = sample_from_args(mesh, source, args.contacts, args)
    write_json_atomic(args.output, contacts.to_dict())
    print(f"wrote {len(contacts)} contacts to {args.output}", file=sys.stderr)
    return 0


#: Children one expansion lists beyond which ``ogcp plan`` says what the request costs (2^20: a few s).
LARGE_EXPANSION = 2**20
#: Grasps exhaustive search evaluates beyond which ``ogcp plan`` says what the request costs.
LARGE_ENUMERATION = 10**9


def size_note(spec: MethodSpec, config: Any, n: int, m: int, time_limit: float | None) -> str | None:
    """One line on a request whose size alone makes it long, with the flags that bound it; None for others.

    A* and its kin replace every super-contact at once, so one expansion lists up to b^m children;
    exhaustive search evaluates C(n, m) grasps.
    """
    if m > n or m < 1:
        return None
    if spec.name in ("astar", "wastar", "dijkstra"):
        children = int(getattr(config, "branching", 2)) ** m
        if children < LARGE_EXPANSION:
            return None
        bounded = (
            f"the time limit of {time_limit:g} s returns the best grasp found and a certified bound"
            if time_limit is not None
            else "set --time-limit S to get the best grasp found and a certified bound in S seconds"
        )
        return (
            f"{spec.title} with m = {m}: one expansion lists up to {children:.2g} children (b^m), so the search "
            f"may not get past its first levels; {bounded}, or plan with --method hfts"
        )
    grasps = math.comb(n, m)
    if spec.name in ("es", "es-pruned") and grasps >= LARGE_ENUMERATION:
        return (
            f"{spec.title} evaluates C({n}, {m}) = {grasps:.2g} grasps: hours to years; "
            + (
                f"the time limit of {time_limit:g} s returns the best grasp evaluated, "
                if time_limit is not None
                else "--time-limit S returns the best grasp evaluated in S seconds, "
            )
            + "--jobs and a Dask cluster (--backend dask) spread them, --checkpoint DIR resumes an interrupted run, "
            "or plan with --method astar"
        )
    return None


#: Exit status of ``ogcp plan`` by the result's status: a stopped search is a result, not an error.
EXIT_STATUS = {"stopped": 3, "memory": 4, "interrupted": 130}


def run_plan(args: argparse.Namespace) -> int:
    from ogcp.benchmarks.cli.interrupt import stop_on_interrupt
    from ogcp.benchmarks.cli.kernels import compile_kernels
    from ogcp.benchmarks.cli.plan_summary import describe

    spec = method_spec(args.method)
    config = config_from_args(spec, args)
    options = run_options_from_args(spec, args)
    check_output(args.output)  # before the search whose result it is to hold
    contacts = load_contact_set(args.object, args)
    note = size_note(spec, config, len(contacts), args.fingers, options.time_limit)
    if note is not None:
        print(f"ogcp: {note}", file=sys.stderr, flush=True)
    compile_kernels([spec.name])  # first use: kept out of the time limit and the reported times

    def run_once(given: RunOptions) -> MethodRun:
        if spec.name in SEARCH_METHODS:  # the searches: Ctrl-C returns their best grasp
            with stop_on_interrupt() as stop:
                return spec.run(config, contacts, args.fingers, dataclasses.replace(given, stop=stop))
        return spec.run(config, contacts, args.fingers, given)

    attempts = getattr(config, "realise", None)
    if attempts is None:
        run = run_once(options)
    else:
        from ogcp.sim_eval.realise import realise

        run = realise(attempts, options, run_once, lambda text: print(f"ogcp: {text}", file=sys.stderr, flush=True))
    if args.output is not None:
        from ogcp.planner.records.plan import add_plan_path

        # Where the plan goes is known only now: its mesh file is found from there when both move.
        write_json_atomic(args.output, add_plan_path(run.record, args.output))
    print(json.dumps(run.record) if args.json else describe(run, contacts))
    return EXIT_STATUS.get(run.record.get("status", ""), 0)
