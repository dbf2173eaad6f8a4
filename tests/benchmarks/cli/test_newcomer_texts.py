"""Texts a newcomer reads: help that names real commands and defaults, and a certificate that says "optimal" when it is."""

from __future__ import annotations

import dataclasses

import pytest

from ogcp.benchmarks.cli import main
from ogcp.benchmarks.cli.plan_summary import search_summary
from ogcp.planner import GraspPlanner, builtin_mesh
from ogcp.planner.grasp import sample_contacts


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
