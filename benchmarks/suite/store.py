"""The results folder of a suite run: ``results.jsonl``, ``manifest.json`` and a lock.

``results.jsonl`` holds one JSON object per line, one line per finished cell. A line is
written with a single ``os.write`` on an ``O_APPEND`` descriptor and fsynced, so a crash
leaves at most one partial line at the very end: the reader reports and ignores a last
line without its newline (and any line that is not a JSON object with an ``id``), and a
resumed run cuts that tail off before appending. A write that fails (a full disk, a file
size limit) is cut off at once, so the file keeps every line written before it, whole, and
the run ends with one error line; ``--resume`` continues from there. ``manifest.json`` is
written atomically. Only the runner's main process writes; workers return records to it.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.planner.infra.atomic import fsync_directory, write_json_atomic
from ogcp.planner.infra.errors import OgcpError

RESULTS = "results.jsonl"
MANIFEST = "manifest.json"
LOCK = ".lock"


@dataclass(frozen=True)
class ReadReport:
    """What ``results.jsonl`` holds.

    Attributes:
        records: Valid records in file order (a cell rerun with ``--retry-errors`` appears twice).
        problems: One line per ignored piece (invalid line, partial tail).
        valid_end: Byte offset just after the last complete line.
        size: File size in bytes.
    """

    records: tuple[dict[str, Any], ...]
    problems: tuple[str, ...]
    valid_end: int
    size: int

    def latest(self) -> dict[str, dict[str, Any]]:
        """id -> the last record of that cell."""
        return {r["id"]: r for r in self.records}

    @property
    def partial_tail(self) -> int:
        """Bytes after the last complete line (a write cut short by a crash)."""
        return self.size - self.valid_end


#: The schema of a suite cell's record (:mod:`ogcp.benchmarks.suite.record` writes it).
CELL_SCHEMA = "ogcp.cell/1"


def read_results(path: str | Path) -> ReadReport:
    """Read a ``results.jsonl`` (a missing file reads as empty).

    Raises:
        OgcpError: When the file exists but cannot be read.
    """
    path = Path(path)
    try:
        data = path.read_bytes() if path.exists() else b""
    except OSError as exc:
        raise OgcpError(f"cannot read {path}: {exc.strerror or exc}") from exc
    end = data.rfind(b"\n") + 1
    records, problems = [], []
    for number, line in enumerate(data[:end].split(b"\n")[:-1], start=1):
        try:
            record = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError):
            problems.append(f"{path.name} line {number}: not valid JSON (ignored)")
            continue
        if not isinstance(record, dict) or not isinstance(record.get("id"), str):
            problems.append(f"{path.name} line {number}: not a cell record with an id (ignored)")
            continue
        schema = record.get("schema", CELL_SCHEMA)  # the oldest records name none
        if schema != CELL_SCHEMA:
            problems.append(f"{path.name} line {number}: schema {schema!r}, this ogcp reads {CELL_SCHEMA!r} (ignored)")
            continue
        records.append(record)
    if end < len(data):
        problems.append(f"{path.name}: last line is incomplete ({len(data) - end} bytes without a newline; ignored)")
    return ReadReport(tuple(records), tuple(problems), end, len(data))


def jsonable(value: Any) -> Any:
    """``value`` with numpy scalars and arrays as Python values and NaN/inf as None (strict JSON)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _cut(fd: int, size: int) -> None:
    """Cut a file back to ``size`` bytes after a failed append (freeing what the torn line took)."""
    with contextlib.suppress(OSError):
        os.ftruncate(fd, size)
        os.fsync(fd)


class ResultStore:
    """A suite run's output folder.

    Args:
        directory: The folder (created on first write).
    """

    def __init__(self, directory: str | Path) -> None:
        self.directory = Path(directory)

    @property
    def results_path(self) -> Path:
        return self.directory / RESULTS

    @property
    def manifest_path(self) -> Path:
        return self.directory / MANIFEST

    def read(self) -> ReadReport:
        """The records written so far; see :func:`read_results`."""
        return read_results(self.results_path)

    def read_manifest(self) -> dict[str, Any] | None:
        """The manifest, or None when there is none.

        Raises:
            OgcpError: When it exists but is not a JSON object.
        """
        if not self.manifest_path.exists():
            return None
        try:
            manifest = json.loads(self.manifest_path.read_text())
        except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise OgcpError(f"cannot read {self.manifest_path}: {exc}") from exc
        if not isinstance(manifest, dict):
            raise OgcpError(f"{self.manifest_path}: not a JSON object")
        return manifest

    def write_manifest(self, manifest: dict[str, Any]) -> None:
        """Replace the manifest atomically."""
        write_json_atomic(self.manifest_path, jsonable(manifest))

    def cut_partial_tail(self) -> int:
        """Remove an incomplete last line; returns the bytes removed."""
        report = self.read()
        if report.partial_tail:
            try:
                os.truncate(self.results_path, report.valid_end)
            except OSError as exc:
                raise OgcpError(f"cannot cut the incomplete last line of {self.results_path}: {exc.strerror}") from exc
        return report.partial_tail

    def append(self, record: dict[str, Any]) -> None:
        """Append one record as one line, durably, or not at all.

        Raises:
            OgcpError: When the line cannot be written in full (the file is then cut back to
                the lines before it; were even that to fail, the torn tail is what a resume
                cuts off).
        """
        line = (json.dumps(jsonable(record), separators=(",", ":"), allow_nan=False) + "\n").encode()
        self.ensure_directory()
        created = not self.results_path.exists()
        try:
            fd = os.open(self.results_path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        except OSError as exc:
            raise OgcpError(f"cannot append to {self.results_path}: {exc.strerror or exc}") from exc
        try:
            # The lock keeps other writers out, so the size now is where this line starts.
            start = os.fstat(fd).st_size
            try:
                # One write call: the line lands whole, or (crash, full disk) as a torn tail.
                written = os.write(fd, line)
                if written != len(line):
                    raise OSError(errno.ENOSPC, f"only {written} of {len(line)} bytes written")
                os.fsync(fd)  # where the disk fills only now (delayed allocation), the line is not kept
            except OSError as exc:
                _cut(fd, start)
                raise OgcpError(
                    f"cannot append to {self.results_path}: {exc.strerror or exc}; the {self._count(start)} cells "
                    "recorded before are kept: free space, then rerun with --resume"
                ) from exc
        finally:
            os.close(fd)
        if created:
            with contextlib.suppress(OSError):  # the line is written; only its survival of a crash is at stake
                fsync_directory(self.directory)

    def _count(self, size: int) -> int:
        """Lines in the first ``size`` bytes of ``results.jsonl`` (for messages; 0 if unreadable)."""
        try:
            with open(self.results_path, "rb") as handle:
                return handle.read(size).count(b"\n")
        except OSError:
            return 0

    def ensure_directory(self) -> None:
        """Create the folder (and its parents) if missing.

        Raises:
            OgcpError: When it cannot be: a file in its place or on its path, a read-only or
                missing file system.
        """
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
        except FileExistsError:
            raise OgcpError(f"--out {self.directory} is a file, not a folder") from None
        except OSError as exc:
            raise OgcpError(f"cannot create the results folder {self.directory}: {exc.strerror or exc}") from exc

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the folder's lock, so that two runs never append to the same file.

        Raises:
            OgcpError: When another process holds it.
        """
        self.ensure_directory()
        try:
            fd = os.open(self.directory / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise OgcpError(f"cannot write in {self.directory}: {exc.strerror or exc}") from exc
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise OgcpError(f"{self.directory} is in use by another ogcp suite run") from None
            yield
        finally:
            os.close(fd)
