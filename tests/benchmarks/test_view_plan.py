"""``ogcp view PLAN.json`` shows the plan's own recorded contacts, on its mesh found as ``ogcp evaluate`` finds it."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh

import ogcp.sim_eval.inputs.plan_input
from ogcp.benchmarks.cli.app import main
from ogcp.benchmarks.report import write_view

_DATA = re.compile(r'<script type="application/json" id="ogcp-data">(.*?)</script>', re.DOTALL)


@pytest.fixture
def moved_plan(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A plan of a mesh file given by a relative path, moved with its mesh to another folder."""
    planned = tmp_path / "planned"
    planned.mkdir()
    trimesh.creation.box((0.1, 0.06, 0.04)).export(planned / "obj.stl")
    monkeypatch.chdir(planned)
    assert main(["plan", "obj.stl", "-n", "30", "-m", "3", "-o", "plan.json"]) == 0
    moved = tmp_path / "moved"
    shutil.move(planned, moved)
    monkeypatch.chdir(tmp_path)
    return moved / "plan.json"


def test_view_finds_the_mesh_next_to_a_moved_plan_and_shows_its_recorded_contacts(moved_plan, monkeypatch):
    record = json.loads(moved_plan.read_text())

    def no_resampling(*args, **kwargs):
        raise AssertionError("the view re-sampled the plan's contact set")

    # As on another build: nothing may re-sample, the recorded set is the reference.
    monkeypatch.setattr(ogcp.sim_eval.inputs.plan_input, "same_sampling_build", lambda record: False)
    monkeypatch.setattr(ogcp.sim_eval.inputs.plan_input, "_resample", no_resampling)
    shown = write_view(moved_plan)
    assert shown.notes == () and shown.grasps == 1
    data = json.loads(_DATA.search(shown.path.read_text()).group(1))
    (contact_set,) = data["sets"]
    recorded = np.asarray(record["contact_set"]["positions"], dtype=float)
    np.testing.assert_allclose(np.reshape(contact_set["points"], (-1, 3)), recorded, atol=1e-5)
    assert len(data["meshes"]) == 1 and data["grasps"][0]["grasp"] == record["grasp"]


def test_view_cli_of_a_moved_plan_prints_no_note(moved_plan, capsys):
    assert main(["view", str(moved_plan), "--no-open"]) == 0
    out, err = capsys.readouterr()
    assert out.strip() == str(moved_plan.with_suffix(".html")) and "note" not in err
