"""Plans carry their contacts, so they evaluate the same on another machine and from another folder."""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import ogcp.sim_eval.inputs.plan_input as plan_input_module
from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.plan import add_plan_path, contact_set_record
from ogcp.planner.search.grasp_planner import GraspPlanner
from ogcp.sim_eval.inputs.plan_input import plan_input

N = 40


def _plan(spec: str) -> dict[str, Any]:
    """A plan of ``spec`` with N contacts, as written to JSON and read back."""
    mesh, source = resolve_object(spec)
    contacts = sample_contacts(mesh, N, 0, source=source)
    record = GraspPlanner().plan(contacts, 3).to_dict(contact_set_record(contacts))
    return json.loads(json.dumps(record))


@pytest.fixture(scope="module")
def donut_plan() -> dict[str, Any]:
    return _plan("donut")


def _as_if_from(record: dict[str, Any], trimesh_version: str) -> dict[str, Any]:
    record = copy.deepcopy(record)
    record["provenance"]["versions"]["trimesh"] = trimesh_version
    return record


def test_a_plan_records_its_whole_contact_set(donut_plan):
    block = donut_plan["contact_set"]
    assert np.shape(block["positions"]) == (N, 3) and np.shape(block["normals"]) == (N, 3)
    best = donut_plan["grasp"]
    assert np.array_equal(np.asarray(block["positions"])[best], donut_plan["contacts"]["positions"])


def test_a_plan_from_other_versions_evaluates_its_recorded_contacts(donut_plan, monkeypatch):
    record = _as_if_from(donut_plan, "0.0.1")
    called = []

    def another_trimesh(*args: Any, **kwargs: Any) -> ContactSet:
        # Another trimesh samples other contacts from the same seed.
        called.append(args)
        contacts = sample_contacts(*args, **kwargs)
        order = np.random.default_rng(7).permutation(len(contacts))
        return ContactSet(
            contacts.positions[order],
            contacts.normals[order],
            contacts.com,
            contacts.torque_scale,
            source=contacts.source,
        )

    monkeypatch.setattr(plan_input_module, "sample_contacts", another_trimesh)
    plan = plan_input(record)
    assert np.array_equal(plan.contacts.positions, donut_plan["contact_set"]["positions"])
    assert np.array_equal(plan.contacts.normals, donut_plan["contact_set"]["normals"])
    assert plan.grasps[0] == tuple(donut_plan["grasp"]) and not called
    q1 = plan_input_module.q1(plan.contacts.subset_wrenches(np.asarray(plan.grasps[0])))
    assert q1 == pytest.approx(donut_plan["q1"], abs=1e-9)


def test_the_same_build_still_checks_that_resampling_reproduces_the_plan(donut_plan):
    record = copy.deepcopy(donut_plan)
    for block in (record["contact_set"]["source"], record["source"]):
        block["seed"] = 3
    with pytest.raises(OgcpError, match="were n, seed or tip_radius changed"):
        plan_input(record)
    # On other versions re-sampling proves nothing, and the recorded set stands.
    assert plan_input(_as_if_from(record, "0.0.1")).grasps[0] == tuple(record["grasp"])


def _mesh_plan(folder: Path) -> tuple[dict[str, Any], Path]:
    folder.mkdir()
    mesh_path = folder / "box.obj"
    resolve_object("box")[0].export(mesh_path)
    record = _plan(str(mesh_path))
    plan_path = folder / "plan.json"
    plan_path.write_text(json.dumps(add_plan_path(record, plan_path)))
    return record, plan_path


def test_a_plan_moved_with_its_mesh_finds_it_relative_to_itself(tmp_path):
    record, plan_path = _mesh_plan(tmp_path / "made")
    assert record["contact_set"]["mesh"]["path_from_plan"] == "box.obj"
    moved = tmp_path / "elsewhere" / "deeper"
    shutil.copytree(plan_path.parent, moved)
    shutil.rmtree(plan_path.parent)
    with pytest.raises(OgcpError, match=r"the plan's mesh .* does not exist \(tried "):
        plan_input(record)
    plan = plan_input(json.loads((moved / "plan.json").read_text()), moved / "plan.json")
    assert plan.grasps[0] == tuple(record["grasp"]) and len(plan.contacts) == N


def test_a_mesh_changed_after_planning_is_refused_by_its_sha256(tmp_path):
    record, plan_path = _mesh_plan(tmp_path / "made")
    with (plan_path.parent / "box.obj").open("a") as handle:
        handle.write("# edited after planning\n")
    with pytest.raises(OgcpError, match="object sha256 recorded '[0-9a-f]{64}', rebuilt '[0-9a-f]{64}'") as info:
        plan_input(record, plan_path)
    assert "\n" not in str(info.value)


def test_recorded_contacts_off_the_mesh_are_refused_by_index(donut_plan):
    record = _as_if_from(donut_plan, "0.0.1")
    unused = next(i for i in range(N) if i not in record["grasp"])
    record["contact_set"]["positions"][unused][2] += 1e-4
    with pytest.raises(OgcpError, match=f"recorded contact {unused} at .* m off the mesh surface") as info:
        plan_input(record)
    # The message says how far off (about the 0.1 mm it was moved: it lies on a face's plane
    # extension at most that far) and that the plan was made with another trimesh than this one.
    distance = float(str(info.value).split(" m is ")[1].split(" m off")[0])
    assert 0 < distance <= 1.0001e-4
    assert "recorded with trimesh 0.0.1, running " in str(info.value) and "\n" not in str(info.value)


def test_an_old_plan_without_contacts_is_resampled(donut_plan):
    record = copy.deepcopy(donut_plan)
    for key in ("positions", "normals"):
        del record["contact_set"][key]
    plan = plan_input(record)
    assert np.array_equal(plan.contacts.positions, donut_plan["contact_set"]["positions"])


def test_evaluate_plan_simulates_the_recorded_contacts(donut_plan, monkeypatch):
    from ogcp.sim_eval.evaluate import evaluate_plan

    monkeypatch.setattr(plan_input_module, "sample_contacts", None)  # never called: nothing re-sampled
    result = evaluate_plan(
        _as_if_from(donut_plan, "0.0.1"),
        {"directions": 0, "threads": 1},
        {"method": "convex_hull"},
        max_grasps=1,
    )
    assert result is not None
