"""Every planning method by name: its title, configuration class, runner and guarantees.

``ogcp plan`` and the suite cells both go through :func:`method_spec` and
:meth:`MethodSpec.run`, so a method is dispatched, configured and recorded in one way::

    spec = method_spec("wastar")
    run = spec.run(spec.config(eps=0.2), contacts, m=3)
    run.record  # the complete ogcp.plan/1 record
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ogcp.planner.config.methods import (
    AStarConfig,
    DijkstraConfig,
    ESConfig,
    ESPrunedConfig,
    HFTSConfig,
    SearchConfig,
    WAStarConfig,
)
from ogcp.planner.config.options import MethodConfig, Option, options_of
from ogcp.planner.infra.errors import OgcpError, choice_error

if TYPE_CHECKING:
    from ogcp.planner.grasp.contact_set import ContactSet
    from ogcp.planner.methods.runners import MethodRun, RunOptions

Runner = Callable[[Any, "ContactSet", int, "RunOptions"], "MethodRun"]


@dataclass(frozen=True)
class _Deferred:
    """The runner ``name`` of :mod:`ogcp.planner.methods.runners`, imported when first called.

    The runners import every engine (numpy, trimesh, scipy, the numba kernels), while the
    registry is also read where only names, titles and options are needed (``ogcp --help``).
    A dataclass rather than a closure, so that a spec still pickles (parallel suite cells).

    Attributes:
        name: The runner function's name in :mod:`ogcp.planner.methods.runners`.
    """

    name: str

    def __call__(self, config: Any, contacts: ContactSet, m: int, options: RunOptions) -> MethodRun:
        from ogcp.planner.methods import runners

        runner: Runner = getattr(runners, self.name)
        return runner(config, contacts, m, options)


@dataclass(frozen=True)
class MethodSpec:
    """One planning method.

    Attributes:
        name: Method name (``--method``, a suite's ``method``).
        title: Readable name for labels and plots.
        config: Its configuration class.
        runner: Runs it: ``runner(config, contacts, m, options)``.
        optimal: Whether its answer is the optimum (unless approximate symmetry removal is on).
        exhaustive: Whether it evaluates every grasp.
        run_options: The :class:`RunOptions` fields it uses that a user sets (not ``progress``
            or ``contact_seed``, which the caller fills in).
    """

    name: str
    title: str
    config: type[MethodConfig]
    runner: Runner
    optimal: bool
    exhaustive: bool
    run_options: tuple[str, ...]

    def options(self) -> dict[str, Option]:
        """Its parameters: name -> declared option, in field order."""
        return options_of(self.config)

    def run(self, config: MethodConfig, contacts: ContactSet, m: int, options: RunOptions | None = None) -> MethodRun:
        """Run it and return the result with its complete ``ogcp.plan/1`` record.

        Raises:
            OgcpError: For a configuration of another method, invalid parameters or no admissible grasp.
        """
        if type(config) is not self.config:
            raise TypeError(f"method {self.name!r} runs a {self.config.__name__}, got a {type(config).__name__}")
        from ogcp.planner.methods.runners import RunOptions  # lazy: see _Deferred

        return self.runner(config, contacts, m, options or RunOptions())


_SEARCH_RUN_OPTIONS = ("time_limit", "memory_limit", "jobs")
_ES_RUN_OPTIONS = ("time_limit", "jobs", "backend", "address", "checkpoint")
_HFTS_RUN_OPTIONS = ("time_limit", "jobs", "backend", "address", "optimum")

#: Every method, in the order that listings and ``--help`` show them.
METHODS: dict[str, MethodSpec] = {
    spec.name: spec
    for spec in (
        MethodSpec("astar", "A*", AStarConfig, _Deferred("run_search"), True, False, _SEARCH_RUN_OPTIONS),
        MethodSpec("dijkstra", "Dijkstra", DijkstraConfig, _Deferred("run_search"), True, False, _SEARCH_RUN_OPTIONS),
        MethodSpec("wastar", "WA*", WAStarConfig, _Deferred("run_search"), False, False, _SEARCH_RUN_OPTIONS),
        MethodSpec("es", "ES", ESConfig, _Deferred("run_exhaustive"), True, True, _ES_RUN_OPTIONS),
        MethodSpec(
            "es-pruned", "ES (pruned)", ESPrunedConfig, _Deferred("run_exhaustive"), True, True, _ES_RUN_OPTIONS
        ),
        MethodSpec("hfts", "HFTS", HFTSConfig, _Deferred("run_hfts"), False, False, _HFTS_RUN_OPTIONS),
    )
}
#: Grasps given in an ``ogcp.grasps/1`` file rather than planned: a suite's method (see
#: ``ogcp.benchmarks.suite``), never a planner here, so :func:`method_spec` names where it belongs.
EXTERNAL = "external"
#: The best-first searches (A*, Dijkstra, WA*).
SEARCH_METHODS = tuple(name for name, spec in METHODS.items() if issubclass(spec.config, SearchConfig))
#: Methods whose answer is the optimum (unless approximate symmetry removal is on).
OPTIMAL_METHODS = tuple(name for name, spec in METHODS.items() if spec.optimal)
EXHAUSTIVE_METHODS = tuple(name for name, spec in METHODS.items() if spec.exhaustive)


def method_spec(name: str) -> MethodSpec:
    """The method called ``name``.

    Raises:
        OgcpError: For an unknown name, listing every method.
    """
    if name == EXTERNAL:
        raise OgcpError(
            f"method {EXTERNAL!r} plans nothing: evaluate an ogcp.grasps/1 file with `ogcp evaluate FILE.json`, or "
            f'list it in a suite (method = "{EXTERNAL}", grasps = "FILE.json"); planners: {", ".join(METHODS)}'
        )
    if name not in METHODS:
        raise choice_error("method", name, METHODS)
    return METHODS[name]
