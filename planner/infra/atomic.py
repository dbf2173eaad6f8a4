"""Atomic file writes: a reader sees the old file or the new one, never a truncated one.

Every writer goes through :func:`write_atomic`: the data goes to a uniquely named temporary
file in the target's folder (so concurrent writers never share one), which is flushed and
fsynced, renamed over the target, and the folder is fsynced so that the rename itself
survives a crash. On any failure the temporary file is removed and the target is untouched.
The file gets the permissions a plain ``open(path, "w")`` gives a new file: 0666 less the umask
(0644 under the usual umask 022), applied by the kernel when the temporary file is created, so
the umask is never read (``os.umask`` cannot be read without setting it, which races other
threads) and a folder's default ACL applies as it would to a plain open.
Other formats pass their writer: ``write_atomic(path, lambda handle: np.savez(handle, **arrays))``.
"""

from __future__ import annotations

import contextlib
import json
import os
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from ogcp.planner.infra.errors import OgcpError

__all__ = [
    "fsync_directory",
    "read_json",
    "write_atomic",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_text_atomic",
]


def fsync_directory(directory: str | Path) -> None:
    """Flush a folder's entries (a rename or a new file in it) to disk.

    Raises:
        OSError: If the folder cannot be opened or synced.
    """
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_atomic(path: str | Path, write: Callable[[BinaryIO], object]) -> None:
    """Replace ``path`` with what ``write`` puts into a binary handle, atomically and durably.

    Args:
        path: The target file; its folder is created if missing.
        write: Writes the whole content into the handle it is given (it must not close it).

    Raises:
        OgcpError: If the folder or the file cannot be written (an ``OSError``, from the
            file system or from ``write``; the message names the path). Any other exception
            from ``write`` propagates unchanged. Either way the target is left as it was and
            no temporary file remains.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # A random name and O_EXCL: concurrent writers never share a temporary file; unlike
        # mkstemp (always 0600) the mode follows the umask, as a plain open would.
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        try:
            with os.fdopen(fd, "wb") as handle:
                write(handle)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    except OSError as exc:
        raise OgcpError(f"cannot write {path}: {exc.strerror or exc}") from exc
    # The new content is on disk either way; a folder that cannot be synced (some network file
    # systems) only risks the old file reappearing after a crash, never a truncated one.
    with contextlib.suppress(OSError):
        fsync_directory(path.parent)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically; see :func:`write_atomic`."""
    write_atomic(path, lambda handle: handle.write(data))


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`write_atomic`."""
    write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: str | Path, data: Any, indent: int | None = 1) -> None:
    """Write ``data`` as JSON with one trailing newline, atomically; see :func:`write_atomic`.

    Args:
        path: The target file.
        data: A JSON-serialisable value.
        indent: ``json.dumps`` indentation; None writes a single line.
    """
    write_text_atomic(path, json.dumps(data, indent=indent) + "\n")


def read_json(path: str | Path, what: str, schema: str | None = None) -> Any:
    """The JSON document in ``path``, or one-line :class:`OgcpError` saying why not.

    Args:
        path: The file.
        what: What the file should hold, for the messages (``plan``, ``grasps``).
        schema: The schema it should have (``ogcp.plan``), named when the file is not JSON at
            all (a mesh or another binary given in its place).

    Raises:
        OgcpError: For a missing or unreadable file, or text that is not JSON (with its line).
    """
    path = Path(path)
    expected = f"expected {schema or what} JSON"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise OgcpError(f"{path}: no such {what} file") from None
    except UnicodeDecodeError:
        raise OgcpError(f"{path}: not a {what} file ({expected}; this one is not text){_mesh_hint(path)}") from None
    except OSError as exc:
        raise OgcpError(f"{path}: cannot read {what}: {exc.strerror or exc}") from exc
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        if not text.lstrip().startswith(("{", "[")):
            raise OgcpError(f"{path}: not a {what} file ({expected}){_mesh_hint(path)}") from None
        raise OgcpError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from exc


#: File suffixes of meshes, which a newcomer may give where a JSON file is read.
_MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf", ".dae")


def _mesh_hint(path: Path) -> str:
    if path.suffix.lower() not in _MESH_SUFFIXES:
        return ""
    return f"; for a mesh, plan first: ogcp plan {path} -o plan.json"
