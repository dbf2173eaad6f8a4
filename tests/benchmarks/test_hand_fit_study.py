"""The hands study prints its table row and where each case's hand trials spent their time."""

from __future__ import annotations

import json


def test_the_study_writes_rows_with_each_phases_seconds(tmp_path, capsys, monkeypatch):
    from ogcp.benchmarks.studies import hand_fit

    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    args = ["--cases", "sdh:box:3", "--contacts", "24", "--seeds", "1", "--directions", "2", "--out", str(out)]
    hand_fit.main(args)
    text = capsys.readouterr().out
    assert "| sdh, box, 3 |" in text
    assert "sdh, box: median s of the grasps valid with both: fit " in text and ", protocol " in text
    assert ", ramps " in text and "the hand's ramps alone / tips trial " in text
    assert "sdh, box: censored ramps (held past their end, left out of the fidelity), median share" in text
    (row,) = json.loads((out / "hand_fit.json").read_text())["cases"][0]["rows"]
    assert row["realised"] and set(row["hand_phase_seconds"]) == {"fit", "close", "protocol", "ramps"}
    assert row["unrealised_because"] is None and "not realised:" not in text
    for side in ("hand", "tips"):  # a share where the grasp is valid, else none
        assert (row[f"{side}_censored"] is None) != row[f"{side}_valid"]
        assert row[f"{side}_censored"] is None or 0.0 <= row[f"{side}_censored"] <= 1.0
    assert (out / "tips_vs_hand.pdf").exists()


def test_a_seed_without_a_grasp_the_hand_reaches_is_recorded_and_the_study_goes_on(tmp_path, capsys, monkeypatch):
    from ogcp.benchmarks.studies import hand_fit

    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    args = ["--cases", "sdh:box:3", "--contacts", "12", "--seeds", "1", "--diagonal", "2.0", "--out", str(out)]
    hand_fit.main(args)  # a 2 m box: wider than the SDH opens
    assert "| sdh, box, 3 | 0.00% | 0 of 1 (1 without a grasp) |" in capsys.readouterr().out
    (row,) = json.loads((out / "hand_fit.json").read_text())["cases"][0]["rows"]
    assert row["planned"] is False and "no grasp satisfies the constraints" in row["error"]


def test_with_realise_a_grasp_the_fit_leaves_short_is_planned_again(tmp_path, capsys, monkeypatch):
    """The first fit is made to fail: the row's grasp is the next plan's, and it counts one rejected."""
    import dataclasses

    from ogcp.benchmarks.studies import hand_fit
    from ogcp.sim_eval.evaluate import GraspEvaluator

    real, calls = GraspEvaluator.fit_hand, []

    def first_fails(self, mesh, contacts, grasp, parts=None):
        fit = real(self, mesh, contacts, grasp, parts)
        calls.append(tuple(grasp))
        return dataclasses.replace(fit, residuals=fit.residuals + 0.01) if len(calls) == 1 else fit

    monkeypatch.setattr(GraspEvaluator, "fit_hand", first_fails)
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    args = ["--cases", "sdh:box:3", "--contacts", "24", "--seeds", "1", "--directions", "0", "--realise", "3"]
    hand_fit.main([*args, "--out", str(out)])
    capsys.readouterr()
    (row,) = json.loads((out / "hand_fit.json").read_text())["cases"][0]["rows"]
    assert row["rejected"] == 1 and len(calls) == 2 and tuple(row["grasp"]) == calls[1] != calls[0]
    assert row["realised"]


def test_the_study_says_why_the_fit_left_grasps_unrealised():
    from ogcp.benchmarks.studies.hand_fit import unrealised_line

    reason = "finger index cannot reach its contact: 3.27 mm off (tolerance 1 mm)"
    rows = [
        {"unrealised_because": None},
        {"unrealised_because": reason},
        {"planned": False, "unrealised_because": None},
    ]
    case = {"hand": "ability", "object": "box", "rows": rows}
    assert unrealised_line(case) == f"ability, box: not realised: {reason}"
    assert unrealised_line({**case, "rows": rows[:1]}) is None
