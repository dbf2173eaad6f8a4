"""Convert fingertip grasps from a CSV table or a numpy array into ``ogcp.grasps/1``.

Run: ``python -m ogcp.benchmarks.studies.convert_grasps IN.csv|IN.npy -o OUT.json --mesh MESH_OR_NAME --mu MU``
[``--diagonal M``] [``--cone-edges K``] [``--method NAME``] [``--units m|cm|mm``] [``--outward``].

Two input formats, both one fingertip contact per row (docs/external_grasps.md has examples):

* CSV with a header row naming at least the columns ``grasp, px, py, pz, nx, ny, nz`` (any order;
  extra columns ignored). Rows with the same ``grasp`` value form one grasp, contacts in row
  order, grasps in order of first appearance. Optional columns ``label``, ``method`` and
  ``score`` are read from a grasp's first row (``label`` defaults to the ``grasp`` value; an empty
  ``score`` is none). Lines starting with ``#`` are comments, blank lines skipped.
* ``.npy``: one float array of shape (G, m, 6), row ``[px, py, pz, nx, ny, nz]`` per fingertip:
  G grasps of m contacts each (the layout of fingertip-array planners); labels ``grasp-<i>``.

Positions are converted from ``--units`` to metres; ``--outward`` negates normals given
pointing out of the object (ogcp's point into it). A mesh path is written relative to the
output file. The output is read back with ogcp's own checks before the command succeeds.
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.planner.grasp.defaults import DEFAULT_CONE_EDGES
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.grasps import GRASPS_SCHEMA, ExternalGrasps, is_object_name, load_grasps, mesh_reference

#: Metres per unit of ``--units``.
UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
REQUIRED = ("grasp", "px", "py", "pz", "nx", "ny", "nz")


def _float(path: Path, line: int, column: str, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise OgcpError(f"{path}:{line}: column {column}: expected a number, got {text!r}") from None


def read_csv(path: Path, scale: float = 1.0, sign: float = 1.0) -> list[dict[str, Any]]:
    """The grasps of a CSV table, as ``ogcp.grasps/1`` entries (positions times ``scale``, normals times ``sign``).

    Raises:
        OgcpError: For a missing column or a cell that is not a number, naming the file and line.
    """
    text = path.read_text(encoding="utf-8")
    # Comments and blank lines dropped, each kept line with its number for the messages.
    rows = [(n, line) for n, line in enumerate(text.splitlines(), start=1) if line.strip() and line.lstrip()[0] != "#"]
    reader = csv.DictReader(io.StringIO("\n".join(line for _, line in rows)), skipinitialspace=True)
    missing = [c for c in REQUIRED if c not in (reader.fieldnames or [])]
    if missing:
        raise OgcpError(f"{path}: missing column(s) {', '.join(missing)}; the header must name {', '.join(REQUIRED)}")
    grasps: dict[str, dict[str, Any]] = {}
    for (line, _), row in zip(rows[1:], reader, strict=True):
        key = (row.get("grasp") or "").strip()
        if not key:
            raise OgcpError(f"{path}:{line}: column grasp: empty")
        p = [scale * _float(path, line, c, row[c] or "") for c in ("px", "py", "pz")]
        n = [sign * _float(path, line, c, row[c] or "") for c in ("nx", "ny", "nz")]
        if key not in grasps:
            entry: dict[str, Any] = {"label": (row.get("label") or "").strip() or key, "contacts": []}
            if (row.get("method") or "").strip():
                entry["method"] = row["method"].strip()
            if (row.get("score") or "").strip():
                entry["score"] = _float(path, line, "score", row["score"])
            grasps[key] = entry
        grasps[key]["contacts"].append({"position": p, "normal": n})
    return list(grasps.values())


def read_npy(path: Path, scale: float = 1.0, sign: float = 1.0) -> list[dict[str, Any]]:
    """The grasps of a (G, m, 6) array, as ``ogcp.grasps/1`` entries.

    Raises:
        OgcpError: For a file that is not such an array.
    """
    try:
        array = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise OgcpError(f"{path}: not a numpy array file ({exc})") from None
    if array.ndim != 3 or array.shape[2] != 6 or not np.issubdtype(array.dtype, np.number):
        raise OgcpError(f"{path}: expected a numeric array of shape (G, m, 6), got {array.dtype} {array.shape}")
    array = array.astype(float)
    return [
        {
            "label": f"grasp-{i}",
            "contacts": [{"position": (scale * r[:3]).tolist(), "normal": (sign * r[3:]).tolist()} for r in grasp],
        }
        for i, grasp in enumerate(array)
    ]


def convert(
    source: Path,
    out: Path,
    mesh: str,
    mu: float,
    *,
    diagonal: float | None = None,
    cone_edges: int = DEFAULT_CONE_EDGES,
    method: str | None = None,
    contact_model: str | None = None,
    torsional_friction: float | None = None,
    units: str = "m",
    outward: bool = False,
) -> ExternalGrasps:
    """Convert a CSV or ``.npy`` file of fingertip contacts and write it as ``ogcp.grasps/1``.

    Returns:
        The grasps as written and read back (checked).

    Raises:
        OgcpError: For an unknown format or unit, a bad input file, or a bad field of the result.
    """
    if units not in UNITS:
        raise OgcpError(f"unknown units {units!r}; valid choices: {', '.join(UNITS)}")
    read = {".csv": read_csv, ".npy": read_npy}.get(source.suffix.lower())
    if read is None:
        raise OgcpError(f"{source}: unknown format {source.suffix!r}; valid: .csv, .npy")
    if not source.is_file():
        raise OgcpError(f"{source}: no such file")
    record = record_head(out, mesh, mu, diagonal, cone_edges, method, contact_model, torsional_friction)
    record["grasps"] = read(source, UNITS[units], -1.0 if outward else 1.0)
    # Checked before writing, so that a bad input never leaves a file behind.
    ExternalGrasps.from_dict(record, where=str(source), base=out.parent)
    write_json_atomic(out, record)
    return load_grasps(out)


def record_head(
    out: Path,
    mesh: str,
    mu: float,
    diagonal: float | None,
    cone_edges: int,
    method: str | None,
    contact_model: str | None,
    torsional_friction: float | None,
) -> dict[str, Any]:
    """An ``ogcp.grasps/1`` record without its grasps: the object, the friction model and the planner.

    The mesh is written as given when it is a built-in or fetched name, else as a path relative
    to the output's folder. Unset optional fields are left out (the schema's defaults); the
    values are checked when the whole record is read (``ExternalGrasps.from_dict``).
    """
    obj: dict[str, Any] = {"mesh": mesh if is_object_name(mesh) else mesh_reference(mesh, out.parent)}
    if diagonal is not None:
        obj["diagonal"] = diagonal
    record: dict[str, Any] = {"schema": GRASPS_SCHEMA, "object": obj, "mu": mu, "cone_edges": cone_edges}
    if contact_model is not None:
        record["contact_model"] = contact_model
    if torsional_friction is not None:
        record["torsional_friction"] = torsional_friction
    if method is not None:
        record["method"] = method
    return record


def converter_parser(
    description: str, source_help: str, units_help: str, method_default: str | None
) -> argparse.ArgumentParser:
    """The arguments every converter takes: the source, the output, the object, friction and units."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("source", type=Path, help=source_help)
    parser.add_argument("-o", "--output", type=Path, required=True, help="the ogcp.grasps/1 file to write")
    parser.add_argument("--mesh", required=True, help="built-in or fetched object name, or mesh path")
    parser.add_argument("--mu", type=float, required=True, help="friction coefficient of the contacts")
    parser.add_argument("--diagonal", type=float, default=None, help="scale the object to this diagonal [m]")
    parser.add_argument("--cone-edges", type=int, default=DEFAULT_CONE_EDGES, help="friction-cone edges k")
    parser.add_argument(
        "--contact-model", default=None, help="hard or soft fingers (soft: with torsional friction; default hard)"
    )
    parser.add_argument(
        "--torsional-friction", type=float, default=None, help="torsional friction coefficient of soft fingers [m]"
    )
    default = f" (default {method_default})" if method_default else ""
    parser.add_argument("--method", default=method_default, help=f"the planner that made the grasps{default}")
    parser.add_argument("--units", choices=tuple(UNITS), default="m", help=f"{units_help} (default m)")
    return parser


def run_converter(name: str, output: Path, convert_file: Callable[[], ExternalGrasps]) -> int:
    """Run a conversion: one summary line and exit status 0, or one error line and 2."""
    try:
        grasps = convert_file()
    except OgcpError as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 2
    print(f"{output}: {len(grasps.grasps)} grasp(s) on {grasps.mesh}, mu {grasps.mu:g}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = converter_parser(
        (__doc__ or "").splitlines()[0], "CSV table or .npy array of fingertip contacts", "units of the positions", None
    )
    parser.add_argument("--outward", action="store_true", help="the normals point out of the object: negate them")
    args = parser.parse_args(argv)
    return run_converter(
        "convert_grasps",
        args.output,
        lambda: convert(
            args.source,
            args.output,
            args.mesh,
            args.mu,
            diagonal=args.diagonal,
            cone_edges=args.cone_edges,
            method=args.method,
            contact_model=args.contact_model,
            torsional_friction=args.torsional_friction,
            units=args.units,
            outward=args.outward,
        ),
    )


if __name__ == "__main__":
    sys.exit(main())
