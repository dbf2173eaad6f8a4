"""``ogcp assets repair``: an open mesh file closed into a new file every command reads; the original kept."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.loading import load_mesh
from ogcp.planner.objects.repair_file import repair_file
from tests.cli_run import run_cli


def _holed(path):
    """A sphere with two simple holes: a five-face fan and one face elsewhere."""
    sphere = trimesh.creation.icosphere(3, radius=0.05)
    fan = np.flatnonzero((sphere.faces == 0).any(axis=1))
    far = [int(np.argmin(sphere.triangles_center[:, 2]))]
    kept = np.setdiff1d(np.arange(len(sphere.faces)), np.concatenate([fan, far]))
    holed = trimesh.Trimesh(sphere.vertices, sphere.faces[kept], process=False)
    holed.remove_unreferenced_vertices()
    holed.export(path)
    return path


def test_a_holed_mesh_is_refused_with_the_way_out_and_repaired_into_a_new_file(tmp_path):
    source = _holed(tmp_path / "scan.stl")
    before = source.read_bytes()
    status, _, err = run_cli(["plan", str(source)])
    assert status == 2 and err.count("\n") == 1
    assert "mesh is open (8 edges border only one face" in err and f"`ogcp assets repair {source} --out FILE`" in err
    out = tmp_path / "fixed" / "scan.ply"
    status, printed, err = run_cli(["assets", "repair", str(source), "--out", str(out)])
    assert status == 0 and err == ""
    assert (
        printed.startswith(f"{out}: 642 vertices, 1280 faces, closed, volume ")
        and "filled 2 holes with 6 faces" in printed
    )
    assert source.read_bytes() == before  # the original is kept
    mesh = load_mesh(out)
    assert mesh.is_watertight and mesh.volume == pytest.approx(4 / 3 * np.pi * 0.05**3, rel=0.02)
    assert run_cli(["plan", str(out), "-n", "30"])[0] == 0


def test_what_repair_cannot_do_or_must_not_overwrite_is_one_line(tmp_path):
    source = _holed(tmp_path / "scan.stl")
    taken = tmp_path / "taken.obj"
    taken.write_text("# mine\n")
    cases = [
        (source, r"is the mesh file itself; write the repair to another file"),
        (taken, r"taken\.obj exists; --force replaces it"),
        (tmp_path / "x.xyz", r"unsupported mesh format '\.xyz'; supported: \.obj"),
    ]
    for out, said in cases:
        with pytest.raises(OgcpError, match=said):
            repair_file(source, out)
    assert taken.read_text() == "# mine\n"
    repair_file(source, taken, force=True)
    assert load_mesh(taken).is_watertight
    # Two boxes sharing one edge: non-manifold, which no hole filling changes.
    a, b = trimesh.creation.box([1, 1, 1]), trimesh.creation.box([1, 1, 1])
    b.apply_translation([1, 1, 0])
    trimesh.util.concatenate([a, b]).export(tmp_path / "pinched.stl")
    with pytest.raises(OgcpError, match=r"pinched\.stl: cannot be made solid"):
        repair_file(tmp_path / "pinched.stl", tmp_path / "out.stl")
    assert not (tmp_path / "out.stl").exists()


def test_a_failed_write_leaves_neither_the_file_nor_its_temporary(tmp_path, monkeypatch):
    source = _holed(tmp_path / "scan.stl")

    def broken(self, path, file_type=None):
        with open(path, "wb") as handle:
            handle.write(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(trimesh.Trimesh, "export", broken)
    with pytest.raises(OgcpError, match="cannot write .*out.stl: No space left on device"):
        repair_file(source, tmp_path / "out.stl")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scan.stl"]
