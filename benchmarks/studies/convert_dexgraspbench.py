"""Convert DexGraspBench-style hand grasps (root pose + joint angles per stage) into ``ogcp.grasps/1``.

Run: ``python -m ogcp.benchmarks.studies.convert_dexgraspbench IN... -o OUT.json --hand HAND --mesh MESH
--mu MU`` [``--diagonal M``] [``--joints a,b,...``] [``--allow-pickle``].

Each input holds one grasp or a batch: ``grasp_qpos`` and, optionally, ``pregrasp_qpos`` and
``squeeze_qpos``, each a vector (or rows of vectors) of the root body's position [m], its
(w, x, y, z) quaternion and the joint angles (``--joints`` names their order; default: every joint
of the hand's model, wrist included, when the count matches, else its finger joints). Optional
``obj_pose`` (position + wxyz quaternion of the object in the same world) moves the hands into the
object's frame, and ``obj_scale`` scales the mesh (its diagonal becomes ``obj_scale`` times the
mesh file's own, unless ``--diagonal`` is given). Formats:

* ``.json``: an object with those keys (or a list of such objects);
* ``.npz``: arrays with those names;
* ``.npy``: a dict saved with ``np.save`` (how DexGraspBench writes its grasps). Reading it runs
  Python's pickle, which can execute code: only with ``--allow-pickle``, for files you trust.

Every stage becomes the palm's pose and the finger joints' angles
(:func:`ogcp.sim_eval.hand.root_pose.stage_from_root_qpos`); the record is read back with ogcp's
own checks before the command succeeds, and ``ogcp evaluate OUT.json`` simulates it.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ogcp.benchmarks.studies.convert_grasps import UNITS, converter_parser, record_head, run_converter
from ogcp.planner.grasp.defaults import DEFAULT_CONE_EDGES
from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.registry import is_descriptor_path, resolve_hand
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.grasps import ExternalGrasps, load_grasps, mesh_reference
from ogcp.sim_eval.hand.given import quaternion_of, rotation_of
from ogcp.sim_eval.hand.root_pose import joint_order, stage_from_root_qpos

STAGES = ("pregrasp_qpos", "grasp_qpos", "squeeze_qpos")


def read_source(path: Path, allow_pickle: bool = False) -> list[dict[str, Any]]:
    """The records of one input file, each a dict of arrays by key.

    Raises:
        OgcpError: For an unknown format, an unreadable file, a pickle without ``allow_pickle``,
            or a record without ``grasp_qpos``.
    """
    suffix = path.suffix.lower()
    if not path.is_file():
        raise OgcpError(f"{path}: no such file")
    try:
        if suffix == ".json":
            data = json.loads(path.read_text(encoding="utf-8"))
            records = data if isinstance(data, list) else [data]
        elif suffix == ".npz":
            with np.load(path, allow_pickle=False) as arrays:
                records = [{key: arrays[key] for key in arrays.files}]
        elif suffix == ".npy":
            if not allow_pickle:
                raise OgcpError(
                    f"{path}: a DexGraspBench .npy grasp is a pickled dict, and unpickling can run code; "
                    "pass --allow-pickle for a file you trust (or convert it to .json or .npz)"
                )
            loaded = np.load(path, allow_pickle=True)
            records = [loaded.item() if loaded.dtype == object and loaded.shape == () else loaded]
        else:
            raise OgcpError(f"{path}: unknown format {path.suffix!r}; valid: .json, .npz, .npy")
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise OgcpError(f"{path}: cannot read ({exc})") from None
    for k, record in enumerate(records):
        if not isinstance(record, dict) or "grasp_qpos" not in record:
            raise OgcpError(f"{path}: record {k}: expected an object with grasp_qpos (and pregrasp_qpos, squeeze_qpos)")
    return records


def _rows(value: Any, where: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise OgcpError(f"{where}: expected numbers") from None
    if array.ndim == 1:
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] < 8:
        raise OgcpError(f"{where}: expected a vector (7 + joints) or rows of them, got shape {array.shape}")
    return array


def _to_object_frame(rows: np.ndarray, object_pose: Any, where: str) -> np.ndarray:
    """Root poses moved from the world into the object's frame (``obj_pose``: position, wxyz quaternion)."""
    pose = np.asarray(object_pose, dtype=float).ravel()
    if pose.shape != (7,) or not np.isfinite(pose).all():
        raise OgcpError(f"{where}: obj_pose: expected 7 numbers (position, w x y z quaternion), got shape {pose.shape}")
    rotation = rotation_of(pose[3:])
    moved = rows.copy()
    moved[:, :3] = (rows[:, :3] - pose[:3]) @ rotation  # R^T (p - t), row-wise
    for k, row in enumerate(rows):
        turned = rotation.T @ rotation_of(row[3:7])
        moved[k, 3:7] = quaternion_of(turned)
    return moved


def hand_grasps(
    kinematics: HandKinematics,
    records: Sequence[tuple[str, dict[str, Any]]],
    joints: Sequence[str] | None,
    scale: float = 1.0,
) -> tuple[list[dict[str, Any]], float | None]:
    """The ``ogcp.grasps/1`` entries of the records, and the records' common ``obj_scale`` (None if absent)."""
    entries: list[dict[str, Any]] = []
    scales = set()
    for label, record in records:
        stages = {}
        for key in STAGES:
            if record.get(key) is not None:
                rows = _rows(record[key], f"{label}: {key}")
                rows[:, :3] *= scale  # positions to metres (slide joints too would need it: none here)
                if record.get("obj_pose") is not None:
                    rows = _to_object_frame(rows, record["obj_pose"], label)
                stages[key] = rows
        count = len(stages["grasp_qpos"])
        for key, rows in stages.items():
            if len(rows) != count:
                raise OgcpError(f"{label}: {key} has {len(rows)} rows, grasp_qpos {count}")
        order = joint_order(kinematics, stages["grasp_qpos"].shape[1] - 7, joints, label)
        if record.get("obj_scale") is not None:
            scales.add(float(np.asarray(record["obj_scale"], dtype=float).ravel()[0]))
        for row in range(count):
            name = label if count == 1 else f"{label}-{row}"
            converted = {
                key: stage_from_root_qpos(kinematics, rows[row], order, f"{name}: {key}")
                for key, rows in stages.items()
            }
            block = converted["grasp_qpos"].to_dict()
            for key, stage in converted.items():
                if key != "grasp_qpos":
                    block[key.removesuffix("_qpos")] = stage.to_dict()
            entries.append({"label": name, "hand": block})
    if len(scales) > 1:
        raise OgcpError(f"the inputs scale the object differently ({sorted(scales)}); convert them separately")
    return entries, scales.pop() if scales else None


def convert(
    sources: Sequence[Path],
    out: Path,
    hand: str,
    mesh: str,
    mu: float,
    *,
    diagonal: float | None = None,
    joints: Sequence[str] | None = None,
    allow_pickle: bool = False,
    units: str = "m",
    method: str = "dexgraspbench",
    cone_edges: int = DEFAULT_CONE_EDGES,
    contact_model: str | None = None,
    torsional_friction: float | None = None,
) -> ExternalGrasps:
    """Convert DexGraspBench-style files into one ``ogcp.grasps/1`` record with the hand's grasps.

    Returns:
        The grasps as written and read back (checked).

    Raises:
        OgcpError: For a bad input, an unknown hand or joint, or a bad field of the result.
    """
    if units not in UNITS:
        raise OgcpError(f"unknown units {units!r}; valid choices: {', '.join(UNITS)}")
    kinematics = HandKinematics(resolve_hand(hand))
    records = [(path.stem, record) for path in sources for record in read_source(path, allow_pickle)]
    labelled = [(label if len(records) == 1 or k == 0 else f"{label}-{k}", r) for k, (label, r) in enumerate(records)]
    entries, scale = hand_grasps(kinematics, labelled, joints, UNITS[units])
    if diagonal is None and scale is not None:
        native, _ = resolve_object(mesh, None)
        diagonal = scale * float(np.linalg.norm(np.ptp(np.asarray(native.vertices), axis=0)))
    record = record_head(out, mesh, mu, diagonal, cone_edges, method, contact_model, torsional_friction)
    record["hand"] = mesh_reference(hand, out.parent) if is_descriptor_path(hand) else hand
    record["grasps"] = entries
    ExternalGrasps.from_dict(record, where=str(out), base=out.parent)  # checked before anything is written
    write_json_atomic(out, record)
    return load_grasps(out)


def main(argv: list[str] | None = None) -> int:
    parser = converter_parser(
        (__doc__ or "").splitlines()[0],
        "DexGraspBench-style grasp file(s)",
        "units of the root positions",
        "dexgraspbench",
    )
    parser.add_argument("more", nargs="*", type=Path, help="more grasp files, merged into one record")
    parser.add_argument("--hand", required=True, help="built-in hand name or ogcp.hand/1 descriptor")
    parser.add_argument("--joints", default=None, help="comma-separated joint names, the order of the angles")
    parser.add_argument("--allow-pickle", action="store_true", help="read .npy pickles (only files you trust)")
    args = parser.parse_args(argv)
    return run_converter(
        "convert_dexgraspbench",
        args.output,
        lambda: convert(
            [args.source, *args.more],
            args.output,
            args.hand,
            args.mesh,
            args.mu,
            diagonal=args.diagonal,
            joints=None if args.joints is None else [j.strip() for j in args.joints.split(",") if j.strip()],
            allow_pickle=args.allow_pickle,
            units=args.units,
            method=args.method,
            cone_edges=args.cone_edges,
            contact_model=args.contact_model,
            torsional_friction=args.torsional_friction,
        ),
    )


if __name__ == "__main__":
    sys.exit(main())
