"""A* with Γ^fc at several position weights, side by side: states, time and the optimum each reaches.

Run: ``python -m benchmarks.studies.position_weight [--cases bunny:4,plane:5] [--weights 1,2]
[--contacts 1000] [--time-limit 300] [--repeats 1]``. Each case samples the object's default
seed-0 contacts once and runs A* (one process) at every weight, weights interleaved within
each repeat so that the machine's drift hits them alike. Prints, per case and weight, the
median wall time, the expanded and created states, Q1 and the certified bound, and the ratios
to the first weight's. A* is optimal at every weight: a finished run's Q1 must not depend on it.
"""

from __future__ import annotations

import argparse
import statistics
import time

from planner import GraspPlanner, resolve_object, sample_contacts
from planner.infra.errors import OgcpError
from planner.search.result import SearchResult

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


def run_case(
    name: str, m: int, weights: list[float], contacts: int, time_limit: float | None, repeats: int
) -> list[tuple[float, list[float], SearchResult]]:
    """(weight, wall times [s], last result) per weight, weights interleaved within each repeat."""
    mesh, source = resolve_object(name, None)
    contact_set = sample_contacts(mesh, contacts, 0, source=source)
    times: dict[float, list[float]] = {w: [] for w in weights}
    results: dict[float, SearchResult] = {}
    for _ in range(repeats):
        for weight in weights:
            planner = GraspPlanner(method="astar", position_weight=weight, time_limit=time_limit)
            start = time.perf_counter()
            results[weight] = planner.plan(contact_set, m)
            times[weight].append(time.perf_counter() - start)
    return [(w, times[w], results[w]) for w in weights]


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--cases", default=DEFAULT_CASES, help="OBJECT:M pairs, comma-separated")
    parser.add_argument("--weights", default="1,2", help="position weights; ratios are to the first")
    parser.add_argument("--contacts", type=int, default=1000)
    parser.add_argument("--time-limit", type=float, default=300.0, help="per search [s]; 0: none")
    parser.add_argument("--repeats", type=int, default=1)
    args = parser.parse_args()
    try:
        cases, weights = parse_cases(args.cases), parse_weights(args.weights)
    except OgcpError as error:
        parser.error(str(error))
    limit = args.time_limit if args.time_limit > 0 else None
    print("case        weight  wall [s]  ratio  expanded  ratio   created  status     Q1         bound")
    for name, m in cases:
        rows = run_case(name, m, weights, args.contacts, limit, args.repeats)
        ref_time, ref_result = statistics.median(rows[0][1]), rows[0][2]
        finished = {r.q1 for _, _, r in rows if r.status == "optimal"}
        for weight, times, result in rows:
            wall = statistics.median(times)
            print(
                f"{name + ' m=' + str(m):<11} {weight:<6g} {wall:8.1f}  {wall / ref_time:5.2f}  "
                f"{result.stats.visited:8d}  {result.stats.visited / ref_result.stats.visited:5.2f}  "
                f"{result.stats.created:8d}  {result.status:<9}  {result.q1:.7f}  {result.bound:.7f}"
            )
        if len(finished) > 1:
            print(f"  !! {name} m={m}: finished runs disagree on the optimum: {sorted(finished)}")


if __name__ == "__main__":
    main()
