"""Soft fingers in MuJoCo: condim 4, the pinch's torsion limit in closed form, and the LP of the same model."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.sim_eval import SimSettings
from ogcp.sim_eval.protocols.phases import ramp_trials, settle
from ogcp.sim_eval.protocols.predict import predicted_resistance
from ogcp.sim_eval.protocols.trial import contact_torsion
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.grasp_scene import build_scene
from tests.sim_eval.test_sim import _ramp as ramp_failure_load

F_MAX, MU, RHO = 10.0, 0.5, 0.1
TWIST = np.array([[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]])  # torque about the pinch axis x


def _pinch():
    box = trimesh.creation.box([0.1, 0.08, 0.06])
    return box, np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


def _scene(torsion: float):
    box, p, n = _pinch()
    settings = SimSettings(threads=1)
    com, inertia = object_inertia(box, settings.object_mass)
    return build_scene([(box.vertices, box.faces)], com, inertia, p, n, settings, MU, 0.008, torsion=torsion), settings


def test_soft_contacts_compile_to_condim_4_with_the_torsional_coefficient():
    soft, _ = _scene(0.01)
    hard, _ = _scene(0.0)
    assert set(soft.model.geom_condim[soft.tip_geoms]) == {4} and set(soft.model.geom_condim[soft.object_geoms]) == {4}
    np.testing.assert_allclose(soft.model.geom_friction[soft.tip_geoms], [[MU, 0.01, 0.0]] * 2)
    assert set(hard.model.geom_condim[hard.tip_geoms]) == {3} and soft.torsion == 0.01 and hard.torsion == 0.0


@pytest.mark.parametrize("torsion", [0.004, 0.02])
def test_a_soft_pinch_resists_torque_about_its_axis_up_to_two_gamma_f(torsion):
    # Each tip presses with F_max and resists a moment gamma F_max about its normal: 2 gamma F_max
    # about the axis, i.e. a disturbance of magnitude 2 gamma F_max / rho in the scaled wrench space.
    _, p, n = _pinch()
    closed_form = 2 * torsion * F_MAX / RHO
    predicted = predicted_resistance(p, n, np.zeros(3), RHO, MU, 32, F_MAX, TWIST, torsion).resistance[0]
    assert predicted == pytest.approx(closed_form, rel=1e-9)
    scene, settings = _scene(torsion)
    settled = settle(scene, settings)
    assert settled.gates["valid"], settled.gates
    trials = ramp_trials(
        scene,
        settled,
        TWIST,
        np.array([closed_form / settings.ramp_time]),
        settings.ramp_extent * settings.ramp_time,
        RHO,
        settings,
    )
    assert trials.failed[0] and trials.failure_load[0] == pytest.approx(closed_form, rel=0.05)


def test_the_hard_pinch_has_no_torsional_resistance_in_the_same_lp():
    _, p, n = _pinch()
    assert predicted_resistance(p, n, np.zeros(3), RHO, MU, 32, F_MAX, TWIST).resistance[0] == 0.0


def test_the_simulated_model_is_the_contact_sets_unless_overridden():
    _, p, n = _pinch()
    soft = ContactSet(p, -n, np.zeros(3), RHO, MU, 8, torsional_friction=0.01)
    hard = ContactSet(p, -n, np.zeros(3), RHO, MU, 8)
    assert contact_torsion(soft, SimSettings()) == 0.01 and contact_torsion(hard, SimSettings()) == 0.0
    assert contact_torsion(hard, SimSettings(torsional_friction=0.03)) == 0.03
    assert contact_torsion(soft, SimSettings(torsional_friction=0.0)) == 0.0
    assert contact_torsion(hard, SimSettings(protocol="dexgraspbench")) == 0.02


@pytest.mark.parametrize("torsion", [0.0, 0.01])
def test_the_hard_closed_forms_hold_for_both_models(torsion):
    # Pure forces need no moment about the normals: soft fingers resist what hard ones do.
    box, p, n = _pinch()
    for direction in ([0, 0, 1, 0, 0, 0], [0, -1, 0, 0, 0, 0]):
        measured = ramp_failure_load(box, p, n, direction, 2 * MU * F_MAX, torsion=torsion)
        assert measured == pytest.approx(2 * MU * F_MAX, rel=0.05)
        lp = predicted_resistance(p, n, np.zeros(3), RHO, MU, 32, F_MAX, np.array([direction], float), torsion)
        assert lp.resistance[0] == pytest.approx(2 * MU * F_MAX, rel=1e-3)
    assert ramp_failure_load(box, p, n, [1, 0, 0, 0, 0, 0], F_MAX, torsion=torsion) == pytest.approx(F_MAX, rel=0.05)
