"""A user's mesh file made into one ogcp plans on, written as a new file (``ogcp assets repair``).

Scans and downloaded models are often open: a few holes where the scanner saw nothing. Every
command refuses such a file (an open surface has no inside, so no inward normal and no centre of
mass). :func:`repair_file` applies the repair ``ogcp assets fetch`` applies to the meshes it
downloads (:func:`~ogcp.planner.objects.repair.repair_mesh`: degenerate and duplicate faces
dropped, winding made consistent, simple holes closed), checks the result as every command
checks a mesh file, writes it beside nothing else (a temporary file renamed into place, so an
interrupted run leaves no half-written mesh) and reads it back. The original is never changed.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import numpy as np

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.loading import MESH_SUFFIXES, load_mesh
from ogcp.planner.objects.repair import repair_mesh, require_solid

__all__ = ["repair_file"]


def repair_file(source: str | Path, out: str | Path, force: bool = False) -> str:
    """Repair a mesh file and write the result to ``out`` (format from its suffix).

    Args:
        source: The mesh file, coordinates in metres (any unit is kept as it is).
        out: The repaired file; must differ from ``source``.
        force: Replace ``out`` if it exists.

    Returns:
        One line saying what was changed and what was written.

    Raises:
        OgcpError: One line, for an unreadable source, an unsupported or existing ``out``, or a
            mesh the repair cannot make solid (a hole through a pinched vertex, non-manifold edges,
            a flat surface), naming what is left.
    """
    source, out = Path(source), Path(out)
    if out.suffix.lower() not in MESH_SUFFIXES:
        raise OgcpError(f"--out {out}: unsupported mesh format {out.suffix!r}; supported: {', '.join(MESH_SUFFIXES)}")
    if out.exists() and source.exists() and out.resolve() == source.resolve():
        raise OgcpError(f"--out {out} is the mesh file itself; write the repair to another file (the original is kept)")
    if out.exists() and not force:
        raise OgcpError(f"--out {out} exists; --force replaces it")
    mesh = load_mesh(source, solid=False)
    repaired, steps = repair_mesh(mesh)
    try:
        solid, turned = require_solid(repaired)
    except OgcpError as exc:
        done = f" after the repair ({'; '.join(steps)})" if steps else ""
        raise OgcpError(f"{source}: cannot be made solid{done}: {exc}") from None
    _write_whole(solid, out)
    written = load_mesh(out)  # what every command will read: checked, as they check it
    changed = "; ".join((*steps, *turned)) or "nothing to repair: it was already a closed surface"
    volume = float(abs(written.volume))
    return (
        f"{out}: {len(written.vertices)} vertices, {len(written.faces)} faces, closed, volume {volume:.4g} m^3, "
        f"bounding-box diagonal {float(np.linalg.norm(written.extents)):.4g} m ({changed})"
    )


def _write_whole(mesh: object, out: Path) -> None:
    """Export to a temporary file beside ``out`` and rename it into place."""
    out.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{out.name}.", suffix=out.suffix, dir=out.parent)
    os.close(handle)
    try:
        mesh.export(temporary, file_type=out.suffix.lower().lstrip("."))  # type: ignore[attr-defined]
        os.replace(temporary, out)
    except OSError as exc:
        raise OgcpError(f"cannot write {out}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
