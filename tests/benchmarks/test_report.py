"""``ogcp report`` and ``ogcp view``: one self-contained HTML file, offline, with a working 3D view.

A tiny suite (box, 30 contacts, m = 3, A*, simulated with cheap settings) is run once per
module. The pages are checked statically (one file, no external URL, data that parses, size,
grasp count) and, where a Chromium is installed, in a headless browser: no JavaScript error
and a canvas that drew.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ogcp.benchmarks.cli.app import main
from ogcp.benchmarks.report import write_report, write_view
from ogcp.benchmarks.report.scene import coarsen
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import RESULTS

SUITE = """schema_version = 1
name = "tiny"
objects = ["box"]
contacts = 30
m = [3]

[[methods]]
method = "astar"
label = "A*"

[simulation]
enabled = true
directions = 0
threads = 1

[simulation.decomposition]
method = "convex_hull"
"""
_DATA = re.compile(r'<script type="application/json" id="ogcp-data">(.*?)</script>', re.DOTALL)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report") / "run"
    summary = SuiteRunner(parse_suite(SUITE), out).run()
    assert summary.ran == 1 and summary.errors == 0
    return out


def _records(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / RESULTS).read_text().splitlines() if line.strip()]


def _data(text: str) -> dict:
    (block,) = _DATA.findall(text)
    return json.loads(block)


def _offline(text: str) -> None:
    """No attribute loads anything from the network (src, href, url(...))."""
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", text, re.IGNORECASE)
    assert not re.search(r"url\(\s*['\"]?(https?:)?//", text, re.IGNORECASE)
    assert "http://" not in text and "https://" not in text


def test_report_is_one_offline_file_with_every_grasp(run: Path, tmp_path: Path) -> None:
    out = tmp_path / "out" / "report.html"
    result = write_report(run, out)
    assert result.path == out and sorted(p.name for p in out.parent.iterdir()) == ["report.html"]
    text = out.read_text(encoding="utf-8")
    _offline(text)
    assert 10_000 < out.stat().st_size < 20_000_000
    data = _data(text)
    simulated = sum(len(r["simulation"]["grasps"]) for r in _records(run))
    assert simulated >= 1 and result.grasps == len(data["grasps"]) == simulated
    assert len(data["meshes"]) == 1 and len(data["sets"]) == 1  # one box, one contact set
    assert len(data["sets"][0]["points"]) == 3 * 30
    grasp = data["grasps"][0]
    assert grasp["simulated"] and len(grasp["points"]) == len(grasp["normals"]) == 9
    assert isinstance(grasp["valid"], bool)
    assert text.count('data-grasp="') == len(data["grasps"])
    assert "No figures" in text and any("figure" in note for note in result.notes)


def test_view_of_a_plan_and_of_a_simulation(run: Path, tmp_path: Path) -> None:
    (record,) = _records(run)
    plan, sim = tmp_path / "plan.json", tmp_path / "sim.json"
    plan.write_text(json.dumps(record["plan"]))
    sim.write_text(json.dumps(record["simulation"]))
    shown = write_view(plan)
    assert shown.path == tmp_path / "plan.html" and shown.grasps == 1
    data = _data(shown.path.read_text())
    assert data["grasps"][0]["simulated"] is False and data["grasps"][0]["grasp"] == record["plan"]["grasp"]
    simulated = write_view(sim, tmp_path / "sim_view.html")
    assert simulated.grasps == len(record["simulation"]["grasps"])
    assert _data(simulated.path.read_text())["grasps"][0]["simulated"] is True


def test_cli_report_and_view(run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.html"
    assert main(["report", str(run), "--out", str(out), "--no-plot"]) == 0
    assert capsys.readouterr().out.strip() == str(out)
    cell = tmp_path / "cell.json"
    cell.write_text(json.dumps(_records(run)[0]))
    assert main(["view", str(cell), "--no-open"]) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "cell.html")
    assert main(["view", str(tmp_path / "r.html"), "--no-open"]) == 2  # not a JSON record
    assert "ogcp: error:" in capsys.readouterr().err


def test_coarsen_keeps_a_large_mesh_under_the_budget() -> None:
    mesh = trimesh.creation.icosphere(subdivisions=5)  # 20480 faces
    vertices, faces = coarsen(mesh, max_faces=2000)
    assert 100 < len(faces) <= 2000 and faces.max() < len(vertices)
    small = trimesh.creation.box()
    assert len(coarsen(small)[1]) == len(small.faces)  # under the budget: unchanged


def _chromium() -> str | None:
    return next((path for name in ("chromium", "chromium-browser") if (path := shutil.which(name))), None)


@pytest.mark.skipif(_chromium() is None, reason="no chromium on PATH")
def test_report_draws_in_a_headless_browser(run: Path, tmp_path: Path) -> None:
    out = write_report(run, tmp_path / "report.html").path
    browser = _chromium()
    assert browser is not None
    done = subprocess.run(
        [
            browser,
            "--headless=new",
            "--disable-gpu",
            "--no-sandbox",
            "--enable-logging=stderr",
            "--v=0",
            f"--user-data-dir={tmp_path / 'profile'}",
            "--virtual-time-budget=5000",
            "--dump-dom",
            out.resolve().as_uri(),
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    # Console messages are logged as "CONSOLE(line)" or "Uncaught ..." lines on stderr.
    errors = [line for line in done.stderr.splitlines() if "Uncaught" in line or "SyntaxError" in line]
    assert not errors, errors
    assert re.search(r'<canvas[^>]*data-drawn="1"', done.stdout), done.stdout[:2000]


@pytest.fixture(scope="module")
def hand_sim(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A box grasp of the built-in gripper, simulated with the hand (no loads)."""
    folder = tmp_path_factory.mktemp("hand_view")
    plan, sim = folder / "plan.json", folder / "sim.json"
    common = ["-n", "40", "-m", "2", "--diagonal", "0.08", "--contact-model", "soft"]
    assert main(["plan", "box", *common, "--hand", "parallel_gripper", "-o", str(plan)]) == 0
    assert main(["evaluate", str(plan), "--directions", "0", "--decomposition", "convex_hull", "-o", str(sim)]) == 0
    return sim


def test_view_draws_the_hand_as_it_settled(hand_sim: Path, tmp_path: Path) -> None:
    """The hand's collision geometry at its settled pose, in the object's frame: its jaws' inner faces
    lie on the contacts."""
    shown = write_view(hand_sim, tmp_path / "hand.html")
    (grasp,) = _data(shown.path.read_text())["grasps"]
    vertices = np.asarray(grasp["hand"]["vertices"], dtype=float).reshape(-1, 3)
    faces = np.asarray(grasp["hand"]["faces"]).reshape(-1, 3)
    assert len(faces) and faces.max() < len(vertices)
    triangles = vertices[faces]
    points = np.asarray(grasp["points"], dtype=float).reshape(-1, 3)
    # Each contact lies within a pad's rounding (4 mm) and the settling of the hand's surface.
    for point in points:
        nearest = trimesh.triangles.closest_point(triangles, np.repeat(point[None], len(triangles), axis=0))
        assert np.linalg.norm(nearest - point, axis=1).min() < 5e-3
    fingertips = json.loads(hand_sim.read_text())
    del fingertips["grasps"][0]["hand"]  # a fingertip record: no hand drawn
    (tmp_path / "tips.json").write_text(json.dumps(fingertips))
    assert "hand" not in _data(write_view(tmp_path / "tips.json").path.read_text())["grasps"][0]


@pytest.mark.skipif(shutil.which("node") is None, reason="no node on PATH")
def test_the_viewer_script_draws_object_and_hand_without_error_in_node(hand_sim: Path, tmp_path: Path) -> None:
    """The page's script run against a stub canvas: it draws, in the object's tint and the hand's."""
    page = write_view(hand_sim, tmp_path / "hand.html").path
    harness = tmp_path / "run.js"
    harness.write_text(_NODE_HARNESS)
    done = subprocess.run(["node", str(harness), str(page)], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    drawn, warm, cool = (int(v) for v in done.stdout.split())
    assert drawn == 1 and warm > 0 and cool > 0


#: Runs the page's scripts with a stub DOM and canvas; prints whether it drew and how many distinct
#: warm (hand) and cool (object) shades it filled.
_NODE_HARNESS = r"""
const fs = require('fs');
const html = fs.readFileSync(process.argv[2], 'utf8');
const data = html.match(/<script type="application\/json" id="ogcp-data">([\s\S]*?)<\/script>/)[1];
const scripts = [...html.matchAll(/<script>([\s\S]*?)<\/script>/g)].map(m => m[1]);
const fills = new Set();
function element() {
  return { appendChild() {}, addEventListener() {}, scrollIntoView() {}, setAttribute(k, v) { this[k] = v; },
           set textContent(v) {}, get textContent() { return data; } };
}
const context = { fillRect() {}, beginPath() {}, moveTo() {}, lineTo() {}, closePath() {}, stroke() {}, arc() {},
                  fill() { fills.add(this.fillStyle); }, fillStyle: '', strokeStyle: '', lineWidth: 1 };
const canvas = Object.assign(element(), { width: 400, height: 300, getContext() { return context; } });
global.document = { getElementById(id) { return id === 'ogcp-canvas' ? canvas : (id === 'ogcp-select' ? null : element()); },
                    createElement() { return element(); }, querySelectorAll() { return []; } };
global.window = { addEventListener() {} };
for (const script of scripts) { eval(script); }
const rgb = [...fills].filter(c => c.startsWith('rgb')).map(c => c.slice(4, -1).split(',').map(Number));
const warm = rgb.filter(([r, g, b]) => r > b + 5).length, cool = rgb.filter(([r, g, b]) => b > r + 5).length;
console.log(canvas['data-drawn'] === '1' ? 1 : 0, warm, cool);
"""
