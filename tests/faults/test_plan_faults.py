"""Edited plans: every field that defines the problem is checked against the rebuilt one.

One real plan (``ogcp plan box -n 30 --json``) is made per module; each test edits a copy of it
and expects the refusal that names the edited field with its recorded and rebuilt values.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from ogcp.planner.grasp.contact_set import sample_contacts
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.plan import contact_set_record
from ogcp.planner.search.grasp_planner import GraspPlanner
from ogcp.sim_eval.inputs.plan_input import plan_input

REFUSAL = "the plan does not match its problem: "
Edit = Callable[[dict[str, Any]], None]


def _cli(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ogcp.benchmarks.cli", *argv], capture_output=True, text=True, timeout=300, check=False
    )


@pytest.fixture(scope="module")
def box_plan() -> dict[str, Any]:
    run = _cli("plan", "box", "-n", "30", "--json")
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def _api_plan(spec: str, n: int = 30) -> dict[str, Any]:
    """A plan made through the API the way ``ogcp plan`` makes it (default tip radius)."""
    mesh, source = resolve_object(spec)
    contacts = sample_contacts(mesh, n, 0, source=source, tip_radius=default_tip_radius(mesh))
    return GraspPlanner().plan(contacts, 3).to_dict(contact_set_record(contacts))


def _both(key: str, value: Any) -> Edit:
    """Edit one key of the contact source in both places a search plan records it."""

    def edit(record: dict[str, Any]) -> None:
        record["contact_set"]["source"][key] = value
        record["source"][key] = value

    return edit


def _set(path: str, value: Any) -> Edit:
    *parents, last = path.split(".")

    def edit(record: dict[str, Any]) -> None:
        node = record
        for part in parents:
            node = node[part]
        node[last] = value

    return edit


def _refused(record: dict[str, Any]) -> str:
    with pytest.raises(OgcpError) as info:
        plan_input(record)
    message = str(info.value)
    assert "\n" not in message
    return message


def test_the_unedited_plan_is_accepted(box_plan):
    plan = plan_input(copy.deepcopy(box_plan))
    assert plan.grasps[0] == tuple(box_plan["grasp"]) and len(plan.contacts) == 30


def _nudge_normal(record: dict[str, Any]) -> None:
    record["contacts"]["normals"][1][0] += 0.01


EDITS: dict[str, tuple[Edit, str]] = {
    "normal": (_nudge_normal, "inward normal of contact {g1} recorded [0.01, 1, 0], rebuilt [0, 1, 0]"),
    "mu": (_set("contact_set.mu", 0.8), "mu recorded 0.8, but its q1 and q_ows fit mu 0.5"),
    "cone_edges": (_set("contact_set.cone_edges", 6), "cone_edges recorded 6, but its q1 and q_ows fit cone_edges 8"),
    "torsional_friction": (
        _set("contact_set.torsional_friction", 0.01),
        "torsional_friction recorded 0.01, but its q1 and q_ows fit torsional_friction 0",
    ),
    "rho": (_set("contact_set.torque_scale", 0.12), "torque scale rho [m] recorded 0.12, rebuilt 0.1;"),
    "com": (_set("contact_set.com", [0.001, 0.0, 0.0]), "centre of mass [m] recorded [0.001, 0, 0], rebuilt [0, 0, 0]"),
    "size": (_set("contact_set.size", 31), "contact set size recorded 31, rebuilt 30"),
    "q1": (_set("q1", 0.2), "q1 of the best grasp recorded 0.2, rebuilt {q1:.12g};"),
    "q_ows": (_set("q_ows", 0.6), "q_ows of the contact set recorded 0.6, rebuilt {q_ows:.12g};"),
    "diagonal": (_both("diagonal", 0.3), "diagonal [m] recorded 0.3, but its torque scale rho 0.1 m (rebuilt 0.15 m)"),
    "seed": (_both("seed", 1), "(the plan's contacts are not on the object as re-sampled: were n, seed or tip_radius"),
    "n": (_both("n", 40), "contact set size recorded 30, rebuilt 40 (sampled with n = 40)"),
    "object": (_both("name", "sphere"), "torque scale rho [m] recorded 0.1, rebuilt 0.0577350269"),
}


@pytest.mark.parametrize("field", sorted(EDITS))
def test_an_edited_field_is_refused_by_name(box_plan, field):
    record = copy.deepcopy(box_plan)
    edit, expected = EDITS[field]
    edit(record)
    message = _refused(record)
    assert message.startswith(REFUSAL), message
    assert expected.format(g1=box_plan["grasp"][1], q1=box_plan["q1"], q_ows=box_plan["q_ows"]) in message, message


def test_friction_model_changed_away_from_the_defaults_names_both_fields(box_plan):
    record = copy.deepcopy(box_plan)
    record["contact_set"].update(mu=0.7, cone_edges=6)
    message = _refused(record)
    recorded = f"[{box_plan['q1']:.12g}, {box_plan['q_ows']:.12g}]"
    assert message.startswith(f"{REFUSAL}(q1, q_ows) recorded {recorded}, rebuilt ["), message
    assert (
        "recomputed with the recorded mu 0.7, cone_edges 6 and torsional_friction 0: was one of them changed?"
        in message
    )


@pytest.mark.parametrize("key, value", [("diagonal", 0.3), ("tip_radius", 0.02)])
def test_the_two_copies_of_the_source_must_agree(box_plan, key, value):
    record = copy.deepcopy(box_plan)
    record["contact_set"]["source"][key] = value
    message = _refused(record)
    assert message.startswith(f"the plan records its contact source twice, differently: {key} is {value:g} in ")


def test_a_changed_mesh_file_is_refused_by_its_sha256(tmp_path):
    path = tmp_path / "box.obj"
    resolve_object("box")[0].export(path)
    record = _api_plan(str(path))
    assert plan_input(record).grasps[0] == tuple(record["grasp"])
    recorded = record["contact_set"]["source"]["sha256"]
    with path.open("a") as handle:
        handle.write("# edited after planning\n")
    message = _refused(record)
    assert message.startswith(f"{REFUSAL}object sha256 recorded '{recorded}', rebuilt '"), message
    assert f"the plan's mesh {path} changed since planning" in message


def test_a_changed_tip_radius_on_a_concave_object_is_refused():
    record = _api_plan("amphora", 60)
    assert plan_input(record).grasps[0] == tuple(record["grasp"])
    _both("tip_radius", 3 * record["source"]["tip_radius"])(record)
    message = _refused(record)
    # A larger tip reaches fewer places: other contacts are drawn, so the best grasp's move.
    assert message.startswith(REFUSAL + "position [m] of contact "), message
    assert "were n, seed or tip_radius changed?" in message


def test_cli_evaluate_refuses_an_edited_plan_in_one_line(box_plan, tmp_path):
    record = copy.deepcopy(box_plan)
    record["contact_set"]["mu"] = 0.8
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(record))
    run = _cli("evaluate", str(path))
    assert run.returncode == 2, run.stderr
    assert run.stderr.startswith("ogcp: error: " + REFUSAL + "mu recorded 0.8, but its q1 and q_ows fit mu 0.5")
    assert run.stderr.count("\n") == 1 and "Traceback" not in run.stderr
    assert Path(path).read_text() == json.dumps(record)


@pytest.mark.parametrize("max_grasps", [0, -1, 1.5, True])
def test_evaluate_plan_refuses_a_grasp_count_below_one(max_grasps):
    """The API refuses what the CLI's --max-grasps refuses: 0 grasps would be a run that does nothing."""
    from ogcp.sim_eval.evaluate import evaluate_plan

    with pytest.raises(OgcpError, match="max_grasps must be an integer >= 1"):
        evaluate_plan({}, max_grasps=max_grasps)
