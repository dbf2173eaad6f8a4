"""The ``ogcp.plan/1`` record read through PlanView: every method's record round trips; gaps read as None."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ogcp.planner.baselines.es import ExhaustiveSearch
from ogcp.planner.baselines.hfts import HFTS
from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.hands.reachability import SDHReachability
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.plan import PlanView, add_hand, add_optimum, contact_set_record, hand_record
from ogcp.planner.search.grasp_planner import GraspPlanner


@pytest.fixture(scope="module")
def contacts() -> ContactSet:
    mesh, source = resolve_object("box")
    return sample_contacts(mesh, 12, 3, 0.7, 6, source)


def _as_written(record: dict) -> dict:
    """The record as a JSON file holds it (NaN as null, as the suite writes it)."""
    return json.loads(json.dumps(record).replace("NaN", "null"))


def test_a_search_record_reads_back(contacts):
    result = GraspPlanner(method="wastar", eps=0.5, record_tree=True).plan(contacts, 3)
    record = _as_written(result.to_dict(contact_set_record(contacts)))
    view = PlanView(record)
    assert (view.method, view.grasp) == ("wastar", tuple(result.grasp))
    assert (view.q1, view.q_ows, view.bound) == (result.q1, result.q_ows, result.bound)
    assert (view.eps, view.eps_bound) == (0.5, result.eps_bound)
    assert view.stats == record["stats"] and view.stats["visited"] == result.stats.visited
    assert (view.cpu_seconds, view.wall_seconds) == (result.stats.cpu_seconds, result.stats.wall_seconds)
    assert view.tree == record["tree"] and view.tree["parent"][0] in (-1, None)
    assert (view.histogram, view.run_q1s, view.hand, view.optimum) == (None, (), None, None)


def test_an_exhaustive_record_reads_its_histogram(contacts):
    result = ExhaustiveSearch(bins=8).run(contacts, 3)
    view = PlanView(_as_written(result.to_dict()))
    histogram = view.histogram
    assert histogram is not None and (view.method, view.q1, view.eps) == ("es", result.q1, 0.0)
    assert histogram.bin_edges.tolist() == result.bin_edges.tolist()
    assert histogram.counts.tolist() == result.counts.tolist()
    assert (histogram.zero, histogram.force_closure_fraction) == (result.zero, result.force_closure_fraction)
    assert view.cpu_seconds == result.cpu_seconds


def test_an_hfts_record_reads_its_runs_optimum_and_hand(contacts, tmp_path):
    result = HFTS(runs=3, iterations=5).run(contacts, 3)
    optimum = GraspPlanner().plan(contacts, 3)
    hand = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
    record = add_hand(add_optimum(result.to_dict(), optimum.method, optimum.grasp, optimum.q1), hand, contacts)
    view = PlanView(_as_written(record))
    assert (
        view.run_q1s == tuple(r.q1 for r in result.runs) and view.bound == result.q_ows
    )  # a heuristic certifies nothing
    assert view.optimum is not None and view.optimum.method == "astar"
    assert (view.optimum.grasp, view.optimum.q1) == (tuple(optimum.grasp), optimum.q1)
    written = hand_record(hand, result.grasp, contacts)
    assert view.hand is not None and (view.hand.name, view.hand.residual) == (written["name"], written["residual"])
    assert list(view.hand.joint_angles) == written["joint_angles"]
    assert list(view.hand.finger_contacts) == written["finger_contacts"]


def test_missing_keys_read_as_none_or_empty():
    view = PlanView({})
    assert [view.method, view.grasp, view.q1, view.q_ows, view.bound, view.eps, view.eps_bound] == [None] * 7
    assert (view.stats, view.cpu_seconds, view.wall_seconds) == ({}, None, None)
    assert (view.histogram, view.run_q1s, view.tree, view.hand, view.optimum) == (None, (), None, None, None)


@pytest.mark.parametrize(
    ("record", "field", "expected"),
    [
        ({"q1": None}, "q1", None),  # NaN as JSON writes it
        ({"q1": math.nan}, "q1", None),
        ({"q_ows": "0.3"}, "q_ows", None),
        ({"bound": True}, "bound", None),
        ({"q1": 2}, "q1", 2.0),
        ({"grasp": [0, True, 2]}, "grasp", None),
        ({"grasp": "0 1 2"}, "grasp", None),
        ({"stats": [1, 2]}, "stats", {}),
        ({"stats": {"cpu_seconds": "fast"}}, "cpu_seconds", None),
        ({"stats": {"wall_seconds": 3}}, "wall_seconds", 3.0),
        ({"runs": [{"q1": 0.1}, 7, {"q1": None}, {}]}, "run_q1s", (0.1, None, None)),
        ({"runs": {"q1": 0.1}}, "run_q1s", ()),
        ({"tree": [1, 2]}, "tree", None),
        ({"hand": "sdh"}, "hand", None),
        ({"optimum": {"q1": "x"}}, "optimum.q1", None),
        ({"histogram": {"bin_edges": [0, 1], "counts": [1, 2]}}, "histogram", None),
        ({"histogram": {"bin_edges": [0, 1], "counts": []}}, "histogram", None),
        ({"histogram": {"bin_edges": "x", "counts": [1]}}, "histogram", None),
        ({"histogram": {"bin_edges": [0, 1], "counts": [4], "zero": 1.5}}, "histogram.zero", None),
        ({"histogram": {"bin_edges": [0, 1], "counts": [4]}}, "histogram.force_closure_fraction", None),
    ],
)
def test_values_of_the_wrong_type_read_as_none(record, field, expected):
    value: object = PlanView(record)
    for name in field.split("."):
        value = getattr(value, name)
    assert value == expected if not isinstance(value, np.ndarray) else value.tolist() == expected
