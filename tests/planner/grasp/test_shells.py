"""Meshes of several closed shells: contacts only on the outer surface, whatever lies inside."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

from ogcp.planner.grasp.contact_set import sample_contacts
from ogcp.planner.grasp.shells import Shells
from ogcp.planner.objects.loading import MeshShellsWarning, load_mesh


def _box(size: float, at: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    box = trimesh.creation.box([size] * 3)
    box.apply_translation(at)
    return box


def _inside(points: np.ndarray, size: float, at: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Strictly inside an axis-aligned cube (a point on its faces is not)."""
    return np.all(np.abs(points - np.asarray(at)) < 0.5 * size - 1e-6, axis=1)


NESTED = trimesh.util.concatenate([_box(0.05), _box(0.03, (0.005, 0.0, 0.0))])  # a part modelled inside
OVERLAPPING = trimesh.util.concatenate([_box(0.05), _box(0.05, (0.03, 0.0, 0.0))])  # a union never computed
APART = trimesh.util.concatenate([_box(0.05), _box(0.05, (0.2, 0.0, 0.0))])


def _cavity() -> trimesh.Trimesh:
    inner = _box(0.03, (0.005, 0.0, 0.0))
    inner.invert()  # faces into the cavity: a hollow body
    return trimesh.util.concatenate([_box(0.05), inner])


def test_shells_are_found_and_a_point_inside_another_one_is_enclosed():
    shells = Shells(NESTED.vertices, NESTED.faces)
    assert shells.count == 2 and sorted(np.bincount(shells.labels)) == [12, 12]
    inner_face = int(np.flatnonzero(shells.labels == shells.labels[-1])[0])
    outer_face = int(np.flatnonzero(shells.labels == shells.labels[0])[0])
    # Just off the inner part: inside the outer body. Just off the outer body: outside the inner part.
    got = shells.enclosed(
        [[0.0201, 0.0, 0.0], [0.0, 0.0, 0.0251], [0.3, 0.0, 0.0]], [inner_face, outer_face, inner_face]
    )
    assert got.tolist() == [True, False, False]
    hollow = _cavity()
    cavity = Shells(hollow.vertices, hollow.faces)
    # A point in the cavity, off the inner (inward) shell, is inside the outer shell: enclosed.
    assert cavity.enclosed(
        [[0.0, 0.0, 0.0]], [int(np.flatnonzero(cavity.labels == cavity.labels[-1])[0])]
    ).tolist() == [True]
    single = _box(0.05)
    assert Shells(single.vertices, single.faces).count == 1


@pytest.mark.parametrize("tip_radius", [None, 0.002])
@pytest.mark.parametrize("name", ["nested", "overlapping", "cavity"])
def test_no_contact_is_sampled_inside_the_object(name, tip_radius):
    mesh = {"nested": NESTED, "overlapping": OVERLAPPING, "cavity": _cavity()}[name]
    contacts = sample_contacts(mesh, 300, seed=0, tip_radius=tip_radius)
    points = contacts.positions
    assert len(points) == 300
    assert not _inside(points, 0.05).any()  # never inside the first body
    if name == "overlapping":
        assert not _inside(points, 0.05, (0.03, 0.0, 0.0)).any()  # nor inside the second
        assert (points[:, 0] > 0.05).any()  # the second body's outer faces are sampled
    again = sample_contacts(mesh, 300, seed=0, tip_radius=tip_radius)
    assert np.array_equal(again.positions, points)  # the refill is seeded


def test_bodies_apart_keep_every_sample_and_a_single_shell_is_sampled_as_before():
    apart = sample_contacts(APART, 200, seed=3)
    assert (apart.positions[:, 0] > 0.1).any() and (apart.positions[:, 0] < 0.1).any()
    box = _box(0.05)
    plain = trimesh.sample.sample_surface_even(box, 50, seed=np.random.default_rng([4, 0]))[0]
    assert np.array_equal(sample_contacts(box, 50, seed=4).positions[: len(plain)], plain[:50])


def test_a_mesh_file_of_several_shells_says_so_once(tmp_path):
    NESTED.export(tmp_path / "nested.stl")
    with pytest.warns(MeshShellsWarning, match=r"nested\.stl: the mesh is 2 closed shells .* one rigid body"):
        load_mesh(tmp_path / "nested.stl")
    _box(0.05).export(tmp_path / "one.stl")
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshShellsWarning)
        load_mesh(tmp_path / "one.stl")
