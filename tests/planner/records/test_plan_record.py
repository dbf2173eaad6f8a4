"""The ``ogcp.plan/1`` record read back: file and schema, the contact sampling, the grasps."""

from __future__ import annotations

import json

import pytest

from ogcp.planner import builtin_mesh, resolve_object
from ogcp.planner.grasp import DEFAULT_CONE_EDGES, DEFAULT_MU, sample_contacts
from ogcp.planner.infra import OgcpError
from ogcp.planner.records.plan import (
    PLAN_SCHEMA,
    contact_sampling,
    contact_set_record,
    load_plan,
    plan_grasps,
    recorded_positions,
)
from ogcp.planner.search import GraspPlanner


@pytest.fixture(scope="module")
def record() -> dict:
    mesh, source = resolve_object("box")
    contacts = sample_contacts(mesh, 12, 3, 0.7, 6, source)
    return GraspPlanner().plan(contacts, 3).to_dict(contact_set_record(contacts))


def test_load_plan_checks_file_json_and_schema(tmp_path, record):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(record))
    assert load_plan(path) == record
    for text, message in ((None, "no such plan file"), ("{x", "not valid JSON"), ('{"schema": "x"}', PLAN_SCHEMA)):
        bad = tmp_path / "bad.json"
        bad.unlink(missing_ok=True)
        if text is not None:
            bad.write_text(text)
        with pytest.raises(OgcpError, match=message):
            load_plan(bad)


def test_contact_sampling_rebuilds_the_recorded_set(record):
    sampling = contact_sampling(record)
    assert (sampling.n, sampling.seed, sampling.mu, sampling.cone_edges) == (12, 3, 0.7, 6)
    assert sampling.object["name"] == "box" and "seed" not in sampling.object
    again = sample_contacts(builtin_mesh("box"), sampling.n, sampling.seed, sampling.mu, sampling.cone_edges)
    assert again.positions[list(record["grasp"])].tolist() == recorded_positions(record).tolist()
    assert sampling.com == tuple(record["contact_set"]["com"])


def test_contact_sampling_defaults_and_refusal(record):
    block = {k: v for k, v in record["contact_set"].items() if k not in ("mu", "cone_edges", "com")}
    sampling = contact_sampling({**record, "contact_set": block})
    assert (sampling.mu, sampling.cone_edges, sampling.com) == (DEFAULT_MU, DEFAULT_CONE_EDGES, None)
    with pytest.raises(OgcpError, match="does not record how its contacts were sampled"):
        contact_sampling({**record, "contact_set": {"source": {"kind": "file"}}})


def test_plan_grasps_are_distinct_best_first_and_checked():
    record = {"grasp": [0, 1, 2], "top": [{"grasp": [0, 1, 2]}, [1, 2, 3]], "runs": [{"grasp": [2, 3, 4]}]}
    assert plan_grasps(record, 5) == (((0, 1, 2), (1, 2, 3), (2, 3, 4)), ("best", "top-1", "hfts-run-0"))
    with pytest.raises(OgcpError, match="indexes outside the 4-contact set"):
        plan_grasps(record, 4)
    with pytest.raises(OgcpError, match="must be a list of contact indices"):
        plan_grasps({"grasp": "0 1 2"}, 5)
