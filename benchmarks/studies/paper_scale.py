"""Paper-scale timing table (the paper's Fig. 9): A*, WA*(eps) and ES per object.

Run: ``python -m ogcp.benchmarks.studies.paper_scale --out results/paper_scale [-n 1000] [--es]``;
more fingers with ``--more-fingers 4,5,6 --more-fingers-objects bunny,plane [--time-limit S]``.
Each finished run is appended to ``runs.csv`` at once, so an interrupted invocation resumes
where it stopped (rows already present are skipped). A search stopped by ``--time-limit`` is
a row too, with status ``stopped`` and its certified bound; ``--retry-stopped`` runs it again
(with a longer ``--time-limit``), and the table takes the newer row. ``table.md`` and ``table.csv`` hold
minutes per object and method, plus created/visited states, b*, whether A* matched ES, and
for a search not proven optimal its status and the gap to its bound. Every row records the
search's status, bound, peak memory (summed over its processes), processes
(``--search-jobs``: one search dealt to that many, see :mod:`ogcp.planner.search.parts`) and the
states it forgot at its memory limit (``--memory-limit``, see :mod:`ogcp.planner.search.memory`); a
``runs.csv`` written before those columns existed is rewritten with them empty.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from ogcp.planner import GraspPlanner, sample_contacts
from ogcp.planner.baselines.es import ExhaustiveSearch
from ogcp.planner.config.options import MAX_TIME_LIMIT, MEMORY_LIMIT
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.objects.resolve import resolve_object
from ogcp.planner.search.result import UNFINISHED

FIELDS = (
    "object",
    "n",
    "m",
    "method",
    "eps",
    "q1",
    "grasp",
    "created",
    "visited",
    "b_star",
    "wall_s",
    "cpu_s",
    "status",
    "bound",
    "peak_mib",
    "jobs",
    "forgotten",
)


def _read_rows(path: Path) -> list[dict[str, str]]:
    """The rows of ``runs.csv``; a file of older columns is first rewritten with the new ones empty."""
    if not path.exists():
        return []
    with open(path, newline="") as handle:
        reader = csv.DictReader(handle)
        rows = list(reader)
        header = tuple(reader.fieldnames or ())
    if header != FIELDS:
        unknown = sorted(set(header) - set(FIELDS))
        if unknown:
            raise SystemExit(f"paper_scale: {path} has columns this version does not know: {', '.join(unknown)}")
        rows = [{key: row.get(key) or "" for key in FIELDS} for row in rows]
        partial = path.with_suffix(".csv.partial")
        with open(partial, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=FIELDS)
            writer.writeheader()
            writer.writerows(rows)
        partial.replace(path)
    return rows


def _append(path: Path, row: dict[str, object]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        if new:
            writer.writeheader()
        writer.writerow(row)
        handle.flush()


def runs(args: argparse.Namespace) -> list[tuple[str, int, str, float]]:
    """(object, m, method, eps) of every run the arguments ask for."""
    todo = []
    for name in filter(None, args.objects.split(",")):  # --objects "" runs only the extra m
        todo.append((name, 3, "astar", 0.0))
        todo += [(name, 3, "wastar", float(eps)) for eps in args.eps.split(",") if eps]
        if args.es:
            todo.append((name, 3, "es", 0.0))
    for name in filter(None, args.more_fingers_objects.split(",")):
        todo += [(name, int(m), "astar", 0.0) for m in args.more_fingers.split(",") if m]
    return todo


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="output directory")
    parser.add_argument("-n", type=int, default=1000, help="contacts per object (default 1000)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--objects", default="box,sphere,donut,amphora", help="built-in or fetched names (ogcp assets fetch paper)"
    )
    parser.add_argument(
        "--fingertip", action="store_true", help="sample with the default tip radius, as ogcp plan and the suites do"
    )
    parser.add_argument("--eps", default="0.4", help="comma-separated WA* eps values")
    parser.add_argument("--es", action="store_true", help="also run exhaustive search (long)")
    parser.add_argument("--jobs", type=int, default=2, help="processes for ES")
    parser.add_argument(
        "--search-jobs", type=int, default=1, help="processes for each A* / WA* search (ogcp.planner.search.parts)"
    )
    parser.add_argument("--more-fingers", default="4,5,6", help="m values for the extra A* runs")
    parser.add_argument("--more-fingers-objects", default="", help="objects for the extra m runs")
    parser.add_argument(
        "--time-limit", type=float, default=None, help="wall seconds per A* / WA* search; a stopped search is a row too"
    )
    parser.add_argument(
        "--memory-limit",
        type=float,
        default=MEMORY_LIMIT.default,
        help=f"GiB per A* / WA* search, all its processes (default {MEMORY_LIMIT.default:g})",
    )
    parser.add_argument(
        "--retry-stopped",
        action="store_true",
        help="run again the searches recorded as stopped or past their memory limit (the last row counts)",
    )
    args = parser.parse_args(argv)
    if args.search_jobs < 1:
        parser.error(f"--search-jobs must be >= 1, got {args.search_jobs}")
    if args.time_limit is not None and not 0 < args.time_limit <= MAX_TIME_LIMIT:
        parser.error(f"--time-limit must be in (0, {MAX_TIME_LIMIT:g}] seconds, got {args.time_limit:g}")
    if not args.memory_limit > 0:
        parser.error(f"--memory-limit must be > 0 GiB, got {args.memory_limit:g}")
    args.out.mkdir(parents=True, exist_ok=True)
    log = args.out / "runs.csv"
    unfinished = UNFINISHED if args.retry_stopped else ()
    done = {
        (r["object"], int(r["m"]), r["method"], float(r["eps"]))
        for r in _read_rows(log)
        if int(r["n"]) == args.n and r["status"] not in unfinished
    }
    for name, m, method, eps in runs(args):
        if (name, m, method, eps) in done:
            continue
        mesh, source = resolve_object(name)
        radius = default_tip_radius(mesh) if args.fingertip else None
        contacts = sample_contacts(mesh, args.n, seed=args.seed, source=source, tip_radius=radius)
        print(f"{name} n={args.n} m={m} {method} eps={eps} ...", file=sys.stderr, flush=True)
        if method == "es":
            es = ExhaustiveSearch(jobs=args.jobs, checkpoint=args.out / f"es_{name}_{args.n}", progress=True)
            r = es.run(contacts, m)
            row = {"created": "", "visited": "", "b_star": "", "wall_s": r.wall_seconds, "cpu_s": r.cpu_seconds}
            row.update({"status": "optimal", "bound": r.q1, "peak_mib": "", "jobs": args.jobs, "forgotten": ""})
        else:
            planner = GraspPlanner(
                method=method,
                eps=eps if method == "wastar" else None,
                seed=args.seed,
                time_limit=args.time_limit,
                jobs=args.search_jobs,
                memory_limit=args.memory_limit,
            )
            r = planner.plan(contacts, m)
            s = r.stats
            row = {
                "created": s.created,
                "visited": s.visited,
                "b_star": round(s.effective_branching_factor, 3),
                "wall_s": s.wall_seconds,
                "cpu_s": s.cpu_seconds,
                "status": r.status,
                "bound": r.bound,
                "peak_mib": round(s.peak_rss_bytes / 2**20),
                "jobs": args.search_jobs,
                "forgotten": s.forgotten,
            }
        row.update(
            {
                "object": name,
                "n": args.n,
                "m": m,
                "method": method,
                "eps": eps,
                "q1": r.q1,
                "grasp": " ".join(map(str, r.grasp)),
            }
        )
        _append(log, row)
    write_tables(_read_rows(log), args.out, args.n)
    print((args.out / "table.md").read_text())
    return 0


def write_tables(rows: list[dict[str, str]], out: Path, n: int) -> None:
    """Markdown and CSV tables: CPU minutes per object and method, like the paper's Fig. 9."""
    rows = [r for r in rows if int(r["n"]) == n]
    objects = list(dict.fromkeys(r["object"] for r in rows))
    methods = list(dict.fromkeys((r["method"], float(r["eps"]), int(r["m"])) for r in rows))
    index = {(r["object"], r["method"], float(r["eps"]), int(r["m"])): r for r in rows}

    def label(method: str, eps: float, m: int) -> str:
        name = {"astar": "A*", "wastar": f"WA* ({eps:g})", "es": "ES"}[method]
        return name if m == 3 else f"{name}, m = {m}"

    lines = [
        f"CPU minutes, |C| = {n} (created/visited states, b*; A* = ES marks an optimum equal to ES)",
        "",
        "| method | " + " | ".join(objects) + " |",
        "|---" * (len(objects) + 1) + "|",
    ]
    with open(out / "table.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["method", *objects])
        for method, eps, m in methods:
            cells, csv_cells = [], []
            for name in objects:
                r = index.get((name, method, eps, m))
                if r is None:
                    cells.append("")
                    csv_cells.append("")
                    continue
                minutes = float(r["cpu_s"]) / 60
                extra = f" ({r['created']}/{r['visited']}, b*={r['b_star']})" if r["created"] else ""
                es = index.get((name, "es", 0.0, 3))
                if method == "astar" and m == 3 and es is not None:
                    extra += " A* = ES" if float(es["q1"]) == float(r["q1"]) else " A* != ES"
                if r.get("status") in UNFINISHED and r.get("bound"):
                    gap = 1.0 - float(r["q1"]) / float(r["bound"]) if float(r["bound"]) > 0 else 0.0
                    extra += f" {r['status']}, gap {100 * gap:.1f} %"
                cells.append(f"{minutes:.2f}{extra}")
                csv_cells.append(f"{minutes:.4f}")
            lines.append(f"| {label(method, eps, m)} | " + " | ".join(cells) + " |")
            writer.writerow([label(method, eps, m), *csv_cells])
    (out / "table.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
