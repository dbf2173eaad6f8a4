"""ogcp's user-facing layer: the ``ogcp`` command line, suites, regression checks and plots.

Typical use::

    from benchmarks import SuiteRunner, compare_dirs, export_run, load_suite, plot_run

    summary = SuiteRunner(load_suite("quick"), "results/quick", jobs=2).run()
    plot_run("results/quick")                      # figures into results/quick/figures
    text, status = compare_dirs("results/quick", "results/baseline")
    export_run("results/quick")                    # grasps.csv, directions.csv, columns.md

Names load on first use, so ``ogcp --help`` (which imports this package) stays instant.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from benchmarks.compare import compare_dirs
    from benchmarks.export import export_run
    from benchmarks.plots.report import plot_run
    from benchmarks.suite.parse import load_suite, parse_suite
    from benchmarks.suite.runner import SuiteRunner
    from benchmarks.suite.store import ResultStore

#: Public name -> the module that defines it.
_EXPORTS = {
    "ResultStore": "benchmarks.suite.store",
    "SuiteRunner": "benchmarks.suite.runner",
    "compare_dirs": "benchmarks.compare",
    "export_run": "benchmarks.export",
    "load_suite": "benchmarks.suite.parse",
    "parse_suite": "benchmarks.suite.parse",
    "plot_run": "benchmarks.plots.report",
}

__all__ = [
    "ResultStore",
    "SuiteRunner",
    "compare_dirs",
    "export_run",
    "load_suite",
    "parse_suite",
    "plot_run",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
