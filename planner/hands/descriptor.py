"""The ``ogcp.hand/1`` descriptor: what ogcp needs to know about a hand beyond its MJCF or URDF.

A descriptor is a TOML file beside the hand's model::

    schema = "ogcp.hand/1"
    name = "my_gripper"
    mjcf = "gripper.xml"          # relative to this file; .xml (MJCF) or .urdf
    palm = "palm"                 # body the simulated wrist holds
    # fetched = "shadow_hand"     # optional: mjcf is inside this hand's `ogcp assets fetch` folder
    # ignore_collisions = [["a", "b"]]  # optional: body pairs whose contacts are not collisions
    [[fingers]]
    name = "left"
    tip_body = "left_tip"
    tip_offset = [0.0, 0.0, 0.02] # [m] the pad's contact point, in tip_body's frame
    pad_normal = [0.0, 1.0, 0.0]  # unit, out of the pad, in tip_body's frame
    tip_radius = 0.008            # [m] pad rounding
    # pad_width = 0.02            # [m] optional: a flat pad's face (a jaw), laid flat, touching anywhere on it
    # joints = [...]              # optional; default: the joints from palm to tip_body
    [actuation]                   # for joints that no servo holds (no actuator, or a motor)
    kp = 5.0                      # [N·m/rad] (or N/m for slide joints)
    force_range = 2.0             # [N·m] (or N)

This module reads and checks the file alone (no MuJoCo): every field's type and range, and that
the model file exists. What needs the compiled model (bodies, joints, actuators) is checked by
:class:`ogcp.planner.hands.kinematics.HandKinematics`. Every error is one line naming the file
and the field.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.fetch import fetched_folder
from ogcp.planner.infra.errors import OgcpError

SCHEMA = "ogcp.hand/1"
MODEL_SUFFIXES = (".xml", ".urdf")
#: How far from 1 a pad normal's length may be (a normal typed to 4 decimals passes).
UNIT_TOLERANCE = 1e-3
#: Largest pad offset accepted [m]: a hand bigger than 2 m is a unit error.
MAX_LENGTH = 2.0
#: Largest pad rounding and pad width accepted [m]: a gripper for a 2 m crate may have jaws 0.3 m wide.
MAX_PAD = MAX_LENGTH / 4
_TOP_KEYS = ("schema", "name", "mjcf", "palm", "fingers", "actuation", "fetched", "reachability", "ignore_collisions")
_REACHABILITY_KEYS = ("samples",)
#: The most joint configurations a descriptor may ask the reachability model to sample.
MAX_REACH_SAMPLES = 2_000_000
_FINGER_KEYS = ("name", "tip_body", "tip_offset", "pad_normal", "tip_radius", "pad_width", "joints")
_ACTUATION_KEYS = ("kp", "force_range", "kv")
#: Defaults of ``[actuation]`` (DexGraspBench's gains for the Shadow hand, a 2 N·m limit).
DEFAULT_KP = 5.0
DEFAULT_FORCE_RANGE = 2.0


@dataclass(frozen=True)
class FingerSpec:
    """One finger of a descriptor.

    Attributes:
        name: The finger's name (unique in the hand).
        tip_body: Body that carries the pad.
        tip_offset: The pad's contact point in ``tip_body``'s frame, shape (3,) [m].
        pad_normal: Unit normal out of the pad in ``tip_body``'s frame, shape (3,).
        tip_radius: Pad rounding [m]: the fit keeps the pad's centre of rounding this far from
            the surface, and contact sampling keeps contacts a pad of this radius can touch.
        joints: Joints that move this finger, or None for the joints on the chain from the
            palm to ``tip_body``.
        pad_width: Width of a flat pad's face [m] (a parallel gripper's jaw); 0: a rounded pad.
            A flat pad tilted by a small angle t touches with its edge, lifted width / 2 t
            off the surface: the fit lays it flat on the contact's surface, anywhere within
            half its width of the contact.
    """

    name: str
    tip_body: str
    tip_offset: tuple[float, float, float]
    pad_normal: tuple[float, float, float]
    tip_radius: float
    joints: tuple[str, ...] | None = None
    pad_width: float = 0.0

    def offset(self) -> NDArray[np.float64]:
        """``tip_offset`` as an array, shape (3,) [m]."""
        return np.array(self.tip_offset, dtype=float)

    def normal(self) -> NDArray[np.float64]:
        """``pad_normal`` normalised, shape (3,)."""
        n = np.array(self.pad_normal, dtype=float)
        return n / np.linalg.norm(n)


@dataclass(frozen=True)
class Actuation:
    """Position servos added to joints that no servo of the model holds (no actuator, or a motor).

    Attributes:
        kp: Stiffness [N·m/rad] (N/m for slide joints).
        force_range: Symmetric force limit [N·m] (N for slide joints).
        kv: Damping [N·m·s/rad]; None: critical damping of the joint's own inertia.
    """

    kp: float = DEFAULT_KP
    force_range: float = DEFAULT_FORCE_RANGE
    kv: float | None = None


@dataclass(frozen=True)
class HandDescriptor:
    """A hand: its model file, the palm the wrist holds and the fingers' pads.

    Attributes:
        name: The hand's name.
        path: The descriptor file (absolute).
        model_path: The MJCF or URDF file (absolute).
        palm: Body the simulated wrist holds; the palm frame is this body's frame.
        fingers: The fingers, in the descriptor's order.
        actuation: Servos for joints without an actuator.
        sha256: Digest of the descriptor file.
        model_sha256: Digest of the model file.
        reach_samples: Joint configurations the reachability model samples (``[reachability]
            samples``); None: as many as the model needs to recall the hand's own configurations
            (:class:`ogcp.planner.hands.reachability.HandReachability`).
        ignore_collisions: Body pairs whose geoms never count as colliding with each other (the
            model's geometry overlaps where the hand's does not), by body name.
    """

    name: str
    path: Path
    model_path: Path
    palm: str
    fingers: tuple[FingerSpec, ...]
    actuation: Actuation
    sha256: str
    model_sha256: str
    reach_samples: int | None = None
    ignore_collisions: tuple[tuple[str, str], ...] = ()

    @property
    def finger_names(self) -> tuple[str, ...]:
        """The fingers' names, in the descriptor's order."""
        return tuple(f.name for f in self.fingers)

    def choose_fingers(self, m: int, names: Sequence[str] | None = None) -> tuple[int, ...]:
        """Indices of the fingers that take an m-contact grasp.

        Args:
            m: Number of contacts.
            names: The fingers to use, by name (``--hand-fingers``); None: the first m listed.

        Returns:
            Finger indices in the order of ``names`` (or the descriptor's).

        Raises:
            OgcpError: If m exceeds the fingers, a name is unknown or repeated, or the number of
                names differs from m.
        """
        count = len(self.fingers)
        if not (isinstance(m, int) and 1 <= m <= count):
            raise OgcpError(f"the {self.name} hand has {count} fingers; a grasp of m = {m} contacts cannot use them")
        if names is None:
            return tuple(range(m))
        chosen = []
        for name in names:
            if name not in self.finger_names:
                raise OgcpError(
                    f"the {self.name} hand has no finger {name!r}; its fingers are {', '.join(self.finger_names)}"
                )
            if self.finger_names.index(name) in chosen:
                raise OgcpError(f"finger {name!r} is named twice in the hand's fingers")
            chosen.append(self.finger_names.index(name))
        if len(chosen) != m:
            raise OgcpError(f"{len(chosen)} hand fingers named ({', '.join(names)}) for a grasp of m = {m} contacts")
        return tuple(chosen)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready identity of the hand (what records carry)."""
        return {
            "name": self.name,
            "descriptor": str(self.path),
            "descriptor_sha256": self.sha256,
            "model_sha256": self.model_sha256,
        }


def load_descriptor(path: str | Path) -> HandDescriptor:
    """Read and check an ``ogcp.hand/1`` file.

    Args:
        path: The descriptor (TOML).

    Returns:
        The descriptor, paths resolved against its folder.

    Raises:
        OgcpError: One line naming the file and the field, for any fault: unreadable file or
            TOML, wrong schema, unknown or missing keys, a value of the wrong type or range, a
            pad normal that is not unit, two fingers on one tip body, a missing model file.
    """
    path = Path(path).expanduser().absolute()
    where = str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise OgcpError(f"{where}: cannot read the hand descriptor ({exc.strerror or exc})") from exc
    try:
        table = tomllib.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise OgcpError(f"{where}: not a TOML hand descriptor ({exc})") from exc
    _known_keys(table, _TOP_KEYS, where)
    schema = table.get("schema")
    if schema != SCHEMA:
        raise OgcpError(f"{where}: schema must be {SCHEMA!r}, got {schema!r}")
    name = _text(table, "name", where)
    palm = _text(table, "palm", where)
    model_name = _text(table, "mjcf", where)
    model_path = (_model_folder(table, where, path) / model_name).resolve()
    if model_path.suffix.lower() not in MODEL_SUFFIXES:
        urdf = model_path.stem if model_path.stem.endswith(".urdf") else f"{model_path.stem}.urdf"
        expand = f" (expand it first: xacro {model_name} > {urdf})" if model_path.suffix == ".xacro" else ""
        raise OgcpError(f"{where}: mjcf = {model_name!r} must be an MJCF (.xml) or URDF (.urdf) file{expand}")
    if not model_path.is_file():
        raise OgcpError(f"{where}: mjcf = {model_name!r}: no such file {model_path}")
    fingers_raw = table.get("fingers")
    if not isinstance(fingers_raw, list) or not fingers_raw:
        raise OgcpError(f"{where}: [[fingers]] must list at least one finger")
    fingers = tuple(_finger(entry, f"{where}: fingers[{k}]") for k, entry in enumerate(fingers_raw))
    _distinct(fingers, where)
    actuation = _actuation(table.get("actuation", {}), f"{where}: [actuation]")
    reach_samples = _reach_samples(table.get("reachability", {}), f"{where}: [reachability]")
    ignored = _body_pairs(table.get("ignore_collisions", []), f"{where}: ignore_collisions")
    return HandDescriptor(
        name=name,
        path=path,
        model_path=model_path,
        palm=palm,
        fingers=fingers,
        actuation=actuation,
        sha256=hashlib.sha256(raw).hexdigest(),
        model_sha256=hashlib.sha256(model_path.read_bytes()).hexdigest(),
        reach_samples=reach_samples,
        ignore_collisions=ignored,
    )


def _model_folder(table: Mapping[str, Any], where: str, path: Path) -> Path:
    """Where ``mjcf`` is taken from: the descriptor's folder, or a fetched hand's verified cache folder."""
    if "fetched" not in table:
        return path.parent
    name = _text(table, "fetched", where)
    try:
        return fetched_folder(name)
    except OgcpError as exc:
        raise OgcpError(f"{where}: fetched = {name!r}: {exc}") from None


def _known_keys(table: Mapping[str, Any], known: Sequence[str], where: str) -> None:
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise OgcpError(f"{where}: unknown key {unknown[0]!r}; valid keys are {', '.join(known)}")


def _text(table: Mapping[str, Any], key: str, where: str) -> str:
    value = table.get(key)
    if not isinstance(value, str) or not value.strip():
        raise OgcpError(f"{where}: {key} must be a non-empty string, got {value!r}")
    return value


def _number(table: Mapping[str, Any], key: str, where: str, low: float, high: float) -> float:
    value = table.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise OgcpError(f"{where}: {key} must be a finite number, got {value!r}")
    if not low < value <= high:
        raise OgcpError(f"{where}: {key} = {value!r} is outside ({low:g}, {high:g}]")
    return float(value)


def _vector(table: Mapping[str, Any], key: str, where: str) -> tuple[float, float, float]:
    value = table.get(key)
    numbers = value if isinstance(value, list) and len(value) == 3 else []
    if not numbers or not all(
        not isinstance(v, bool) and isinstance(v, int | float) and math.isfinite(v) for v in numbers
    ):
        raise OgcpError(f"{where}: {key} must be 3 finite numbers, got {value!r}")
    x, y, z = (float(v) for v in numbers)
    return x, y, z


def _finger(entry: object, where: str) -> FingerSpec:
    if not isinstance(entry, dict):
        raise OgcpError(f"{where}: a finger must be a table ([[fingers]]), got {entry!r}")
    _known_keys(entry, _FINGER_KEYS, where)
    offset = _vector(entry, "tip_offset", where)
    if np.linalg.norm(offset) > MAX_LENGTH:
        raise OgcpError(f"{where}: tip_offset {list(offset)} is more than {MAX_LENGTH:g} m from tip_body (units?)")
    normal = _vector(entry, "pad_normal", where)
    length = float(np.linalg.norm(normal))
    if abs(length - 1.0) > UNIT_TOLERANCE:
        raise OgcpError(f"{where}: pad_normal {list(normal)} is not a unit vector (length {length:.6g})")
    raw = entry.get("joints")
    joints: tuple[str, ...] | None = None
    if raw is not None:
        if not (isinstance(raw, list) and raw and all(isinstance(j, str) and j for j in raw)):
            raise OgcpError(f"{where}: joints must be a non-empty list of joint names, got {raw!r}")
        if len(set(raw)) != len(raw):
            raise OgcpError(f"{where}: joints {raw} name a joint twice")
        joints = tuple(raw)
    return FingerSpec(
        name=_text(entry, "name", where),
        tip_body=_text(entry, "tip_body", where),
        tip_offset=offset,
        pad_normal=normal,
        tip_radius=_number(entry, "tip_radius", where, 0.0, MAX_PAD),
        joints=joints,
        pad_width=_number(entry, "pad_width", where, 0.0, MAX_PAD) if "pad_width" in entry else 0.0,
    )


def _distinct(fingers: Sequence[FingerSpec], where: str) -> None:
    for attribute, what in (("name", "name"), ("tip_body", "tip body")):
        seen: dict[str, int] = {}
        for k, finger in enumerate(fingers):
            value = getattr(finger, attribute)
            if value in seen:
                raise OgcpError(f"{where}: fingers[{seen[value]}] and fingers[{k}] have the same {what} {value!r}")
            seen[value] = k


def _actuation(table: object, where: str) -> Actuation:
    if not isinstance(table, dict):
        raise OgcpError(f"{where} must be a table, got {table!r}")
    _known_keys(table, _ACTUATION_KEYS, where)
    kp = _number(table, "kp", where, 0.0, 1e6) if "kp" in table else DEFAULT_KP
    force = _number(table, "force_range", where, 0.0, 1e6) if "force_range" in table else DEFAULT_FORCE_RANGE
    kv = _number(table, "kv", where, 0.0, 1e6) if "kv" in table else None
    return Actuation(kp, force, kv)


def _reach_samples(table: object, where: str) -> int | None:
    if not isinstance(table, dict):
        raise OgcpError(f"{where} must be a table, got {table!r}")
    _known_keys(table, _REACHABILITY_KEYS, where)
    if "samples" not in table:
        return None
    value = table["samples"]
    if isinstance(value, bool) or not isinstance(value, int) or not 1_000 <= value <= MAX_REACH_SAMPLES:
        raise OgcpError(f"{where}: samples must be an integer in [1000, {MAX_REACH_SAMPLES}], got {value!r}")
    return value


def _body_pairs(value: object, where: str) -> tuple[tuple[str, str], ...]:
    pairs = value if isinstance(value, list) else None
    if pairs is None or not all(
        isinstance(p, list) and len(p) == 2 and all(isinstance(b, str) and b for b in p) for p in pairs
    ):
        raise OgcpError(f"{where} must be a list of [body, body] name pairs, got {value!r}")
    for a, b in pairs:
        if a == b:
            raise OgcpError(f"{where}: [{a!r}, {b!r}] pairs a body with itself")
    return tuple((a, b) for a, b in pairs)
