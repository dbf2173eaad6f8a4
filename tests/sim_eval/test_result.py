"""The ``ogcp.sim/2`` record: written by SimResult, read back by SimRecord (``/1`` too), leniently."""

from __future__ import annotations

import json
import math

import numpy as np

from ogcp.sim_eval import SIM_SCHEMA, GraspSimResult, SimGraspRecord, SimRecord, SimResult


def _grasp(label: str, measured: list[float], error: str | None = None) -> GraspSimResult:
    d = len(measured)
    return GraspSimResult(
        grasp=(3, 1, 7),
        label=label,
        q1=0.25,
        directions=np.eye(6)[:d],
        direction_labels=tuple(f"d{i}" for i in range(d)),
        predicted=np.linspace(1.0, 2.0, d),
        measured=np.array(measured),
        censored=np.arange(d) % 2 == 0,
        fidelity=np.abs(np.array(measured) / np.linspace(1.0, 2.0, d) - 1),
        gates={"valid": error is None, "creep": 1e-6},
        normal_forces=np.array([1.0, 2.0, 3.0]),
        surface_distance=np.array([0.0, 1e-4, 2e-4]),
        hold_tests={"weight": {"success": True, "axes": ["+z"], "passed": [True]}},
        error=error,
        predicted_planned=np.linspace(1.1, 2.1, d),
        realized={"points": [[0.0, 0.0, 0.0]] * 3, "offsets": [0.0, 1e-4, 0.0], "q1": 0.2, "q1_change": -0.2},
        collision={"threshold": 0.02, "offsets": [0.0, -1e-4, None], "within_tolerance": False},
    )


def _result() -> SimResult:
    return SimResult(
        object={"name": "box"},
        grasps=(_grasp("best", [1.5, 2.5, 1.0]), _grasp("random-1", [math.nan, 1.0, 2.0], error="diverged")),
        set_metrics={"n_valid": 1, "median_fidelity": 0.2, "holding_load": 3.0},
        settings={"directions": 3},
        decomposition={"method": "convex_hull"},
        wall_seconds=4.5,
        provenance={"git_commit": "abc"},
    )


def test_a_record_reads_back_what_was_written() -> None:
    result = _result()
    record = SimRecord.from_dict(json.loads(json.dumps(result.to_dict(), allow_nan=False)))
    assert record.schema == SIM_SCHEMA and record.object == {"name": "box"} and record.wall_seconds == 4.5
    assert record.set_metrics == result.set_metrics and record.settings == {"directions": 3}
    assert record.decomposition == {"method": "convex_hull"} and record.provenance == {"git_commit": "abc"}
    for written, read in zip(result.grasps, record.grasps, strict=True):
        assert (read.label, read.grasp, read.q1, read.error) == (written.label, written.grasp, 0.25, written.error)
        assert read.valid == written.valid and read.gates == written.gates and read.hold_tests == written.hold_tests
        assert read.direction_labels == written.direction_labels
        np.testing.assert_array_equal(read.directions, written.directions)
        assert read.realized == written.realized and read.collision == written.collision
        assert (read.q1_realized, read.q1_change) == (0.2, -0.2)
        for name in ("predicted", "predicted_planned", "measured", "fidelity", "normal_forces", "surface_distance"):
            np.testing.assert_array_equal(getattr(read, name), getattr(written, name))  # NaN read back as NaN
        np.testing.assert_array_equal(read.censored, written.censored)
        for name in ("predicted_min", "median_fidelity"):
            assert read.__getattribute__(name) == getattr(written, name)
    assert record.grasps[0].measured_min == 1.0 and record.grasps[1].measured_min is None  # not all measured


def test_partial_and_hand_written_records_read_leniently() -> None:
    record = SimRecord.from_dict({"grasps": [{"label": "best", "valid": True, "measured_min": 2}, "junk", 3]})
    assert record.schema is None and record.object == {} and record.wall_seconds is None
    (grasp,) = record.grasps
    assert (grasp.label, grasp.valid, grasp.measured_min, grasp.grasp, grasp.q1) == ("best", True, 2.0, None, None)
    assert grasp.measured.shape == (0,) and grasp.directions.shape == (0, 6) and grasp.censored.dtype == bool
    odd = SimGraspRecord.from_dict({"valid": "yes", "measured": [1, None, "x"], "measured_min": True})
    assert odd.label == "None" and odd.valid is None and odd.measured_min is None
    np.testing.assert_array_equal(odd.measured, [1.0, np.nan, np.nan])
    assert SimRecord.from_dict({"grasps": "none"}).grasps == ()


def test_a_sim_1_record_reads_with_its_tips_at_the_planned_contacts() -> None:
    """In ``/1`` the tips started at the planned contacts: the prediction is the planned one too."""
    old = {"schema": "ogcp.sim/1", "grasps": [{"label": "best", "predicted": [1.0, 2.0], "q1": 0.3}]}
    record = SimRecord.from_dict(old)
    (grasp,) = record.grasps
    assert record.schema == "ogcp.sim/1"
    np.testing.assert_array_equal(grasp.predicted_planned, [1.0, 2.0])
    assert grasp.realized == {} and grasp.collision == {} and grasp.q1_realized is None and grasp.q1_change is None
