"""Start-up time of the ``ogcp`` command: ``--help`` of every command, and a small plan.

Run: ``python -m ogcp.benchmarks.perf.cli_startup [--runs 7]``. Every case is a fresh process of the
``ogcp`` console script, timed from launch to exit; the rounds interleave the cases with a
reference process (``python -c pass``), so that a busy machine slows all of them alike. Prints
per-case medians, their ratio to the reference's median, and the issue's targets (0.3 s for a
``--help``, 0.8 s for ``ogcp plan box -n 20`` with numba's kernel cache warm; one untimed plan
runs first to warm it, and the contact cache). A second reference, a process that only loads the
compiled Q1 kernel from numba's cache and calls it once, shows the part of a plan's time that
numba takes before ogcp does anything of its own (about 0.3 s of it is numba setting up its
compiler, on any cached function).
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from ogcp.benchmarks.cli.app import build_parser

#: Wall-clock targets of the issue [s]: every ``--help``, and the small plan.
HELP_TARGET = 0.3
PLAN_TARGET = 0.8
#: The plan case: small enough that start-up, not the search, dominates.
PLAN_ARGS = ("plan", "box", "-n", "20")
#: Label of the second reference: the compiled kernel loaded from numba's cache and called once.
FLOOR = "kernel alone (numpy, numba, one cached call)"
_FLOOR_SCRIPT = "import numpy as n; from ogcp.planner.grasp.kernel import kernel_q1; kernel_q1(n.eye(7, 6) - 0.1)"


def ogcp_command() -> list[str]:
    """The installed ``ogcp`` console script (next to this Python), else ``python -m ogcp.benchmarks.cli``."""
    script = Path(sys.executable).parent / "ogcp"
    if script.is_file():
        return [str(script)]
    found = shutil.which("ogcp")
    return [found] if found else [sys.executable, "-m", "ogcp.benchmarks.cli"]


def command_paths(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every command and sub-command of ``parser`` (``("assets", "list")``...), in ``--help`` order."""
    paths: list[tuple[str, ...]] = []
    for action in parser._actions:  # argparse keeps sub-parsers only in this private list
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                paths.append((*prefix, name))
                paths.extend(command_paths(child, (*prefix, name)))
    return paths


def seconds(argv: list[str]) -> float:
    """Wall-clock seconds of one process, from launch to exit; raises if it fails."""
    start = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    """Time every case ``--runs`` times, interleaved with the reference, and print the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="processes per case (default 7)")
    args = parser.parse_args()

    ogcp = ogcp_command()
    reference = [sys.executable, "-c", "pass"]
    floor = [sys.executable, "-c", _FLOOR_SCRIPT]
    cases: dict[str, tuple[list[str], float]] = {"ogcp --help": ([*ogcp, "--help"], HELP_TARGET)}
    for path in command_paths(build_parser()):
        cases[f"ogcp {' '.join(path)} --help"] = ([*ogcp, *path, "--help"], HELP_TARGET)
    cases[f"ogcp {' '.join(PLAN_ARGS)}"] = ([*ogcp, *PLAN_ARGS], PLAN_TARGET)

    seconds([*ogcp, *PLAN_ARGS])  # warm numba's kernel cache, the contact cache and the OS's file cache
    times: dict[str, list[float]] = {"python -c pass": [], FLOOR: [], **{label: [] for label in cases}}
    for _ in range(args.runs):
        times["python -c pass"].append(seconds(reference))
        times[FLOOR].append(seconds(floor))
        for label, (argv, _) in cases.items():
            times[label].append(seconds(argv))

    base = statistics.median(times["python -c pass"])
    width = max(len(label) for label in times)
    print(f"{'case':<{width}}  median [s]  x reference  target [s]")
    for label in ("python -c pass", FLOOR):
        median = statistics.median(times[label])
        print(f"{label:<{width}}  {median:10.3f}  {median / base:11.1f}")
    for label, (_, target) in cases.items():
        median = statistics.median(times[label])
        verdict = "ok" if median <= target else "OVER"
        print(f"{label:<{width}}  {median:10.3f}  {median / base:11.1f}  {target:10.1f} {verdict}")
    print(f"({args.runs} runs per case, interleaved; {' '.join(ogcp)})")


if __name__ == "__main__":
    main()
