"""A* with Γ^fc's tree built several ways, side by side: states, time and the optimum each reaches.

Run: ``python -m ogcp.benchmarks.studies.position_weight [--cases bunny:4,plane:5] [--weights 1,2]
[--iterations 10,100] [--contacts 1000] [--time-limit 300] [--repeats 1]``. A setting is a
position weight w and a k-means iteration cap t (the i-th of each list; a list of one serves
every setting): the default compares the searches' settings before (w = 1, t = 10) and now.
Each case samples the object's default seed-0 contacts once and runs A* (one process) at every
setting, settings interleaved within each repeat so that the machine's drift hits them alike.
Prints, per case and setting, the median wall time, the expanded and created states, Q1 and the
certified bound, and the ratios to the first setting's. A* is optimal in every tree: a finished
run's Q1 must not depend on the setting.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from ogcp.planner import GraspPlanner, resolve_object, sample_contacts
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.search.result import SearchResult

#: A tree's setting: (position weight w, most k-means iterations t).
Setting = tuple[float, int]

#: Objects and finger counts measured when the searches' default weight became 2 (README).
DEFAULT_CASES = (
    "sphere:3,bunny:3,homer:3,donut:3,box:3,plane:3,amphora:3,bunny:4,plane:4,homer:4,amphora:4,donut:4,box:5,plane:5"
)


def parse_cases(text: str) -> list[tuple[str, int]]:
    """``"bunny:4,plane:5"`` -> [("bunny", 4), ("plane", 5)]."""
    cases = []
    for item in text.split(","):
        name, _, fingers = item.strip().partition(":")
        if not name or not fingers.isdigit() or int(fingers) < 2:
            raise OgcpError(f"--cases: {item!r} is not OBJECT:M with M >= 2 (for example bunny:4)")
        cases.append((name, int(fingers)))
    return cases


def parse_weights(text: str) -> list[float]:
    """``"1,2"`` -> [1.0, 2.0]; each weight must be a positive number."""
    try:
        weights = [float(w) for w in text.split(",")]
    except ValueError:
        raise OgcpError(f"--weights: {text!r} is not a comma-separated list of numbers") from None
    if not weights or any(not w > 0 for w in weights):
        raise OgcpError(f"--weights: every weight must be > 0, got {text!r}")
    return weights


def parse_settings(weights: str, iterations: str) -> list[Setting]:
    """(w, t) pairs from ``--weights`` and ``--iterations`` (a list of one is repeated)."""
    ws = parse_weights(weights)
    try:
        ts = [int(t) for t in iterations.split(",")]
    except ValueError:
        raise OgcpError(f"--iterations: {iterations!r} is not a comma-separated list of integers") from None
    if any(t < 1 for t in ts):
        raise OgcpError(f"--iterations: every cap must be >= 1, got {iterations!r}")
    if len(ws) != len(ts) and 1 not in (len(ws), len(ts)):
        raise OgcpError(f"--weights has {len(ws)} values and --iterations {len(ts)}: give as many, or one")
    count = max(len(ws), len(ts))
    return [(ws[i % len(ws)], ts[i % len(ts)]) for i in range(count)]


def run_case(
    name: str, m: int, settings: list[Setting], contacts: int, time_limit: float | None, repeats: int
) -> list[tuple[Setting, list[float], SearchResult]]:
    """(setting, wall times [s], last result) per setting, settings interleaved within each repeat."""
    mesh, source = resolve_object(name, None)
    contact_set = sample_contacts(mesh, contacts, 0, source=source)
    times: dict[Setting, list[float]] = {s: [] for s in settings}
    results: dict[Setting, SearchResult] = {}
    for _ in range(repeats):
        for weight, iterations in settings:
            planner = GraspPlanner(
                method="astar", position_weight=weight, kmeans_iterations=iterations, time_limit=time_limit
            )
            start = time.perf_counter()
            results[(weight, iterations)] = planner.plan(contact_set, m)
            times[(weight, iterations)].append(time.perf_counter() - start)
    return [(s, times[s], results[s]) for s in settings]


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--cases", default=DEFAULT_CASES, help="OBJECT:M pairs, comma-separated")
    parser.add_argument("--weights", default="1,2", help="position weights w; ratios are to the first setting")
    parser.add_argument("--iterations", default="10,100", help="most k-means iterations t, one per weight")
    parser.add_argument("--contacts", type=int, default=1000)
    parser.add_argument("--time-limit", type=float, default=300.0, help="per search [s]; 0: none")
    parser.add_argument("--repeats", type=int, default=1)
    args = parser.parse_args()
    try:
        cases, settings = parse_cases(args.cases), parse_settings(args.weights, args.iterations)
    except OgcpError as error:
        parser.error(str(error))
    for flag, value, least in (("--contacts", args.contacts, 1), ("--repeats", args.repeats, 1)):
        if value < least:
            parser.error(f"{flag}: expected an integer >= {least}, got {value}")
    if not args.time_limit >= 0:
        parser.error(f"--time-limit: expected seconds >= 0 (0: none), got {args.time_limit}")
    limit = args.time_limit if args.time_limit > 0 else None
    print("case        w, t      wall [s]  ratio  expanded  ratio   created  status     Q1         bound")
    for name, m in cases:
        try:
            rows = run_case(name, m, settings, args.contacts, limit, args.repeats)
        except OgcpError as error:  # an unknown object, too few contacts, no grasp in time: one line
            sys.exit(f"position_weight: {name} m={m}: {error}")
        ref_time, ref_result = statistics.median(rows[0][1]), rows[0][2]
        finished = {r.q1 for _, _, r in rows if r.status == "optimal"}
        for (weight, iterations), times, result in rows:
            wall = statistics.median(times)
            print(
                f"{name + ' m=' + str(m):<11} {f'{weight:g}, {iterations}':<9} {wall:8.1f}  {wall / ref_time:5.2f}  "
                f"{result.stats.visited:8d}  {result.stats.visited / ref_result.stats.visited:5.2f}  "
                f"{result.stats.created:8d}  {result.status:<9}  {result.q1:.7f}  {result.bound:.7f}"
            )
        if len(finished) > 1:
            print(f"  !! {name} m={m}: finished runs disagree on the optimum: {sorted(finished)}")


if __name__ == "__main__":
    main()
