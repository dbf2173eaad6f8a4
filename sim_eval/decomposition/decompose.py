"""Convex decomposition of object meshes for MuJoCo (which collides mesh geoms as convex hulls).

:func:`decompose` splits a mesh into convex parts with CoACD (or takes its convex hull) and
caches the result by content: the key is the sha256 of the mesh arrays, the settings (except
the timeout) and the CoACD version. An entry is a folder ``<key>/`` holding ``parts.npz``,
``meta.json`` and CoACD's log, stored and verified by :mod:`ogcp.planner.infra.cache`: readers see a
whole entry or none, a damaged entry is reported, discarded and recomputed, and when two
processes write the same entry the first one wins and the other uses it.

CoACD runs in a child Python process, so that a run past the timeout can be killed and a crash
in its native code cannot take the caller down; arrays travel through ``.npz`` files.
Its log goes to a file and never to the terminal; it also tells whether CoACD's ``auto``
preprocessing judged the mesh non-manifold and remeshed it.

Non-watertight meshes: preprocess ``on`` (and ``auto``, for meshes that fail CoACD's manifold
check) remeshes them into a closed manifold first; preprocess ``off`` needs a closed,
consistently oriented mesh and is refused otherwise. The remesh of an open surface is a thin
closed shell around it, not a solid (measured: a box missing one triangle became 26 parts
holding 31 % of its volume): contacts still meet a surface near the mesh, but the object's
mass properties must not come from the parts (see :func:`ogcp.sim_eval.scene.body.object_inertia`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import inspect
import io
import json
import re
import time
import warnings
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

from ogcp.planner.grasp.shells import Shells
from ogcp.planner.infra.cache import cache_dir, read_entry, write_entry
from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.decomposition.coacd_child import run_coacd_child
from ogcp.sim_eval.decomposition.settings import DecompositionSettings
from ogcp.sim_eval.scene.body import Part, hull_part, is_closed_manifold, object_inertia

__all__ = [
    "CacheWriteWarning",
    "Decomposition",
    "DecompositionSettings",
    "cache_key",
    "decompose",
    "mesh_sha256",
    "object_inertia",  # re-exported from ogcp.sim_eval.scene.body for the evaluator
]

SCHEMA = "ogcp.decomposition/1"
#: Settings that only exist in some CoACD releases; passed only when the installed one has them.
OPTIONAL_COACD_ARGS = ("decimate", "max_ch_vertex")
_MANIFOLD_LOG = re.compile(r"Mesh Manifoldness:\s*(true|false|1|0)", re.IGNORECASE)


class CacheWriteWarning(UserWarning):
    """A decomposition was computed but could not be stored in the cache."""


@dataclass(frozen=True, eq=False)
class Decomposition:
    """Convex parts of one mesh.

    Attributes:
        parts: Per part ``(vertices (v, 3) [m], faces (f, 3))``: a closed convex hull with
            outward faces; arrays are read-only.
        meta: What was computed and how (schema ``ogcp.decomposition/1``): ``hull_count``,
            ``volume_ratio`` (sum of part volumes / mesh volume, None for an open mesh),
            ``compute_seconds``, ``remeshed``, versions, settings, mesh sha256 and sizes.
        cache_path: The cache entry folder, or None when it could not be written.
    """

    parts: tuple[Part, ...]
    meta: dict[str, Any] = field(default_factory=dict)
    cache_path: Path | None = None

    @property
    def hull_count(self) -> int | None:
        """Number of convex parts as the metadata records it (None when absent)."""
        count = self.meta.get("hull_count")
        return count if isinstance(count, int) and not isinstance(count, bool) else None

    @property
    def volume_ratio(self) -> float | None:
        """Sum of part volumes / mesh volume (None for an open mesh or when absent)."""
        ratio = self.meta.get("volume_ratio")
        return float(ratio) if isinstance(ratio, (int, float)) and not isinstance(ratio, bool) else None

    @property
    def compute_seconds(self) -> float:
        """Time the decomposition took when it was computed [s] (0 when not recorded)."""
        seconds = self.meta.get("compute_seconds")
        return float(seconds) if isinstance(seconds, (int, float)) and not isinstance(seconds, bool) else 0.0


def coacd_version() -> str:
    """Version of the installed CoACD ("missing" when it is not installed)."""
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return "missing"


def _mesh_arrays(mesh: trimesh.Trimesh) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise OgcpError("cannot decompose: the mesh holds no triangles")
    if not np.all(np.isfinite(vertices)):
        raise OgcpError("cannot decompose: the mesh has non-finite vertex coordinates")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise OgcpError("cannot decompose: the mesh has faces that index missing vertices")
    return vertices, faces


def _mesh_bytes(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> bytes:
    # The counts separate the two arrays, so no other pair of arrays gives the same bytes.
    header = f"{len(vertices)} {len(faces)}\n".encode()
    return header + vertices.astype("<f8").tobytes() + faces.astype("<i8").tobytes()


def mesh_sha256(mesh: trimesh.Trimesh) -> str:
    """Hex sha256 of a mesh's vertices (float64) and faces (int64)."""
    return hashlib.sha256(_mesh_bytes(*_mesh_arrays(mesh))).hexdigest()


def cache_key(mesh: trimesh.Trimesh, settings: DecompositionSettings) -> str:
    """Content key of a decomposition: sha256 of mesh arrays, settings (no timeout), CoACD version."""
    settings_json = json.dumps(settings.key_dict(), sort_keys=True, separators=(",", ":"))
    payload = _mesh_bytes(*_mesh_arrays(mesh)) + settings_json.encode() + b"\n" + coacd_version().encode()
    return hashlib.sha256(payload).hexdigest()


def _pack(parts: tuple[Part, ...]) -> bytes:
    buffer = io.BytesIO()
    np.savez(
        buffer,
        vertices=np.concatenate([v for v, _ in parts]),
        faces=np.concatenate([f for _, f in parts]),
        vertex_counts=np.array([len(v) for v, _ in parts], dtype=np.int64),
        face_counts=np.array([len(f) for _, f in parts], dtype=np.int64),
    )
    return buffer.getvalue()


def _unpack(path: Path) -> list[tuple[NDArray[np.float64], NDArray[np.int64]]]:
    with np.load(path, allow_pickle=False) as data:
        vertices, faces = data["vertices"], data["faces"]
        vertex_counts, face_counts = data["vertex_counts"], data["face_counts"]
    if (
        len(vertex_counts) != len(face_counts)
        or vertex_counts.sum() != len(vertices)
        or face_counts.sum() != len(faces)
    ):
        raise ValueError("part counts do not match the arrays")
    v_split = np.split(np.asarray(vertices, dtype=np.float64).reshape(-1, 3), np.cumsum(vertex_counts)[:-1])
    f_split = np.split(np.asarray(faces, dtype=np.int64).reshape(-1, 3), np.cumsum(face_counts)[:-1])
    parts = []
    for v, f in zip(v_split, f_split, strict=True):
        if len(f) == 0 or f.min() < 0 or f.max() >= len(v):
            raise ValueError("a part's faces index missing vertices")
        parts.append((v, f))
    return parts


def _read_entry(folder: Path, key: str) -> Decomposition:
    """The decomposition a verified cache entry holds.

    Raises:
        ValueError: (or what numpy and json raise) for parts or metadata that fail their
            checks: the entry is damaged and :func:`read_entry` discards it.
    """
    meta = json.loads((folder / "meta.json").read_text(encoding="utf-8"))
    loaded = _unpack(folder / "parts.npz")
    if not isinstance(meta, dict) or meta.get("key") != key or meta.get("hull_count") != len(loaded):
        raise ValueError("meta.json does not describe these parts")
    parts = []
    for v, f in loaded:
        v.setflags(write=False)
        f.setflags(write=False)
        parts.append((v, f))
    return Decomposition(tuple(parts), meta, folder)


def _store(root: Path, key: str, parts: tuple[Part, ...], meta: dict[str, Any], log: str) -> Path | None:
    """Write an entry; returns the entry folder (ours or a concurrent writer's), None if it cannot be written."""

    def build(stage: Path) -> None:
        (stage / "parts.npz").write_bytes(_pack(parts))
        (stage / "coacd.log").write_bytes(log.encode())
        (stage / "meta.json").write_bytes((json.dumps(meta, indent=1) + "\n").encode())

    try:
        return write_entry(root / key, build)
    except OgcpError as exc:
        warnings.warn(f"decomposition not cached: {exc}", CacheWriteWarning, stacklevel=3)
        return None


def _coacd_kwargs(settings: DecompositionSettings) -> dict[str, Any]:
    """Keyword arguments of ``coacd.run_coacd``, checked against the installed signature."""
    try:
        import coacd
    except ImportError as exc:
        raise OgcpError(f"CoACD is not importable ({exc}); install coacd or use method 'convex_hull'") from exc

    accepted = inspect.signature(coacd.run_coacd).parameters
    defaults = DecompositionSettings()
    kwargs = {k: v for k, v in settings.key_dict().items() if k != "method"}
    for name in OPTIONAL_COACD_ARGS:
        if name not in accepted:
            if kwargs[name] != getattr(defaults, name):
                raise OgcpError(f"the installed CoACD {coacd_version()} has no {name} option")
            del kwargs[name]
    return kwargs


def _run_coacd(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], settings: DecompositionSettings, name: str, progress: bool
) -> tuple[list[NDArray[np.float64]], float, str]:
    """Run CoACD in a child process; returns part vertex sets, CoACD's wall time [s] and its log."""
    return run_coacd_child(vertices, faces, _coacd_kwargs(settings), settings.timeout_s, name, progress)


def _remeshed(settings: DecompositionSettings, log: str) -> bool | None:
    if settings.method == "convex_hull" or settings.preprocess_mode == "off":
        return False
    if settings.preprocess_mode == "on":
        return True
    found = _MANIFOLD_LOG.search(log)  # "auto": CoACD remeshes what fails its manifold check
    return None if found is None else found.group(1).lower() in ("false", "0")


def decompose(
    mesh: trimesh.Trimesh,
    settings: DecompositionSettings | None = None,
    cache: Path | None = None,
    progress: bool = False,
    name: str | None = None,
) -> Decomposition:
    """Convex parts of a mesh, from the cache or computed (and then cached).

    Args:
        mesh: Object mesh [m] (not modified).
        settings: Decomposition settings; default :class:`DecompositionSettings()`.
        cache: Cache folder; default ``ogcp.planner.infra.cache.cache_dir("decompositions")``.
        progress: Show an elapsed-time indicator on stderr while CoACD runs.
        name: Object name for messages; default the mesh's ``metadata["name"]`` or its hash.

    Returns:
        The decomposition; parts whose hull is flat (no volume) are dropped and counted in
        ``meta["dropped_parts"]``.

    Raises:
        OgcpError: For an empty mesh, an open mesh with preprocess ``off``, a CoACD run past
            the timeout, a CoACD error or crash, or a decomposition without any solid part.
    """
    settings = settings or DecompositionSettings()
    vertices, faces = _mesh_arrays(mesh)
    key = cache_key(mesh, settings)
    mesh_sha = mesh_sha256(mesh)
    name = name or str(mesh.metadata.get("name") or mesh.metadata.get("file_name") or f"mesh {mesh_sha[:12]}")
    root = Path(cache) if cache is not None else cache_dir("decompositions")
    cached = read_entry(root / key, lambda folder: _read_entry(folder, key))
    if cached is not None:
        return cached
    manifold = is_closed_manifold(faces)
    given = settings
    if settings.preprocess_mode == "if_open":
        # CoACD's own "auto" test also remeshes closed meshes it dislikes (a pinched vertex), and its
        # voxel remesh inflates the surface by about a voxel: the parts then stand proud everywhere.
        settings = dataclasses.replace(settings, preprocess_mode="off" if manifold else "on")
    if settings.method == "coacd":
        if settings.preprocess_mode == "off" and not manifold:
            raise OgcpError(
                f"{name} is not a closed, consistently oriented mesh; CoACD needs one with preprocess "
                "'off': use preprocess 'on' or 'auto' to remesh it"
            )
        # Shell by shell (CoACD crashed on a part modelled inside another); enclosed shells add nothing
        # a finger or the floor could touch.
        raw: list[NDArray[np.float64]] = []
        seconds, log = 0.0, ""
        for shell_vertices, shell_faces in Shells(vertices, faces).outer():
            shell_raw, shell_seconds, shell_log = _run_coacd(shell_vertices, shell_faces, settings, name, progress)
            raw, seconds, log = [*raw, *shell_raw], seconds + shell_seconds, log + shell_log
        hulls = [hull_part(v) for v in raw]
    else:
        start = time.perf_counter()
        hulls, log = [hull_part(vertices)], ""
        seconds = time.perf_counter() - start
    parts = tuple(h for h in hulls if h is not None)
    if not parts:
        raise OgcpError(f"decomposition of {name} has no part with volume (is the mesh flat?)")
    hull_volume = float(sum(ConvexHull(np.array(v)).volume for v, _ in parts))
    mesh_volume = float(mesh.volume) if mesh.is_watertight and mesh.is_winding_consistent else None
    meta = {
        "schema": SCHEMA,
        "key": key,
        "method": settings.method,
        "hull_count": len(parts),
        "dropped_parts": len(hulls) - len(parts),
        "part_vertices": [len(v) for v, _ in parts],
        "hull_volume_sum": hull_volume,
        "mesh_volume": mesh_volume,
        "volume_ratio": hull_volume / mesh_volume if mesh_volume and mesh_volume > 0 else None,
        "compute_seconds": seconds,
        "preprocess_mode": settings.preprocess_mode if settings.method == "coacd" else None,
        "preprocess_mode_given": given.preprocess_mode,
        "input_closed_manifold": manifold,
        "remeshed": _remeshed(settings, log),
        "coacd_version": coacd_version(),
        "settings": given.key_dict(),
        "mesh_sha256": mesh_sha,
        "vertices": len(vertices),
        "faces": len(faces),
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    stored = _store(root, key, parts, meta, log)
    entry = read_entry(stored, lambda folder: _read_entry(folder, key)) if stored is not None else None
    return entry or Decomposition(parts, meta, None)
