"""evaluate reports a contact the simulated fingertip cannot touch instead of simulating another grasp."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.benchmarks.cli.simulate import sim_summary
from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import sample_contacts
from ogcp.planner.grasp.reach import DEFAULT_TIP_RADIUS_RATIO, default_tip_radius, reachable
from ogcp.sim_eval import GraspEvaluator, SimSettings
from ogcp.sim_eval.decomposition import Decomposition, DecompositionSettings
from ogcp.sim_eval.result import SimRecord
from tests.planner.grasp.test_reach import SLOT, in_slot, u_bracket

TIP = 0.8 * SLOT  # wider than half the slot: no tip this size touches its floor or inner walls
HULL = DecompositionSettings(method="convex_hull")


def _parts(mesh) -> Decomposition:
    return Decomposition([(np.asarray(mesh.vertices), np.asarray(mesh.faces))], {"method": "convex_hull"})


def test_the_simulation_default_tip_is_the_planner_s():
    assert SimSettings().tip_radius_ratio == DEFAULT_TIP_RADIUS_RATIO == 0.04
    mesh = builtin_mesh("donut")
    assert default_tip_radius(mesh) == pytest.approx(0.04 * np.linalg.norm(np.ptp(mesh.vertices, axis=0)))


def test_a_grasp_with_a_contact_in_a_slot_narrower_than_the_tip_is_reported_not_simulated():
    mesh = u_bracket()
    contacts = sample_contacts(mesh, 200, seed=0)  # plain sampling: the slot is sampled too
    slot = np.flatnonzero(in_slot(contacts.positions))
    outside = np.flatnonzero(reachable(mesh, contacts.positions, contacts.normals, TIP))
    assert len(slot) and len(outside) >= 3
    grasp = (int(outside[0]), int(slot[0]), int(outside[1]))
    settings = SimSettings(tip_radius=TIP, directions=0, threads=1)
    result = GraspEvaluator(settings, HULL).evaluate(mesh, contacts, [grasp], ["best"], parts=_parts(mesh))
    (g,) = result.grasps
    assert not g.valid and g.unreachable == (1,)
    assert g.error is not None and g.error.startswith(f"unreachable contact: finger 1 on contact {slot[0]} at [")
    assert f"radius {TIP:.4g} m" in g.error and "--tip-radius" in g.error
    assert len(g.measured) == 0 and len(g.normal_forces) == 0  # never simulated
    assert g.gates == {"valid": False, "reachable": False, "tip_radius": TIP}
    assert result.set_metrics["n_unreachable"] == 1 and result.set_metrics["n_valid"] == 0
    record = result.to_dict()
    assert record["grasps"][0]["unreachable"] == [1] and record["grasps"][0]["valid"] is False
    read = SimRecord.from_dict(record)
    assert read.grasps[0].unreachable == (1,) and read.grasps[0].error == g.error
    assert "UNREACHABLE unreachable contact: finger 1" in sim_summary(record)
    assert "(1 unreachable, not simulated)" in sim_summary(record)


def test_records_without_the_key_read_as_reachable():
    assert SimRecord.from_dict({"grasps": [{"label": "best", "grasp": [0, 1]}]}).grasps[0].unreachable == ()


def test_contacts_sampled_for_the_simulated_tip_are_all_simulated():
    mesh = builtin_mesh("box")
    contacts = sample_contacts(mesh, 30, seed=0, tip_radius=default_tip_radius(mesh))
    settings = SimSettings(directions=0, threads=1)
    result = GraspEvaluator(settings, HULL).evaluate(mesh, contacts, [(0, 10, 20)], parts=_parts(mesh))
    assert result.grasps[0].unreachable == () and result.grasps[0].error is None
    assert result.set_metrics["n_unreachable"] == 0
