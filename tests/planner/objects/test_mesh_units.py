"""A mesh file read at its own size in metres that spans kilometres or millimetres says so, once."""

from __future__ import annotations

import warnings

import pytest
import trimesh

from ogcp.planner.objects import resolve_object
from ogcp.planner.objects.resolve import MeshScaleWarning


def _box(path, size: float):
    trimesh.creation.box([size, 0.6 * size, 0.4 * size]).export(path)
    return str(path)


def test_a_mesh_in_millimetres_says_what_it_would_be_in_metres(tmp_path):
    path = _box(tmp_path / "part.stl", 80.0)  # a CAD export: 80 mm read as 80 m
    with pytest.warns(
        MeshScaleWarning, match=r"part\.stl: the mesh is 98\.63 m across .* in millimetres it would be 0\.09863 m"
    ):
        mesh, _ = resolve_object(path)
    assert mesh.extents.max() == pytest.approx(80.0)  # read as given: the warning changes nothing


def test_a_tiny_mesh_is_named_too_and_a_given_diagonal_or_a_plausible_size_is_quiet(tmp_path):
    with pytest.warns(MeshScaleWarning, match=r"0\.001973 m across"):
        resolve_object(_box(tmp_path / "speck.obj", 0.0016))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshScaleWarning)
        resolve_object(_box(tmp_path / "part.stl", 80.0), diagonal=0.1)  # the user scaled it
        resolve_object(_box(tmp_path / "cup.stl", 0.09))
        resolve_object(_box(tmp_path / "crate.stl", 1.5))
