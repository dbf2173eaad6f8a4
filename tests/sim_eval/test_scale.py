"""The simulation is scale-free: lengths at the 0.2 m reference diagonal, scaled with the object."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.planner.infra import OgcpError
from ogcp.sim_eval import GraspEvaluator, SimSettings
from ogcp.sim_eval.decomposition import Decomposition, DecompositionSettings
from ogcp.sim_eval.settings import LENGTH_SETTINGS, SERVO_MASSES

HULL = DecompositionSettings(method="convex_hull")


def test_scaled_settings_are_today_s_at_0_2_m_and_proportional_elsewhere():
    given = SimSettings()
    assert given.scaled(0.2) == given.with_updates(scale_lengths=False)  # bit for bit
    big = given.scaled(2.0)
    for name in LENGTH_SETTINGS:
        assert getattr(big, name) == pytest.approx(10 * getattr(given, name), rel=1e-12)
    for name in SERVO_MASSES:
        assert getattr(big, name) == pytest.approx(getattr(given, name) / 10, rel=1e-12)
    assert big.contact_solimp[2] == pytest.approx(10 * given.contact_solimp[2], rel=1e-12)
    assert big.object_mass == given.object_mass and big.max_normal_force == given.max_normal_force
    assert big.body_mass == pytest.approx(given.object_mass / 10.0, rel=1e-12)  # dynamics similar at any size
    assert big.scaled(2.0) == big  # scaled settings are absolute: scaling again changes nothing
    absolute = SimSettings.from_dict({"scale_lengths": False, "penetration_tolerance": 1e-3})
    assert absolute.scaled(2.0) == absolute  # explicit absolute metres at every size
    with pytest.raises(OgcpError, match="scale_lengths"):
        SimSettings(scale_lengths=1)  # type: ignore[arg-type]
    with pytest.raises(OgcpError, match="positive number of metres"):
        given.scaled(0.0)


def _three_tips(diagonal: float):
    """A box pinch with a third tip on the top face (force closure), scaled to ``diagonal``."""
    k = diagonal / float(np.linalg.norm([0.1, 0.08, 0.06]))
    box = trimesh.creation.box(np.array([0.1, 0.08, 0.06]) * k)
    p = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]]) * k
    n = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    contacts = ContactSet(p, n, np.zeros(3), 0.1 * k, 0.5, 8, {})
    parts = Decomposition(((np.asarray(box.vertices), np.asarray(box.faces)),), {"hull_count": 1})
    settings = SimSettings(directions=8, threads=2)
    return GraspEvaluator(settings, HULL).evaluate(box, contacts, [(0, 1, 2)], parts=parts)


def test_the_same_grasp_at_5_cm_0_2_m_and_2_m_gates_and_resists_alike():
    results = {d: _three_tips(d) for d in (0.05, 0.2, 2.0)}
    reference = results[0.2].grasps[0]
    for diagonal, result in results.items():
        grasp = result.grasps[0]
        assert grasp.valid and not grasp.gates["diverged"] and grasp.gates["tips_in_contact"] == 3
        # Measured in scaled wrench units (torques / rho, rho ~ size): the same numbers at any size.
        ratio = grasp.measured / reference.measured
        assert np.nanmedian(ratio) == pytest.approx(1.0, abs=0.01), (diagonal, ratio)
        record = result.to_dict()["settings"]
        assert record["length_scale"] == pytest.approx(diagonal / 0.2, rel=1e-9)
        assert record["penetration_tolerance"] == 1e-3  # the given setting, at the reference size
        assert record["scaled_lengths"]["penetration_tolerance"] == pytest.approx(1e-3 * diagonal / 0.2, rel=1e-9)
