"""Compiled kernels that ship with ogcp, so that a fresh install plans without compiling first.

numba compiles the kernels at their first call and caches them beside the sources (about 30 s on
two cores, :mod:`ogcp.planner.methods.warm_up`). The repository also carries that cache, built
once for a common CPU level (``NUMBA_CPU_NAME=x86-64-v3``), in ``shipped/``: when numba's own cache has no entry for a signature, :mod:`.jit` looks here.
They are compiled for the x86-64-v3 level (AVX2 and FMA: every x86-64 CPU since about 2015),
and used only on a CPU that has its features: the fully generic level ran the kernels about
15 % slower, this one as fast as code compiled for the host (A* on the sphere, m = 3, median of
five runs).

numba keys its cache by the source file's time and size, which a clone does not keep. A shipped
index is keyed by content instead: :func:`source_digest`, the sha256 of every source a kernel is
compiled from (the kernels' modules and the constants they import). A source edited since the
build, another numba (each file's header names it), another Python (the file names carry its
tag) or another platform (numba's key holds the target triple) finds no shipped entry, and the
kernel compiles as before. Shipped files are sealed like the local cache's; a damaged one is
reported in one line and skipped, never deleted (it is part of the installation).

``OGCP_SHIPPED_KERNELS=0`` turns them off: every kernel is then compiled for this CPU (what a
benchmark of the compiled code's speed may want). Rebuild them after editing a kernel's source
(a test says when they are stale)::

    python -m ogcp.benchmarks.perf.ship_kernels
"""

from __future__ import annotations

import hashlib
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

__all__ = ["SHIPPED", "SHIPPED_CPU", "enabled", "shipped_index", "shipped_key", "shipped_stamp", "source_digest"]

#: Where the shipped cache files are (package data).
SHIPPED = Path(__file__).resolve().parent / "shipped"
#: The CPU the shipped kernels are compiled for (an LLVM CPU name): the x86-64-v3 level.
SHIPPED_CPU = "x86-64-v3"
#: The host CPU features that level needs (LLVM's names): without one of them the shipped code
#: could meet an instruction the CPU lacks, so it is not loaded.
SHIPPED_CPU_FEATURES = (
    "avx",
    "avx2",
    "bmi",
    "bmi2",
    "cx16",
    "f16c",
    "fma",
    "lzcnt",
    "movbe",
    "popcnt",
    "sahf",
    "sse3",
    "sse4.1",
    "sse4.2",
    "ssse3",
    "xsave",
)
#: Stamp of a shipped index: this tag and the source digest (numba's own stamp is (mtime, size)).
STAMP_TAG = "ogcp-shipped/1"
_PLANNER = Path(__file__).resolve().parents[2]
#: The sources a kernel is compiled from, relative to the planner package: the kernels' modules and
#: every module whose constants they import (frozen into the compiled code).
SOURCES = (
    "grasp/kernel/__init__.py",
    "grasp/kernel/batch.py",
    "grasp/kernel/certify.py",
    "grasp/kernel/epa.py",
    "grasp/kernel/geometry.py",
    "grasp/kernel/ray_bound.py",
    "grasp/kernel/refit.py",
    "grasp/subset_quality.py",
    "hands/box_index.py",
    "infra/arrays.py",
    "search/children_kernel.py",
    "search/expansion.py",
    "search/open_list.py",
    "search/outcome.py",
    "search/refine.py",
    "search/refine_kernel.py",
    "search/search_space.py",
)


def enabled() -> bool:
    """Whether shipped kernels may be loaded: ``OGCP_SHIPPED_KERNELS`` is not ``0`` and this CPU
    has every feature of :data:`SHIPPED_CPU`."""
    return os.environ.get("OGCP_SHIPPED_KERNELS", "1") != "0" and _cpu_runs_shipped()


@lru_cache(maxsize=1)
def _cpu_runs_shipped() -> bool:
    try:
        from llvmlite import binding  # type: ignore[import-untyped]

        features = binding.get_host_cpu_features()
    except Exception:  # noqa: BLE001 - a CPU whose features cannot be read gets code compiled for it
        return False
    return all(features.get(name, False) for name in SHIPPED_CPU_FEATURES)


@lru_cache(maxsize=1)
def source_digest() -> str:
    """sha256 of every source in :data:`SOURCES` (path and content): the shipped caches' key."""
    digest = hashlib.sha256()
    for relative in SOURCES:
        digest.update(relative.encode() + b"\0")
        try:
            digest.update((_PLANNER / relative).read_bytes())
        except OSError:
            digest.update(b"<missing>")
        digest.update(b"\0")
    return digest.hexdigest()


def shipped_stamp() -> tuple[str, str]:
    """The stamp a current shipped index carries."""
    return (STAMP_TAG, source_digest())


def shipped_index(filename_base: str) -> Path:
    """Path of a kernel's shipped index (``filename_base`` as numba names its cache files)."""
    return SHIPPED / f"{filename_base}.ogcp.nbi"


def shipped_key(key: tuple[Any, ...]) -> tuple[Any, ...]:
    """numba's index key ``(signature, (triple, cpu, features), hashes)`` for :data:`SHIPPED_CPU`."""
    signature, (triple, _cpu, _features), hashes = key
    return (signature, (triple, SHIPPED_CPU, ""), hashes)
