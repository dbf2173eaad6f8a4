"""Structure checks of mesh files before trimesh parses them: counts and indices that disagree.

trimesh's loaders are lenient: an OFF or ASCII PLY file cut short loads the part before the
cut, surplus faces after a header's count are ignored, and an OBJ face that points at a
missing vertex ends in an ``IndexError``. Each check here reads the file's own structure
(header counts, face sizes, vertex indices) and names the first disagreement, so that a
damaged file is refused instead of planned on. Parsing the numbers stays trimesh's job.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from ogcp.planner.infra.errors import OgcpError

__all__ = ["check_mesh_file"]

#: Bytes of one value of each PLY property type.
_PLY_SIZES = {
    "char": 1,
    "int8": 1,
    "uchar": 1,
    "uint8": 1,
    "short": 2,
    "int16": 2,
    "ushort": 2,
    "uint16": 2,
    "int": 4,
    "int32": 4,
    "uint": 4,
    "uint32": 4,
    "float": 4,
    "float32": 4,
    "double": 8,
    "float64": 8,
}
#: numpy dtype codes of PLY list counts by size: read unsigned, since a negative count is no count.
_PLY_DTYPES = {1: "u1", 2: "u2", 4: "u4"}
_STL_HEADER = 84  # [bytes] 80-byte comment + uint32 triangle count
_STL_TRIANGLE = 50  # [bytes] normal, 3 corners (12 float32) + uint16 attribute


def check_mesh_file(path: Path) -> None:
    """Refuse an OFF, OBJ, PLY or STL file whose counts or face indices disagree.

    GLB and glTF files are left to trimesh, which reads their accessors' declared counts.

    Args:
        path: Mesh file; its suffix chooses the check.

    Raises:
        OgcpError: One line naming the file, the count that is wrong and where, e.g.
            ``mesh.off: header says 2904 vertices, file has 283``.
    """
    checks: dict[str, Callable[[bytes], str | None]] = {
        ".off": _check_off,
        ".obj": _check_obj,
        ".ply": _check_ply,
        ".stl": _check_stl,
    }
    check = checks.get(path.suffix.lower())
    if check is None:
        return
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise OgcpError(f"{path}: cannot read mesh ({exc.strerror or exc})") from exc
    problem = check(data)
    if problem is not None:
        raise OgcpError(f"{path}: {problem}")


def _rows(text: str) -> Iterator[tuple[int, list[str]]]:
    """Non-empty lines as ``(line number from 1, tokens)``, without ``#`` comments."""
    for number, line in enumerate(text.split("\n"), start=1):
        tokens = line.split("#", 1)[0].split()
        if tokens:
            yield number, tokens


def _text(data: bytes) -> str:
    # Undecodable bytes cannot be numbers or keywords, so replacing them changes no count.
    return data.decode("utf-8", errors="replace")


def _not_text(data: bytes, kind: str) -> str | None:
    """Why an OBJ or OFF file (text formats) is no UTF-8 text, or None: trimesh would hand it to
    an optional character-set detector and fail with an error about that module instead."""
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        return f"cannot read mesh: the byte at offset {exc.start} (0x{data[exc.start]:02x}) is not UTF-8 text, as {kind} is; binary or damaged?"
    return None


def _plural(name: str, count: int) -> str:
    word = name if count == 1 else ("vertices" if name == "vertex" else f"{name}s")
    return f"{count} {word}"


def _as_int(token: str) -> int | None:
    try:
        return int(token)
    except ValueError:
        return None


# -- OFF ---------------------------------------------------------------------------------------


def _check_off(data: bytes) -> str | None:
    """The first disagreement of an OFF file's counts, face sizes or indices with its lines, or None."""
    not_text = _not_text(data, "OFF")
    if not_text is not None:
        return not_text
    rows = list(_rows(_text(data)))
    # Only the keywords trimesh's OFF reader accepts; anything else it refuses itself.
    if not rows or rows[0][1][0].upper() not in ("OFF", "COFF"):
        return None
    line, counts = rows[0][0], rows[0][1][1:]
    body = 1
    if not counts:
        if len(rows) < 2:
            return "file ends before the vertex and face counts"
        line, counts = rows[1]
        body = 2
    numbers = [_as_int(token) for token in counts[:2]]
    if len(numbers) < 2 or None in numbers or min(n for n in numbers if n is not None) < 0:
        return f"line {line}: expected the vertex and face counts, found {' '.join(counts)!r}"
    n_vertices, n_faces = (int(n) for n in numbers if n is not None)
    vertices = rows[body : body + n_vertices]
    faces = rows[body + n_vertices : body + n_vertices + n_faces]
    if len(vertices) < n_vertices:
        return f"header says {_plural('vertex', n_vertices)}, file has {len(vertices)}"
    if len(faces) < n_faces:
        return f"header says {_plural('face', n_faces)}, file has {len(faces)}"
    extra = rows[body + n_vertices + n_faces :]
    if extra:
        return (
            f"header says {_plural('vertex', n_vertices)} and {_plural('face', n_faces)}, "
            f"file has {len(extra)} more lines after them (from line {extra[0][0]})"
        )
    for index, (number, tokens) in enumerate(vertices):
        if len(tokens) < 3:
            return f"line {number}: vertex {index} has {len(tokens)} coordinates, 3 needed"
    for index, (number, tokens) in enumerate(faces):
        size = _as_int(tokens[0])
        if size is None or size < 3:
            return f"line {number}: face {index} has {tokens[0]} vertices, at least 3 needed"
        if len(tokens) - 1 < size:
            return f"line {number}: face {index} lists {len(tokens) - 1} vertex indices, its count says {size}"
        for token in tokens[1 : size + 1]:
            vertex = _as_int(token)
            if vertex is None or not 0 <= vertex < n_vertices:
                return (
                    f"line {number}: face {index} references vertex {token}, "
                    f"file has {_plural('vertex', n_vertices)} (0 to {n_vertices - 1})"
                )
    return None


# -- OBJ ---------------------------------------------------------------------------------------


def _check_obj(data: bytes) -> str | None:
    """The first short ``v`` or ``f`` statement, or face index without a vertex, of an OBJ file, or None."""
    not_text = _not_text(data, "OBJ")
    if not_text is not None:
        return not_text
    # A trailing backslash continues an OBJ statement on the next line.
    text = _text(data).replace("\\\r\n", " ").replace("\\\n", " ")
    n_vertices = 0
    n_faces = 0
    # Positive indices may name vertices defined later, so they are checked against the total.
    highest: list[tuple[int, int, int]] = []  # (highest positive index, line, face number)
    for number, tokens in _rows(text):
        keyword = tokens[0]
        if keyword == "v":
            n_vertices += 1
            if len(tokens) < 4:
                return f"line {number}: vertex {n_vertices} has {len(tokens) - 1} coordinates, 3 needed"
        elif keyword == "f":
            n_faces += 1
            if len(tokens) < 4:
                return f"line {number}: face {n_faces} has {len(tokens) - 1} vertices, at least 3 needed"
            top = 0
            for token in tokens[1:]:
                vertex = _as_int(token.split("/", 1)[0])
                if vertex is None or vertex == 0 or vertex < -n_vertices:
                    return (
                        f"line {number}: face {n_faces} references vertex {token!r}, "
                        f"{_plural('vertex', n_vertices)} precede it (OBJ counts them from 1, or back from -1)"
                    )
                top = max(top, vertex)
            highest.append((top, number, n_faces))
    for top, number, face in highest:
        if top > n_vertices:
            return (
                f"line {number}: face {face} references vertex {top}, "
                f"file has {_plural('vertex', n_vertices)} (1 to {n_vertices})"
            )
    return None


# -- PLY ---------------------------------------------------------------------------------------


def _ply_header(data: bytes) -> tuple[str, list[tuple[str, int, list[list[str]]]], int] | str:
    """``(format, [(element, count, properties)], data offset)`` of a PLY file, or a problem."""
    if not data.startswith(b"ply"):
        return "not a PLY file (it does not start with 'ply')"
    end = data.find(b"end_header")
    if end < 0:
        return "the header has no 'end_header': the file is cut short"
    offset = data.find(b"\n", end)
    offset = len(data) if offset < 0 else offset + 1
    fmt = ""
    elements: list[tuple[str, int, list[list[str]]]] = []
    for number, tokens in enumerate((line.split() for line in _text(data[:end]).split("\n")), start=1):
        if not tokens:
            continue
        if tokens[0] == "format" and len(tokens) > 1:
            fmt = tokens[1]
        elif tokens[0] == "element":
            count = _as_int(tokens[2]) if len(tokens) > 2 else None
            if count is None or count < 0:
                return f"header line {number}: expected 'element NAME COUNT', found {' '.join(tokens)!r}"
            elements.append((tokens[1], count, []))
        elif tokens[0] == "property" and elements:
            elements[-1][2].append(tokens[1:])
    return fmt, elements, offset


def _check_ply(data: bytes) -> str | None:
    """The first disagreement of a PLY file's header counts with its data, or None."""
    header = _ply_header(data)
    if isinstance(header, str):
        return header
    fmt, elements, offset = header
    for name, _, properties in elements:
        for prop in properties:
            types = prop[1:3] if prop[0] == "list" else prop[:1]
            if len(prop) < (4 if prop[0] == "list" else 2) or any(t not in _PLY_SIZES for t in types):
                return f"element {name}: unsupported property {' '.join(prop)!r}"
    if fmt == "ascii":
        return _check_ply_ascii(_text(data[offset:]).split(), elements)
    if fmt in ("binary_little_endian", "binary_big_endian"):
        return _check_ply_binary(data[offset:], elements, "<" if fmt == "binary_little_endian" else ">")
    return None  # an unknown format: trimesh names it


def _check_ply_ascii(tokens: list[str], elements: list[tuple[str, int, list[list[str]]]]) -> str | None:
    """The first element an ASCII PLY body holds fewer rows of than declared, a bad face, or None."""
    # ASCII PLY is a stream of values (line breaks carry no meaning), so rows are counted in values.
    at = 0
    n_vertices = next((count for name, count, _ in elements if name == "vertex"), None)
    for name, count, properties in elements:
        for row in range(count):
            if at >= len(tokens) and properties:
                return f"header says {_plural(name, count)}, file has {row}"
            for prop in properties:
                if prop[0] != "list":
                    at += 1
                    continue
                size = _as_int(tokens[at]) if at < len(tokens) else 0
                if size is None or size < 0:
                    return f"{name} {row}: list length {tokens[at]!r} is not a count"
                values = tokens[at + 1 : at + 1 + size]
                at += 1 + size
                complete = at <= len(tokens)
                if complete and name == "face" and prop[-1] in ("vertex_indices", "vertex_index"):
                    problem = _ply_face(values, row, n_vertices)
                    if problem is not None:
                        return problem
            if at > len(tokens):
                # The values ran out inside this row: only the rows before it are in the file.
                return f"header says {_plural(name, count)}, file has {row}"
    if at < len(tokens):
        return f"file has {len(tokens) - at} more values after the {elements[-1][0]} data its header declares"
    return None


def _ply_face(indices: list[str], row: int, n_vertices: int | None) -> str | None:
    """The problem of face ``row`` of an ASCII PLY file (vertex indices as written), or None."""
    if len(indices) < 3:
        return f"face {row} has {len(indices)} vertices, at least 3 needed"
    if n_vertices is None:
        return None
    for token in indices:
        vertex = _as_int(token)
        if vertex is None or not 0 <= vertex < n_vertices:
            return f"face {row} references vertex {token}, file has {_plural('vertex', n_vertices)} (0 to {n_vertices - 1})"
    return None


def _check_ply_binary(body: bytes, elements: list[tuple[str, int, list[list[str]]]], order: str) -> str | None:
    """The first element a binary PLY body holds fewer rows of than declared, or surplus bytes, or None."""
    at = 0
    for name, count, properties in elements:
        rows = _ply_binary_rows(body, at, count, properties, order)
        if rows[0] < count:
            return f"header says {_plural(name, count)}, file has {rows[0]}"
        at = rows[1]
    if at < len(body):
        return f"file has {len(body) - at} more bytes after the {elements[-1][0]} data its header declares"
    return None


def _ply_row(body: bytes, at: int, properties: list[list[str]], order: str) -> tuple[int, list[tuple[int, str, int]]]:
    """Walk one binary row from byte ``at``: its end (past ``len(body)`` when cut short) and its lists.

    Each list is ``(byte offset of its count, count dtype, count)``.
    """
    lists: list[tuple[int, str, int]] = []
    for prop in properties:
        if prop[0] != "list":
            at += _PLY_SIZES[prop[0]]
            continue
        size = _PLY_SIZES[prop[1]]
        if at + size > len(body):
            return len(body) + 1, lists
        length = int.from_bytes(body[at : at + size], "little" if order == "<" else "big")
        lists.append((at, f"{order}{_PLY_DTYPES[size]}", length))
        at += size + length * _PLY_SIZES[prop[2]]
    return at, lists


def _ply_binary_rows(body: bytes, at: int, count: int, properties: list[list[str]], order: str) -> tuple[int, int]:
    """How many of ``count`` rows starting at byte ``at`` the file holds, and the byte after them."""
    if not count or not properties:
        return count, at
    end, lists = _ply_row(body, at, properties, order)
    stride = end - at
    whole = min(count, (len(body) - at) // stride)
    # Fast path: every row as long as the first (all triangles), read off each row's list counts.
    if all(np.all(np.ndarray((whole,), dtype, body, offset, (stride,)) == length) for offset, dtype, length in lists):
        return whole, at + whole * stride
    # Lists of mixed lengths (polygons): walk the rows one by one.
    for row in range(count):
        end, _ = _ply_row(body, at, properties, order)
        if end > len(body):
            return row, at
        at = end
    return count, at


# -- STL ---------------------------------------------------------------------------------------


def _check_stl(data: bytes) -> str | None:
    """A binary STL's count that disagrees with its size, or an ASCII STL cut short, or None."""
    if len(data) >= _STL_HEADER:
        triangles = int.from_bytes(data[80:_STL_HEADER], "little")
        if _STL_HEADER + _STL_TRIANGLE * triangles == len(data):
            return None  # a binary STL whose size matches its count
    if data.lstrip()[:5].lower() == b"solid" and b"\0" not in data[:_STL_HEADER]:
        return _check_stl_ascii(_text(data))
    if len(data) < _STL_HEADER:
        return f"cannot read mesh: not an ASCII STL, and {len(data)} bytes are too few for a binary STL (84 at least)"
    room = (len(data) - _STL_HEADER) // _STL_TRIANGLE
    return (
        f"cannot read mesh: not an ASCII STL, and as a binary STL its header says {_plural('triangle', triangles)} "
        f"({_STL_HEADER + _STL_TRIANGLE * triangles} bytes), file has {len(data)} bytes (room for {room})"
    )


def _check_stl_ascii(text: str) -> str | None:
    """The first facet without 3 vertices, or the cut, of an ASCII STL, or None."""
    facets = 0
    corners = 0
    inside: int | None = None  # line where the open facet started
    closed = False
    for number, line in enumerate(text.split("\n"), start=1):
        tokens = line.split()
        keyword = tokens[0].lower() if tokens else ""
        if keyword == "solid":
            closed = False
        elif keyword == "facet":
            facets += 1
            corners, inside = 0, number
        elif keyword == "vertex":
            corners += 1
            if len(tokens) < 4:
                return f"line {number}: facet {facets} has a vertex with {len(tokens) - 1} coordinates, 3 needed"
        elif keyword == "endfacet":
            if corners != 3:
                return f"line {number}: facet {facets} has {corners} vertices, 3 needed"
            inside = None
        elif keyword == "endsolid":
            closed = True
    if inside is not None:
        return f"file ends inside facet {facets} (begun on line {inside}): it is cut short"
    if not closed:
        return f"file ends after {_plural('facet', facets)} without 'endsolid': it is cut short"
    return None
