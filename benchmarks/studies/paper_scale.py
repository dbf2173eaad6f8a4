"""Paper-scale timing table (the paper's Fig. 9): A*, WA*(eps) and ES per object.

Run: ``python -m benchmarks.studies.paper_scale --out results/paper_scale [-n 1000] [--es]``.
Each finished run is appended to ``runs.csv`` at once, so an interrupted invocation resumes
where it stopped (rows already present are skipped). ``table.md`` and ``table.csv`` hold
minutes per object and method, plus created/visited states, b* and whether A* matched ES.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from planner import GraspPlanner, sample_contacts
from planner.baselines.es import ExhaustiveSearch
from planner.grasp.reach import default_tip_radius
from planner.objects.resolve import resolve_object

FIELDS = ("object", "n", "m", "method", "eps", "q1", "grasp", "created", "visited", "b_star", "wall_s", "cpu_s")


def _read_rows(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


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
    parser.add_argument("--more-fingers", default="4,5,6", help="m values for the extra A* runs")
    parser.add_argument("--more-fingers-objects", default="", help="objects for the extra m runs")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    log = args.out / "runs.csv"
    done = {(r["object"], int(r["m"]), r["method"], float(r["eps"])) for r in _read_rows(log) if int(r["n"]) == args.n}
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
        else:
            r = GraspPlanner(method=method, eps=eps if method == "wastar" else None, seed=args.seed).plan(contacts, m)
            s = r.stats
            row = {
                "created": s.created,
                "visited": s.visited,
                "b_star": round(s.effective_branching_factor, 3),
                "wall_s": s.wall_seconds,
                "cpu_s": s.cpu_seconds,
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
                cells.append(f"{minutes:.2f}{extra}")
                csv_cells.append(f"{minutes:.4f}")
            lines.append(f"| {label(method, eps, m)} | " + " | ".join(cells) + " |")
            writer.writerow([label(method, eps, m), *csv_cells])
    (out / "table.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
