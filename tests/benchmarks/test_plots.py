"""``ogcp plot``: every paper figure from a small run, Type 42 fonts, tables, partial runs, errors."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import subprocess
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ogcp.benchmarks import cli, plots
from ogcp.benchmarks.plots.data import SkipFigure, load_run
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.planner.infra import OgcpError

matplotlib.use("Agg")
ROOT = Path(__file__).resolve().parents[2]
FIGURE_NAMES = (
    "fig4_q1_histograms",
    "fig5_search_tree",
    "fig6_states_per_level",
    "fig7_iterations_f",
    "fig8_wastar_tradeoff",
    "sim_q1_vs_resistance",
    "sim_fidelity",
    "sim_survival",
)
TINY_SUITE = """
schema_version = 1
name = "tiny-plot"
objects = ["box"]
contacts = 12
m = [3]

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "astar"
record_tree = true
label = "A* (tree)"

[[methods]]
method = "astar"
symmetry = true
label = "A* symmetry"

[[methods]]
method = "astar"
heuristic = "ru"
label = "A* Γh=ru"

[[methods]]
method = "wastar"
eps = [0.5, 1.0]
label = "WA* eps={eps:g}"

[[methods]]
method = "dijkstra"
label = "Dijkstra"

[[methods]]
method = "es"
label = "ES"

[[methods]]
method = "hfts"
runs = 3
iterations = 5
label = "HFTS"
"""


# ------------------------------------------------------------ synthetic records with the real shapes
def _stats(created: list[int], visited: list[int], b: float | None, trace_len: int, seconds: float) -> dict:
    f = np.maximum.accumulate(np.linspace(0.0, 0.3, trace_len) + 0.01 * np.sin(np.arange(trace_len)))
    return {
        "created": sum(created),
        "visited": sum(visited),
        "created_per_level": created,
        "visited_per_level": visited,
        "q1_evaluations": 10,
        "q1_cache_hits": 0,
        "bound_evaluations": 0,
        "bound_rejections": 0,
        "hull_calls": 0,
        "pruned": 0,
        "symmetric_removed": 0,
        "effective_branching_factor": b,
        "solution_depth": len(created) - 1,
        "trace": [[i, float(v)] for i, v in enumerate(f)],
        "wall_seconds": seconds,
        "cpu_seconds": seconds,
    }


def _plan(method: str, q1: float, **extra) -> dict:
    plan = {
        "schema": "ogcp.plan/1",
        "method": method,
        "grasp": [1, 5, 9],
        "q1": q1,
        "q_ows": 0.5,
        "bound": q1,
        "force_closure": q1 > 0,
        "contacts": {"positions": [[0, 0, 0]] * 3, "normals": [[1, 0, 0]] * 3},
        "contact_set": {},
        "stats": {},
        "config": {},
        "tolerances": {},
        "provenance": {},
    }
    plan.update(extra)
    return plan


def _search_plan(
    method: str,
    q1: float,
    eps: float = 0.0,
    symmetry: bool = False,
    trace_len: int = 30,
    seconds: float = 2.0,
    tree: dict | None = None,
) -> dict:
    created = [1, 8, 40, 60, 20, 4] if not symmetry else [1, 4, 12, 20, 8, 3]
    visited = [1, 3, 9, 6, 2, 1] if not symmetry else [1, 2, 4, 3, 2, 1]
    plan = _plan(
        method,
        q1,
        eps=eps,
        eps_bound=min(0.5, q1 * (1 + eps)),
        stats=_stats(created, visited, 1.9 if not symmetry else 1.5, trace_len, seconds),
    )
    plan["bound"] = min(0.5, q1 * (1 + eps / 2))
    if tree is not None:
        plan["tree"] = tree
    return plan


def _es_plan(q1: float, seconds: float = 900.0) -> dict:
    edges = np.linspace(0, 0.5, 11)
    counts = [4000, 900, 200, 40, 8, 2, 1, 0, 0, 0]
    hist = {"bin_edges": edges.tolist(), "counts": counts, "zero": 150000, "force_closure_fraction": 0.0333}
    return _plan(
        "es", q1, eps=0.0, histogram=hist, stats={"grasps": 155151, "cpu_seconds": seconds, "wall_seconds": seconds / 2}
    )


def _hfts_plan(values: list[float]) -> dict:
    runs = [
        {"seed": i, "grasp": [0, 1, 2], "q1": v, "evaluations": 5, "cpu_seconds": 0.1} for i, v in enumerate(values)
    ]
    return _plan(
        "hfts",
        max(values),
        runs=runs,
        stats={"runs": len(values), "cpu_seconds": 0.1 * len(values), "wall_seconds": 1.0},
    )


def _tree() -> dict:
    parent, level, visited = [-1], [0], [True]
    for child in range(4):  # level 1: four states, two visited
        parent.append(0), level.append(1), visited.append(child < 2)
    for p in (1, 2):  # level 2: three children each under the visited states
        for _ in range(3):
            parent.append(p), level.append(2), visited.append(len(parent) % 2 == 0)
    return {"parent": parent, "level": level, "visited": visited, "f": [0.1] * len(parent), "path": [0, 1, 5]}


def _simulation(q1s: list[float], rng: np.random.Generator, first: int = 0) -> dict:
    grasps = []
    for i, q in enumerate(q1s):
        predicted = rng.uniform(1, 30, 13)
        measured = predicted * rng.uniform(0.8, 1.2, 13)
        censored = [bool(j == 0 and i == 0) for j in range(13)]
        fidelity = [None if c else float(abs(m / p - 1)) for m, p, c in zip(measured, predicted, censored)]
        k = first + i
        grasps.append(
            {
                "grasp": [k, k + 1, k + 2],
                "label": "best" if i == 0 else f"run-{i}",
                "q1": q,
                "valid": i != 3,
                "error": None,
                "gates": {"valid": i != 3},
                "predicted": predicted.tolist(),
                "measured": measured.tolist(),
                "censored": censored,
                "fidelity": fidelity,
                "predicted_min": float(predicted.min()),
                "measured_min": float(measured.min()),
                "median_fidelity": 0.1,
            }
        )
    return {
        "schema": "ogcp.sim/1",
        "grasps": grasps,
        "median_fidelity": 0.1,
        "set_metrics": {
            "n_valid": len(q1s) - 1,
            "holding_load": 5.0,
            "q1_vs_measured": {"spearman": 0.5, "kendall": 0.4},
            "auc_q1_holds": 0.7,
            "median_fidelity": 0.1,
        },
    }


def _record(
    index: int,
    obj: str,
    method: str,
    plan: dict | None,
    variant: dict | None = None,
    label: str = "",
    simulation: dict | None = None,
    status: str = "ok",
    contacts: int = 100,
) -> dict:
    params = {
        "object": obj,
        "contacts": contacts,
        "contact_seed": 0,
        "m": 3,
        "mu": 0.5,
        "cone_edges": 8,
        "diagonal": 0.2,
        "method": method,
        "variant": variant or {},
        "label": label or method,
    }
    error = None if status == "ok" else {"type": "OgcpError", "message": "boom", "traceback": "..."}
    return {
        "schema": "ogcp.cell/1",
        "id": f"{index:016x}",
        "params": params,
        "groups": [],
        "status": status,
        "error": error,
        "plan": plan if status == "ok" else None,
        "simulation": simulation,
        "simulation_seconds": None,
        "wall_seconds": 1.0,
        "cpu_seconds": 1.0,
        "finished_at": "2025-01-01T00:00:00",
    }


SEARCH = {
    "branching": 2,
    "successor": "fc",
    "heuristic": "fc",
    "heuristic_branching": 2,
    "symmetry": False,
    "ordered": False,
    "seed": 0,
    "record_tree": False,
    "max_spread": None,
    "hand": None,
}


def synthetic_records() -> list[dict]:
    """Two objects with every method, symmetry and successor variants, a tree and simulations."""
    rng = np.random.default_rng(0)
    records: list[dict] = []

    def add(*args, **kwargs) -> None:
        records.append(_record(len(records), *args, **kwargs))

    for obj, opt in (("box", 0.35), ("donut", 0.2)):
        add(
            obj,
            "es",
            _es_plan(opt),
            {"chunk": 200000, "bins": 10, "hand": None, "max_spread": None},
            "ES",
            simulation=_simulation([opt, 0.3, 0.2, 0.1], rng),
        )
        add(
            obj,
            "astar",
            _search_plan("astar", opt, tree=_tree() if obj == "box" else None),
            SEARCH,
            "A*",
            simulation=_simulation([opt], rng),
        )
        add(obj, "astar", _search_plan("astar", opt * 0.9, symmetry=True), {**SEARCH, "symmetry": True}, "A* sym")
        for seed in range(3):
            add(
                obj,
                "astar",
                _search_plan("astar", opt, trace_len=60 + seed),
                {**SEARCH, "heuristic": "ru", "seed": seed},
                "A* Γh=ru",
            )
        add(obj, "dijkstra", _search_plan("dijkstra", opt, trace_len=90), {**SEARCH, "heuristic": "none"}, "Dijkstra")
        for eps in (0.4, 1.0):
            add(
                obj,
                "wastar",
                _search_plan("wastar", opt * (1 - eps / 5), eps=eps, seconds=1.0 / (1 + eps)),
                {**SEARCH, "eps": eps},
                f"WA* eps={eps:g}",
            )
        add(
            obj,
            "hfts",
            _hfts_plan([0.05, 0.1, opt * 0.8]),
            {"runs": 3, "iterations": 40, "seed": 0, "hand": None},
            "HFTS",
            simulation=_simulation([opt * 0.8, 0.1, 0.05, 0.02], rng, first=10),
        )
    add("box", "astar", None, SEARCH, "A*", status="error", contacts=50)  # errored cell
    return records


def write_run(directory: Path, records: list[dict], manifest: bool = True) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    with open(directory / "results.jsonl", "w") as handle:
        handle.writelines(json.dumps(record) + "\n" for record in records)
    if manifest:
        # The suite lists one cell more than the folder holds: a sphere A* that never ran.
        content = 'schema_version = 1\nobjects = ["sphere"]\n[[methods]]\nmethod = "astar"\n'
        (directory / "manifest.json").write_text(json.dumps({"suite": {"name": "t", "content": content, "cells": 1}}))
    return directory


@pytest.fixture(scope="module")
def run_data(tmp_path_factory) -> plots.RunData:
    return load_run(write_run(tmp_path_factory.mktemp("run"), synthetic_records()))


def _labels(ax) -> list[str]:
    return ax.get_legend_handles_labels()[1]


def _titles(figure: Figure) -> list[str]:
    return [ax.get_title() for ax in figure.axes]


def _figure_legend(figure: Figure) -> list[str]:
    return [text.get_text() for legend in figure.legends for text in legend.get_texts()]


# ------------------------------------------------------------ figures
def test_fig4_histogram_per_problem_with_every_method_marked(run_data):
    figure = plots.fig4_q1_histograms(run_data)
    assert isinstance(figure, Figure) and len(figure.axes) == 2
    assert figure.get_figwidth() == pytest.approx(7.16)
    box, donut = figure.axes
    assert box.get_title() == "box\nFC 3.33 %, Q1 = 0: 150,000" and donut.get_title().startswith("donut")
    assert _labels(box) == [
        "A* (optimum)",
        "HFTS runs: min-max, mean",
        "WA* eps=0.4: Q1 (o) to bound (|)",
        "WA* eps=1: Q1 (o) to bound (|)",
        "ES: grasps per Q1 bin",
    ]
    assert len(box.patches) == 10  # one bar per histogram bin
    optimum = next(line for line in box.lines if line.get_label() == "A* (optimum)")
    assert optimum.get_xdata()[0] == pytest.approx(0.35)
    hfts = next(line for line in box.lines if line.get_label().startswith("HFTS"))
    assert list(hfts.get_xdata()) == pytest.approx([0.05, 0.28])  # min-max of the runs
    assert box.get_yscale() == "log"  # counts span 4000 : 1
    assert _figure_legend(figure) == _labels(box)
    # The axis ends just past the highest bar or marker, not at Q_OWS (0.5), the histogram's range.
    highest = max(max(np.ravel(line.get_xdata())) for line in box.lines)
    highest = max(highest, max(bar.get_x() + bar.get_width() for bar in box.patches if bar.get_height() > 0))
    assert 1.08 * highest < 0.5 and box.get_xlim()[1] == pytest.approx(1.08 * highest)


def test_fig5_circular_tree_with_visited_states_and_the_solution_path(run_data):
    figure = plots.fig5_search_tree(run_data)
    (ax,) = figure.axes
    assert ax.name == "polar" and ax.get_title() == "box: A*, created 11, visited 6"
    assert sorted(_labels(ax)) == ["created, not visited (5)", "solution path", "visited (6)"]
    assert len(ax.patches) == 6  # one wedge per visited state
    (path,) = [line for line in ax.lines if line.get_label() == "solution path"]
    assert list(path.get_ydata()) == [1.0, 2.0, 3.0]  # radius = level + 1
    assert any(isinstance(c, LineCollection) and len(c.get_segments()) == 5 for c in ax.collections)


def test_tree_layout_nests_children_in_their_parent_sector():
    layout = plots.layout_tree(_tree())
    assert layout.width[0] == pytest.approx(2 * np.pi)
    for child, parent in enumerate(_tree()["parent"]):
        if parent >= 0:
            low, high = layout.angle[parent] - layout.width[parent] / 2, layout.angle[parent] + layout.width[parent] / 2
            assert low - 1e-12 <= layout.angle[child] <= high + 1e-12
    level_1 = [i for i, level in enumerate(_tree()["level"]) if level == 1]
    assert list(np.argsort(layout.angle[level_1])) == [0, 1, 2, 3]  # creation order within the parent
    with pytest.raises(ValueError, match="out of range"):
        plots.layout_tree({"parent": [-1, 7], "level": [0, 1], "visited": [True, False]})
    with pytest.raises(ValueError, match="cycle|not connected"):
        plots.layout_tree({"parent": [-1, 2, 1], "level": [0, 1, 1], "visited": [True, False, False]})


def test_fig6_created_and_visited_with_and_without_symmetry_removal(run_data):
    figure = plots.fig6_states_per_level(run_data)
    assert _titles(figure) == ["box: A*", "donut: A*"]
    labels = _labels(figure.axes[0])
    assert labels == [
        "created, with symmetry removal (b*=1.50)",
        "visited, with symmetry removal",
        "created, without symmetry removal (b*=1.90)",
        "visited, without symmetry removal",
    ]
    assert list(figure.axes[0].lines[3].get_ydata()) == [1, 3, 9, 6, 2, 1]
    assert figure.axes[0].get_yscale() == "log" and figure.axes[0].get_xlabel() == "search level"


def test_fig7_one_series_per_successor_heuristic_variant(run_data):
    figure = plots.fig7_iterations_f(run_data)
    assert _titles(figure) == ["box", "donut"]
    assert _labels(figure.axes[0]) == ["A* (b*=1.90)", "A* Γh=ru (b*=1.90, 3 runs)", "Dijkstra (b*=1.90)"]
    ax = figure.axes[0]
    assert len(ax.lines) == 3 and ax.lines[2].get_linestyle() == "--"
    assert ax.lines[0].get_color() == plots.method_colour("astar")  # a method's first variant: its colour
    faint = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(faint) == 1 and len(faint[0].get_segments()) == 2  # the other two seeds of Γh=ru
    assert len(ax.lines[1].get_xdata()) == 61  # the seed with the median number of iterations


def test_fig8_wastar_tradeoff_against_eps(run_data):
    figure = plots.fig8_wastar_tradeoff(run_data)
    time_ax, _, quality_ax = figure.axes
    assert [ax.get_ylabel() for ax in figure.axes] == ["search time [s]", "visited states", "$Q_1$ / optimum"]
    box = next(line for line in quality_ax.lines if line.get_label() == "box")
    assert list(box.get_xdata()) == [0.0, 0.4, 1.0]
    assert list(box.get_ydata()) == pytest.approx([1.0, 0.92, 0.8])
    assert [line.get_label() for line in time_ax.lines] == ["box", "donut"]
    assert list(time_ax.lines[0].get_ydata()) == pytest.approx([2.0, 1 / 1.4, 0.5])
    assert "(1+eps) guarantee" in _figure_legend(figure)


def test_simulation_figures(run_data):
    scatter = plots.sim_q1_vs_resistance(run_data)
    assert len(scatter.axes) == 2
    assert "Spearman" in scatter.axes[0].get_title() and "Kendall" in scatter.axes[0].get_title()
    # ES 3 + HFTS 3 valid grasps: A*'s grasp is ES's best (counted once), the invalid ones are left out
    assert "(n=6)" in scatter.axes[0].get_title()
    assert {"ES", "A*", "HFTS", "held to the end (lower bound)"} <= set(_figure_legend(scatter))

    fidelity = plots.sim_fidelity(run_data)
    ax = fidelity.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log" and "y = x" in _labels(ax)
    assert ax.get_title().startswith("box\nmedian |meas/pred - 1|")

    curves = plots.sim_survival(run_data)
    per_method, per_object = curves.axes
    assert _labels(per_method) == ["ES (n=6)", "A* (n=2)", "HFTS (n=6)", "holding load 5 N"]
    assert _labels(per_object) == ["box (n=7)", "donut (n=7)", "holding load 5 N"]


def test_survival_is_the_fraction_holding_at_least_each_load():
    loads, fraction = plots.survival([1.0, 2.0, 3.0])
    assert list(loads) == [0.0, 1.0, 2.0, 3.0, pytest.approx(3.15)]
    assert list(fraction) == pytest.approx([1.0, 1.0, 2 / 3, 1 / 3, 0.0])


def test_method_colours_are_one_fixed_mapping():
    assert plots.method_colour("astar") == plots.method_colour("astar")
    colours = {plots.method_colour(m) for m in ("astar", "wastar", "dijkstra", "es", "es-pruned", "hfts")}
    assert len(colours) == 6
    light, dark = plots.method_colour("wastar", 0.2), plots.method_colour("wastar", 1.4)
    assert light != dark and sum(int(light[i : i + 2], 16) for i in (1, 3, 5)) > sum(
        int(dark[i : i + 2], 16) for i in (1, 3, 5)
    )
    assert (
        len(
            {
                plots.method_colour("astar"),
                plots.method_colour("astar", constraint="SDH"),
                plots.method_colour("astar", constraint="spread<=0.1 m"),
            }
        )
        == 3
    )


# ------------------------------------------------------------ table
def test_time_table_rows_objects_columns_methods(run_data, tmp_path):
    table = plots.time_table(run_data)
    assert table.rows == ("box", "donut")
    assert table.columns == ("A*", "WA* (eps=0.4)", "WA* (eps=1)", "Dijkstra", "ES", "HFTS")
    assert table.unit == "min"  # ES took 900 s
    assert table.values[0][4] == pytest.approx(15.0) and table.values[0][0] == pytest.approx(2.0 / 60)
    assert plots.time_table(run_data, unit="s").values[0][4] == pytest.approx(900.0)
    md, csv_path, tex = table.write(tmp_path, "t")
    rows = list(csv.reader(io.StringIO(csv_path.read_text())))
    assert rows[0] == [
        "object",
        "A* [min]",
        "WA* (eps=0.4) [min]",
        "WA* (eps=1) [min]",
        "Dijkstra [min]",
        "ES [min]",
        "HFTS [min]",
    ]
    assert [r[0] for r in rows[1:]] == ["box", "donut"] and float(rows[1][5]) == pytest.approx(15.0)
    lines = md.read_text().splitlines()
    assert len(lines) == 4 and lines[0].count("|") == 8 and lines[2].startswith("| box | 0.0333 |")
    latex = tex.read_text()
    for needed in (
        r"\begin{tabular}{lrrrrrr}",
        r"\toprule",
        r"\midrule",
        r"\bottomrule",
        r"WA* ($\varepsilon{=}0.4$)",
        r"box & 0.0333 & ",
    ):
        assert needed in latex
    with pytest.raises(OgcpError, match="unknown time unit"):
        plots.time_table(run_data, unit="h")


# ------------------------------------------------------------ whole runs
def test_plot_run_writes_type42_pdfs_pngs_and_tables(tmp_path):
    run = write_run(tmp_path / "run", synthetic_records())
    report = plots.plot_run(run, tmp_path / "out")
    names = [p.name for p in report.written]
    assert names == [f"{n}.{fmt}" for n in FIGURE_NAMES for fmt in ("pdf", "png")] + [
        "fig9_times.md",
        "fig9_times.csv",
        "fig9_times.tex",
    ]
    for path in report.written:
        if path.suffix == ".pdf":
            data = path.read_bytes()
            assert data.startswith(b"%PDF") and b"/FontFile2" in data and b"/Type3" not in data, path.name
        if path.suffix == ".png":
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    width = int.from_bytes((tmp_path / "out" / "fig8_wastar_tradeoff.png").read_bytes()[16:20], "big")
    assert width == round(7.16 * 200)


def test_partial_run_plots_what_it_has(tmp_path):
    records = [r for r in synthetic_records() if not (r["params"]["method"] == "es" and r["params"]["object"] == "box")]
    for record in records:  # no tree recorded anywhere
        if record["plan"]:
            record["plan"].pop("tree", None)
    run = write_run(tmp_path / "run", records)
    with open(run / "results.jsonl", "ab") as handle:
        handle.write(b'{"id": "torn')  # a crash mid-write
    report = plots.plot_run(run, tmp_path / "out", formats=["png"])
    notes = "\n".join(report.notes)
    assert "1 cell(s) with status error skipped: box A* (OgcpError: boom)" in notes
    assert "1 cell(s) of the suite not run yet (skipped): sphere |C|=100 m=3 A*" in notes
    assert "last line is incomplete" in notes
    assert "fig5_search_tree: skipped, no plan records a search tree" in notes
    written = {p.stem for p in report.written}
    assert set(FIGURE_NAMES) - {"fig5_search_tree"} <= written and "fig9_times" in written
    figure = plots.fig4_q1_histograms(load_run(run))
    assert _titles(figure)[0].startswith("donut")  # box lost its ES cell: one panel left


def test_figures_without_their_cells_are_skipped_with_a_note(tmp_path):
    records = [r for r in synthetic_records() if r["params"]["method"] == "hfts"]
    for record in records:
        record["simulation"] = None
    report = plots.plot_run(write_run(tmp_path / "run", records, manifest=False), tmp_path / "out")
    assert [p.name for p in report.written] == ["fig9_times.md", "fig9_times.csv", "fig9_times.tex"]
    skipped = [n for n in report.notes if ": skipped, " in n]
    assert [n.split(":")[0] for n in skipped] == list(FIGURE_NAMES)
    assert all("\n" not in n for n in report.notes)
    with pytest.raises(SkipFigure, match="needs an ES cell"):
        plots.fig4_q1_histograms(load_run(tmp_path / "run"))


def test_a_malformed_record_costs_only_its_figure(tmp_path):
    records = synthetic_records()
    for record in records:
        if record["plan"] and record["params"]["variant"].get("symmetry"):
            record["plan"]["stats"]["created_per_level"] = ["many"]
    report = plots.plot_run(write_run(tmp_path / "run", records), tmp_path / "out", formats=["png"])
    (note,) = [n for n in report.notes if n.startswith("fig6")]
    assert note.startswith("fig6_states_per_level: skipped, could not draw it from these records (ValueError")
    assert len(report.written) == len(FIGURE_NAMES) - 1 + 3


def test_tiny_real_suite_plots(tmp_path):
    """A real run: every search figure and the table from the runner's records."""
    SuiteRunner(parse_suite(TINY_SUITE), tmp_path / "run", log=lambda _: None).run()
    report = plots.plot_run(tmp_path / "run", tmp_path / "out", formats=["pdf"])
    written = {p.name for p in report.written}
    assert {
        "fig4_q1_histograms.pdf",
        "fig5_search_tree.pdf",
        "fig6_states_per_level.pdf",
        "fig7_iterations_f.pdf",
        "fig8_wastar_tradeoff.pdf",
        "fig9_times.md",
    } <= written
    run = load_run(tmp_path / "run")
    assert len(plots.fig4_q1_histograms(run).axes) == 1
    assert plots.time_table(run).columns == ("A*", "WA* (eps=0.5)", "WA* (eps=1)", "Dijkstra", "ES", "HFTS")
    assert len(_labels(plots.fig7_iterations_f(run).axes[0])) == 3  # A* (the tree cell joins it), A* Γh=ru, Dijkstra
    tree = next(c.plan["tree"] for c in run.cells if "tree" in c.plan)
    (ax,) = plots.fig5_search_tree(run).axes
    assert ax.get_title() == f"box: A*, created {len(tree['parent'])}, visited {sum(tree['visited'])}"


# ------------------------------------------------------------ command line
def _ogcp(argv: list[str], monkeypatch: pytest.MonkeyPatch) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(argv)
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("content", [None, "", "not json\n"])
def test_plot_without_results_exits_2_with_one_line(tmp_path, monkeypatch, content):
    folder = tmp_path / "run"
    folder.mkdir()
    if content is not None:
        (folder / "results.jsonl").write_text(content)
    status, out, err = _ogcp(["plot", str(folder), "--out", str(tmp_path / "out")], monkeypatch)
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("ogcp: error: ") and str(folder) in err
    status, _, err = _ogcp(["plot", str(tmp_path / "absent")], monkeypatch)
    assert status == 2 and "no such folder" in err and err.count("\n") == 1


def test_plot_command_lists_the_files_it_wrote(tmp_path, monkeypatch):
    run = write_run(tmp_path / "run", synthetic_records())
    argv = ["plot", str(run), "--only", "fig9_times", "fig6_states_per_level", "--format", "pdf"]
    status, out, err = _ogcp(argv, monkeypatch)
    assert status == 0
    assert out.splitlines() == [
        str(run / "figures" / n)
        for n in ("fig6_states_per_level.pdf", "fig9_times.md", "fig9_times.csv", "fig9_times.tex")
    ]
    assert "ogcp: note: 1 cell(s) with status error skipped" in err
    status, _, err = _ogcp(["plot", str(run), "--only", "fig10"], monkeypatch)
    assert status == 2 and "unknown figure 'fig10'" in err
    status, _, err = _ogcp(["plot", str(run), "--format", "eps"], monkeypatch)
    assert status == 2 and err == "ogcp: error: unknown figure format 'eps'; valid choices: pdf, png, svg\n"


def test_core_packages_never_import_matplotlib():
    code = (
        "import sys, planner, sim_eval, ogcp.benchmarks.plots, ogcp.benchmarks.cli.app as cli; cli.build_parser();"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, timeout=120)
