"""A hand's MuJoCo model from its descriptor: MJCF or URDF, checked, with servos on joints none holds.

MuJoCo compiles URDF itself but looks mesh files up by their base name in the model's folder and
fuses bodies that no joint moves (a pad's link would vanish). :func:`hand_spec` therefore hands a
URDF's meshes over by name, resolving ``package://`` and relative paths against the URDF's folder
and the folders above it, and keeps every body. Joints on a finger that no servo holds get a
position servo from the descriptor's ``[actuation]`` (:mod:`~ogcp.planner.hands.servos`), as a
user's actuator-less model must be closed somehow; the model's own servos are kept as they are.
An MJCF whose palm and fingers sit on the world side by side is gathered below one body
(:mod:`~ogcp.planner.hands.gather`).
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

from ogcp.planner.hands.descriptor import HandDescriptor
from ogcp.planner.hands.gather import gather_roots
from ogcp.planner.infra.errors import OgcpError

#: How many folders above a URDF a ``package://`` mesh path is looked for in.
PACKAGE_SEARCH_DEPTH = 3
#: MuJoCo's refusal of a body inertia that breaks the triangle inequality.
_UNBALANCED = "inertia must satisfy A + B >= C"
#: Compiler attributes of a URDF's ``<mujoco>`` extension that ogcp replaces (its meshes come in memory).
_URDF_FOLDERS = frozenset({"meshdir", "assetdir", "texturedir"})
#: The mesh formats MuJoCo reads.
MESH_FORMATS = ("STL", "OBJ", "MSH")


class HandLoadWarning(UserWarning):
    """Something in a hand's model file that ogcp repaired to load it (said once, one line)."""


def hand_spec(descriptor: HandDescriptor) -> mujoco.MjSpec:
    """The hand's model as an editable MjSpec (not compiled).

    Raises:
        OgcpError: If MuJoCo cannot parse the file or a URDF mesh file is missing, naming the
            descriptor, the model file and MuJoCo's reason.
    """
    path = descriptor.model_path
    urdf = path.suffix.lower() == ".urdf"
    text, assets = _urdf_with_assets(path, descriptor) if urdf else ("", {})
    try:
        spec = mujoco.MjSpec.from_string(text, assets=assets) if urdf else mujoco.MjSpec.from_file(str(path))
    except ValueError as exc:
        raise compile_error(descriptor, exc) from exc
    if urdf:  # one tree, its meshes already in memory
        return spec
    spec = gather_roots(spec, descriptor)
    _merge_obj_objects(spec, descriptor)
    return spec


def compile_error(descriptor: HandDescriptor, exc: Exception) -> OgcpError:
    """One line for a model MuJoCo refused."""
    reason = " ".join(str(exc).replace("Error:", "").split())
    if "no decoder found for mesh" in reason:  # a COLLADA, glTF or PLY mesh, common in ROS packages
        reason += f"; MuJoCo reads {', '.join(MESH_FORMATS)} meshes: convert it (trimesh can)"
    return OgcpError(f"{descriptor.path}: mjcf = {descriptor.model_path.name}: MuJoCo cannot compile it ({reason})")


def compile_spec(descriptor: HandDescriptor, spec: mujoco.MjSpec) -> mujoco.MjModel:
    """Compile, with MuJoCo's refusal as one line naming the descriptor.

    A body whose inertia breaks the triangle inequality (A + B >= C), common in URDFs exported
    from CAD (the Schunk SVH's of dex-urdf), is balanced as MuJoCo's ``balanceinertia`` does, in
    the spec, so that every scene the hand is copied into compiles too; a warning names the bodies.
    """
    try:
        return spec.compile()
    except ValueError as exc:
        if _UNBALANCED not in str(exc):
            raise compile_error(descriptor, exc) from exc
        _balance_inertias(descriptor, spec)
        try:
            return spec.compile()
        except ValueError as again:
            raise compile_error(descriptor, again) from again


def _balance_inertias(descriptor: HandDescriptor, spec: mujoco.MjSpec) -> None:
    """Write MuJoCo's balanced inertias (its ``balanceinertia``) into the spec's bodies whose own break
    the triangle inequality, and warn once naming them."""
    before = spec.compiler.balanceinertia
    spec.compiler.balanceinertia = True
    try:
        balanced = spec.compile()
    except ValueError as exc:
        raise compile_error(descriptor, exc) from exc
    finally:
        spec.compiler.balanceinertia = before
    changed = []
    for body in spec.bodies:
        if body.name and _unbalanced(body):
            index = mujoco.mj_name2id(balanced, mujoco.mjtObj.mjOBJ_BODY, body.name)
            body.fullinertia = [math.nan] * 6
            body.ipos, body.iquat = balanced.body_ipos[index].copy(), balanced.body_iquat[index].copy()
            body.inertia = balanced.body_inertia[index].copy()
            body.explicitinertial = True
            changed.append(body.name)
    warnings.warn(
        f"{descriptor.path}: mjcf = {descriptor.model_path.name}: the inertia of {', '.join(changed) or 'a body'} breaks "
        "the triangle inequality (A + B >= C); balanced as MuJoCo's balanceinertia does (their principal moments set to their mean)",
        HandLoadWarning,
        stacklevel=3,
    )


def _unbalanced(body: mujoco.MjsBody) -> bool:
    """Whether a body's explicit inertia (full or diagonal) breaks the triangle inequality."""
    full = np.asarray(body.fullinertia, dtype=float)
    if np.isfinite(full).all():
        matrix = np.array([[full[0], full[3], full[4]], [full[3], full[1], full[5]], [full[4], full[5], full[2]]])
        moments = np.linalg.eigvalsh(matrix)
    else:
        moments = np.asarray(body.inertia, dtype=float)
    a, b, c = np.sort(moments)
    return bool(body.mass > 0 and a + b < c * (1.0 - 1e-9))


def _urdf_with_assets(path: Path, descriptor: HandDescriptor) -> tuple[str, dict[str, bytes]]:
    try:
        root = ET.fromstring(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ET.ParseError) as exc:
        raise OgcpError(f"{descriptor.path}: mjcf = {path.name} is not a readable URDF ({exc})") from exc
    if root.tag != "robot":
        raise OgcpError(
            f"{descriptor.path}: mjcf = {path.name}: a URDF's root element must be <robot>, got <{root.tag}>"
        )
    # ogcp simulates and draws collision geometry only: a visual's mesh (often COLLADA, which
    # MuJoCo cannot read, or left out of a package) must not stop the hand from loading.
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
    assets: dict[str, bytes] = {}
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        found = _find_mesh(path.parent, name)
        if found is None:
            raise OgcpError(f"{descriptor.path}: mjcf = {path.name}: mesh file {name!r} not found near {path.parent}")
        key = found.name
        data = found.read_bytes()
        if key.lower().endswith(".obj"):
            data = one_object_obj(data) or data
        if key in assets and assets[key] != data:
            raise OgcpError(
                f"{descriptor.path}: mjcf = {path.name}: two different mesh files are named {key!r}; MuJoCo "
                "looks URDF meshes up by name, so rename one"
            )
        assets[key] = data
        mesh.set("filename", key)
    # The file's own compiler settings stay (balanceinertia, boundmass, ...), but for the folders
    # (the meshes are in memory, by name) and what ogcp needs: every body kept (a pad's link is
    # often fixed to the last joint's link), collision geometry only, meshes by name.
    kept: dict[str, str] = {}
    for old in root.findall("mujoco"):
        for compiler in old.findall("compiler"):
            kept.update({k: v for k, v in compiler.attrib.items() if k not in _URDF_FOLDERS})
        root.remove(old)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", {**kept, "fusestatic": "false", "discardvisual": "true", "strippath": "true"})
    return ET.tostring(root, encoding="unicode"), assets


def one_object_obj(data: bytes) -> bytes | None:
    """An OBJ file's bytes with its objects and groups made one, or None where it has one already.

    MuJoCo reads the faces of an OBJ's first object or group only. It keeps every vertex, so the
    convex hull it collides is whole, but rays (the pads' check), drawings and the volume that gives
    a link its mass see part of the mesh (an Inspire hand's thumb tip: 340 of 2,394 faces).
    Dropping the ``o`` and ``g`` lines leaves one object with every face (their indices are global).
    """
    lines = data.split(b"\n")
    tokens = [line.split(None, 1)[0] if line.strip() else b"" for line in lines]
    shapes, in_shape = 0, False  # runs of faces that an object or group line starts
    for token in tokens:
        if token in (b"o", b"g"):
            in_shape = False
        elif token == b"f" and not in_shape:
            shapes, in_shape = shapes + 1, True
    if shapes <= 1:
        return None
    return b"\n".join(line for line, token in zip(lines, tokens, strict=True) if token not in (b"o", b"g"))


def _merge_obj_objects(spec: mujoco.MjSpec, descriptor: HandDescriptor) -> None:
    """Give MuJoCo each OBJ mesh of an MJCF with several objects as one (:func:`one_object_obj`), in memory."""
    folder = descriptor.model_path.parent
    meshdir = Path(spec.meshdir) if spec.meshdir else Path()
    merged: dict[str, bytes] = {}
    for k, mesh in enumerate(spec.meshes):
        if not mesh.file.lower().endswith(".obj"):
            continue
        path = Path(mesh.file)
        if not path.is_absolute():
            path = (meshdir if meshdir.is_absolute() else folder / meshdir) / path
        try:
            data = one_object_obj(path.read_bytes())
        except OSError:  # MuJoCo says what is missing when it compiles
            continue
        if data is not None:
            mesh.file = f"ogcp_one_object_{k}_{path.name}"
            merged[mesh.file] = data
    if merged:
        spec.assets = {**spec.assets, **merged}


def _find_mesh(folder: Path, name: str) -> Path | None:
    relative = name
    if name.startswith("package://"):
        relative = name[len("package://") :].split("/", 1)[-1]
    elif name.startswith("file://"):
        relative = name[len("file://") :]
    candidate = Path(relative)
    if candidate.is_absolute():
        return candidate if candidate.is_file() else None
    for parent in [folder, *folder.parents][: PACKAGE_SEARCH_DEPTH + 1]:
        for option in (parent / candidate, parent / candidate.name):
            if option.is_file():
                return option
    return None
