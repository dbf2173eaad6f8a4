"""Reach-aware contacts: a fingertip sphere touching the surface there does not cut the object."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, sample_contacts
from ogcp.planner.grasp import reach as reach_module
from ogcp.planner.grasp.reach import REACH_TOLERANCE, reach_settings, reachable
from ogcp.planner.infra import OgcpError

DIAGONAL = 0.2  # [m], the built-ins' default
#: The simulation's default tip is 4 % of the diagonal (sim_eval's SimSettings.tip_radius_ratio).
DEFAULT_TIP = 0.04 * DIAGONAL
# The donut before scaling: major radius 1, minor radius 0.4, bounding box 2.8 x 2.8 x 0.8.
DONUT_SCALE = DIAGONAL / np.sqrt(2.8**2 + 2.8**2 + 0.8**2)
HOLE_RADIUS = 0.6 * DONUT_SCALE  # 0.0297 m, 3.7 default tips
OUTER_RADIUS = 1.4 * DONUT_SCALE
TUBE_RADIUS = 0.4 * DONUT_SCALE

# A U-shaped bracket: two arms of thickness T on a base of thickness T, a slot of width W
# between them, extruded by DEPTH. Built from a hand triangulation of the outline (no
# shapely), so it is watertight.
T, SLOT, HEIGHT, DEPTH = 0.01, 0.01, 0.03, 0.02
WIDTH = 2 * T + SLOT


def u_bracket() -> trimesh.Trimesh:
    outline = np.array(
        [
            [0, 0],
            [WIDTH, 0],
            [WIDTH, T],
            [WIDTH, HEIGHT],
            [WIDTH - T, HEIGHT],
            [WIDTH - T, T],
            [T, T],
            [T, HEIGHT],
            [0, HEIGHT],
            [0, T],
        ]
    )
    triangles = np.array([[0, 1, 2], [0, 2, 5], [0, 5, 6], [0, 6, 9], [5, 2, 3], [5, 3, 4], [9, 6, 7], [9, 7, 8]])
    mesh = trimesh.creation.extrude_triangulation(outline, triangles, DEPTH)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    return mesh


def in_slot(points: np.ndarray) -> np.ndarray:
    """Points on the slot's faces: its floor and the inner walls of both arms."""
    x, y = points[:, 0], points[:, 1]
    eps = 1e-9
    floor = (np.abs(y - T) < eps) & (x > T - eps) & (x < WIDTH - T + eps)
    walls = ((np.abs(x - T) < eps) | (np.abs(x - (WIDTH - T)) < eps)) & (y > T - eps)
    return floor | walls


def dense_clearance(mesh: trimesh.Trimesh, centres: np.ndarray, samples: int = 400_000) -> np.ndarray:
    """Distance from points to a dense sample of the surface (and its vertices): an independent
    upper bound on the exact distance, too large by at most the sample spacing."""
    dense, _ = trimesh.sample.sample_surface(mesh, samples, seed=np.random.default_rng(99))
    return cKDTree(np.vstack([dense, mesh.vertices])).query(centres)[0]


def radial(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.hypot(points[:, 0], points[:, 1]), points[:, 2]


# ---------------------------------------------------------------- no tip: sampling as before


@pytest.mark.parametrize("tip", [None, 0, 0.0])
def test_no_tip_samples_as_before(tip: float | None) -> None:
    mesh = builtin_mesh("amphora")
    plain = sample_contacts(mesh, 120, seed=4, source={"kind": "builtin"})
    same = sample_contacts(mesh, 120, seed=4, source={"kind": "builtin"}, tip_radius=tip)
    assert same.to_dict() == plain.to_dict()
    assert "tip_radius" not in same.source


@pytest.mark.parametrize("name", ["box", "sphere"])
@pytest.mark.parametrize("n", [7, 200, 1000])
def test_convex_objects_keep_the_plain_sample(name: str, n: int) -> None:
    mesh = builtin_mesh(name)
    plain = sample_contacts(mesh, n, seed=2)
    for tip in (DEFAULT_TIP, 0.5 * DIAGONAL):
        tipped = sample_contacts(mesh, n, seed=2, tip_radius=tip)
        np.testing.assert_array_equal(tipped.positions, plain.positions)
        np.testing.assert_array_equal(tipped.normals, plain.normals)
        assert tipped.source == {**plain.source, "tip_radius": tip, "reach_tolerance": REACH_TOLERANCE * tip}


# ---------------------------------------------------------------- the donut


def test_donut_default_tip_fits_the_hole_and_never_cuts() -> None:
    # The hole's radius is 3.7 tips and every concave curvature radius is at least that,
    # so a default tip touches the whole donut: only the facets' creases could cut, and
    # the tolerance absorbs them.
    mesh = builtin_mesh("donut")
    plain = sample_contacts(mesh, 1000, seed=0)
    assert reachable(mesh, plain.positions, plain.normals, DEFAULT_TIP).all()
    tipped = sample_contacts(mesh, 1000, seed=0, tip_radius=DEFAULT_TIP)
    clearance = dense_clearance(mesh, tipped.positions - DEFAULT_TIP * tipped.normals)
    assert clearance.min() >= DEFAULT_TIP * (1 - REACH_TOLERANCE)
    # Without the tolerance the creases between facets would remove contacts.
    assert not reachable(mesh, plain.positions, plain.normals, DEFAULT_TIP, tolerance=0.0).all()


def test_donut_hole_narrower_than_the_tip_loses_its_inner_wall() -> None:
    mesh = builtin_mesh("donut")
    tip = 0.2 * DIAGONAL  # 0.04 m, larger than the hole's radius (0.0297 m)
    plain = sample_contacts(mesh, 2000, seed=1)
    keep = reachable(mesh, plain.positions, plain.normals, tip)
    rho, z = radial(plain.positions)
    equator = np.abs(z) < 0.3 * TUBE_RADIUS
    inner = equator & (rho < HOLE_RADIUS + 0.1 * TUBE_RADIUS)
    outer = equator & (rho > OUTER_RADIUS - 0.1 * TUBE_RADIUS)
    assert inner.sum() > 20 and outer.sum() > 20
    assert not keep[inner].any()
    assert keep[outer].all()
    # Checked against an independent distance: no kept sphere comes closer to the surface
    # than the tolerance allows, and the removed ones do cut (up to the sample spacing).
    centres = plain.positions - tip * plain.normals
    clearance = dense_clearance(mesh, centres)
    tolerance = REACH_TOLERANCE * tip
    assert clearance[keep].min() >= tip - tolerance
    assert np.all(clearance[~keep] < tip - tolerance + 1e-3)
    tipped = sample_contacts(mesh, 2000, seed=1, tip_radius=tip)
    rho, z = radial(tipped.positions)
    assert len(tipped) == 2000
    assert not np.any((np.abs(z) < 0.3 * TUBE_RADIUS) & (rho < HOLE_RADIUS + 0.1 * TUBE_RADIUS))
    assert dense_clearance(mesh, tipped.positions - tip * tipped.normals).min() >= tip - tolerance


# ---------------------------------------------------------------- a U-shaped bracket


def test_u_bracket_slot_narrower_than_the_tip_is_removed() -> None:
    mesh = u_bracket()
    tip = 0.8 * SLOT  # a slot of 1.25 tip radii: the sphere cannot reach its walls or floor
    plain = sample_contacts(mesh, 1000, seed=0)
    slot = in_slot(plain.positions)
    assert slot.sum() > 50
    keep = reachable(mesh, plain.positions, plain.normals, tip)
    np.testing.assert_array_equal(keep, ~slot)
    tipped = sample_contacts(mesh, 1000, seed=0, tip_radius=tip)
    assert len(tipped) == 1000 and not in_slot(tipped.positions).any()
    # The reachable contacts of the even sample come first, in their order.
    np.testing.assert_array_equal(tipped.positions[: keep.sum()], plain.positions[keep])
    # In a slot wider than the tip's diameter only the strips along its two concave
    # creases are out of reach: there the sphere touching one face cuts the other.
    tip = 0.45 * SLOT
    reach = tip * (1 - REACH_TOLERANCE)
    x, y = plain.positions[:, 0], plain.positions[:, 1]
    floor, wall = slot & (np.abs(y - T) < 1e-9), slot & (np.abs(y - T) >= 1e-9)
    crease = (floor & (np.minimum(x - T, WIDTH - T - x) < reach)) | (wall & (y - T < reach))
    assert crease.sum() > 10 and (slot & ~crease).sum() > 10
    np.testing.assert_array_equal(reachable(mesh, plain.positions, plain.normals, tip), ~crease)


def test_u_bracket_tolerance_is_the_allowed_cut_depth() -> None:
    mesh = u_bracket()
    floor_centre = np.array([[WIDTH / 2, T, DEPTH / 2]])
    up = np.array([[0.0, -1.0, 0.0]])  # inward normal of the slot's floor
    tip = 0.8 * SLOT
    cut = tip - SLOT / 2  # the sphere sinks this far into both walls
    assert not reachable(mesh, floor_centre, up, tip, tolerance=0.99 * cut)[0]
    assert reachable(mesh, floor_centre, up, tip, tolerance=1.01 * cut)[0]


def test_centre_inside_the_object_is_unreachable() -> None:
    # A normal given the wrong way puts the sphere inside; far from every face it would
    # not cut the surface, but it is inside, so the contact is not reachable.
    mesh = builtin_mesh("box")
    top = np.array([[0.0, 0.0, mesh.bounds[1, 2]]])
    assert reachable(mesh, top, [[0.0, 0.0, -1.0]], 0.01)[0]
    assert not reachable(mesh, top, [[0.0, 0.0, 1.0]], 0.01)[0]


# ---------------------------------------------------------------- determinism, scale, records


@pytest.mark.parametrize("n", [1, 50, 333])
def test_exact_n_and_deterministic(n: int) -> None:
    mesh = builtin_mesh("amphora")
    first = sample_contacts(mesh, n, seed=5, tip_radius=DEFAULT_TIP)
    again = sample_contacts(mesh, n, seed=5, tip_radius=DEFAULT_TIP)
    assert len(first) == n
    np.testing.assert_array_equal(first.positions, again.positions)
    np.testing.assert_array_equal(first.normals, again.normals)
    assert reachable(mesh, first.positions, first.normals, DEFAULT_TIP).all()
    if n > 1:
        other = sample_contacts(mesh, n, seed=6, tip_radius=DEFAULT_TIP)
        assert not np.array_equal(first.positions, other.positions)


def test_amphora_default_tip_removes_its_neck() -> None:
    mesh = builtin_mesh("amphora")
    plain = sample_contacts(mesh, 1000, seed=0)
    keep = reachable(mesh, plain.positions, plain.normals, DEFAULT_TIP)
    assert 0 < (~keep).sum() < 100
    # Everything removed lies in the concave band under the lip and around the neck.
    assert plain.positions[~keep, 2].min() > 0.03


def test_scale_invariance() -> None:
    reference = builtin_mesh("amphora", DIAGONAL)
    plain = sample_contacts(reference, 500, seed=0)
    tipped = sample_contacts(reference, 500, seed=0, tip_radius=0.1 * DIAGONAL)
    masks = []
    for diagonal in (0.05, DIAGONAL, 2.0):
        scale = diagonal / DIAGONAL
        mesh = builtin_mesh("amphora", diagonal)
        masks.append(reachable(mesh, plain.positions * scale, plain.normals, 0.1 * diagonal))
        scaled = sample_contacts(mesh, 500, seed=0, tip_radius=0.1 * diagonal)
        np.testing.assert_allclose(scaled.positions / scale, tipped.positions, rtol=0, atol=1e-12)
    assert 0 < (~masks[0]).sum()
    np.testing.assert_array_equal(masks[0], masks[1])
    np.testing.assert_array_equal(masks[1], masks[2])


def test_json_round_trip_keeps_the_tip(tmp_path) -> None:
    contacts = sample_contacts(builtin_mesh("amphora"), 40, seed=1, tip_radius=DEFAULT_TIP, reach_tolerance=1e-5)
    assert contacts.source["tip_radius"] == DEFAULT_TIP and contacts.source["reach_tolerance"] == 1e-5
    contacts.save(tmp_path / "c.json")
    loaded = ContactSet.load(tmp_path / "c.json")
    assert loaded.source == contacts.source
    np.testing.assert_array_equal(loaded.positions, contacts.positions)


# ---------------------------------------------------------------- errors


def test_too_little_reachable_surface_is_an_error(monkeypatch) -> None:
    monkeypatch.setattr(reach_module, "FILL_BATCHES", 0)
    with pytest.raises(OgcpError, match=r"radius 0\.008 m .*diagonal.*smaller --tip-radius"):
        sample_contacts(u_bracket(), 300, seed=0, tip_radius=0.8 * SLOT)


@pytest.mark.parametrize(
    ("tip", "tolerance", "match"),
    [
        (-0.01, None, "tip radius"),
        (float("nan"), None, "tip radius"),
        (float("inf"), None, "tip radius"),
        (True, None, "tip radius"),
        ("0.01", None, "tip radius"),
        (0.01, 0.01, "reach tolerance"),
        (0.01, -1e-6, "reach tolerance"),
    ],
)
def test_bad_tip_or_tolerance(tip: object, tolerance: float | None, match: str) -> None:
    with pytest.raises(OgcpError, match=match):
        sample_contacts(builtin_mesh("box"), 10, tip_radius=tip, reach_tolerance=tolerance)  # type: ignore[arg-type]


def test_reach_settings_and_reachable_validation() -> None:
    assert reach_settings(None) is None and reach_settings(0) is None
    assert reach_settings(0.02) == (0.02, REACH_TOLERANCE * 0.02)
    mesh = builtin_mesh("box")
    with pytest.raises(OgcpError, match="shape"):
        reachable(mesh, np.zeros((2, 3)), np.ones((3, 3)), 0.01)
    with pytest.raises(OgcpError, match="finite"):
        reachable(mesh, np.full((1, 3), np.nan), np.ones((1, 3)), 0.01)
    with pytest.raises(OgcpError, match="zero"):
        reachable(mesh, np.zeros((1, 3)), np.zeros((1, 3)), 0.01)
