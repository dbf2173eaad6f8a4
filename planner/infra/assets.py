"""Where ogcp's data files are: the hand model, the manifest of fetchable objects, the suites.

The files live in the repository's top-level ``assets/`` folder. A wheel installs that folder as
the data-only package ``ogcp_assets`` (pyproject's ``package-dir``), beside ``planner``; a
checkout or an editable install keeps it at the repository root, also beside ``planner``. Every
reader asks :func:`asset_path` rather than building a path itself.
"""

from __future__ import annotations

from pathlib import Path

from planner.infra.errors import OgcpError

# Located from this file rather than with importlib.resources("ogcp_assets"): a checkout must
# read its own assets even when another copy of ogcp (say an editable install of a different
# worktree) is what the import system would find under that name.
_SITE = Path(__file__).resolve().parents[2]
# The installed name comes first: site-packages may hold an unrelated top-level "assets".
_CANDIDATES = (_SITE / "ogcp_assets", _SITE / "assets")


def assets_dir() -> Path:
    """The folder holding ogcp's data files.

    Returns:
        ``ogcp_assets`` of a wheel install, else the checkout's ``assets``.

    Raises:
        OgcpError: If neither exists (a broken install).
    """
    for candidate in _CANDIDATES:
        if candidate.is_dir():
            return candidate
    raise OgcpError(
        f"ogcp's data files are missing (looked for {' and '.join(map(str, _CANDIDATES))}); the ogcp "
        "install is incomplete, reinstall it (pip install --force-reinstall ogcp, or pip install -e . from a checkout)"
    )


def asset_path(relative: str) -> Path:
    """Absolute path of one shipped data file.

    Args:
        relative: Path inside ``assets/`` with forward slashes, e.g. ``"hands/sdh.xml"``.

    Returns:
        The existing file's absolute path.

    Raises:
        OgcpError: If the file is missing (a broken install or a misspelt name).
    """
    path = assets_dir() / relative
    if not path.is_file():
        raise OgcpError(
            f"ogcp data file {relative} not found at {path}; the ogcp install is incomplete, reinstall it "
            "(pip install --force-reinstall ogcp, or pip install -e . from a checkout)"
        )
    return path
