"""The first run on a fresh install: compiling the kernels, timed with cold caches.

Run: ``python -m ogcp.benchmarks.perf.first_run [--runs 3]``. Every case is a fresh process with
an empty numba cache and an empty ogcp cache, each in its own temporary folder:

* ``ogcp plan box -n 200 -m 3`` cold (the kernels that ship with ogcp, :mod:`ogcp.planner.grasp.kernel.shipped`,
  load; nothing compiles), and the same command warm (its cache from the cold run) as the
  reference of the same round;
* the same cold plan with the shipped kernels turned off (``OGCP_SHIPPED_KERNELS=0``: it compiles
  what A* needs), to show what shipping them saves;
* a suite's warm-up (:func:`ogcp.planner.methods.warm_up.warm_up`, every kernel family) cold, with
  the shipped kernels, and without them with the search family compiled in a helper process
  alongside (the default) and in one process (``parallel=False``), to show what the helper saves.

Prints each case's median over ``--runs`` rounds, the ratio of the cold plan to the warm one, and
the issue's targets (first plan at most 15 s, a suite's warm-up at most 30 s, on two cores).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

from ogcp.benchmarks.perf.cli_startup import ogcp_command

#: Targets of the issue [s] on two cores: the first plan, and a suite's kernel warm-up.
PLAN_TARGET = 15.0
WARM_UP_TARGET = 30.0
PLAN_ARGS = ("plan", "box", "-n", "200", "-m", "3")
_WARM_UP = "from ogcp.planner.methods.warm_up import warm_up; warm_up(parallel={parallel})"


def timed(argv: list[str], env: dict[str, str]) -> float:
    """Wall-clock seconds of one process, from launch to exit; raises if it fails."""
    start = time.perf_counter()
    subprocess.run(argv, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def one_round() -> dict[str, float]:
    """Every case once, each cold case with caches of its own."""
    out: dict[str, float] = {}
    cases = {
        "plan, cold": ([*ogcp_command(), *PLAN_ARGS], "1"),
        "plan, cold, compiled": ([*ogcp_command(), *PLAN_ARGS], "0"),
        "warm-up": ([sys.executable, "-c", _WARM_UP.format(parallel=True)], "1"),
        "warm-up, helper process": ([sys.executable, "-c", _WARM_UP.format(parallel=True)], "0"),
        "warm-up, one process": ([sys.executable, "-c", _WARM_UP.format(parallel=False)], "0"),
    }
    for name, (argv, ships) in cases.items():
        with tempfile.TemporaryDirectory(prefix="ogcp-first-run-") as folder:
            env = {
                **os.environ,
                "NUMBA_CACHE_DIR": f"{folder}/numba",
                "OGCP_CACHE": f"{folder}/ogcp",
                "OGCP_SHIPPED_KERNELS": ships,
            }
            out[name] = timed(argv, env)
            if name == "plan, cold":
                out["plan, warm"] = timed(argv, env)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="rounds; each case's median is printed (default 3)")
    args = parser.parse_args(argv)
    rounds = [one_round() for _ in range(args.runs)]
    medians = {name: statistics.median(r[name] for r in rounds) for name in rounds[0]}
    print(f"median of {args.runs} rounds, {os.cpu_count()} cores, cold caches in temporary folders:")
    for name, value in medians.items():
        print(f"  {name:<26} {value:6.1f} s")
    print(f"  cold plan / warm plan     x{medians['plan, cold'] / medians['plan, warm']:.1f}")
    saved = medians["warm-up, one process"] - medians["warm-up, helper process"]
    print(f"  the helper process saves  {saved:.1f} s of the warm-up without shipped kernels")
    shipped = medians["plan, cold, compiled"] - medians["plan, cold"]
    print(f"  the shipped kernels save  {shipped:.1f} s of the first plan")
    print(f"targets: first plan <= {PLAN_TARGET:g} s, warm-up <= {WARM_UP_TARGET:g} s (two cores)")


if __name__ == "__main__":
    main()
