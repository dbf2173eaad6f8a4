"""``ogcp plan --realise N``: planned grasps the hand cannot realise are excluded and the plan made again."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.sim_eval.evaluate import GraspEvaluator

GRIPPER = ["box", "-n", "40", "-m", "2", "--diagonal", "0.08", "--contact-model", "soft", "--hand", "parallel_gripper"]


def _run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = main(argv)
        except SystemExit as exit_:  # argparse's own refusals (a count below 1)
            status = int(exit_.code or 0)
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["plan", "box", "-n", "20", "--realise", "2"], "--realise needs --hand"),
        (["plan", *GRIPPER, "--method", "hfts", "--realise", "2"], "--realise applies to astar, wastar, dijkstra, es"),
        (["plan", *GRIPPER, "--realise", "51"], "--realise takes at most 50 plans"),
        (["plan", *GRIPPER, "--realise", "0"], "expected an integer >= 1"),
    ],
)
def test_realise_is_refused_in_one_line_where_it_cannot_apply(argv, message):
    status, _, err = _run(argv)
    assert status == 2 and message in err and err.count("\n") == 1, err


def test_a_grasp_the_hand_cannot_realise_is_excluded_and_the_plan_made_again(tmp_path, monkeypatch):
    """The first fit is made to fail (its residuals 10 mm): the second plan is the best other grasp,
    realised, and the record says which grasp was rejected and why."""
    real = GraspEvaluator.fit_hand
    calls: list[tuple[int, ...]] = []

    def first_fails(self, mesh, contacts, grasp, parts=None):
        fit = real(self, mesh, contacts, grasp, parts)
        calls.append(tuple(sorted(grasp)))
        return dataclasses.replace(fit, residuals=fit.residuals + 0.01) if len(calls) == 1 else fit

    monkeypatch.setattr(GraspEvaluator, "fit_hand", first_fails)
    once, again = tmp_path / "once.json", tmp_path / "again.json"
    assert _run(["plan", *GRIPPER, "-o", str(once)])[0] == 0
    status, out, err = _run(["plan", *GRIPPER, "--realise", "3", "-o", str(again)])
    assert status == 0, err
    first, record = json.loads(once.read_text()), json.loads(again.read_text())
    block = record["realise"]
    assert block["attempts"] == 2 and block["realised"] and len(calls) == 2
    (rejected,) = block["rejected"]
    assert rejected["grasp"] == sorted(first["grasp"]) and "cannot reach its contact" in rejected["reason"]
    assert sorted(record["grasp"]) != rejected["grasp"] and record["q1"] <= first["q1"] + 1e-12
    assert "planning again without it" in err and "realise: plan 2 realised by the hand's fit" in out
    # The plan it returns is simulated like any other.
    status, _, err = _run(["evaluate", str(again), "--directions", "0", "--decomposition", "convex_hull"])
    assert status == 0, err


def test_a_grasp_realised_at_once_needs_one_plan(tmp_path):
    path = tmp_path / "p.json"
    status, _, err = _run(["plan", *GRIPPER, "--realise", "3", "-o", str(path)])
    assert status == 0, err
    block = json.loads(path.read_text())["realise"]
    assert block == {"attempts": 1, "realised": True, "rejected": []}
    assert np.isfinite(json.loads(path.read_text())["q1"])
