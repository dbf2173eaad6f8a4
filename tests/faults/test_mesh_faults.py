"""Broken mesh files: each is refused in one line that names the file and the fault, or fixed loudly.

Every input is built here in tmp_path from a clean mesh, so the fault is the only difference.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import BUILTIN_OBJECTS, builtin_mesh, load_mesh
from ogcp.planner.objects.repair import MeshOrientationWarning

ICO = trimesh.creation.icosphere(subdivisions=2)  # 162 vertices, 320 faces
BOX = trimesh.creation.box(extents=(0.1, 0.1, 0.1))  # 8 vertices, 12 faces


def _write(path: Path, data: str | bytes) -> Path:
    if isinstance(data, str):
        path.write_text(data)
    else:
        path.write_bytes(data)
    return path


def _refused(path: Path, fragment: str) -> str:
    """Assert that loading ``path`` fails with one line naming the file and holding ``fragment``."""
    with pytest.raises(OgcpError) as info:
        load_mesh(path)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    assert fragment in message, message
    assert "\n" not in message
    return message


def _off_lines() -> list[str]:
    return ICO.export(file_type="off").splitlines()


# -- truncated and inconsistent files ------------------------------------------------------------


def test_truncated_off_names_the_missing_vertices(tmp_path):
    lines = _off_lines()  # OFF, counts, 162 vertex lines, 320 face lines
    path = _write(tmp_path / "mesh.off", "\n".join(lines[:42]) + "\n")
    assert _refused(path, "header says 162 vertices, file has 40") == f"{path}: header says 162 vertices, file has 40"


def test_truncated_off_names_the_missing_faces(tmp_path):
    lines = _off_lines()
    path = _write(tmp_path / "mesh.off", "\n".join(lines[: 2 + 162 + 100]) + "\n")
    _refused(path, "header says 320 faces, file has 100")


def test_off_with_more_lines_than_its_header_is_refused(tmp_path):
    lines = _off_lines()
    extra = len(lines) + 1
    path = _write(tmp_path / "mesh.off", "\n".join([*lines, "3 0 1 2"]) + "\n")
    _refused(path, f"header says 162 vertices and 320 faces, file has 1 more lines after them (from line {extra})")


def test_off_face_pointing_at_a_missing_vertex(tmp_path):
    lines = _off_lines()
    lines[2 + 162 + 5] = "3 0 1 999"
    path = _write(tmp_path / "mesh.off", "\n".join(lines) + "\n")
    _refused(path, f"line {2 + 162 + 5 + 1}: face 5 references vertex 999, file has 162 vertices (0 to 161)")


def test_obj_face_pointing_at_a_missing_vertex(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 9\nf 3 1 4\n"
    _refused(_write(tmp_path / "mesh.obj", text), "line 7: face 3 references vertex 9, file has 4 vertices (1 to 4)")
    zero = text.replace("f 2 3 9", "f 2 3 0")
    _refused(_write(tmp_path / "zero.obj", zero), "line 7: face 3 references vertex '0', 4 vertices precede it")
    relative = text.replace("f 2 3 9", "f 2 3 -5")
    _refused(_write(tmp_path / "rel.obj", relative), "line 7: face 3 references vertex '-5', 4 vertices precede it")


def test_obj_cut_inside_a_line_is_refused(tmp_path):
    text = ICO.export(file_type="obj")
    start = text.index("\nf ") + 1
    cut = text[: text.index(" ", start + 2)]  # the first face line, cut after its first index
    line = text[:start].count("\n") + 1
    _refused(_write(tmp_path / "mesh.obj", cut), f"line {line}: face 1 has 1 vertices, at least 3 needed")


@pytest.mark.parametrize("suffix", [".obj", ".off"])
def test_binary_bytes_in_a_text_format_are_named(tmp_path, suffix):
    """Not an error about trimesh's optional character-set detector, which it would reach."""
    text = ICO.export(file_type=suffix[1:]).encode()
    damaged = text[:200] + b"\xff\xfe\x00" + text[200:]
    _refused(
        _write(tmp_path / f"mesh{suffix}", damaged),
        f"the byte at offset 200 (0xff) is not UTF-8 text, as {suffix[1:].upper()} is",
    )
    glb = ICO.export(file_type="glb")  # a binary mesh under a text format's name
    _refused(_write(tmp_path / f"glb{suffix}", glb), "is not UTF-8 text")


def test_ply_cut_short_is_refused_in_both_encodings(tmp_path):
    ascii_ply = ICO.export(file_type="ply", encoding="ascii")
    _refused(_write(tmp_path / "a.ply", ascii_ply[: int(len(ascii_ply) * 0.9)]), "header says 320 faces, file has ")
    binary = ICO.export(file_type="ply")
    header = binary.index(b"end_header\n") + len(b"end_header\n")
    _refused(_write(tmp_path / "b.ply", binary[: header + 12 * 100]), "header says 162 vertices, file has 100")
    _refused(_write(tmp_path / "c.ply", binary + b"\0" * 7), "file has 7 more bytes after the face data")


def test_ply_faces_pointing_at_missing_vertices(tmp_path):
    lines = BOX.export(file_type="ply", encoding="ascii").decode().splitlines()
    lines[-1] = "3 0 1 20"
    _refused(_write(tmp_path / "a.ply", "\n".join(lines) + "\n"), "face 11 references vertex 20, file has 8 vertices")
    binary = bytearray(BOX.export(file_type="ply"))
    binary[-4:] = struct.pack("<i", 20)  # the last index of the last face
    _refused(_write(tmp_path / "b.ply", bytes(binary)), "face 11 references vertex 20, file has 8 vertices (0 to 7)")


def test_stl_cut_short_is_refused(tmp_path):
    binary = BOX.export(file_type="stl")
    _refused(_write(tmp_path / "b.stl", binary[:-50]), "header says 12 triangles (684 bytes), file has 634 bytes")
    text = BOX.export(file_type="stl_ascii")
    text = text if isinstance(text, str) else text.decode()
    _refused(_write(tmp_path / "a.stl", text[: text.index("endloop")]), "file ends inside facet 1 (begun on line 2)")
    no_end = text[: text.rindex("endsolid")]
    _refused(_write(tmp_path / "c.stl", no_end), "file ends after 12 facets without 'endsolid'")


def test_non_finite_coordinates_name_count_and_first_vertex(tmp_path):
    lines = _off_lines()
    lines[2 + 7] = "nan 0 0"
    lines[2 + 30] = "0 inf 0"
    path = _write(tmp_path / "mesh.off", "\n".join(lines) + "\n")
    _refused(path, "2 of 162 vertices have non-finite coordinates (NaN or inf), the first is vertex 7")
    text = "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\nf 1 4 3\n"
    _refused(
        _write(tmp_path / "nan.obj", text),
        "1 of 5 vertices have non-finite coordinates (NaN or inf), the first is vertex 2",
    )


# -- surfaces that bound no solid ----------------------------------------------------------------


def test_single_square_is_flat(tmp_path):
    square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"
    _refused(_write(tmp_path / "square.obj", square), "mesh is flat (all 4 vertices lie in one plane")


def test_open_box_is_refused_with_where(tmp_path):
    path = tmp_path / "open.obj"
    trimesh.Trimesh(BOX.vertices, BOX.faces[1:], process=False).export(path)
    _refused(path, "mesh is open (3 edges border only one face, the first from [")
    assert "ogcp needs a closed, watertight surface" in _refused(path, "open")


def test_duplicated_face_is_not_a_closed_surface(tmp_path):
    path = tmp_path / "dup.off"
    trimesh.Trimesh(BOX.vertices, np.vstack([BOX.faces, BOX.faces[:1]]), process=False).export(path)
    _refused(path, "mesh is not a closed surface (3 edges are shared by more than two faces")


def test_closed_mesh_enclosing_no_volume_is_refused(tmp_path):
    # Two equal cubes, the second inside out: closed and consistently wound per piece, volume 0.
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    other = cube.copy()
    other.invert()
    other.apply_translation([3.0, 0.0, 0.0])
    path = tmp_path / "zero.obj"
    trimesh.util.concatenate([cube, other]).export(path)
    _refused(path, "mesh encloses no volume (signed volume")


def test_inside_out_box_is_flipped_with_a_warning(tmp_path):
    inverted = BOX.copy()
    inverted.invert()
    path = tmp_path / "inside_out.obj"
    inverted.export(path)
    with pytest.warns(MeshOrientationWarning, match=r"inside_out\.obj: mesh is inside out .*flipped all 12 faces"):
        mesh = load_mesh(path)
    assert mesh.volume == pytest.approx(1e-3) and len(mesh.vertices) == 8
    assert np.allclose(mesh.center_mass, 0.0)


def test_mixed_winding_is_made_consistent_with_a_warning(tmp_path):
    faces = BOX.faces.copy()
    faces[3] = faces[3, ::-1]
    path = tmp_path / "mixed.obj"
    trimesh.Trimesh(BOX.vertices, faces, process=False).export(path)
    with pytest.warns(MeshOrientationWarning, match="winding was mixed: flipped 1 face that disagreed"):
        mesh = load_mesh(path)
    assert mesh.is_winding_consistent and mesh.volume == pytest.approx(1e-3)


# -- what loaded before still loads unchanged ---------------------------------------------------


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".off", ".glb"])
def test_builtin_objects_load_exactly_as_trimesh_reads_them(tmp_path, suffix):
    for name in BUILTIN_OBJECTS:
        path = tmp_path / f"{name}{suffix}"
        builtin_mesh(name).export(path)
        reference = trimesh.load(path, force="mesh", process=True)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            mesh = load_mesh(path)
        assert np.array_equal(mesh.vertices, reference.vertices) and np.array_equal(mesh.faces, reference.faces)


def _fetched_raw_files() -> list[tuple[Path, dict]]:
    root = Path(os.environ.get("OGCP_CACHE") or Path.home() / ".cache" / "ogcp") / "meshes"
    found = []
    for meta_file in sorted(root.glob("*/meta.json")):
        meta = json.loads(meta_file.read_text())
        raw = meta_file.parent / str(meta.get("raw_file"))
        if raw.is_file() and meta.get("repair") == []:
            found.append((raw, meta))
    return found


FETCHED = _fetched_raw_files()


@pytest.mark.parametrize("raw, meta", FETCHED, ids=[raw.name for raw, _ in FETCHED])
def test_fetched_raw_meshes_load_unchanged(raw, meta):
    # Repair changed nothing in these, so the cached mesh has the raw file's counts.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = load_mesh(raw)
    assert (len(mesh.vertices), len(mesh.faces)) == (meta["vertices"], meta["faces"])


# -- the command line ----------------------------------------------------------------------------


def test_cli_refuses_a_truncated_off_in_one_line(tmp_path):
    path = _write(tmp_path / "mesh.off", "\n".join(_off_lines()[:42]) + "\n")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "ogcp.benchmarks.cli",
            "contacts",
            str(path),
            "-n",
            "20",
            "-o",
            str(tmp_path / "c.json"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert run.returncode == 2, run.stderr
    assert run.stderr == f"ogcp: error: {path}: header says 162 vertices, file has 40\n"
    assert "Traceback" not in run.stderr and not (tmp_path / "c.json").exists()


def test_faces_that_name_a_vertex_twice_are_dropped_with_a_warning(tmp_path):
    """CAD exports hold slivers whose corners merge into one vertex: no area, and a zero-length edge
    that made a closed box look open ("2 edges border only one face, from [..] to the same point")."""
    from ogcp.planner.objects.loading import load_mesh
    from ogcp.planner.objects.repair import MeshOrientationWarning

    path = tmp_path / "slivers.obj"
    extra = np.vstack([BOX.vertices[:1] + 1e-12, BOX.vertices])  # vertex 0 again, merged on loading
    faces = np.vstack([BOX.faces + 1, [[0, 1, 2], [2, 3, 3]]])  # a sliver on the copy, one naming 3 twice
    text = "".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in extra) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces
    )
    path.write_text(text)
    with pytest.warns(MeshOrientationWarning, match="dropped 2 degenerate faces"):
        mesh = load_mesh(path)
    assert mesh.is_watertight and len(mesh.faces) == len(BOX.faces)
    assert mesh.volume == pytest.approx(BOX.volume)
