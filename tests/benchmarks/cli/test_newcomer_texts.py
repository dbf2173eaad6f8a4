"""Texts a newcomer reads: help that names real commands and defaults, and a certificate that says "optimal" when it is."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import re
from pathlib import Path
from typing import Any

import pytest

from ogcp.benchmarks.cli import main
from ogcp.benchmarks.cli.plan_summary import search_summary
from ogcp.planner import GraspPlanner, builtin_mesh
from ogcp.planner.grasp import sample_contacts
from ogcp.planner.infra.errors import OgcpError


def test_view_help_names_real_commands_and_its_real_default(capsys):
    with pytest.raises(SystemExit):
        main(["view", "--help"])
    text = capsys.readouterr().out
    assert "ogcp simulate" not in text and "ogcp evaluate" in text
    assert "RESULT with the suffix .html" in text


def test_a_wastar_result_whose_bound_equals_its_q1_is_called_optimal():
    contacts = sample_contacts(builtin_mesh("box"), 12, seed=0)
    result = GraspPlanner(method="wastar").plan(contacts, 2)
    closed = dataclasses.replace(result, bound=result.q1)
    open_bound = dataclasses.replace(result, bound=result.q1 + 0.01)
    assert "optimal (certified: the bound equals Q1)" in search_summary(closed, contacts)
    assert f"within bound: optimum <= {result.q1 + 0.01:.6f}" in search_summary(open_bound, contacts)


@pytest.fixture(scope="module")
def small_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A plan of the box with 20 contacts, planned once for the tests below."""
    path = tmp_path_factory.mktemp("plan") / "plan.json"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["plan", "box", "-n", "20", "-m", "3", "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("content", [b"solid box\n\x96\x00\x01\x02", b"solid box\nfacet normal 0 0 1\n"])
def test_a_mesh_given_to_evaluate_is_named_not_a_plan(tmp_path: Path, capsys, content: bytes) -> None:
    mesh = tmp_path / "mesh.stl"
    mesh.write_bytes(content)
    assert main(["evaluate", str(mesh)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"ogcp: error: {mesh}: not a plan file (expected ogcp.plan JSON")
    assert "utf-8" not in err and "codec" not in err and f"ogcp plan {mesh} -o plan.json" in err
    assert len(err.splitlines()) == 1


def test_render_is_checked_before_simulating(small_plan: Path, tmp_path: Path, capsys, monkeypatch) -> None:
    def no_gl() -> None:
        raise OgcpError("offscreen rendering is not available here: set MUJOCO_GL=egl")

    def simulate(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("simulated although the picture could not be drawn")

    monkeypatch.setattr("ogcp.sim_eval.render.check_offscreen_rendering", no_gl)
    monkeypatch.setattr("ogcp.sim_eval.evaluate.evaluate_plan", simulate)
    assert main(["evaluate", str(small_plan), "--render", str(tmp_path / "a.png")]) == 2
    assert "offscreen rendering is not available" in capsys.readouterr().err


def test_results_are_written_when_the_picture_fails(small_plan: Path, tmp_path: Path, capsys, monkeypatch) -> None:
    def late_failure(record: Any, args: Any) -> None:
        raise OgcpError("offscreen rendering is not available here")

    monkeypatch.setattr("ogcp.sim_eval.render.check_offscreen_rendering", lambda: None)
    monkeypatch.setattr("ogcp.benchmarks.cli.simulate._render", late_failure)
    out = tmp_path / "sim.json"
    argv = ["evaluate", str(small_plan), "--max-grasps", "1", "--directions", "2", "-o", str(out)]
    assert main([*argv, "--render", str(tmp_path / "a.png")]) == 1
    record = json.loads(out.read_text(encoding="utf-8"))
    text = capsys.readouterr()
    assert "ogcp: error: offscreen rendering is not available here" in text.err
    # The table: Q1 without a unit, forces in N, torques in N·m (rho recorded with the object).
    rho = record["object"]["torque_scale"]
    assert rho > 0
    grasp = record["grasps"][0]
    table = text.out
    assert re.search(r": Q1 [0-9.]+ +valid", table) and " N\n" not in table.split("valid")[0]
    row = next(line for line in table.splitlines() if line.strip().startswith("+tx"))
    index = grasp["directions"].index("+tx")
    assert row.split()[1] == f"{grasp['predicted'][index] * rho:.3f}" and "N·m" in row
    assert any(line.strip().startswith("+fx") and " N " in line for line in table.splitlines())


def test_a_request_too_big_to_finish_says_so_in_one_line_with_the_flags_that_bound_it() -> None:
    from ogcp.benchmarks.cli.plan import size_note
    from ogcp.planner.methods.registry import METHODS

    astar, es = METHODS["astar"], METHODS["es"]
    assert size_note(astar, astar.config(), 60, 3, None) is None  # an ordinary request: nothing
    note = size_note(astar, astar.config(), 60, 30, None)
    assert note is not None and "1.1e+09 children" in note and "--time-limit" in note and "\n" not in note
    assert "the time limit of 5 s returns" in (size_note(astar, astar.config(), 60, 30, 5.0) or "")
    assert size_note(es, es.config(), 200, 3, None) is None
    assert "C(60, 20) = 4.2e+15 grasps" in (size_note(es, es.config(), 60, 20, None) or "")


def test_a_plan_that_resists_nothing_says_what_to_change(tmp_path: Path, capsys) -> None:
    """Q1 = 0 (two hard contacts never resist a torsion about their line) gets a note with the remedy; Q1 > 0 none."""
    assert main(["plan", "box", "-n", "12", "-m", "2", "-o", str(tmp_path / "hard.json")]) == 0
    hard = capsys.readouterr().out
    assert "Q1 = 0.000000" in hard
    assert "note: Q1 = 0, the grasp resists no wrench in some direction" in hard and "--contact-model soft" in hard
    assert main(["plan", "box", "-n", "12", "-m", "3", "-o", str(tmp_path / "three.json")]) == 0
    assert "note: Q1 = 0" not in capsys.readouterr().out


def test_a_render_that_is_not_a_png_is_refused_before_simulating(small_plan: Path, tmp_path: Path, capsys) -> None:
    assert main(["evaluate", str(small_plan), "--render", str(tmp_path / "picture")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"ogcp: error: --render {tmp_path / 'picture'}: the picture is a PNG; give a file name ending in .png"


def test_a_mujoco_gl_that_mujoco_cannot_load_is_one_line(tmp_path: Path) -> None:
    """An unknown backend breaks ``import mujoco`` itself: one line, exit 2, never its traceback."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "MUJOCO_GL": "bogus"}
    argv = [sys.executable, "-m", "ogcp.benchmarks.cli", "evaluate", "missing.json"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300, check=False, cwd=tmp_path, env=env)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert (
        line.startswith("ogcp: error: MUJOCO_GL=bogus: MuJoCo cannot load this OpenGL backend here") and "unset" in line
    )
