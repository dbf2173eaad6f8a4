"""A suite run as the figures read it: finished cells, grouped by problem and method.

A *problem* is one contact set and finger count (object, |C|, contact seed, m, mu, k,
diagonal); a *constraint* is a cell's hand / spread restriction. Records that errored,
cells the suite lists but the folder does not hold yet, and unreadable lines become
one-line notes, never errors, so a partial run still plots.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ogcp.benchmarks.suite.config import EXTERNAL_METHOD
from ogcp.benchmarks.suite.manifest import ManifestSuite
from ogcp.benchmarks.suite.record import PROBLEM_FIELDS, CellRecord, Problem
from ogcp.benchmarks.suite.store import MANIFEST, RESULTS, read_results
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import SEARCH_METHODS
from ogcp.planner.records.plan import PlanView
from ogcp.sim_eval.result import SimRecord

from .style import METHOD_TITLES

#: Search parameters at their suite defaults: the "plain" A*/WA*/Dijkstra of tables and Fig. 4.
PLAIN_SEARCH = {"branching": 2, "successor": "fc", "symmetry": False, "ordered": False}
DEFAULT_HEURISTIC = {"astar": "fc", "wastar": "fc", "dijkstra": "none"}
#: Notes listing individual cells stop after this many.
MAX_LISTED = 5


class SkipFigure(Exception):
    """A figure cannot be drawn from this run; the message says what it needs."""


def number(value: Any) -> float | None:
    """``value`` as a finite float, else None (JSON writes NaN as null)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


@dataclass(frozen=True)
class CellData:
    """One finished cell (``status`` ok with a plan).

    Attributes:
        id: Cell id.
        params: The record's ``params`` block.
        plan: The ``ogcp.plan/1`` record as written (read it through :attr:`plan_view`).
        simulation: The ``ogcp.sim/1`` record, or None.
        record: The whole cell record.
    """

    id: str
    params: dict[str, Any]
    plan: dict[str, Any]
    simulation: SimRecord | None
    record: CellRecord

    @property
    def plan_view(self) -> PlanView:
        """Typed read access to the plan."""
        return PlanView(self.plan)

    @property
    def method(self) -> str:
        return str(self.record.method or self.plan_view.method)

    @property
    def variant(self) -> dict[str, Any]:
        return self.record.variant

    @property
    def object(self) -> str:
        return self.record.object

    @property
    def label(self) -> str:
        return self.record.label or METHOD_TITLES.get(self.method, self.method)

    @property
    def problem(self) -> Problem:
        return self.record.problem

    @property
    def eps(self) -> float | None:
        # The cell's own parameter wins; the plan's eps covers methods that do not take one.
        return number(self.variant["eps"]) if "eps" in self.variant else self.plan_view.eps

    @property
    def constraint(self) -> str:
        """``""`` without constraints, else e.g. ``SDH`` or ``spread<=0.1 m``."""
        parts = []
        if self.variant.get("hand"):
            parts.append(str(self.variant["hand"]).upper())
        if self.variant.get("max_spread") is not None:
            parts.append(f"spread<={self.variant['max_spread']:g} m")
        return " + ".join(parts)

    @property
    def stats(self) -> dict[str, Any]:
        return self.plan_view.stats

    @property
    def q1(self) -> float | None:
        return self.plan_view.q1

    @property
    def plain(self) -> bool:
        """No constraint, and for searches the default expansion without symmetry removal."""
        if self.constraint:
            return False
        if self.method not in SEARCH_METHODS:
            return True
        variant = self.variant
        if any(variant.get(k, v) != v for k, v in PLAIN_SEARCH.items()):
            return False
        if variant.get("heuristic", DEFAULT_HEURISTIC[self.method]) != DEFAULT_HEURISTIC[self.method]:
            return False
        hb = variant.get("heuristic_branching")
        return hb is None or hb == variant.get("branching", 2)

    def cpu_seconds(self) -> float | None:
        """The method's CPU time (summed over workers where the method records it)."""
        value = self.plan_view.cpu_seconds
        return value if value is not None else number(self.record.cpu_seconds)

    def wall_seconds(self) -> float | None:
        """The method's wall time."""
        value = self.plan_view.wall_seconds
        return value if value is not None else number(self.record.wall_seconds)


@dataclass(frozen=True)
class RunData:
    """A suite output folder.

    Attributes:
        directory: The folder.
        cells: Finished cells in file order (latest record per id).
        notes: One line per record or cell that cannot be plotted.
        manifest: The manifest, or None.
    """

    directory: Path
    cells: tuple[CellData, ...]
    notes: tuple[str, ...] = ()
    manifest: dict[str, Any] | None = field(default=None, repr=False)

    def by_problem(self, cells: Iterable[CellData] | None = None) -> dict[Problem, list[CellData]]:
        """Cells grouped by problem, problems in order of first appearance."""
        groups: dict[Problem, list[CellData]] = {}
        for cell in self.cells if cells is None else cells:
            groups.setdefault(cell.problem, []).append(cell)
        return groups

    def problem_names(self) -> dict[Problem, str]:
        """A short name per problem: the object, plus what tells problems of one object apart.

        External cells' problems (their own contacts, no seed) are named among themselves, so
        that they do not lengthen the names of the planners' problems of the same object.
        """
        names = problem_names(c.problem for c in self.cells if c.method != EXTERNAL_METHOD)
        external = problem_names(c.problem for c in self.cells if c.method == EXTERNAL_METHOD)
        return {**external, **names}


def frozen(mapping: dict[str, Any], leave_out: Iterable[str] = ()) -> tuple[tuple[str, Any], ...]:
    """``mapping`` without ``leave_out`` as a hashable, order-independent key."""
    skip = set(leave_out)
    return tuple(sorted((k, repr(v)) for k, v in mapping.items() if k not in skip))


def problem_names(problems: Iterable[Problem]) -> dict[Problem, str]:
    """Short names: ``box``, or ``box |C|=100 m=4`` where one object has several problems."""
    unique = list(dict.fromkeys(problems))
    names = {}
    short = {
        "contacts": "|C|={}",
        "contact_seed": "seed {}",
        "m": "m={}",
        "mu": "mu={}",
        "cone_edges": "k={}",
        "diagonal": "d={}",
        "tip_radius": "r={}",
        "torsional_friction": "soft {} m",
    }
    for problem in unique:
        siblings = [p for p in unique if p[0] == problem[0]]
        parts = [str(problem[0])]
        for index, name in enumerate(PROBLEM_FIELDS[1:], start=1):
            if len({p[index] for p in siblings}) > 1 and problem[index] is not None:  # external: no seed
                parts.append(short[name].format(problem[index]))
        names[problem] = " ".join(parts)
    return names


def load_run(directory: str | Path) -> RunData:
    """Read a suite output folder for plotting.

    Raises:
        OgcpError: When the folder, its ``results.jsonl`` or any cell record is missing.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise OgcpError(f"{directory}: no such folder (expected the --out folder of ogcp suite)")
    results = directory / RESULTS
    if not results.is_file():
        raise OgcpError(f"{directory}: no {RESULTS} (expected the --out folder of ogcp suite)")
    report = read_results(results)
    latest = report.latest()
    if not latest:
        raise OgcpError(f"{results}: no cell records yet; nothing to plot")
    notes = list(report.problems)
    cells, errors, unusable = [], [], []
    for line in latest.values():
        try:
            record = CellRecord.from_dict(line)
        except OgcpError:
            unusable.append(line["id"])
            continue
        if record.status == "error":
            errors.append(record)
        elif not record.ok or record.plan is None:
            unusable.append(record.id)
        else:
            simulation = SimRecord.from_dict(record.simulation) if record.simulation is not None else None
            cells.append(CellData(record.id, record.params, record.plan, simulation, record))
    if errors:
        notes.append(f"{len(errors)} cell(s) with status error skipped: {_list(_describe(r) for r in errors)}")
    if unusable:
        notes.append(f"{len(unusable)} record(s) without an ok status, params and plan skipped: {_list(unusable)}")
    manifest = _manifest(directory, notes)
    missing = _missing(manifest, set(latest))
    if missing:
        notes.append(missing)
    if not cells:
        raise OgcpError(f"{results}: none of its {len(latest)} cells finished without error; nothing to plot")
    return RunData(directory, tuple(cells), tuple(notes), manifest)


def _describe(record: CellRecord) -> str:
    error = record.error
    what = " ".join(v for v in (record.object, record.label) if v) or record.id
    return f"{what} ({error.type if error else 'error'}: {error.message if error else ''})"


def _list(items: Iterable[str]) -> str:
    items = list(items)
    more = f"; and {len(items) - MAX_LISTED} more" if len(items) > MAX_LISTED else ""
    return "; ".join(items[:MAX_LISTED]) + more


def _manifest(directory: Path, notes: list[str]) -> dict[str, Any] | None:
    path = directory / MANIFEST
    if not path.is_file():
        notes.append(f"{directory}: no {MANIFEST}; cells the suite has not run yet are not counted")
        return None
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        notes.append(f"{path}: unreadable ({exc}); cells the suite has not run yet are not counted")
        return None
    return manifest if isinstance(manifest, dict) else None


def _missing(manifest: dict[str, Any] | None, recorded: set[str]) -> str | None:
    """The note on cells the suite lists that the folder does not hold yet."""
    suite = ManifestSuite.of(manifest)
    if suite is None:
        return None
    expected = _suite_cells(suite)
    if expected is not None:
        absent = [label for cell_id, label in expected.items() if cell_id not in recorded]
        if absent:
            return f"{len(absent)} cell(s) of the suite not run yet (skipped): {_list(absent)}"
        return None
    if suite.cells is not None and suite.cells > len(recorded):
        return f"{suite.cells - len(recorded)} cell(s) of the suite not run yet (skipped)"
    return None


def _suite_cells(suite: ManifestSuite) -> dict[str, str] | None:
    """id -> description of every cell of the manifest's suite, or None when it cannot be re-read."""
    from ogcp.benchmarks.suite.parse import parse_suite

    if suite.content is None:
        return None
    try:
        parsed = parse_suite(suite.content, source=suite.source or "manifest")
    except OgcpError:
        # Mesh paths relative to a suite file elsewhere do not resolve here; count instead.
        return None
    return {c.id: f"{c.object.spec} |C|={c.contacts} m={c.m} {c.label}" for c in parsed.cells}
