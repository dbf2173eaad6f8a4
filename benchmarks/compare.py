"""Regression checks between two suite output folders (``ogcp compare RUN BASELINE``).

Cells are matched by id. A finding is a regression of RUN against BASELINE, or a broken
guarantee inside RUN:

* ``optimality``: an optimal method (astar, dijkstra, es, es-pruned; search without
  symmetry removal) differs from the exhaustive optimum of the same contact set, m and
  constraints in RUN by more than the optimality tolerance;
* ``bound``: a WA* grasp below its own (1 + eps) guarantee relative to that optimum;
* ``q1``: a cell's Q1 dropped by more than the Q1 tolerance (absolute);
* ``resistance``: a simulated grasp's minimum measured resistance (over the disturbance
  directions) dropped by more than the resistance tolerance (relative);
* ``gates``: a simulated grasp that passed the validity gates in BASELINE fails them in RUN;
* ``time``: a cell's time (default: the method's CPU seconds) grew beyond the ratio (both
  times raised to a noise floor first). Runs of ``ogcp suite`` compile the numba kernels in
  each process before its first cell, so a cold cache is not in any cell's time; the report
  notes a run that compiled (warm-up above :data:`COMPILE_SECONDS`) and a run made before
  the warm-up, whose first cell in each process may include the compilation;
* ``error``: a cell that succeeded in BASELINE failed in RUN;
* ``missing``: a BASELINE cell absent from RUN (a finding unless allowed).

Simulated grasps (``simulation.grasps`` of an ``ogcp.sim/1`` record) are matched by their
``label`` (``best``, ``hfts-run-3``, ...) and read through ``valid`` and ``measured_min``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ogcp.benchmarks.suite.manifest import kernel_warmups, suite_hash
from ogcp.benchmarks.suite.params import EXHAUSTIVE_METHODS, OPTIMAL_METHODS
from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.sim_eval.result import SimGraspRecord, SimRecord

TIME_KEYS = ("cpu", "plan", "wall")
CONSTRAINT_KEYS = ("max_spread", "hand", "hand_threshold")
#: A kernel warm-up longer than this [s] compiled the kernels (loading numba's cache takes < 1 s).
COMPILE_SECONDS = 2.0


@dataclass(frozen=True)
class Tolerances:
    """What counts as a regression.

    Attributes:
        q1: Largest allowed drop of a cell's Q1 (absolute).
        optimality: Largest allowed |Q1 - exhaustive optimum| of an optimal method.
        time_ratio: Largest allowed RUN / BASELINE time.
        min_time: Noise floor [s]: both times are raised to it before the ratio.
        time_key: ``plan`` (the method's CPU seconds, ``plan.stats.cpu_seconds``: no contact
            sampling, caches or simulation), ``cpu`` or ``wall`` (the whole cell's seconds).
        resistance: Largest allowed relative drop of the minimum measured resistance.
        allow_missing: Report BASELINE cells absent from RUN without failing.
    """

    q1: float = 1e-9
    optimality: float = 1e-9
    time_ratio: float = 2.0
    min_time: float = 1.0
    time_key: str = "plan"
    resistance: float = 0.05
    allow_missing: bool = False

    def validate(self) -> None:
        """Raises OgcpError for a negative or non-finite tolerance, a relative one above 1, a ratio below 1 or an
        unknown time key."""
        if self.time_key not in TIME_KEYS:
            raise choice_error("time key", self.time_key, TIME_KEYS)
        for name in ("q1", "optimality", "min_time", "resistance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise OgcpError(f"{name} tolerance must be a number >= 0, got {value!r}")
        # A relative drop above 100 % cannot happen: such a tolerance would switch the check off unseen.
        if self.resistance > 1:
            raise OgcpError(f"resistance tolerance is a relative drop from 0 to 1, got {self.resistance!r}")
        ratio = self.time_ratio
        if isinstance(ratio, bool) or not (isinstance(ratio, (int, float)) and math.isfinite(ratio) and ratio >= 1):
            raise OgcpError(f"time ratio must be a number >= 1, got {ratio!r}")


@dataclass(frozen=True)
class Finding:
    """One regression: its kind, the table row (object, label), the cell and what happened."""

    kind: str
    object: str
    label: str
    cell: str
    detail: str

    def line(self) -> str:
        return f"{self.kind}: {self.object} / {self.label} {self.cell}: {self.detail}"


@dataclass(frozen=True)
class RunData:
    """A suite output folder as read for comparison."""

    directory: Path
    records: dict[str, CellRecord]
    manifest: dict[str, Any] | None
    problems: tuple[str, ...]


def load_run(directory: str | Path) -> RunData:
    """Read a suite output folder.

    Raises:
        OgcpError: When the folder or its ``results.jsonl`` is missing or unreadable.
    """
    store = ResultStore(directory)
    if not store.directory.is_dir():
        raise OgcpError(f"{directory}: no such folder (expected the --out folder of ogcp suite)")
    if not store.results_path.is_file():
        raise OgcpError(f"{directory}: no results.jsonl (expected the --out folder of ogcp suite)")
    report = store.read()
    records = {}
    for line in report.records:
        try:
            record = CellRecord.from_dict(line)
        except OgcpError as exc:
            raise OgcpError(f"{store.results_path}: {exc}") from None
        records[record.id] = record  # the latest record of a cell wins
    return RunData(store.directory, records, store.read_manifest(), report.problems)


def simulated_grasps(record: CellRecord) -> dict[str, SimGraspRecord]:
    """label -> simulated grasp of the cell's ``ogcp.sim/1`` record (empty without simulation)."""
    if record.simulation is None:
        return {}
    return {g.label: g for g in SimRecord.from_dict(record.simulation).grasps}


def invalid_grasps(record: CellRecord) -> set[str]:
    """Labels of the simulated grasps that fail the validity gates."""
    return {label for label, g in simulated_grasps(record).items() if g.valid is False}


def resistance_changes(new: CellRecord, base: CellRecord) -> dict[str, tuple[float, float]]:
    """label -> (RUN, BASELINE) minimum measured resistance, for grasps measured in both."""
    run, reference = simulated_grasps(new), simulated_grasps(base)
    pairs = {}
    for label, grasp in reference.items():
        after = run[label].measured_min if label in run else None
        if grasp.measured_min is not None and after is not None:
            pairs[label] = (after, grasp.measured_min)
    return pairs


def _time(record: CellRecord, key: str) -> float | None:
    if key == "plan":
        plan = record.plan_view
        return plan.cpu_seconds if plan is not None else None
    return record.cpu_seconds if key == "cpu" else record.wall_seconds


def _q1(record: CellRecord) -> float | None:
    plan = record.plan_view
    return plan.q1 if record.ok and plan is not None else None


def _q_ows(record: CellRecord) -> float | None:
    plan = record.plan_view
    return plan.q_ows if plan is not None else None


class Comparison:
    """RUN against BASELINE under the given tolerances.

    Args:
        run: The folder under test.
        baseline: The reference folder.
        tolerances: What counts as a regression.
    """

    def __init__(self, run: RunData, baseline: RunData, tolerances: Tolerances) -> None:
        self.run = run
        self.baseline = baseline
        self.tolerances = tolerances

    def findings(self) -> list[Finding]:
        """Every regression, in table order."""
        self.tolerances.validate()
        found = self._optimality()
        for cell, base in self.baseline.records.items():
            new = self.run.records.get(cell)
            if new is None:
                found.append(_finding("missing", base, cell, "cell of BASELINE not in RUN"))
            else:
                found.extend(self._cell(cell, new, base))
        return sorted(found, key=lambda f: (f.object, f.label, f.cell, f.kind))

    def failures(self) -> list[Finding]:
        """The findings that fail the comparison (``missing`` only unless allowed)."""
        return [f for f in self.findings() if not (f.kind == "missing" and self.tolerances.allow_missing)]

    def _cell(self, cell: str, new: CellRecord, base: CellRecord) -> list[Finding]:
        t = self.tolerances
        if not new.ok:
            if base.ok:
                error = new.error
                what = f"{error.type}: {error.message}" if error is not None else "None: None"
                return [_finding("error", new, cell, f"failed: {what}")]
            return []
        found = []
        q_new, q_base = _q1(new), _q1(base)
        if q_new is not None and q_base is not None and q_new < q_base - t.q1:
            found.append(_finding("q1", new, cell, f"Q1 {q_new:.9g} < baseline {q_base:.9g} (tolerance {t.q1:g})"))
        for label, (after, before) in resistance_changes(new, base).items():
            if after < before * (1 - t.resistance):
                found.append(
                    _finding(
                        "resistance",
                        new,
                        cell,
                        f"grasp {label}: minimum measured resistance "
                        f"{after:.6g} < baseline {before:.6g} by more than {100 * t.resistance:g} %",
                    )
                )
        newly = sorted(invalid_grasps(new) - invalid_grasps(base))
        if newly:
            found.append(
                _finding("gates", new, cell, f"simulated grasps now failing the validity gates: {', '.join(newly)}")
            )
        s_new, s_base = _time(new, t.time_key), _time(base, t.time_key)
        if s_new is not None and s_base is not None:
            ratio = max(s_new, t.min_time) / max(s_base, t.min_time)
            if ratio > t.time_ratio:
                found.append(
                    _finding(
                        "time",
                        new,
                        cell,
                        f"{t.time_key} time {s_new:.3g} s vs baseline {s_base:.3g} s "
                        f"(x{ratio:.2f} > x{t.time_ratio:g})",
                    )
                )
        return found

    def _optimality(self) -> list[Finding]:
        optimum: dict[tuple[Any, ...], float] = {}
        for record in self.run.records.values():
            if record.method in EXHAUSTIVE_METHODS and (q1 := _q1(record)) is not None:
                optimum.setdefault(_problem(record), q1)
        found = []
        for cell, record in self.run.records.items():
            value = _q1(record)
            reference = optimum.get(_problem(record))
            if reference is None or value is None:
                continue
            symmetry = record.variant.get("symmetry", False)
            if record.method in OPTIMAL_METHODS and not symmetry:
                if abs(value - reference) > self.tolerances.optimality:
                    found.append(
                        _finding(
                            "optimality",
                            record,
                            cell,
                            f"Q1 {value:.12g} differs from the exhaustive optimum {reference:.12g}",
                        )
                    )
            elif record.method == "wastar" and not symmetry and (q_ows := _q_ows(record)) is not None:
                eps = record.variant["eps"]
                guarantee = q_ows - (1 + eps) * (q_ows - reference)
                if value < guarantee - self.tolerances.optimality:
                    found.append(
                        _finding(
                            "bound", record, cell, f"Q1 {value:.9g} below the eps={eps:g} guarantee {guarantee:.9g}"
                        )
                    )
        return found

    def table(self) -> str:
        """Per object and method label: cells, Q1 change, time ratio, gate failures, resistance change."""
        t = self.tolerances
        rows: dict[tuple[str, str], list[tuple[CellRecord | None, CellRecord]]] = {}
        for cell, base in self.baseline.records.items():
            new = self.run.records.get(cell)
            rows.setdefault(_row(new or base), []).append((new, base))
        flagged = {(f.object, f.label) for f in self.failures()}
        width = max([len(label) for _, label in rows] + [6])
        header = (
            f"{'object':<12} {'method':<{width}} {'cells':>7} {'dQ1 min':>11} {'time x':>7} "
            f"{'invalid':>7} {'resist':>8}  verdict"
        )
        lines = [header]
        for key in sorted(rows):
            pairs = rows[key]
            matched = [(n, b) for n, b in pairs if n is not None]
            deltas = [qn - qb for n, b in matched if (qn := _q1(n)) is not None and (qb := _q1(b)) is not None]
            ratios = [
                max(tn, t.min_time) / max(tb, t.min_time)
                for n, b in matched
                if (tn := _time(n, t.time_key)) is not None and (tb := _time(b, t.time_key)) is not None
            ]
            gates = (sum(len(invalid_grasps(n)) for n, _ in matched), sum(len(invalid_grasps(b)) for _, b in pairs))
            resist = [
                after / before - 1
                for n, b in matched
                for after, before in resistance_changes(n, b).values()
                if before > 0
            ]
            lines.append(
                f"{key[0]:<12} {key[1]:<{width}} {f'{len(matched)}/{len(pairs)}':>7} "
                f"{f'{min(deltas):+.2e}' if deltas else '-':>11} {f'{max(ratios):.2f}' if ratios else '-':>7} "
                f"{f'{gates[0]}/{gates[1]}':>7} {f'{100 * min(resist):+.1f}%' if resist else '-':>8}  "
                f"{'REGRESSED' if key in flagged else 'ok'}"
            )
        return "\n".join(lines)

    def report(self) -> tuple[str, int]:
        """The printed report and the exit status (0: no regression, 1: regressions)."""
        failures = self.failures()
        lines = [f"RUN {self.run.directory} vs BASELINE {self.baseline.directory}", self.table()]
        hashes = [suite_hash(d.manifest) for d in (self.run, self.baseline)]
        if hashes[0] != hashes[1]:
            lines.append(f"note: suite hashes differ (RUN {hashes[0]}, BASELINE {hashes[1]}); cells matched by id")
        extra = len(set(self.run.records) - set(self.baseline.records))
        if extra:
            lines.append(f"note: {extra} cells of RUN are not in BASELINE (not compared)")
        for name, data in (("RUN", self.run), ("BASELINE", self.baseline)):
            lines.extend(f"note: {name}: {problem}" for problem in data.problems)
            lines.extend(f"note: {name}: {text}" for text in _warmup_notes(data.manifest))
        missing = [f for f in self.findings() if f.kind == "missing"]
        if missing and self.tolerances.allow_missing:
            lines.append(f"note: {len(missing)} cells of BASELINE missing from RUN (allowed)")
        if failures:
            lines.append(f"regressions ({len(failures)}):")
            lines.extend("  " + f.line() for f in failures)
        else:
            lines.append("no regressions")
        return "\n".join(lines), 1 if failures else 0


def compare_dirs(run: str | Path, baseline: str | Path, tolerances: Tolerances | None = None) -> tuple[str, int]:
    """Compare two suite output folders: (report text, exit status 0 or 1).

    Raises:
        OgcpError: For unreadable folders or invalid tolerances (exit status 2 in the CLI).
    """
    tolerances = tolerances or Tolerances()
    tolerances.validate()
    return Comparison(load_run(run), load_run(baseline), tolerances).report()


def _warmup_notes(manifest: dict[str, Any] | None) -> list[str]:
    """What a run's kernel warm-up says about its times: nothing when its processes ran warm."""
    if manifest is None:
        return []
    seconds = kernel_warmups(manifest)
    if seconds is None:
        note = "no kernel warm-up recorded (a run made before it): the first cell of each process may include"
        return [f"{note} numba's compilation in its time"]
    slowest = max(seconds, default=0.0)
    if slowest > COMPILE_SECONDS:
        return [f"compiled the kernels (warm-up up to {slowest:.1f} s per process, kept out of the cell times)"]
    return []


def _problem(record: CellRecord) -> tuple[Any, ...]:
    """The optimisation problem a cell solves: contact set, m and constraints."""
    return record.problem + tuple(record.variant.get(k) for k in CONSTRAINT_KEYS)


def _row(record: CellRecord) -> tuple[str, str]:
    return record.object, str(record.label)


def _finding(kind: str, record: CellRecord, cell: str, detail: str) -> Finding:
    where = f"[n={record.contacts} seed={record.contact_seed} m={record.m} id={cell}]"
    return Finding(kind, *_row(record), where, detail)
