"""Exact point-to-mesh distance: the point-triangle routine, the pruned index and the side test."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp.mesh_distance import (
    CORNER_A,
    CORNER_B,
    EDGE_AB,
    EDGE_BC,
    FACE,
    SurfaceIndex,
    _point_triangle,
    triangle_distances,
)
from ogcp.planner.infra import OgcpError
from tests.conftest import winding_number


def brute_force(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """Nearest distance by the all-pairs matrix, in blocks."""
    return np.concatenate(
        [triangle_distances(points[i : i + 50], mesh.triangles).min(axis=1) for i in range(0, len(points), 50)]
    )


def triangle_soup(rng: np.random.Generator) -> trimesh.Trimesh:
    """Unconnected triangles of sizes over three decades: many size groups in the index."""
    centres = rng.uniform(-1.0, 1.0, (400, 1, 3))
    sizes = 10.0 ** rng.uniform(-3.0, 0.0, (400, 1, 1))
    vertices = (centres + sizes * rng.normal(size=(400, 3, 3))).reshape(-1, 3)
    return trimesh.Trimesh(vertices, np.arange(1200).reshape(-1, 3), process=False)


def test_triangle_distances_in_every_region() -> None:
    a, b, c = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    rotation = Rotation.from_euler("zyx", [0.4, 0.2, -0.9]).as_matrix()
    shift = np.array([0.3, -0.2, 0.5])
    local = np.array(
        [
            [0.2, 0.2, 0.7],  # above the interior: height
            [-0.3, -0.4, 0.0],  # beyond corner a
            [0.5, -0.2, 0.1],  # beyond edge ab
            [1.0, 1.0, 0.0],  # beyond edge bc (its midpoint is nearest)
            [2.0, -1.0, 0.0],  # beyond corner b
        ]
    )
    expected = [0.7, 0.5, np.hypot(0.2, 0.1), np.sqrt(0.5), np.sqrt(2.0)]
    nearest_local = np.array([[0.2, 0.2, 0.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.5, 0.5, 0.0], [1.0, 0.0, 0.0]])
    triangle = np.stack([a, b, c]) @ rotation.T + shift
    points = local @ rotation.T + shift
    np.testing.assert_allclose(triangle_distances(points, triangle[None])[:, 0], expected, atol=1e-12)
    distance, nearest, feature = _point_triangle(
        points, *(np.broadcast_to(v, points.shape) for v in triangle), nearest=True
    )
    np.testing.assert_allclose(distance, expected, atol=1e-12)
    assert nearest is not None and feature is not None
    np.testing.assert_allclose(nearest, nearest_local @ rotation.T + shift, atol=1e-12)
    assert feature.tolist() == [FACE, CORNER_A, EDGE_AB, EDGE_BC, CORNER_B]


@pytest.mark.parametrize("name", ["donut", "amphora", "box"])
def test_nearest_distance_equals_brute_force_on_builtins(name: str) -> None:
    mesh = builtin_mesh(name)
    rng = np.random.default_rng(0)
    surface, _ = trimesh.sample.sample_surface(mesh, 150, seed=rng)
    points = np.vstack(
        [
            rng.uniform(-0.15, 0.15, (150, 3)),  # around and inside the object
            surface + rng.normal(scale=0.01, size=(150, 3)),  # near the surface
            surface,  # on it
            rng.normal(scale=5.0, size=(20, 3)),  # far away
        ]
    )
    near = SurfaceIndex(mesh).nearest(points)
    np.testing.assert_allclose(near.distance, brute_force(mesh, points), rtol=0, atol=1e-15)
    # The reported point is on the reported face, at the reported distance.
    np.testing.assert_allclose(np.linalg.norm(points - near.point, axis=1), near.distance, atol=1e-12)
    own = mesh.triangles[near.face]
    assert _point_triangle(near.point, own[:, 0], own[:, 1], own[:, 2], nearest=False)[0].max() < 1e-12


def test_nearest_distance_equals_brute_force_on_mixed_triangle_sizes() -> None:
    rng = np.random.default_rng(1)
    soup = triangle_soup(rng)
    index = SurfaceIndex(soup)
    assert len(index.groups) >= 5
    points = rng.uniform(-1.5, 1.5, (600, 3))
    np.testing.assert_allclose(index.distance(points), brute_force(soup, points), rtol=0, atol=1e-15)


def test_max_distance_reports_only_what_lies_within() -> None:
    mesh = builtin_mesh("sphere")  # radius 0.0577 m about the origin
    points = np.array([[0.0, 0.0, 0.07], [0.0, 0.0, 0.2], [0.0, 0.0, 0.0]])
    near = SurfaceIndex(mesh).nearest(points, max_distance=0.06)
    exact = brute_force(mesh, points)
    assert near.distance[0] == exact[0] and near.distance[2] == exact[2]
    assert near.distance[1] == np.inf and near.face[1] == -1 and np.isnan(near.point[1]).all()
    assert not near.outside[1]


@pytest.mark.parametrize("name", ["donut", "amphora"])
def test_outside_agrees_with_winding_number(name: str) -> None:
    mesh = builtin_mesh(name)
    rng = np.random.default_rng(2)
    surface, _ = trimesh.sample.sample_surface(mesh, 250, seed=rng)
    points = np.vstack(
        [
            rng.uniform(-0.12, 0.12, (250, 3)),
            # A thin shell around the surface and around its vertices: nearest points on
            # edges and corners, where only the pseudonormals give the right side.
            surface + rng.normal(scale=1e-3, size=(250, 3)),
            mesh.vertices[rng.choice(len(mesh.vertices), 250)] + rng.normal(scale=1e-3, size=(250, 3)),
        ]
    )
    near = SurfaceIndex(mesh).nearest(points)
    np.testing.assert_array_equal(near.outside, winding_number(mesh, points) < 0.5)


def test_side_ignores_unmerged_vertices() -> None:
    mesh = builtin_mesh("amphora")
    soup = trimesh.Trimesh(mesh.triangles.reshape(-1, 3), np.arange(3 * len(mesh.faces)).reshape(-1, 3), process=False)
    rng = np.random.default_rng(3)
    points = mesh.vertices[rng.choice(len(mesh.vertices), 500)] + rng.normal(scale=1e-3, size=(500, 3))
    np.testing.assert_array_equal(
        SurfaceIndex(soup).nearest(points).outside, SurfaceIndex(mesh).nearest(points).outside
    )


def test_open_mesh_sides_are_local() -> None:
    # A box without its top: near the remaining walls the side is still the wall's side.
    box = builtin_mesh("box")
    top = box.face_normals[:, 2] > 0.5
    open_box = trimesh.Trimesh(box.vertices, box.faces[~top], process=False)
    lo, hi = box.bounds
    inside = np.array([[0.0, 0.0, lo[2] + 0.01], [lo[0] + 0.01, 0.0, 0.0]])
    outside = np.array([[0.0, 0.0, lo[2] - 0.01], [hi[0] + 0.01, 0.0, 0.0]])
    near = SurfaceIndex(open_box).nearest(np.vstack([inside, outside]))
    assert near.outside.tolist() == [False, False, True, True]


def test_bad_input_is_refused() -> None:
    with pytest.raises(OgcpError, match="without faces"):
        SurfaceIndex(trimesh.Trimesh(np.zeros((3, 3)), np.zeros((0, 3), dtype=np.int64)))
    index = SurfaceIndex(builtin_mesh("box"))
    with pytest.raises(OgcpError, match="shape"):
        index.nearest(np.zeros(3))
    with pytest.raises(OgcpError, match="finite"):
        index.nearest(np.array([[np.nan, 0.0, 0.0]]))
    assert index.nearest(np.zeros((0, 3))).distance.shape == (0,)
