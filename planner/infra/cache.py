"""Where ogcp keeps what it computes once and reuses, and how one cache entry is stored and checked.

A cache entry (a reachability model, a decomposition, a fetched mesh) is a folder of files.
:func:`write_entry` builds it in a hidden staging folder beside its final place, adds
``manifest.json`` (schema ``ogcp.cache-entry/1``: the size and sha256 of every file), fsyncs
the files and the folder and renames the folder into place, so a reader sees a whole entry or
none. :func:`verify_entry` checks the files against that manifest, so damage on disk (a
truncated or overwritten file) is caught before anything is parsed; :func:`read_entry` adds
the loader's own shape and value checks, reports a bad entry in one line
(:class:`CacheEntryWarning`), discards it and returns None, and the caller rebuilds it.

Entries written before manifests existed have none; they are read as before, with the
loader's checks alone deciding.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
import warnings
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from ogcp.planner.infra.atomic import fsync_directory
from ogcp.planner.infra.errors import OgcpError

__all__ = [
    "ENTRY_MANIFEST",
    "ENTRY_SCHEMA",
    "CacheEntryWarning",
    "DamagedEntryError",
    "cache_dir",
    "discard_entry",
    "read_entry",
    "verify_entry",
    "write_entry",
]

ENTRY_SCHEMA = "ogcp.cache-entry/1"
ENTRY_MANIFEST = "manifest.json"
#: What a loader raises for content that fails its checks: the entry is damaged, not the caller.
LOAD_ERRORS = (OSError, ValueError, KeyError, IndexError, EOFError, zipfile.BadZipFile)

T = TypeVar("T")


class DamagedEntryError(OgcpError):
    """A cache entry whose files do not match its manifest; the message says which file and how."""


class CacheEntryWarning(UserWarning):
    """A damaged cache entry was found and discarded; it is rebuilt."""


def cache_dir(subdir: str | None = None) -> Path:
    """The ogcp cache folder: ``$OGCP_CACHE`` or ``~/.cache/ogcp``, plus an optional subfolder.

    The folder is not created here; writers create it when they first store something.
    """
    root = Path(os.environ.get("OGCP_CACHE") or Path.home() / ".cache" / "ogcp")
    return root / subdir if subdir else root


def write_entry(folder: str | Path, build: Callable[[Path], None], replace: bool = False) -> Path:
    """Build a cache entry in a staging folder, seal it with its manifest and move it into place.

    Args:
        folder: Where the entry goes; its parent is created if missing.
        build: Writes the entry's files (plain files, no subfolders, none named
            ``manifest.json``) into the staging folder it is given. Plain writes are enough:
            nothing is visible before the whole folder is renamed into place.
        replace: Replace an existing entry as a whole (a forced re-fetch). Without it an entry
            already at ``folder`` wins when it verifies: entries are keyed by content, so a
            concurrent writer that finished first stored the same thing; a damaged one is
            discarded and this one takes its place.

    Returns:
        ``folder``, holding this entry or a concurrent writer's.

    Raises:
        OgcpError: When the entry cannot be written (the staging folder is removed); an
            exception raised by ``build`` propagates, an ``OSError`` as ``OgcpError``.
    """
    folder = Path(folder)
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        # mkdir, not mkdtemp: the entry keeps the usual folder permissions once renamed into place.
        stage = folder.with_name(f".{folder.name}.{uuid.uuid4().hex[:12]}.partial")
        stage.mkdir()
    except OSError as exc:
        raise OgcpError(f"cannot write the cache folder {folder.parent}: {exc.strerror or exc}") from exc
    try:
        build(stage)
        _seal(stage)
        _move_into_place(stage, folder, replace)
    except OSError as exc:
        raise OgcpError(f"cannot store the cache entry {folder}: {exc.strerror or exc}") from exc
    finally:
        shutil.rmtree(stage, ignore_errors=True)  # already gone when the rename succeeded
    return folder


def verify_entry(folder: str | Path) -> bool:
    """Check every file of an entry against its manifest.

    Returns:
        True when every file the manifest lists has its recorded size and sha256; False when
        the folder has no manifest (no entry, or one written before manifests existed).

    Raises:
        DamagedEntryError: For an unreadable manifest, or a file that is missing, of another
            size or with another sha256.
    """
    folder = Path(folder)
    try:
        text = (folder / ENTRY_MANIFEST).read_bytes()
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise DamagedEntryError(f"{ENTRY_MANIFEST} is unreadable ({exc.strerror or exc})") from exc
    for name, (size, digest) in _parse_manifest(text).items():
        path = folder / name
        try:
            actual = path.stat().st_size
            if actual != size:
                raise DamagedEntryError(f"{name} holds {actual} bytes, its manifest says {size}")
            if file_sha256(path) != digest:
                raise DamagedEntryError(f"the sha256 of {name} differs from its manifest")
        except FileNotFoundError:
            raise DamagedEntryError(f"{name} is missing") from None
        except OSError as exc:
            raise DamagedEntryError(f"{name} is unreadable ({exc.strerror or exc})") from exc
    return True


def read_entry(folder: str | Path, load: Callable[[Path], T]) -> T | None:
    """Load a verified cache entry; a damaged one is reported, discarded and read as absent.

    Args:
        folder: The entry folder.
        load: Reads the entry's content from the folder and checks its shapes and values,
            raising ``ValueError`` (or ``OSError``, ``KeyError``, ... as numpy and json do)
            for content it cannot use.

    Returns:
        What ``load`` returned, or None when there is no entry or it was damaged (then one
        :class:`CacheEntryWarning` names it and why, and the folder is removed so that the
        caller's rebuilt entry can take its place).
    """
    folder = Path(folder)
    if not folder.is_dir():
        return None
    try:
        verify_entry(folder)
        return load(folder)
    except DamagedEntryError as exc:
        reason = str(exc)
    except LOAD_ERRORS as exc:
        reason = f"{type(exc).__name__}: {exc}"
    warnings.warn(f"cache entry {folder} is damaged ({reason}); discarded, it is rebuilt", CacheEntryWarning, 2)
    discard_entry(folder)
    return None


def discard_entry(folder: str | Path) -> None:
    """Remove an entry: one atomic rename aside, then delete; another process may do it first."""
    folder = Path(folder)
    trash = folder.with_name(f".{folder.name}.{uuid.uuid4().hex[:12]}.trash")
    try:
        os.rename(folder, trash)
    except OSError:
        return  # gone already, or not ours to remove: a writer replaces it or reports why not
    if trash.is_dir() and not trash.is_symlink():
        shutil.rmtree(trash, ignore_errors=True)
    else:
        trash.unlink(missing_ok=True)


def file_sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    with open(path, "rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()


def _manifest(files: dict[str, tuple[int, str]]) -> dict[str, Any]:
    """The ``ogcp.cache-entry/1`` record of files (name -> (size [bytes], sha256))."""
    return {
        "schema": ENTRY_SCHEMA,
        "files": {name: {"bytes": size, "sha256": digest} for name, (size, digest) in sorted(files.items())},
    }


def _parse_manifest(text: bytes) -> dict[str, tuple[int, str]]:
    """The files of an ``ogcp.cache-entry/1`` record: name -> (size [bytes], sha256).

    Raises:
        DamagedEntryError: For anything but a well-formed record of plain file names.
    """
    try:
        data = json.loads(text)
        if data.get("schema") != ENTRY_SCHEMA:
            raise ValueError(f"schema {data.get('schema')!r}")
        files = {}
        for name, entry in data["files"].items():
            if not name or name in (".", "..", ENTRY_MANIFEST) or "/" in name or "\\" in name:
                raise ValueError(f"file name {name!r}")
            size, digest = entry["bytes"], entry["sha256"]
            if not (isinstance(size, int) and size >= 0 and isinstance(digest, str) and len(digest) == 64):
                raise ValueError(f"record of {name}")
            files[name] = (size, digest)
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise DamagedEntryError(f"{ENTRY_MANIFEST} is malformed ({exc})") from exc
    return files


def _seal(stage: Path) -> None:
    """Fsync every file of a staging folder, write its manifest, fsync the folder."""
    files = {}
    for path in sorted(stage.iterdir()):
        if path.name == ENTRY_MANIFEST or not path.is_file() or path.is_symlink():
            raise OgcpError(f"a cache entry holds plain files other than {ENTRY_MANIFEST}; {path.name} is not one")
        with open(path, "rb") as handle:
            os.fsync(handle.fileno())  # Linux syncs through a read-only descriptor too
            files[path.name] = (os.fstat(handle.fileno()).st_size, hashlib.file_digest(handle, "sha256").hexdigest())
    with open(stage / ENTRY_MANIFEST, "w", encoding="utf-8") as handle:
        handle.write(json.dumps(_manifest(files), indent=1) + "\n")
        handle.flush()
        os.fsync(handle.fileno())
    fsync_directory(stage)


def _move_into_place(stage: Path, folder: Path, replace: bool) -> None:
    """Rename a sealed staging folder to ``folder``; see :func:`write_entry` for an existing one."""
    if replace:
        old = None
        if folder.exists():
            old = folder.with_name(f".{folder.name}.{uuid.uuid4().hex[:12]}.old")
            os.replace(folder, old)
        try:
            os.replace(stage, folder)
        except OSError:
            if old is not None and not folder.exists():
                os.replace(old, folder)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    else:
        for attempt in range(2):
            try:
                os.rename(stage, folder)  # fails when `folder` exists and is not empty
                break
            except OSError:
                if attempt or not folder.exists():
                    raise
                try:
                    if verify_entry(folder):
                        return  # a concurrent writer finished first: keep its entry
                except DamagedEntryError:
                    pass
                discard_entry(folder)
    fsync_directory(folder.parent)
