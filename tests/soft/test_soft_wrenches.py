"""Soft-finger wrenches: the linearisation, its error bound, and the contact set's model."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, q1, sample_contacts
from ogcp.planner.grasp.contact_model import torsion_of
from ogcp.planner.grasp.wrench import contact_wrenches, primitives_per_contact, soft_directions, soft_inradius
from ogcp.planner.infra import OgcpError
from tests.conftest import q1_by_facet_enumeration

POSITIONS = np.array([[0.05, 0.01, -0.02], [-0.03, 0.04, 0.0]])
NORMALS = np.array([[-1.0, 0.0, 0.0], [0.0, -0.6, 0.8]])


@pytest.mark.parametrize("k", [3, 4, 8, 13, 16])
def test_soft_primitives_start_with_the_hard_edges_bit_for_bit(k):
    hard = contact_wrenches(POSITIONS, NORMALS, np.zeros(3), 0.1, 0.5, k)
    soft = contact_wrenches(POSITIONS, NORMALS, np.zeros(3), 0.1, 0.5, k, 0.02)
    assert soft.shape == (2, primitives_per_contact(k, 0.02), 6)
    assert np.array_equal(soft[:, :k], hard)
    assert np.array_equal(contact_wrenches(POSITIONS, NORMALS, np.zeros(3), 0.1, 0.5, k, 0.0), hard)


@pytest.mark.parametrize("dense", [False, True])
@pytest.mark.parametrize("k", [4, 8, 16, 32])
def test_linearisation_is_inscribed_in_the_elliptic_set(k, dense):
    d = soft_directions(k, dense)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)  # on the unit ball: never optimistic
    assert len(np.unique(np.round(d, 12), axis=0)) == len(d)
    # Unit normal force: tangential force mu (x, y), torsion gamma z, all on the ellipsoid's surface.
    n, mu, gamma = np.array([[0.0, 0.0, 1.0]]), 0.4, 0.03
    w = contact_wrenches(np.zeros((1, 3)), n, np.zeros(3), 1.0, mu, k, gamma, dense=dense)[0]
    assert np.allclose(w[:, 2], 1.0)
    tangential = np.linalg.norm(w[:, :2], axis=1) / mu
    torsion = w[:, 5] - 0.0  # the arm is zero: the moment is the torsion alone
    np.testing.assert_allclose(tangential**2 + (torsion / gamma) ** 2, 1.0, atol=1e-12)


def test_documented_inradii():
    # The error statement of ogcp.planner.grasp.wrench: the soft set contains the exact one scaled by r.
    assert [round(soft_inradius(k), 3) for k in (8, 12, 16, 64)] == [0.816, 0.877, 0.898, 0.922]
    assert soft_inradius(32, dense=True) > 0.99
    # A point at r times any unit direction lies inside the hull: check against random directions.
    rng = np.random.default_rng(0)
    u = rng.normal(size=(2000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    from scipy.spatial import ConvexHull

    hull = ConvexHull(soft_directions(8))
    inside = (u * soft_inradius(8)) @ hull.equations[:, :3].T + hull.equations[:, 3]
    assert np.all(inside <= 1e-12)


def test_two_soft_fingers_can_be_in_force_closure_hard_ones_never():
    box = builtin_mesh("box")
    hard = sample_contacts(box, 24, seed=3)
    soft = sample_contacts(box, 24, seed=3, torsional_friction=0.02)
    assert np.array_equal(hard.positions, soft.positions)
    pairs = list(itertools.combinations(range(24), 2))
    assert all(q1(hard.subset_wrenches(np.array(p))) == 0.0 for p in pairs)
    values = [q1(soft.subset_wrenches(np.array(p))) for p in pairs]
    assert max(values) > 0.05
    # Soft contacts add wrenches: Q1 never drops (hard grasps' hulls are inside the soft ones).
    for g in itertools.islice(itertools.combinations(range(24), 3), 0, 400, 7):
        assert q1(soft.subset_wrenches(np.array(g))) >= q1(hard.subset_wrenches(np.array(g))) - 1e-12


def test_soft_q1_agrees_with_facet_enumeration():
    # Two soft contacts with k = 3: 2 x 9 = 18 wrenches, few enough to enumerate every facet.
    n = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    p = np.array([[0.05, 0.0, 0.0], [-0.05, 0.01, 0.0]])
    contacts = ContactSet(p, n, np.zeros(3), 0.1, 0.5, 3, torsional_friction=0.02)
    w = contacts.wrenches.reshape(-1, 6)
    assert q1(w) == pytest.approx(q1_by_facet_enumeration(w), abs=1e-9) and q1(w) > 0


def test_the_model_round_trips_and_hard_sets_are_written_as_before(tmp_path):
    box = builtin_mesh("box")
    soft = sample_contacts(box, 10, seed=0, torsional_friction=0.01)
    assert soft.contact_model == "soft" and soft.to_dict()["torsional_friction"] == 0.01
    soft.save(tmp_path / "c.json")
    again = ContactSet.load(tmp_path / "c.json")
    assert again.torsional_friction == 0.01 and np.array_equal(again.wrenches, soft.wrenches)
    hard = sample_contacts(box, 10, seed=0)
    assert hard.contact_model == "hard" and "torsional_friction" not in hard.to_dict()
    data = json.loads((tmp_path / "c.json").read_text())
    data["torsional_friction"] = -0.1
    with pytest.raises(OgcpError, match="torsional_friction"):
        ContactSet.from_dict(data)


@pytest.mark.parametrize(
    "model,torsion,expected",
    [(None, None, 0.0), ("hard", None, 0.0), ("soft", None, 0.02), ("soft", 0.005, 0.005), (None, 0.01, 0.01)],
)
def test_contact_model_resolution(model, torsion, expected):
    assert torsion_of(model, torsion) == expected


@pytest.mark.parametrize(
    "model,torsion,message",
    [
        ("hard", 0.01, "needs the soft contact model"),
        ("soft", 0.0, "need a torsional friction coefficient > 0"),
        ("rubber", None, "hard, soft"),
        ("soft", 1e9, "valid: 0 to 100"),
        ("soft", float("nan"), "expected a number"),
    ],
)
def test_bad_contact_models_are_one_line_errors(model, torsion, message):
    with pytest.raises(OgcpError, match=message):
        torsion_of(model, torsion)


@pytest.mark.parametrize(
    "fields,message",
    [
        ({"contact_model": "squishy"}, "f.json: contact_model 'squishy'; valid choices: hard, soft"),
        ({"torsional_friction": "a lot"}, "f.json: torsional_friction: expected a number"),
        ({"contact_model": "hard", "torsional_friction": 0.01}, "f.json: torsional_friction: a torsional"),
    ],
)
def test_a_grasps_record_names_the_bad_model_field(fields, message):
    from ogcp.planner.records.grasps import ExternalGrasps

    pinch = [{"position": [x, 0.0, 0.0], "normal": [-x / abs(x), 0.0, 0.0]} for x in (0.05, -0.05)]
    record = {"schema": "ogcp.grasps/1", "object": {"mesh": "box"}, "mu": 0.5, "grasps": [{"contacts": pinch}]}
    assert ExternalGrasps.from_dict(record, "f.json").torsional_friction == 0.0
    soft = ExternalGrasps.from_dict({**record, "contact_model": "soft"}, "f.json")
    assert soft.torsional_friction == 0.02 and soft.to_dict()["contact_model"] == "soft"
    with pytest.raises(OgcpError, match=message):
        ExternalGrasps.from_dict({**record, **fields}, "f.json")
