"""Contact models against protocols: the quick suite's grasps, hard and soft, under both simulated tests.

Run: ``python -m ogcp.benchmarks.studies.contact_models --out results/contact_models [--jobs 2]``.
It plans the quick suite's ``baselines`` group (box and donut, 200 contacts, m = 3: A*, WA* at
eps 0.4 and 1.0, HFTS; ES is left out, its grasp is A*'s) with hard fingers and with soft ones
(torsional friction 0.02 m), simulates every returned grasp with ogcp's resistance protocol
and with ``--protocol dexgraspbench``, and prints one row per contact model and protocol:
grasps judged, valid (ogcp's gates), successes, and the ROC-AUC of the planned Q1 against
success, exact (Mann-Whitney) and DexGraspBench's binned way. Success is, for the resistance
protocol, a valid grasp whose weakest measured direction holds the holding load (1 N); for
DexGraspBench's, their verdict (never true when one of ogcp's gates failed). Each run is an
ordinary suite folder (``<out>/<protocol>``), resumable, and ``table.md`` is written beside them.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.benchmarks.plots.data import CellData, RunData, load_run
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import RESULTS
from ogcp.sim_eval.protocols.metrics import binned_roc, roc_auc

PROTOCOLS = ("resistance", "dexgraspbench")
SUITE = """schema_version = 1
name = "contact-models-{protocol}"
objects = ["box", "donut"]
contacts = 200
contact_seeds = [0]
m = [3]
contact_model = ["hard", "soft"]
torsional_friction = 0.02

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "wastar"
eps = [0.4, 1.0]
label = "WA* eps={{eps:g}}"

[[methods]]
method = "hfts"
runs = 20
iterations = 40
label = "HFTS"

[simulation]
enabled = true
protocol = "{protocol}"
"""


def weakest_resistances(run: RunData, model: str) -> list[float]:
    """The weakest measured resistance [N] of every valid grasp of the run's cells of one contact model."""
    out = []
    for cell in run.cells:
        if cell.params.get("contact_model", "hard") != model or cell.simulation is None:
            continue
        out += [g.measured_min for g in cell.simulation.grasps if g.valid and g.measured_min is not None]
    return out


def resistance_outcomes(cell: CellData) -> list[tuple[float, bool, bool]]:
    """``(Q1, valid, holds)`` per simulated grasp: holds = valid and its weakest direction held the holding load."""
    sim = cell.simulation
    if sim is None:
        return []
    load = sim.set_metrics.get("holding_load")
    out = []
    for g in sim.grasps:
        if g.error is not None:
            continue
        holds = bool(g.valid) and g.measured_min is not None and load is not None and g.measured_min >= load
        out.append((float(g.q1 or 0.0), bool(g.valid), holds))
    return out


def dexgraspbench_outcomes(cell: CellData) -> list[tuple[float, bool, bool]]:
    """``(Q1, valid, success)`` per grasp DexGraspBench's test judged (see :func:`protocol_outcomes`)."""
    out = []
    for g in cell.simulation.grasps if cell.simulation is not None else ():
        test = g.hold_tests.get("dexgraspbench") if isinstance(g.hold_tests, dict) else None
        if isinstance(test, dict) and "success" in test:
            out.append((float(g.q1 or 0.0), bool(g.valid), test["success"] is True))
    return out


def rows(run: RunData, protocol: str) -> list[dict[str, Any]]:
    """One row per contact model: counts, success rate and both AUCs."""
    by_model: dict[str, list[tuple[float, bool, bool]]] = {}
    for cell in run.cells:
        model = cell.params.get("contact_model", "hard")
        outcomes = dexgraspbench_outcomes(cell) if protocol == "dexgraspbench" else resistance_outcomes(cell)
        by_model.setdefault(model, []).extend(outcomes)
    table = []
    for model, outcomes in by_model.items():
        q1 = np.array([q for q, _, _ in outcomes])
        success = np.array([s for _, _, s in outcomes], dtype=bool)
        table.append(
            {
                "model": model,
                "protocol": protocol,
                "grasps": len(outcomes),
                "valid": sum(v for _, v, _ in outcomes),
                "success": int(success.sum()),
                "rate": float(success.mean()) if len(success) else float("nan"),
                "auc": roc_auc(q1, success),
                "auc_theirs": binned_roc(-q1, success).auc,
                "median_weakest": float(np.median(weakest)) if (weakest := weakest_resistances(run, model)) else None,
            }
        )
    return table


def _number(value: float | None, digits: int = 3) -> str:
    """A table entry: ``-`` for what is undefined (an AUC with one class, no measured resistance)."""
    return "-" if value is None or not np.isfinite(value) else f"{value:.{digits}f}"


def markdown(table: list[dict[str, Any]]) -> str:
    """The README's table."""
    lines = [
        (
            "| contact model | protocol | grasps | valid | successes | success rate | AUC(Q1) exact | AUC(Q1) theirs "
            "| median weakest resistance [N] |"
        ),
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(table, key=lambda r: (r["model"], r["protocol"])):
        lines.append(
            f"| {r['model']} | {r['protocol']} | {r['grasps']} | {r['valid']} | {r['success']} | "
            f"{100 * r['rate']:.0f} % | {_number(r['auc'])} | {_number(r['auc_theirs'])} | "
            f"{_number(r['median_weakest'], 2)} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="folder of the two suite runs and table.md")
    parser.add_argument("--jobs", type=int, default=1, help="cells run in parallel")
    args = parser.parse_args(argv)
    table = []
    for protocol in PROTOCOLS:
        folder = args.out / protocol
        suite = parse_suite(SUITE.format(protocol=protocol))
        SuiteRunner(suite, folder, jobs=args.jobs, resume=(folder / RESULTS).exists(), progress=True).run()
        table += rows(load_run(folder), protocol)
    text = markdown(table)
    (args.out / "table.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
