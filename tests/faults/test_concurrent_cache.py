"""One cache, many processes: four evaluations, or two suites with their own ``--out``, of one new mesh
started together with an empty cache.

Each process that finds no entry decomposes the mesh itself and offers its entry; the first to
finish is kept (entries are keyed by content, :func:`ogcp.planner.infra.cache.write_entry`), and
every process then reads the kept entry back (:func:`ogcp.sim_eval.decomposition.decompose`). So a
decomposition may be computed more than once, but every process simulates the same one.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import trimesh

from ogcp.planner.infra.cache import verify_entry

PROCESSES = 4


def _ogcp(*argv: str, env: dict[str, str]) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "ogcp.benchmarks.cli", *argv]
    return subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_four_evaluations_on_an_empty_cache_agree_and_leave_one_valid_entry(tmp_path: Path) -> None:
    mesh = trimesh.creation.torus(major_radius=0.05, minor_radius=0.018, major_sections=24, minor_sections=12)
    mesh.export(tmp_path / "torus.stl")
    env = {**os.environ, "OGCP_CACHE": str(tmp_path / "cache")}
    plan = _ogcp("plan", str(tmp_path / "torus.stl"), "-n", "30", "-m", "3", "-o", str(tmp_path / "plan.json"), env=env)
    assert plan.wait(timeout=300) == 0, plan.stderr.read() if plan.stderr else ""
    runs = [
        _ogcp(
            "evaluate",
            str(tmp_path / "plan.json"),
            "--max-grasps",
            "1",
            "--directions",
            "2",
            "-o",
            str(tmp_path / f"sim{k}.json"),
            env=env,
        )
        for k in range(PROCESSES)
    ]
    for run in runs:
        _, err = run.communicate(timeout=600)
        assert run.returncode == 0, err
    records = [json.loads((tmp_path / f"sim{k}.json").read_text(encoding="utf-8")) for k in range(PROCESSES)]
    assert records[0]["decomposition"]["method"] == "coacd"  # a real decomposition, not one hull
    assert all(r["decomposition"] == records[0]["decomposition"] for r in records)
    assert all(r["grasps"][0]["measured"] == records[0]["grasps"][0]["measured"] for r in records)
    entries = [p for p in (tmp_path / "cache").rglob("manifest.json") if p.parent.parent.name == "decompositions"]
    assert entries and all(verify_entry(p.parent) for p in entries)
    assert not [p for p in (tmp_path / "cache").rglob("*") if p.name.endswith((".partial", ".old"))]


def test_two_suites_with_their_own_out_share_an_empty_cache(tmp_path: Path) -> None:
    mesh = trimesh.creation.torus(major_radius=0.05, minor_radius=0.018, major_sections=24, minor_sections=12)
    mesh.export(tmp_path / "torus.stl")
    suite = tmp_path / "shared.toml"
    suite.write_text(
        'schema_version = 1\nname = "shared"\nobjects = ["torus.stl"]\ncontacts = 30\nm = [3]\n'
        '[[methods]]\nmethod = "astar"\n[simulation]\nenabled = true\ndirections = 2\nmax_grasps = 1\n'
    )
    env = {**os.environ, "OGCP_CACHE": str(tmp_path / "cache")}
    runs = [_ogcp("suite", str(suite), "--out", str(tmp_path / f"out{k}"), env=env) for k in range(2)]
    for run in runs:
        _, err = run.communicate(timeout=900)
        assert run.returncode == 0, err
    records = []
    for k in range(2):
        lines = (tmp_path / f"out{k}" / "results.jsonl").read_text(encoding="utf-8").splitlines()
        assert len(lines) == 1
        records.append(json.loads(lines[0]))
    assert all(r["status"] == "ok" and r["simulation"] is not None for r in records)
    first, second = (r["simulation"] for r in records)
    assert first["decomposition"]["method"] == "coacd"
    assert first["decomposition"] == second["decomposition"]  # both simulated the one kept entry
    assert first["grasps"][0]["measured"] == second["grasps"][0]["measured"]
    entries = [p for p in (tmp_path / "cache").rglob("manifest.json") if p.parent.parent.name == "decompositions"]
    assert entries and all(verify_entry(p.parent) for p in entries)
    assert not [p for p in (tmp_path / "cache").rglob("*") if p.name.endswith((".partial", ".old"))]
