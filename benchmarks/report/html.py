"""Self-contained HTML pages: the report of a suite run and the view of one result.

Everything a page needs is inside it (styles, the viewer script, the scene data as JSON, the
figures as base64 ``data:`` URIs), so it opens offline and makes no network request. The run's
records are read through :class:`ogcp.benchmarks.suite.record.CellRecord`; the scenes are built by
:mod:`ogcp.benchmarks.report.scene`.
"""

from __future__ import annotations

import base64
import html
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ogcp.benchmarks.report.scene import Scenes
from ogcp.benchmarks.report.viewer import VIEWER_JS
from ogcp.benchmarks.suite.record import CellRecord
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner.infra.atomic import read_json
from ogcp.planner.infra.errors import OgcpError

#: The file ``ogcp report`` writes into the run folder.
REPORT_NAME = "report.html"
#: The time table ``ogcp plot`` writes, shown as Fig. 9's table.
TIME_TABLE = "fig9_times.md"

_STYLE = """
body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 1200px; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
tr[data-grasp] { cursor: pointer; }
tr.current { background: #fff3c4; }
.valid { color: #1a9b3c; } .invalid { color: #d12a1f; }
#ogcp-viewer { display: flex; gap: 1em; align-items: flex-start; position: sticky; top: 0; background: #fff; }
#ogcp-canvas { border: 1px solid #999; cursor: grab; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
.note { color: #666; font-size: 0.9em; }
"""


@dataclass(frozen=True)
class ReportResult:
    """What :func:`write_report` or :func:`write_view` wrote.

    Attributes:
        path: The HTML file.
        grasps: How many grasps it shows in 3D.
        notes: One line per thing left out (a missing figure folder, a mesh that could not be rebuilt).
    """

    path: Path
    grasps: int
    notes: tuple[str, ...]


def _number(value: Any, digits: int = 3) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "-"
    return f"{value:.{digits}g}"


def _table(header: list[str], rows: list[list[str]], row_attributes: list[str] | None = None) -> str:
    """An HTML table of already escaped cells; ``row_attributes`` go into each ``<tr>``."""
    head = "".join(f"<th>{cell}</th>" for cell in header)
    body = []
    for index, row in enumerate(rows):
        attributes = f" {row_attributes[index]}" if row_attributes else ""
        body.append(f"<tr{attributes}>" + "".join(f"<td>{cell}</td>" for cell in row) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def markdown_table(text: str) -> str:
    """A GitHub Markdown table (as ``ogcp plot`` writes it) as an HTML table."""
    rows = [
        [html.escape(cell.strip()) for cell in line.strip().strip("|").split("|")]
        for line in text.splitlines()
        if line.strip().startswith("|")
    ]
    # The second line is the alignment row (``|:---|---:|``), not data.
    body = [row for index, row in enumerate(rows) if index != 1]
    return _table(body[0], body[1:]) if body else ""


def _summary(records: list[CellRecord]) -> str:
    """One row per cell: object, method, status, plan quality and time, simulated outcome."""
    rows = []
    for record in sorted(records, key=lambda r: (r.object, r.contacts or 0, r.m or 0, r.label or "")):
        view, sim = record.plan_view, record.simulation or {}
        grasps = [g for g in sim.get("grasps", []) if isinstance(g, dict)]
        valid = sum(1 for g in grasps if g.get("valid") is True)
        best = next((g for g in grasps if g.get("label") == "best"), grasps[0] if grasps else {})
        rows.append(
            [
                html.escape(record.object),
                html.escape(str(record.contacts)),
                html.escape(str(record.m)),
                html.escape(record.label or str(record.method)),
                html.escape(record.status),
                _number(view.q1 if view else None),
                _number(view.bound if view else None),
                _number(view.cpu_seconds if view else None),
                f"{valid}/{len(grasps)}" if grasps else "-",
                _number(best.get("measured_min")),
            ]
        )
    header = ["object", "|C|", "m", "method", "status", "Q1", "bound", "plan CPU [s]", "valid sims", "min res. [N]"]
    return _table(header, rows)


def _grasp_table(grasps: list[dict[str, Any]]) -> str:
    """The grasps of the page, one clickable row each (the viewer shows the clicked one)."""
    rows = []
    for grasp in grasps:
        if not grasp.get("simulated"):
            outcome = "not simulated"
        elif grasp.get("error"):
            outcome = '<span class="invalid">error</span>'
        else:
            outcome = (
                '<span class="valid">valid</span>' if grasp.get("valid") else '<span class="invalid">invalid</span>'
            )
        contacts = " ".join(str(i) for i in grasp.get("grasp", []))
        rows.append(
            [
                html.escape(grasp["title"]),
                contacts,
                _number(grasp.get("q1")),
                outcome,
                _number(grasp.get("measured_min")),
            ]
        )
    attributes = [f'data-grasp="{index}"' for index in range(len(grasps))]
    return _table(["grasp", "contacts", "Q1", "simulation", "min res. [N]"], rows, attributes)


def _figures(folder: Path | None) -> tuple[str, list[str]]:
    """The PNGs of ``folder`` inlined as ``data:`` URIs, and a note when there are none."""
    pngs = sorted(folder.glob("*.png")) if folder is not None and folder.is_dir() else []
    if not pngs:
        return '<p class="note">No figures: run <code>ogcp plot RUN</code> first.</p>', ["no PNG figures found"]
    parts = []
    for png in pngs:
        encoded = base64.b64encode(png.read_bytes()).decode("ascii")
        parts.append(
            f'<figure><img alt="{html.escape(png.stem)}" src="data:image/png;base64,{encoded}">'
            f"<figcaption>{html.escape(png.name)}</figcaption></figure>"
        )
    return "".join(parts), []


def _viewer(scenes: Scenes) -> str:
    """The viewer block: canvas, grasp selector, description, grasp table, data and script."""
    # "</" inside a script element would end it early; JSON allows the escaped form.
    data = json.dumps(scenes.to_dict(), separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return (
        '<div id="ogcp-viewer"><canvas id="ogcp-canvas" width="640" height="480"></canvas>'
        '<div><select id="ogcp-select"></select><div id="ogcp-info"></div>'
        '<p class="note">Drag to rotate, wheel to zoom, double-click to reset. Grey dots: the contact set; '
        "large dots and arrows: the grasp's contacts and inward normals (green valid, red invalid, "
        "blue not simulated); orange: the weakest disturbance direction.</p></div></div>"
        + _grasp_table(scenes.grasps)
        + f'<script type="application/json" id="ogcp-data">{data}</script>'
        + f"<script>{VIEWER_JS}</script>"
    )


def page(title: str, body: str) -> str:
    """A complete HTML document with the report's style."""
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
        f"<body><h1>{html.escape(title)}</h1>{body}</body></html>\n"
    )


def _write(path: Path, text: str) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise OgcpError(f"cannot write {path}: {exc.strerror or exc}") from exc


def write_report(run: str | Path, out: str | Path | None = None, figures: str | Path | None = None) -> ReportResult:
    """Write the HTML report of a suite run.

    Args:
        run: The run folder (``results.jsonl``, ``manifest.json``).
        out: The HTML file (default ``RUN/report.html``).
        figures: Folder of the PNG figures and ``fig9_times.md`` (default ``RUN/figures``).

    Returns:
        The file, the number of grasps shown and the notes.

    Raises:
        OgcpError: When the run holds no results or the file cannot be written.
    """
    run = Path(run)
    store = ResultStore(run)
    read = store.read()
    records = [CellRecord.from_dict(r) for r in read.latest().values()]
    if not records:
        raise OgcpError(f"{run} holds no results (no {store.results_path.name} lines)")
    manifest = store.read_manifest() or {}
    name = str((manifest.get("suite") or {}).get("name") or run.name)
    folder = Path(figures) if figures is not None else run / "figures"
    notes = list(read.problems)
    scenes = Scenes()
    for record in records:
        if record.plan is None:
            continue
        try:
            scenes.add_plan(record.describe(), record.plan, record.simulation)
        except (OgcpError, ValueError, TypeError, KeyError, IndexError) as exc:
            # One odd record costs its own view, not the report.
            notes.append(f"{record.describe()}: not shown ({type(exc).__name__}: {exc})")
    notes += scenes.notes
    times = folder / TIME_TABLE
    time_html = (
        markdown_table(times.read_text(encoding="utf-8"))
        if times.is_file()
        else f'<p class="note">No time table ({html.escape(TIME_TABLE)}): run <code>ogcp plot RUN</code> first.</p>'
    )
    figure_html, figure_notes = _figures(folder)
    notes += figure_notes
    body = (
        f'<p class="note">{len(records)} cells from {html.escape(str(run))}; '
        f"{len(scenes.grasps)} grasps in 3D.</p>"
        "<h2>Summary per object and method</h2>" + _summary(records) + "<h2>Fig. 9: planning times</h2>" + time_html
    )
    body += "<h2>Grasps in 3D</h2>" + _viewer(scenes) + "<h2>Figures</h2>" + figure_html
    path = Path(out) if out is not None else run / REPORT_NAME
    _write(path, page(f"ogcp report: {name}", body))
    return ReportResult(path, len(scenes.grasps), tuple(notes))


def write_view(result: str | Path, out: str | Path | None = None) -> ReportResult:
    """Write the 3D view of one result: an ``ogcp.plan/1``, ``ogcp.sim/1``/``/2`` or ``ogcp.cell/1`` record.

    Args:
        result: The JSON file (``ogcp plan --out``, ``ogcp evaluate --out``, or one cell record).
        out: The HTML file (default: next to ``result``, with the suffix ``.html``).

    Raises:
        OgcpError: For a file that cannot be read or is none of those records.
    """
    result = Path(result)
    if result.name == "results.jsonl" or result.is_dir():
        folder = result.parent if result.name == "results.jsonl" else result
        raise OgcpError(
            f"{result} is a suite's results: ogcp report {folder} draws them all; ogcp view shows one record"
        )
    record = read_json(result, "result", "ogcp.plan, ogcp.sim or ogcp.cell")
    schema = str(record.get("schema", "")) if isinstance(record, dict) else ""
    scenes = Scenes()
    if schema.startswith("ogcp.plan/"):
        scenes.add_plan(result.stem, record, plan_file=result)
    elif schema.startswith("ogcp.sim/"):
        scenes.add_sim(result.stem, record)
    elif schema.startswith("ogcp.cell/"):
        cell = CellRecord.from_dict(record)
        if cell.plan is None:
            raise OgcpError(f"{result}: the cell has no plan to show (status {cell.status})")
        scenes.add_plan(cell.describe(), cell.plan, cell.simulation, plan_file=result)
    else:
        raise OgcpError(f"{result} is not a plan, simulation or cell record (schema {schema or 'missing'!r})")
    path = Path(out) if out is not None else result.with_suffix(".html")
    _write(path, page(f"ogcp view: {result.name}", _viewer(scenes)))
    return ReportResult(path, len(scenes.grasps), tuple(scenes.notes))
