"""Where ogcp's data files are: the hand model, the manifest of fetchable objects, the suites.

The files live in the repository's top-level ``assets/`` folder, beside ``planner/``. A wheel
installs that folder as the data-only package ``ogcp.assets``, again beside ``ogcp/planner``. Every
reader asks :func:`asset_path` rather than building a path itself.
"""

from __future__ import annotations

from pathlib import Path

from ogcp.planner.infra.errors import OgcpError

# Located from this file rather than with importlib.resources("ogcp.assets"): a checkout must
# read its own assets even when another copy of ogcp (say an editable install of a different
# worktree) is what the import system would find under that name. resolve() follows ogcp/'s
# links, so in a checkout this is the repository root and in a wheel site-packages/ogcp.
_FOLDER = Path(__file__).resolve().parents[2] / "assets"


def assets_dir() -> Path:
    """The folder holding ogcp's data files.

    Returns:
        ``ogcp/assets`` of a wheel install, the top-level ``assets`` of a checkout.

    Raises:
        OgcpError: If it is missing (a broken install).
    """
    if _FOLDER.is_dir():
        return _FOLDER
    raise OgcpError(
        f"ogcp's data files are missing (looked for {_FOLDER}); the ogcp "
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
