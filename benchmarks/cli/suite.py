"""The ``ogcp suite`` and ``ogcp compare`` commands (registered by :mod:`ogcp.benchmarks.cli.app`).

Exit status: ``suite`` 0 when every cell of the suite is recorded without error (or the
run stopped at ``--max-cells`` without errors), 1 when a cell is recorded as an error or
as stopped at ``--time-limit``;
``compare`` 0 without regressions, 1 with regressions; both 2 on invalid input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ogcp.benchmarks.cli.options import number, positive_int, typed, valid
from ogcp.planner.config.options import JOBS, MEMORY_LIMIT, TIME_LIMIT
from ogcp.planner.infra.parallel import BACKENDS


def register(commands: Any) -> None:
    """Add the ``suite`` and ``compare`` sub-commands to the ``ogcp`` parser.

    Args:
        commands: The sub-parsers object of the ``ogcp`` parser.
    """
    suite = commands.add_parser("suite", help="run a benchmark suite into a results folder (resumable)")
    suite.add_argument("suite", metavar="FILE_OR_NAME", help="suite TOML file or built-in suite (quick, paper, sdh)")
    suite.add_argument(
        "--out",
        required=True,
        type=Path,
        metavar="DIR",
        help="results folder: results.jsonl + manifest.json; must be empty unless --resume",
    )
    suite.add_argument(
        "--jobs",
        type=typed(JOBS),
        default=1,
        help=f"cells run in parallel; {valid(JOBS)}, 4 per CPU core (default 1)",
    )
    suite.add_argument("--backend", default="loky", help=f"parallel backend: {', '.join(BACKENDS)} (default loky)")
    suite.add_argument("--address", default=None, metavar="HOST:PORT", help="Dask scheduler address (backend dask)")
    suite.add_argument("--resume", action="store_true", help="continue the run in DIR, skipping its finished cells")
    suite.add_argument(
        "--retry-errors",
        action="store_true",
        help="with --resume: rerun cells recorded as errors or as stopped at --time-limit",
    )
    suite.add_argument(
        "--max-cells",
        type=positive_int,
        default=None,
        metavar="N",
        help="stop after N cells (continue later with --resume)",
    )
    suite.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="KEY=VALUE[,VALUE]",
        help="run only matching cells; keys object, method, group, label, m, mu, contact_model, contacts; "
        "repeat to narrow (the rest: a later run with --resume)",
    )
    suite.add_argument(
        "--time-limit",
        type=typed(TIME_LIMIT),
        default=None,
        metavar="SECONDS",
        help=f"wall-clock budget per planning cell (any method), {TIME_LIMIT.bounds()}; a cell past it is "
        "recorded as stopped, with its best grasp, certified bound and gap (rerun it with "
        "--resume --retry-errors and a larger budget)",
    )
    suite.add_argument(
        "--memory-limit",
        type=typed(MEMORY_LIMIT),
        default=MEMORY_LIMIT.default,
        metavar="GIB",
        help=f"most memory of each search cell, all its processes (default {MEMORY_LIMIT.default:g}); a cell "
        "past it is recorded as stopped, with status 'memory', its best grasp and certified bound",
    )
    suite.add_argument(
        "--no-simulation",
        action="store_true",
        help="skip the simulation even if the suite enables it (a different suite hash)",
    )
    chatter = suite.add_mutually_exclusive_group()
    chatter.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress on stderr (failed cells and the final summary still print)",
    )
    chatter.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="one line per finished cell: the cell, its status, Q1 and wall seconds",
    )
    suite.set_defaults(handler=run_suite)

    compare = commands.add_parser("compare", help="compare two suite results folders; exit 1 on regressions")
    compare.add_argument("run", type=Path, metavar="RUN", help="results folder under test")
    compare.add_argument("baseline", type=Path, metavar="BASELINE", help="reference results folder")
    compare.add_argument(
        "--q1-tolerance",
        type=number,
        default=1e-9,
        help="largest allowed drop of a cell's Q1, absolute, >= 0 (default 1e-9)",
    )
    compare.add_argument(
        "--optimality-tolerance",
        type=number,
        default=1e-9,
        help="largest |Q1 - ES optimum| of optimal methods, >= 0 (default 1e-9)",
    )
    compare.add_argument(
        "--time-ratio", type=number, default=2.0, help="largest allowed RUN/BASELINE time of a cell, >= 1 (default 2)"
    )
    compare.add_argument(
        "--min-time",
        type=number,
        default=1.0,
        help="times below this many seconds count as this (noise floor), >= 0 (default 1)",
    )
    compare.add_argument(
        "--time-key",
        default="plan",
        help="time compared: plan (the method's CPU seconds), or the whole cell's cpu or wall seconds (default plan)",
    )
    compare.add_argument(
        "--resistance-tolerance",
        type=number,
        default=0.05,
        help="largest allowed relative drop of the minimum measured resistance, 0 to 1 (default 0.05)",
    )
    compare.add_argument(
        "--allow-missing", action="store_true", help="report BASELINE cells missing from RUN without failing"
    )
    compare.set_defaults(handler=run_compare)


def run_suite(args: argparse.Namespace) -> int:
    """Handler of ``ogcp suite``."""
    from ogcp.benchmarks.suite.parse import load_suite
    from ogcp.benchmarks.suite.runner import SuiteRunner, summary_table  # lazy: ogcp plan never pays for it

    suite = load_suite(args.suite)
    if args.no_simulation:
        suite = suite.without_simulation()
    # A bar on a terminal; off one (CI, nohup) a line per finished cell, at most every 10 s.
    terminal = sys.stderr.isatty()
    lines = "none" if args.quiet else "each" if args.verbose else "none" if terminal else "periodic"
    runner = SuiteRunner(
        suite,
        args.out,
        jobs=args.jobs,
        backend=args.backend,
        address=args.address,
        resume=args.resume,
        retry_errors=args.retry_errors,
        max_cells=args.max_cells,
        only=args.only,
        time_limit=args.time_limit,
        memory_limit=args.memory_limit,
        progress=terminal and not args.quiet,
        lines=lines,
    )
    summary = runner.run()
    print(summary_table(suite, summary.records))
    print(
        f"{summary.ran} cells run, {summary.skipped} already recorded, {summary.errors} errors, "
        f"{summary.remaining} remaining; results in {args.out / 'results.jsonl'}"
    )
    if summary.remaining:
        print(f"continue with: ogcp suite {args.suite} --out {args.out} --resume")
    return 1 if summary.errors else 0


def run_compare(args: argparse.Namespace) -> int:
    """Handler of ``ogcp compare``."""
    from ogcp.benchmarks.compare import Tolerances, compare_dirs

    tolerances = Tolerances(
        q1=args.q1_tolerance,
        optimality=args.optimality_tolerance,
        time_ratio=args.time_ratio,
        min_time=args.min_time,
        time_key=args.time_key,
        resistance=args.resistance_tolerance,
        allow_missing=args.allow_missing,
    )
    text, status = compare_dirs(args.run, args.baseline, tolerances)
    print(text)
    return status
