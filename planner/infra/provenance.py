"""Provenance for result records: library versions, git commit, machine."""

from __future__ import annotations

import importlib.metadata
import platform
import subprocess
from functools import lru_cache
from pathlib import Path

TRACKED_PACKAGES = ("ogcp", "numpy", "scipy", "trimesh", "mujoco", "coacd", "joblib")


def _version(package: str) -> str | None:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None


@lru_cache(maxsize=1)
def git_commit() -> str | None:
    """Commit of the ogcp checkout this code runs from, with ``-dirty`` if modified; None outside git."""
    return checkout_commit(Path(__file__).resolve().parents[2])


def checkout_commit(root: Path) -> str | None:
    """Commit of the git checkout whose top level is ``root``, with ``-dirty`` if tracked files changed.

    Args:
        root: Folder expected to be the top level of a checkout.

    Returns:
        The commit hash, or None when ``root`` is not a checkout's top level (a folder nested in
        some other repository counts as not) or git is unavailable.
    """
    root = Path(root).resolve()
    try:
        toplevel = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "--show-toplevel"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
        # A wheel install inside some other repository (a venv in a user's project) must not
        # report that repository's commit as ogcp's.
        if Path(toplevel).resolve() != root:
            return None
        commit = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return commit + ("-dirty" if dirty else "") if commit else None


@lru_cache(maxsize=1)
def provenance() -> dict[str, object]:
    """Versions of ogcp and its key dependencies, the git commit, Python and the CPU."""
    return {
        "versions": {name: _version(name) for name in TRACKED_PACKAGES},
        "python": platform.python_version(),
        "git_commit": git_commit(),
        "machine": {"platform": platform.platform(), "processor": platform.processor() or platform.machine()},
    }
