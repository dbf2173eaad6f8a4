"""Convert Dex-Net parallel-jaw grasps into ``ogcp.grasps/1`` by closing the jaws on the mesh.

Run: ``python -m ogcp.benchmarks.studies.convert_dexnet IN.npy|IN.txt -o OUT.json --mesh MESH_OR_NAME --mu MU``
[``--diagonal M``] [``--cone-edges K``] [``--method NAME``] [``--units m|cm|mm``] [``--skip-missed``].

The format (facts read from BerkeleyAutomation/dex-net, commit
cccf93319095374b0eefc24b8b6cd40bc23966d2, files ``src/dexnet/grasping/grasp.py``,
``src/dexnet/grasping/contacts.py``, ``src/dexnet/database/hdf5_factory.py`` and
``src/dexnet/database/keys.py``; that code is under the UC Berkeley (Regents) educational,
research and not-for-profit licence, and none of it is copied here):

* A ``ParallelJawPtGrasp3D`` is stored as its ``configuration``, a float vector of 10 (or 9)
  entries: ``[0:3]`` the jaw centre, ``[3:6]`` the unit grasp axis (between the jaws), ``[6]``
  the maximum opening width, ``[7]`` the approach angle [rad], ``[8]`` the jaw width, ``[9]`` the
  minimum closing width (0 when the vector has 9 entries). Lengths are in the object's mesh
  frame (metres for Dex-Net's meshes) when the grasp's ``frame`` is ``"object"`` (the default).
* A Dex-Net HDF5 database keeps it as the attribute ``configuration`` of the group
  ``grasp_<id>`` (attributes ``id``, ``type``, ``frame`` beside it) under an object's grasps.
* The contacts are found by closing the jaws: jaw 1 starts at the endpoint ``centre - width/2 *
  axis`` and moves along ``+axis``, jaw 2 at ``centre + width/2 * axis`` along ``-axis``, each
  over ``(width - min_width) / 2``; a jaw's contact is the first surface point it meets, and the
  grasp has no contacts when either jaw meets none. Dex-Net's contact normal points out of the
  object (flipped against the jaw's direction).

This module reads those vectors as a ``.npy`` array of shape (G, 10) or (G, 9), or a text table
of the same rows (whitespace or comma separated, ``#`` comments; ``numpy.savetxt`` of the
vectors). Extract them from a database with h5py (not a dependency of ogcp), e.g. the
``configuration`` attribute of every ``grasp_<id>`` group, stacked in id order.

Approximated: Dex-Net finds the surface crossing on a signed-distance grid and takes the normal
from the grid's gradient; here each jaw's line is ray-cast against the exact triangle mesh that
ogcp loads (the first face the jaw enters, with the face's inward normal). The approach angle and
jaw width only place the gripper body (collisions), not the contacts, so they are dropped; the
two contacts are hard fingers at points, so Q1 of such a grasp is 0 (never force closure).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from ogcp.benchmarks.studies.convert_grasps import UNITS, converter_parser, record_head, run_converter
from ogcp.planner.grasp.defaults import DEFAULT_CONE_EDGES
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.grasps import ExternalGrasps, is_object_name, load_grasps

#: Largest deviation from 1 of a configuration's axis length (Dex-Net refuses beyond it).
AXIS_TOLERANCE = 1e-5
#: Slack at both ends of a jaw's travel [m], so a contact exactly at an end is kept.
TRAVEL_SLACK = 1e-9


def read_configurations(path: Path) -> NDArray[np.float64]:
    """The Dex-Net configuration vectors of a ``.npy`` array or a text table, one row per grasp.

    Returns:
        A (G, 10) array; a 9-entry row gets minimum width 0, as Dex-Net reads it.

    Raises:
        OgcpError: For an unreadable file or rows that are not 9 or 10 finite numbers.
    """
    try:
        if path.suffix.lower() == ".npy":
            array = np.load(path, allow_pickle=False)
        else:
            text = path.read_text(encoding="utf-8")
            rows = [line.split("#", 1)[0].strip() for line in text.splitlines()]
            rows = [row for row in rows if row]
            delimiter = "," if rows and "," in rows[0] else None
            array = np.loadtxt(rows, delimiter=delimiter, ndmin=2)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise OgcpError(f"{path}: not an array of Dex-Net grasp configurations ({exc})") from None
    if array.ndim == 1 and array.shape[0] in (9, 10):
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] not in (9, 10) or array.shape[0] == 0:
        raise OgcpError(f"{path}: expected Dex-Net configurations of shape (G, 10) or (G, 9), got {array.shape}")
    if not np.issubdtype(array.dtype, np.number) or not np.all(np.isfinite(array.astype(float))):
        raise OgcpError(f"{path}: expected finite numbers, got {array.dtype} with non-finite entries")
    array = array.astype(float)
    if array.shape[1] == 9:
        array = np.hstack([array, np.zeros((array.shape[0], 1))])
    return array


def close_jaws(
    mesh: trimesh.Trimesh, configuration: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The two contacts of a Dex-Net parallel-jaw grasp, found by ray casting the closing jaws.

    Args:
        mesh: The object, in the frame of the configuration [m].
        configuration: ``[centre (3) [m], axis (3), max width [m], approach angle [rad], jaw width
            [m], min width [m]]``.

    Returns:
        ``(positions (2, 3) [m], inward normals (2, 3))``, jaw 1 (moving along ``+axis``) first;
        None when a jaw meets no surface over its travel.

    Raises:
        OgcpError: For an axis that is not a unit vector or a width that is not positive.
    """
    centre, axis = configuration[0:3], configuration[3:6]
    width, min_width = float(configuration[6]), float(configuration[9])
    if abs(float(np.linalg.norm(axis)) - 1.0) > AXIS_TOLERANCE:
        raise OgcpError(f"grasp axis {axis.tolist()} is not a unit vector (length {np.linalg.norm(axis):.6g})")
    if not width > 0 or not 0 <= min_width <= width:
        raise OgcpError(f"widths must satisfy 0 <= min width <= max width, 0 < max width; got {min_width}, {width}")
    axis = axis / np.linalg.norm(axis)
    travel = (width - min_width) / 2
    origins = np.stack([centre - width / 2 * axis, centre + width / 2 * axis])
    directions = np.stack([axis, -axis])
    positions, normals = np.zeros((2, 3)), np.zeros((2, 3))
    for jaw in (0, 1):
        hit = _first_entry(mesh, origins[jaw], directions[jaw], travel + TRAVEL_SLACK)
        if hit is None:
            return None
        positions[jaw], normals[jaw] = hit
    return positions, normals


def _first_entry(
    mesh: trimesh.Trimesh, origin: NDArray[np.float64], direction: NDArray[np.float64], reach: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The first face a ray enters within ``reach`` [m]: ``(point [m], inward unit normal)``, or None.

    Moller-Trumbore against every triangle at once (no spatial index: trimesh's needs rtree,
    which ogcp does not depend on, and one ray per jaw is cheap).
    """
    triangles = mesh.triangles
    a = triangles[:, 0]
    e1, e2 = triangles[:, 1] - a, triangles[:, 2] - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    outward = mesh.face_normals
    # Only faces the jaw enters (outward normal against its motion) are contacts: a face the jaw
    # leaves lies behind a surface it already met; edge-on faces (det 0) are never hit.
    entering = (outward @ direction < 0) & (np.abs(det) > 1e-15)
    safe = np.where(entering, det, 1.0)
    s = origin - a
    u = np.einsum("ij,ij->i", s, p) / safe
    q = np.cross(s, e1)
    v = (q @ direction) / safe
    t = np.einsum("ij,ij->i", e2, q) / safe
    eps = 1e-12
    ok = entering & (u >= -eps) & (v >= -eps) & (u + v <= 1 + eps) & (t >= -TRAVEL_SLACK) & (t <= reach)
    if not np.any(ok):
        return None
    first = int(np.argmin(np.where(ok, t, np.inf)))
    return origin + t[first] * direction, -outward[first]


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
    skip_missed: bool = False,
) -> ExternalGrasps:
    """Convert Dex-Net configurations into two-contact grasps and write them as ``ogcp.grasps/1``.

    The configurations must be in the frame of the mesh ogcp loads: a mesh file's own frame, or,
    with ``diagonal`` (always for built-in objects), the centred and scaled one.

    Args:
        source: ``.npy`` array or text table of configurations.
        out: The ``ogcp.grasps/1`` file to write.
        mesh: Built-in or fetched object name, or mesh path.
        mu: Friction coefficient of the contacts.
        diagonal: Scale the object to this bounding-box diagonal [m].
        cone_edges: Friction-cone edges k.
        method: The planner that made the grasps.
        contact_model: ``hard`` or ``soft`` (written to the record; None: the record's default, hard).
        torsional_friction: Torsional friction coefficient of soft fingers [m] (None: the default).
        units: Units of the centres and widths (``m``, ``cm``, ``mm``).
        skip_missed: Drop grasps a jaw of which meets no surface, instead of refusing the file.

    Returns:
        The grasps as written and read back (checked); labels ``grasp-<row>``.

    Raises:
        OgcpError: For a bad file, unit or configuration, a missed grasp (unless skipped), or no
            grasp left.
    """
    if units not in UNITS:
        raise OgcpError(f"unknown units {units!r}; valid choices: {', '.join(UNITS)}")
    if not source.is_file():
        raise OgcpError(f"{source}: no such file")
    configurations = read_configurations(source)
    # Lengths scale (centre and the three widths); the unit axis and the angle do not.
    configurations[:, [0, 1, 2, 6, 8, 9]] *= UNITS[units]
    spec = mesh if is_object_name(mesh) else str(Path(mesh))
    loaded, _ = resolve_object(spec, diagonal)
    entries: list[dict[str, Any]] = []
    missed: list[int] = []
    for row, configuration in enumerate(configurations):
        try:
            contacts = close_jaws(loaded, configuration)
        except OgcpError as exc:
            raise OgcpError(f"{source}: row {row}: {exc}") from None
        if contacts is None:
            missed.append(row)
            continue
        positions, normals = contacts
        entries.append(
            {
                "label": f"grasp-{row}",
                "contacts": [{"position": p, "normal": n} for p, n in zip(positions.tolist(), normals.tolist())],
            }
        )
    if missed and not skip_missed:
        raise OgcpError(
            f"{source}: {len(missed)} grasp(s) whose jaws meet no surface (first: row {missed[0]}); "
            "check the frame and units, or pass --skip-missed"
        )
    if not entries:
        raise OgcpError(f"{source}: no grasp left: every jaw pair misses the object")
    record = record_head(out, mesh, mu, diagonal, cone_edges, method, contact_model, torsional_friction)
    record["grasps"] = entries
    # Checked before writing, so that a bad input never leaves a file behind.
    ExternalGrasps.from_dict(record, where=str(source), base=out.parent)
    write_json_atomic(out, record)
    return load_grasps(out)


def main(argv: list[str] | None = None) -> int:
    parser = converter_parser(
        (__doc__ or "").splitlines()[0],
        "Dex-Net configurations: .npy (G, 10|9) or a text table",
        "units of centres and widths",
        "dexnet",
    )
    parser.add_argument("--skip-missed", action="store_true", help="drop grasps whose jaws meet no surface")
    args = parser.parse_args(argv)
    return run_converter(
        "convert_dexnet",
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
            skip_missed=args.skip_missed,
        ),
    )


if __name__ == "__main__":
    sys.exit(main())
