"""``ogcp evaluate GRASPS.json``: simulate grasps from any planner (schema ``ogcp.grasps/1``).

``ogcp evaluate`` takes a plan or a grasps file; :mod:`ogcp.benchmarks.cli.simulate` hands a file
whose schema is ``ogcp.grasps/1`` (:func:`is_external`) to :func:`run_external`, with the
settings it built from the same flags. This module never imports ``simulate``, so that the
dispatch does not close an import cycle: the settings and the table come in as arguments.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ogcp.benchmarks.cli.options import check_output
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError

if TYPE_CHECKING:
    from ogcp.sim_eval.decomposition.settings import DecompositionSettings
    from ogcp.sim_eval.settings import SimSettings

#: The ``--on-surface`` choices (see ``ogcp.sim_eval.external.ON_SURFACE``); the first is the default.
ON_SURFACE_CHOICES = ("project", "refuse")


def is_external(path: Path) -> bool:
    """Whether ``path`` is an ``ogcp.grasps/1`` file (a plan, or an unreadable file, is not)."""
    from ogcp.planner.records.grasps import is_grasps_file

    return is_grasps_file(path)


def _number(value: Any, digits: int, scale: float = 1.0) -> str:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "-"
    return f"{scale * value:.{digits}f}"


def _mapping(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def _soft(block: dict[str, Any]) -> str:
    """``, soft fingers (torsion 0.02 m)`` for a record of soft contacts; nothing for hard ones."""
    if block.get("contact_model") != "soft":
        return ""
    return f", soft fingers (torsion {block.get('torsional_friction')} m)"


def external_summary(record: dict[str, Any]) -> str:
    """Lines of an external evaluation's record: per grasp its method, score, Q1 and surface fit."""
    obj = _mapping(record.get("object"))
    block = _mapping(obj.get("external"))
    entries = [e for e in block.get("grasps") or [] if isinstance(e, dict)]
    head = (
        f"external grasps ({obj.get('file') or 'given'}): {len(entries)} grasp(s), mu {block.get('mu')}, "
        f"cone edges {block.get('cone_edges')}{_soft(block)}; contacts off the surface by at most "
        f"{_number(block.get('max_surface_distance'), 3, 1e3)} mm (tolerance "
        f"{_number(block.get('surface_tolerance'), 3, 1e3)} mm, {block.get('n_projected', 0)} projected), "
        f"normals at most {_number(block.get('max_normal_angle'), 1)} deg off"
    )
    lines = [head]
    for entry in entries:
        distances = [abs(d) for d in entry.get("surface_distance") or [] if isinstance(d, (int, float))]
        angles = [a for a in entry.get("normal_angle") or [] if isinstance(a, (int, float))]
        moved = sum(bool(p) for p in entry.get("projected") or [])
        lines.append(
            f"  {entry.get('label')} ({entry.get('method') or 'external'}): score {_number(entry.get('score'), 4)}, "
            f"ogcp Q1 {_number(entry.get('q1'), 4)}, surface distance <= "
            f"{_number(max(distances, default=math.nan), 3, 1e3)} mm, normal <= "
            f"{_number(max(angles, default=math.nan), 1)} deg" + (f", {moved} projected" if moved else "")
        )
    return "\n".join(lines)


def run_external(
    args: argparse.Namespace,
    settings: SimSettings,
    decomposition: DecompositionSettings,
    summary: Callable[[dict[str, Any]], str] | None = None,
) -> int:
    """Simulate the grasps of an ``ogcp.grasps/1`` file: the ``ogcp evaluate`` handler for it.

    Args:
        args: The ``evaluate`` command's arguments: ``plan`` (the grasps file), ``max_grasps``,
            ``output``, ``json``, ``render``, ``tips`` (fingertips even for a record that names
            a hand), and ``on_surface`` if the command has that flag (default ``project``).
        settings: The simulation settings built from the same flags.
        decomposition: The decomposition settings built from them.
        summary: The table of an ``ogcp.sim/2`` record, printed after the grasps' own lines.

    Returns:
        The exit status (0).

    Raises:
        OgcpError: For a bad file or field, contacts off the surface with ``--on-surface
            refuse``, ``--render`` (it draws plans only), or an output that cannot be written.
    """
    from ogcp.planner.records.grasps import load_grasps
    from ogcp.sim_eval.external import evaluate_grasps

    check_output(args.output)
    if getattr(args, "render", None) is not None:
        raise OgcpError("--render draws a plan's best grasp; it does not draw ogcp.grasps/1 files")
    grasps = load_grasps(args.plan)
    result = evaluate_grasps(
        None,
        grasps,
        settings,
        decomposition,
        on_surface=getattr(args, "on_surface", None) or ON_SURFACE_CHOICES[0],
        progress=sys.stderr.isatty(),
        max_grasps=getattr(args, "max_grasps", None),
        tips=bool(getattr(args, "tips", False)),
    )
    data = result.to_dict()
    if args.output is not None:
        write_json_atomic(args.output, data)
    if args.json:
        print(json.dumps(data))
    else:
        print(external_summary(data) + ("\n" + summary(data) if summary is not None else ""))
    return 0
