"""``ogcp evaluate GRASPS.json``: grasps from any planner through the same command as ogcp's plans."""

from __future__ import annotations

import json

import numpy as np

from ogcp.benchmarks.cli import main
from ogcp.planner import builtin_mesh

HALF = np.ptp(np.asarray(builtin_mesh("box").vertices), axis=0) / 2


def _tripod(offset: float = 0.0) -> list[dict]:
    """Three contacts on the box's x and z faces, ``offset`` [m] off the +x face."""
    x, z = float(HALF[0]), float(HALF[2])
    return [
        {"position": [x + offset, 0.01, 0.0], "normal": [-1.0, 0.0, 0.0]},
        {"position": [-x, -0.01, 0.0], "normal": [1.0, 0.0, 0.0]},
        {"position": [0.0, 0.0, z], "normal": [0.0, 0.0, -1.0]},
    ]


def test_evaluate_takes_a_grasps_file_and_writes_the_sim_record(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    grasps = tmp_path / "mine.json"
    grasps.write_text(
        json.dumps(
            {
                "schema": "ogcp.grasps/1",
                "object": {"mesh": "box"},
                "mu": 0.5,
                "method": "my-planner",
                "grasps": [{"label": "tripod", "score": 0.7, "contacts": _tripod()}],
            }
        )
    )
    out = tmp_path / "sim.json"
    argv = ["evaluate", str(grasps), "--directions", "0", "--decomposition", "convex_hull", "-o", str(out)]
    assert main(argv) == 0
    record = json.loads(out.read_text())
    (grasp,) = record["grasps"]
    external = record["object"]["external"]["grasps"][0]
    assert external["method"] == "my-planner" and external["score"] == 0.7 and external["q1"] > 0
    assert grasp["valid"] is True and min(grasp["measured"]) > 0
    assert "tripod" in capsys.readouterr().out


def test_off_surface_contacts_are_refused_with_on_surface_refuse(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    grasps = tmp_path / "off.json"
    document = {
        "schema": "ogcp.grasps/1",
        "object": {"mesh": "box"},
        "mu": 0.5,
        "grasps": [{"contacts": _tripod(0.002)}],
    }
    grasps.write_text(json.dumps(document))
    argv = ["evaluate", str(grasps), "--on-surface", "refuse", "--directions", "0", "--decomposition", "convex_hull"]
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("ogcp: error:") and "contacts[0]" in err[0]
