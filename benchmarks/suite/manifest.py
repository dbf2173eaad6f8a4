"""The manifest of a suite run (schema ``ogcp.suite-run/1``), written and read here.

``manifest.json`` beside ``results.jsonl`` records the suite (its text and hash), its seeds,
the machine and versions, and one session per invocation of ``ogcp suite``. The runner builds
it with :func:`new_manifest` and :func:`session_record` and extends it on ``--resume`` with
:func:`with_session`; the runner, ``ogcp compare`` and ``ogcp plot`` read the suite back
through :class:`ManifestSuite`. :class:`ogcp.benchmarks.suite.store.ResultStore` reads and writes
the file.
"""

from __future__ import annotations

import datetime
import os
import platform
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ogcp.planner.infra.provenance import provenance

if TYPE_CHECKING:
    from ogcp.benchmarks.suite.config import Suite

MANIFEST_SCHEMA = "ogcp.suite-run/1"


@dataclass(frozen=True)
class ManifestSuite:
    """The ``suite`` block of a manifest, as read back (a missing or mistyped key reads as None).

    Attributes:
        name: Suite name.
        source: Where the suite came from (built-in name or file path).
        hash: Hash of what the suite runs (:attr:`ogcp.benchmarks.suite.config.Suite.hash`).
        cells: Number of cells in the suite.
        simulation_enabled: Whether the suite simulates.
        content: The suite file's full text.
    """

    name: str | None
    source: str | None
    hash: str | None
    cells: int | None
    simulation_enabled: bool | None
    content: str | None

    @classmethod
    def of(cls, manifest: dict[str, Any] | None) -> ManifestSuite | None:
        """The suite block of a manifest; None without a manifest or a ``suite`` object in it."""
        suite = (manifest or {}).get("suite")
        if not isinstance(suite, dict):
            return None
        name, source, digest, cells = suite.get("name"), suite.get("source"), suite.get("hash"), suite.get("cells")
        enabled, content = suite.get("simulation_enabled"), suite.get("content")
        return cls(
            name=None if name is None else str(name),
            source=None if source is None else str(source),
            hash=digest if isinstance(digest, str) else None,
            cells=cells if isinstance(cells, int) and not isinstance(cells, bool) else None,
            simulation_enabled=enabled if isinstance(enabled, bool) else None,
            content=content if isinstance(content, str) else None,
        )


def suite_hash(manifest: dict[str, Any] | None) -> str | None:
    """The hash of the suite a manifest records (None when it records none)."""
    suite = ManifestSuite.of(manifest)
    return None if suite is None else suite.hash


def first_commit(manifest: dict[str, Any]) -> str | None:
    """The git commit of the manifest's first session (None when unknown)."""
    sessions = manifest.get("sessions")
    first = sessions[0] if isinstance(sessions, list) and sessions and isinstance(sessions[0], dict) else {}
    return first.get("git_commit")


def with_session(manifest: dict[str, Any], session: dict[str, Any]) -> dict[str, Any]:
    """The manifest with one more session (a resumed run)."""
    sessions = manifest.get("sessions")
    return {**manifest, "sessions": [*(sessions if isinstance(sessions, list) else []), session]}


def with_kernel_warmup(manifest: dict[str, Any], seconds: Sequence[float]) -> dict[str, Any]:
    """The manifest with its last session's ``kernel_warmup_seconds``: one entry per process.

    Each process that ran cells compiled (or loaded from numba's cache) the kernels once,
    before its first cell, so no cell's times include it; these are those seconds [s].
    """
    sessions = manifest.get("sessions")
    if not isinstance(sessions, list) or not sessions or not isinstance(sessions[-1], dict):
        return manifest
    last = {**sessions[-1], "kernel_warmup_seconds": [round(float(s), 6) for s in seconds]}
    return {**manifest, "sessions": [*sessions[:-1], last]}


def kernel_warmups(manifest: dict[str, Any] | None) -> list[float] | None:
    """Every process's kernel warm-up seconds over the manifest's sessions [s].

    None when no session records them: a run made before the runner warmed the kernels, whose
    first cell in each process may include numba's compilation in its times.
    """
    sessions = (manifest or {}).get("sessions")
    found = None
    for session in sessions if isinstance(sessions, list) else []:
        values = session.get("kernel_warmup_seconds") if isinstance(session, dict) else None
        if isinstance(values, list):
            found = (found or []) + [
                float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)
            ]
    return found


def session_record(
    jobs: int,
    backend: str,
    address: str | None,
    resume: bool,
    retry_errors: bool,
    max_cells: int | None,
    only: Sequence[str],
    time_limit: float | None,
    memory_limit: float | None = None,
) -> dict[str, Any]:
    """One session of a run: when it started, the code and how it ran (the runner's options)."""
    info = provenance()
    return {
        "started_at": _now(),
        "git_commit": info["git_commit"],
        "versions": info["versions"],
        "jobs": jobs,
        "backend": backend,
        "address": address,
        "resume": resume,
        "retry_errors": retry_errors,
        "max_cells": max_cells,
        "only": list(only),
        "time_limit": time_limit,
        "memory_limit": memory_limit,
    }


def new_manifest(suite: Suite, session: dict[str, Any]) -> dict[str, Any]:
    """The manifest of a new run of ``suite``, whose first session is ``session``."""
    info = provenance()
    return {
        "schema": MANIFEST_SCHEMA,
        "suite": {
            "name": suite.name,
            "source": suite.source,
            "hash": suite.hash,
            "cells": len(suite.cells),
            "simulation_enabled": suite.simulate,
            "content": suite.text,
        },
        "seeds": suite.seeds(),
        "started_at": session["started_at"],
        "versions": info["versions"],
        "git_commit": info["git_commit"],
        "python": info["python"],
        "cpu": {"model": _cpu_model(), "count": os.cpu_count(), "platform": platform.platform()},
        "sessions": [session],
    }


def _now() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()
