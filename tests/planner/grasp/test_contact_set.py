"""Contact sets, built-in objects, mesh loading and the wrench convention."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest
import trimesh

from ogcp.planner import BUILTIN_OBJECTS, builtin_mesh, load_mesh, resolve_object
from ogcp.planner.grasp import cone_edges, contact_wrenches, tangent_basis
from ogcp.planner.grasp.contact_set import SCHEMA, ContactSet, NonWatertightWarning, mass_properties, sample_contacts
from ogcp.planner.infra import OgcpError
from tests.conftest import winding_number

# ---------------------------------------------------------------- built-in objects


@pytest.mark.parametrize("name", sorted(BUILTIN_OBJECTS))
def test_builtin_objects_watertight_with_default_diagonal(name):
    mesh = builtin_mesh(name)
    assert mesh.is_watertight
    assert mesh.volume > 0
    lo, hi = mesh.bounds
    assert abs(np.linalg.norm(hi - lo) - 0.2) < 1e-9
    np.testing.assert_allclose((lo + hi) / 2, 0.0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(BUILTIN_OBJECTS))
def test_builtin_objects_custom_diagonal(name):
    mesh = builtin_mesh(name, diagonal=0.5)
    lo, hi = mesh.bounds
    assert abs(np.linalg.norm(hi - lo) - 0.5) < 1e-9
    assert mesh.is_watertight


# ---------------------------------------------------------------- sampling


def test_even_sampling_falls_short_for_some_n():
    """Guard: the fill-up path of sample_contacts is really exercised below."""
    mesh = builtin_mesh("box")
    log = logging.getLogger("trimesh")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        counts = {
            n: len(trimesh.sample.sample_surface_even(mesh, n, seed=np.random.default_rng([0, 0]))[0])
            for n in (7, 13, 20)
        }
    finally:
        log.setLevel(level)
    assert any(counts[n] < n for n in counts), counts


@pytest.mark.parametrize("n", [1, 7, 13, 20, 60])
def test_sample_contacts_returns_exactly_n(n):
    contacts = sample_contacts(builtin_mesh("box"), n, seed=0)
    assert len(contacts) == n
    assert contacts.positions.shape == (n, 3) and contacts.normals.shape == (n, 3)
    assert contacts.wrenches.shape == (n, 8, 6)


def test_sample_contacts_deterministic_and_seed_dependent():
    mesh = builtin_mesh("donut")
    a, b = sample_contacts(mesh, 40, seed=5), sample_contacts(mesh, 40, seed=5)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.normals, b.normals)
    c = sample_contacts(mesh, 40, seed=6)
    assert not np.array_equal(a.positions, c.positions)
    # The fill-up stream is seeded too.
    box = builtin_mesh("box")
    assert np.array_equal(sample_contacts(box, 7, seed=1).positions, sample_contacts(box, 7, seed=1).positions)


@pytest.mark.parametrize("name", sorted(BUILTIN_OBJECTS))
def test_normals_unit_and_inward(name):
    mesh = builtin_mesh(name)
    contacts = sample_contacts(mesh, 40, seed=2)
    np.testing.assert_allclose(np.linalg.norm(contacts.normals, axis=1), 1.0, atol=1e-12)
    # A small step along the inward normal lands inside the solid.
    assert (winding_number(mesh, contacts.positions + 1e-3 * contacts.normals) > 0.5).all()
    assert (winding_number(mesh, contacts.positions - 1e-3 * contacts.normals) < 0.5).all()


def test_sphere_normals_point_to_centre():
    contacts = sample_contacts(builtin_mesh("sphere"), 50, seed=3)
    dots = np.einsum("ij,ij->i", contacts.normals, contacts.positions - contacts.com)
    assert np.all(dots < 0)


def test_box_points_on_surface_with_inward_axis_normals():
    mesh = builtin_mesh("box")
    half = mesh.extents / 2
    contacts = sample_contacts(mesh, 13, seed=4)
    for p, n in zip(contacts.positions, contacts.normals):
        assert np.all(np.abs(p) <= half + 1e-9)
        on_face = np.abs(np.abs(p) - half) < 1e-9
        assert on_face.any(), p
        axis = int(np.argmax(np.abs(n)))
        assert on_face[axis] and abs(abs(n[axis]) - 1) < 1e-12
        assert np.sign(n[axis]) == -np.sign(p[axis])


def test_defaults_com_and_torque_scale():
    mesh = builtin_mesh("amphora")
    contacts = sample_contacts(mesh, 20, seed=0)
    assert contacts.mu == 0.5 and contacts.cone_edges == 8
    np.testing.assert_allclose(contacts.com, mesh.center_mass, rtol=0, atol=1e-15)
    rho = np.max(np.linalg.norm(mesh.vertices - mesh.center_mass, axis=1))
    assert contacts.torque_scale == pytest.approx(rho, rel=1e-12)
    # The amphora is not symmetric top/bottom: its COM is off the bounding-box centre.
    assert abs(contacts.com[2]) > 1e-3 or abs(contacts.com[1]) > 1e-3 or abs(contacts.com[0]) > 1e-3


def test_non_watertight_mesh_warns_and_gives_finite_com():
    box = builtin_mesh("box")
    open_box = trimesh.Trimesh(vertices=box.vertices, faces=box.faces[1:], process=False)
    assert not open_box.is_watertight
    with pytest.warns(NonWatertightWarning):
        com, rho = mass_properties(open_box)
    assert np.all(np.isfinite(com)) and np.isfinite(rho) and rho > 0
    with pytest.warns(NonWatertightWarning):
        contacts = sample_contacts(open_box, 10, seed=0)
    assert len(contacts) == 10 and np.all(np.isfinite(contacts.com))


# ---------------------------------------------------------------- JSON


def _assert_same(a: ContactSet, b: ContactSet) -> None:
    for field in ("positions", "normals", "com"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert (a.torque_scale, a.mu, a.cone_edges, a.source) == (b.torque_scale, b.mu, b.cone_edges, b.source)


def test_json_round_trip_exact(tmp_path):
    contacts = sample_contacts(builtin_mesh("box"), 20, seed=1, mu=0.3, cone_edges=6, source={"name": "box"})
    path = tmp_path / "c.json"
    contacts.save(path)
    _assert_same(contacts, ContactSet.load(path))
    data = contacts.to_dict()
    assert data["schema"] == SCHEMA == "ogcp.contacts/1"
    assert {"positions", "normals", "com", "torque_scale", "mu", "cone_edges", "source"} <= set(data)
    assert json.loads(path.read_text())["schema"] == "ogcp.contacts/1"


def test_json_round_trip_exact_curved_normals(tmp_path):
    contacts = sample_contacts(builtin_mesh("amphora"), 60, seed=0)
    contacts.save(tmp_path / "c.json")
    _assert_same(contacts, ContactSet.load(tmp_path / "c.json"))


def test_json_round_trip_curved_normals_close(tmp_path):
    contacts = sample_contacts(builtin_mesh("amphora"), 60, seed=0)
    contacts.save(tmp_path / "c.json")
    loaded = ContactSet.load(tmp_path / "c.json")
    assert np.array_equal(contacts.positions, loaded.positions)
    np.testing.assert_allclose(loaded.normals, contacts.normals, rtol=0, atol=1e-15)


# ---------------------------------------------------------------- validation


def _valid(**changes):
    kwargs = {"positions": np.eye(3), "normals": -np.eye(3), "com": np.zeros(3), "torque_scale": 1.0}
    kwargs.update(changes)
    return kwargs


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"positions": np.array([[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]])}, "positions contain NaN"),
        ({"normals": np.array([[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]])}, "normals contain NaN"),
        ({"normals": np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 1]])}, "normal 1 has zero length"),
        ({"positions": np.zeros((3, 2)), "normals": np.ones((3, 2))}, r"positions must have shape \(n, 3\)"),
        ({"positions": np.zeros((0, 3)), "normals": np.zeros((0, 3))}, r"positions must have shape \(n, 3\)"),
        ({"normals": np.ones((2, 3))}, "normals must have shape"),
        ({"com": np.zeros(2)}, "centre of mass"),
        ({"mu": 0.0}, "friction coefficient mu must be positive"),
        ({"mu": -0.5}, "friction coefficient mu must be positive"),
        ({"cone_edges": 2}, "cone_edges must be an integer >= 3"),
        ({"torque_scale": 0.0}, "torque scale rho must be a positive"),
        ({"torque_scale": -1.0}, "torque scale rho must be a positive"),
    ],
)
def test_contact_set_validation(changes, match):
    with pytest.raises(OgcpError, match=match):
        ContactSet(**_valid(**changes))


def test_load_errors(tmp_path):
    with pytest.raises(OgcpError, match="contact file not found"):
        ContactSet.load(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(OgcpError, match="not a readable JSON file"):
        ContactSet.load(bad)
    data = ContactSet(**_valid()).to_dict()
    bad.write_text(json.dumps({**data, "schema": "other/1"}))
    with pytest.raises(OgcpError, match="schema is 'other/1'"):
        ContactSet.load(bad)
    del data["positions"]
    bad.write_text(json.dumps(data))
    with pytest.raises(OgcpError, match=r"missing key\(s\) positions"):
        ContactSet.load(bad)


# ---------------------------------------------------------------- mesh files


def test_load_mesh_errors(tmp_path):
    with pytest.raises(OgcpError, match="mesh file not found"):
        load_mesh(tmp_path / "nope.obj")
    txt = tmp_path / "x.txt"
    txt.write_text("hello")
    with pytest.raises(OgcpError, match=r"unsupported mesh format '\.txt'"):
        load_mesh(txt)
    stl = tmp_path / "x.stl"
    stl.write_bytes(b"\x00\xffnot a mesh at all\x13\x37" * 7)
    obj = tmp_path / "x.obj"
    obj.write_text("# vertices only\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")
    for path in (stl, obj):
        with pytest.raises(OgcpError, match="cannot read mesh|holds no triangle mesh") as info:
            load_mesh(path)
        assert str(path) in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".off"])
def test_load_mesh_round_trip(tmp_path, suffix):
    mesh = builtin_mesh("donut")
    path = tmp_path / f"donut{suffix}"
    mesh.export(path)
    loaded = load_mesh(path)
    assert len(loaded.faces) == len(mesh.faces)
    assert loaded.area == pytest.approx(mesh.area, rel=1e-5)


def test_resolve_object_unknown_name_lists_choices():
    with pytest.raises(OgcpError, match="teapot") as info:
        resolve_object("teapot")
    for name in BUILTIN_OBJECTS:
        assert name in str(info.value)


def test_resolve_object_builtin_and_file(tmp_path):
    mesh, source = resolve_object("sphere", 0.3)
    assert source == {"kind": "builtin", "name": "sphere", "diagonal": 0.3}
    assert np.linalg.norm(mesh.extents) == pytest.approx(0.3, abs=1e-9)
    path = tmp_path / "s.stl"
    mesh.export(path)
    _, source = resolve_object(str(path))
    assert source["kind"] == "mesh" and len(source["sha256"]) == 64


# ---------------------------------------------------------------- wrench convention


def test_tangent_basis_convention():
    normals = np.array([[1.0, 0, 0], [-0.95, 0.3122499, 0], [0.9, 0, np.sqrt(0.19)], [0, 0, 1], [0.5, -0.5, 0.7071068]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    a, b = tangent_basis(normals)
    for n, ai, bi in zip(normals, a, b):
        e = np.array([0.0, 1, 0]) if abs(n[0]) >= 0.9 else np.array([1.0, 0, 0])
        expected = np.cross(n, e) / np.linalg.norm(np.cross(n, e))
        np.testing.assert_allclose(ai, expected, atol=1e-15)
        np.testing.assert_allclose(bi, np.cross(n, ai), atol=1e-15)
        gram = np.array([ai, bi, n]) @ np.array([ai, bi, n]).T
        np.testing.assert_allclose(gram, np.eye(3), atol=1e-12)


def test_cone_edges_and_wrenches():
    contacts = sample_contacts(builtin_mesh("amphora"), 10, seed=7, mu=0.4, cone_edges=5)
    n = contacts.normals
    edges = cone_edges(n, 0.4, 5)
    assert edges.shape == (10, 5, 3)
    normal_part = np.einsum("ikj,ij->ik", edges, n)
    np.testing.assert_allclose(normal_part, 1.0, atol=1e-12)
    tangential = edges - normal_part[..., None] * n[:, None, :]
    np.testing.assert_allclose(np.linalg.norm(tangential, axis=2), 0.4, atol=1e-12)
    w = contact_wrenches(contacts.positions, n, contacts.com, contacts.torque_scale, 0.4, 5)
    np.testing.assert_array_equal(w[..., :3], edges)
    for i in range(10):
        for j in range(5):
            torque = np.cross(contacts.positions[i] - contacts.com, edges[i, j]) / contacts.torque_scale
            np.testing.assert_allclose(w[i, j, 3:], torque, atol=1e-14)
    np.testing.assert_array_equal(contacts.wrenches, w)
    np.testing.assert_array_equal(contacts.subset_wrenches(np.array([3, 1])), w[[3, 1]].reshape(-1, 6))
