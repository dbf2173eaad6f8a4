"""The collision surface where fingers touch: offsets from the mesh, tips placed on it, refinement."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp import ContactSet
from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval import Decomposition, DecompositionSettings, GraspEvaluator, SimSettings
from ogcp.sim_eval.decomposition import ladder as fit_module
from ogcp.sim_eval.decomposition.ladder import DecompositionLadder
from ogcp.sim_eval.scene.body import hull_part, object_inertia
from ogcp.sim_eval.scene.collision import PLACEMENT_TOLERANCE, CollisionSurface, place_tips
from ogcp.sim_eval.scene.grasp_scene import build_scene

BOX = (0.1, 0.08, 0.06)
TOP = np.array([[0.0, 0.0, 0.03]])
DOWN = np.array([[0.0, 0.0, -1.0]])


def _box(extents, centre=(0.0, 0.0, 0.0)):
    box = trimesh.creation.box(extents)
    box.apply_translation(centre)
    return np.asarray(box.vertices), np.asarray(box.faces)


def _parts(*boxes):
    return Decomposition(tuple(boxes), {"hull_count": len(boxes)})


def test_offsets_are_signed_along_the_normal_and_bounded_by_the_reach():
    proud = CollisionSurface.from_parts([_box((0.1, 0.08, 0.066))])  # top 3 mm above the mesh's
    short = CollisionSurface.from_parts([_box((0.1, 0.08, 0.056))])  # top 2 mm below it
    assert proud.offsets(TOP, DOWN, 0.01)[0] == pytest.approx(-3e-3, abs=1e-12)
    assert short.offsets(TOP, DOWN, 0.01)[0] == pytest.approx(2e-3, abs=1e-12)
    # Standing out by more than the reach: the ray starts inside, the offset says "at least".
    assert proud.offsets(TOP, DOWN, 0.002)[0] == pytest.approx(-0.002)
    # Nothing within twice the reach beyond the contact.
    assert np.isnan(short.offsets(TOP, DOWN, 0.0005)[0])
    # The first part along the ray counts, even one beside the contact's own.
    two = CollisionSurface.from_parts([_box(BOX), _box((0.02, 0.02, 0.01), (0.0, 0.0, 0.034))])
    assert two.offsets(TOP, DOWN, 0.01)[0] == pytest.approx(-9e-3, abs=1e-12)


def test_signed_distance_is_exact_inside_and_outside_a_part():
    surface = CollisionSurface.from_parts([_box(BOX)])
    points = np.array([[0.0, 0.0, 0.05], [0.07, 0.06, 0.0], [0.0, 0.0, 0.02]])
    distance, nearest = surface.signed_distance(points)
    np.testing.assert_allclose(distance, [0.02, np.hypot(0.02, 0.02), -0.01], atol=1e-12)
    np.testing.assert_allclose(nearest, [[0.0, 0.0, 0.03], [0.05, 0.04, 0.0], [0.0, 0.0, 0.03]], atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_a_tip_never_starts_in_penetration_of_random_parts(seed):
    """Random overlapping hulls; contacts on a sphere of radius 0.1 m around them: every tip just touches."""
    rng = np.random.default_rng(seed)
    parts = []
    for _ in range(6):
        centre = rng.normal(size=3) * 0.05
        part = hull_part(centre + rng.normal(size=(12, 3)) * 0.04)
        assert part is not None
        parts.append(part)
    surface = CollisionSurface.from_parts(parts)
    directions = rng.normal(size=(30, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radius = 0.008
    placement = place_tips(surface, 0.1 * directions, -directions, radius, max_inward=0.5)
    assert placement.placed.all()
    gap = surface.signed_distance(placement.centres, nearest=False)[0] - radius
    assert np.all(gap >= 0) and np.all(gap <= PLACEMENT_TOLERANCE * radius)
    # The realized contact is on the parts, one radius from the centre, along the realized normal.
    assert np.abs(surface.signed_distance(placement.points, nearest=False)[0]).max() < 1e-9
    np.testing.assert_allclose(placement.points, placement.centres + radius * placement.normals, atol=2e-6)


def test_placed_tips_touch_the_simulated_parts_without_penetration_in_mujoco():
    box = trimesh.creation.box(BOX)
    parts = [_box((0.1, 0.08, 0.066)), _box((0.104, 0.07, 0.05))]  # proud on top and on the sides
    positions = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]])
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    placement = place_tips(CollisionSurface.from_parts(parts), positions, normals, 0.008, max_inward=0.008)
    np.testing.assert_allclose(placement.travel, [2e-3, 2e-3, 3e-3], atol=1e-6)
    com, inertia = object_inertia(box, 0.1)
    settings = SimSettings(threads=1)
    scene = build_scene(parts, com, inertia, placement.points, placement.normals, settings, 0.5, 0.008)
    data = mujoco.MjData(scene.model)
    mujoco.mj_forward(scene.model, data)
    assert all(data.contact[c].dist > -1e-6 for c in range(data.ncon))


def test_a_part_that_falls_short_pulls_the_tip_in_and_a_missing_one_is_an_error():
    box = trimesh.creation.box(BOX)
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    positions = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]])
    contacts = ContactSet(positions, normals, np.zeros(3), 0.1, 0.5, 8, {})
    evaluator = GraspEvaluator(SimSettings(directions=0, threads=1), DecompositionSettings(method="convex_hull"))
    short = evaluator.evaluate(box, contacts, [(0, 1, 2)], parts=_parts(_box((0.1, 0.08, 0.056))))
    grasp = short.grasps[0]
    assert grasp.valid
    np.testing.assert_allclose(grasp.realized["travel"], [0.0, 0.0, -2e-3], atol=1e-6)
    assert grasp.realized["q1"] > 0 and grasp.realized["q1_change"] is not None
    # A part 2 cm short of the top: the top tip (radius 4 % of the diagonal, 5.7 mm) finds nothing.
    lost = evaluator.evaluate(box, contacts, [(0, 1, 2)], parts=_parts(_box((0.1, 0.08, 0.02))))
    assert not lost.grasps[0].valid and "finger(s) 2: no collision part" in lost.grasps[0].error


def test_fidelity_is_measured_against_the_realized_contacts():
    box = trimesh.creation.box(BOX)
    # The side parts stand 2 mm proud on one side only, so the realized grasp differs from the plan.
    parts = _parts(_box((0.104, 0.08, 0.06), (0.002, 0.0, 0.0)))
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    positions = np.array([[0.05, 0.01, 0.0], [-0.05, -0.01, 0.0], [0.0, 0.0, 0.03]])
    contacts = ContactSet(positions, normals, np.zeros(3), 0.1, 0.5, 8, {})
    settings = SimSettings(directions=8, threads=1)
    result = GraspEvaluator(settings, DecompositionSettings(method="convex_hull")).evaluate(
        box, contacts, [(0, 1, 2)], parts=parts
    )
    grasp = result.grasps[0]
    assert grasp.valid
    np.testing.assert_allclose(grasp.realized["points"][0], [0.054, 0.01, 0.0], atol=1e-6)
    assert not np.allclose(grasp.predicted, grasp.predicted_planned)
    ok = np.isfinite(grasp.fidelity)
    expected = np.abs(grasp.measured[ok] / grasp.predicted[ok] - 1)
    np.testing.assert_allclose(grasp.fidelity[ok], expected)


def _ladder(monkeypatch, levels, tolerance=0.0025, thresholds=(0.03, 0.02)):
    """A ladder whose decompositions come from ``levels`` (threshold -> parts or an error)."""
    calls = []

    def fake_decompose(mesh, settings, cache=None, progress=False):
        calls.append(settings.threshold)
        made = levels[settings.threshold]
        if isinstance(made, Exception):
            raise made
        return made

    monkeypatch.setattr(fit_module, "decompose", fake_decompose)
    settings = DecompositionSettings(contact_tolerance=tolerance, refine_thresholds=thresholds)
    diagonal = float(np.linalg.norm(BOX))
    return DecompositionLadder(trimesh.creation.box(BOX), settings, diagonal, 0.008), calls


def test_a_contact_outside_the_tolerance_is_refined(monkeypatch):
    proud = _parts(_box((0.1, 0.08, 0.066)))
    closer = _parts(_box((0.1, 0.08, 0.0608)))  # 0.4 mm proud: 0.28 % of the diagonal, still too far
    exact = _parts(_box(BOX))
    ladder, calls = _ladder(monkeypatch, {0.05: proud, 0.03: closer, 0.02: exact})
    fit = ladder.fit(TOP, DOWN)
    assert fit.threshold == 0.02 and fit.within_tolerance and fit.tried == (0.05, 0.03, 0.02)
    assert fit.note(0.14) is None
    # Each level is decomposed once, whatever the number of grasps.
    ladder.fit(TOP, DOWN)
    assert calls == [0.05, 0.03, 0.02]
    # A contact the coarse parts already fit stops at the coarsest level.
    side = ladder.fit(np.array([[0.05, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0]]))
    assert side.threshold == 0.05 and side.tried == (0.05,)


def test_a_tolerance_that_cannot_be_met_is_reported_in_one_line(monkeypatch):
    proud = _parts(_box((0.1, 0.08, 0.066)))
    less = _parts(_box((0.1, 0.08, 0.064)))
    ladder, _ = _ladder(monkeypatch, {0.05: proud, 0.03: less, 0.02: OgcpError("CoACD timed out after 300 s")})
    fit = ladder.fit(TOP, DOWN)
    assert not fit.within_tolerance and fit.threshold == 0.03 and fit.tried == (0.05, 0.03)
    note = fit.note(float(np.linalg.norm(BOX)))
    assert note is not None and "\n" not in note
    assert "2 mm" in note and "finger 0" in note and "CoACD timed out" in note
    assert fit.to_dict()["refine_error"] == "CoACD timed out after 300 s"


def test_without_the_coarsest_decomposition_the_error_is_raised(monkeypatch):
    ladder, _ = _ladder(monkeypatch, {0.05: OgcpError("CoACD failed")})
    with pytest.raises(OgcpError, match="CoACD failed"):
        ladder.fit(TOP, DOWN)


def test_refinement_settings_validate_and_stay_out_of_the_cache_key():
    plain = DecompositionSettings()
    refined = DecompositionSettings(contact_tolerance=0.001, refine_thresholds=[0.01, 0.03])
    assert plain.key_dict() == refined.key_dict()
    assert refined.ladder == (0.05, 0.03, 0.01)
    assert DecompositionSettings(threshold=0.02, refine_thresholds=(0.03,)).ladder == (0.02,)
    assert DecompositionSettings(method="convex_hull").ladder == (0.05,)
    with pytest.raises(OgcpError, match="refine_thresholds"):
        DecompositionSettings(refine_thresholds=(0.001,))
    with pytest.raises(OgcpError, match="contact_tolerance"):
        DecompositionSettings(contact_tolerance=0.0)
