"""Where ogcp keeps what it computes once and reuses (reachability models, decompositions, meshes)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir(subdir: str | None = None) -> Path:
    """The ogcp cache folder: ``$OGCP_CACHE`` or ``~/.cache/ogcp``, plus an optional subfolder.

    The folder is not created here; writers create it when they first store something.
    """
    root = Path(os.environ.get("OGCP_CACHE") or Path.home() / ".cache" / "ogcp")
    return root / subdir if subdir else root
