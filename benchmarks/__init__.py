"""ogcp's user-facing layer: the ``ogcp`` command line, suites, regression checks and plots.

Typical use::

    from ogcp.benchmarks import SuiteRunner, compare_dirs, export_run, load_suite, plot_run

    summary = SuiteRunner(load_suite("quick"), "results/quick", jobs=2).run()
    plot_run("results/quick")                      # figures into results/quick/figures
    text, status = compare_dirs("results/quick", "results/baseline")
    export_run("results/quick")                    # grasps.csv, directions.csv, columns.md

Names load on first use, so ``ogcp --help`` (which imports this package) stays instant.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.benchmarks.compare import compare_dirs
    from ogcp.benchmarks.export import export_run
    from ogcp.benchmarks.plots.report import plot_run
    from ogcp.benchmarks.suite.parse import load_suite, parse_suite
    from ogcp.benchmarks.suite.runner import SuiteRunner
    from ogcp.benchmarks.suite.store import ResultStore

#: Public name -> the module that defines it.
_EXPORTS = {
    "ResultStore": "ogcp.benchmarks.suite.store",
    "SuiteRunner": "ogcp.benchmarks.suite.runner",
    "compare_dirs": "ogcp.benchmarks.compare",
    "export_run": "ogcp.benchmarks.export",
    "load_suite": "ogcp.benchmarks.suite.parse",
    "parse_suite": "ogcp.benchmarks.suite.parse",
    "plot_run": "ogcp.benchmarks.plots.report",
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
