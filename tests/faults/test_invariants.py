"""No result ever has Q1 > Q_OWS, Q1 > bound or bound > Q_OWS: every method's result is refused first.

Real results of every method are made on a small contact set, then copied with an impossible
value: the copy is refused where it is built (the result's constructor) and where its record
is built (``plan_record``), in one line naming the values.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from ogcp.planner import builtin_mesh
from ogcp.planner.baselines import HFTS, ExhaustiveSearch
from ogcp.planner.grasp import sample_contacts
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.plan import RESULT_RTOL, check_result, contact_set_record, plan_record
from ogcp.planner.search import GraspPlanner


@pytest.fixture(scope="module")
def contacts() -> ContactSet:
    return sample_contacts(builtin_mesh("amphora"), 14, seed=1)


@pytest.fixture(scope="module")
def results(contacts: ContactSet) -> dict[str, Any]:
    """One real result of every method."""
    return {
        "astar": GraspPlanner(method="astar").plan(contacts, 3),
        "wastar": GraspPlanner(method="wastar", eps=0.5).plan(contacts, 3),
        "dijkstra": GraspPlanner(method="dijkstra").plan(contacts, 3),
        "es": ExhaustiveSearch().run(contacts, 3),
        "es-pruned": ExhaustiveSearch(pruned=True).run(contacts, 3),
        "hfts": HFTS(runs=2, iterations=3, jobs=1).run(contacts, 3),
    }


METHODS = ["astar", "wastar", "dijkstra", "es", "es-pruned", "hfts"]


@pytest.mark.parametrize("method", METHODS)
def test_every_methods_real_result_passes_and_is_recorded(
    results: dict[str, Any], contacts: ContactSet, method: str
) -> None:
    result = results[method]
    record = result.to_dict(contact_set_record(contacts))
    assert record["method"] == method
    assert 0 <= record["q1"] <= record["bound"] <= record["q_ows"] * (1 + RESULT_RTOL)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("impossible", ["q1_above_q_ows", "q1_nan", "q_ows_negative"])
def test_an_impossible_copy_of_every_methods_result_is_refused(
    results: dict[str, Any], method: str, impossible: str
) -> None:
    result = results[method]
    changes = {
        "q1_above_q_ows": {"q1": result.q_ows * 1.35},
        "q1_nan": {"q1": math.nan},
        "q_ows_negative": {"q_ows": -1.0},
    }[impossible]
    with pytest.raises(OgcpError, match=rf"^impossible {method} result: ") as refused:
        dataclasses.replace(result, **changes)
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize("method", ["astar", "wastar", "dijkstra"])
def test_a_search_result_with_a_bound_out_of_order_is_refused(results: dict[str, Any], method: str) -> None:
    result = results[method]
    with pytest.raises(OgcpError, match=r"Q1 .* > bound "):
        dataclasses.replace(result, bound=result.q1 * 0.5)
    with pytest.raises(OgcpError, match=r"bound .* > Q_OWS "):
        dataclasses.replace(result, bound=result.q_ows * 1.01)


def _record(q1: float, q_ows: float, bound: float) -> dict[str, Any]:
    return plan_record("es", (0, 1, 2), q1, q_ows, bound, np.zeros((3, 3)), np.zeros((3, 3)), stats={}, config={})


@pytest.mark.parametrize(
    ("q1", "q_ows", "bound", "message"),
    [
        (0.9, 0.67, 0.9, r"Q1 0\.9 > Q_OWS 0\.67"),  # the report
        (0.5, 0.67, 0.4, r"Q1 0\.5 > bound 0\.4"),
        (0.5, 0.67, 0.7, r"bound 0\.7 > Q_OWS 0\.67"),
        (math.nan, 0.67, 0.67, r"Q1 = nan \(expected finite and >= 0\)"),
        (0.5, math.inf, 0.67, r"Q_OWS = inf"),
        (-0.1, 0.67, 0.67, r"Q1 = -0\.1"),
        (0.5, 0.67, None, r"bound is None, not a number"),
        (True, 0.67, 0.67, r"Q1 is True, not a number"),
    ],
)
def test_a_record_with_impossible_values_is_refused_in_one_line(q1: Any, q_ows: Any, bound: Any, message: str) -> None:
    with pytest.raises(OgcpError, match=rf"^impossible es result: {message}") as refused:
        _record(q1, q_ows, bound)
    assert "\n" not in str(refused.value)


def test_values_within_rounding_of_each_other_pass() -> None:
    q = 0.1775
    check_result("es", q * (1 + 0.5 * RESULT_RTOL), q, q * (1 + 0.5 * RESULT_RTOL))  # a last-bit difference
    check_result("astar", 0.0, 0.0, 0.0)  # no force closure anywhere
    check_result("hfts", np.float64(0.1), np.float64(0.2), 0.2)
    with pytest.raises(OgcpError):
        check_result("es", q * (1 + 3 * RESULT_RTOL), q, q * (1 + 3 * RESULT_RTOL))
    assert _record(0.1, 0.2, 0.15)["q1"] == 0.1
