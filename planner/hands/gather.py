"""A hand modelled as several bodies on the world, gathered below one root body.

Some models put the palm and each finger's base on the world body side by side (MuJoCo
Menagerie's Shadow DEX-EE does): fixed in the world, so fixed to each other, and a hand as far
as MuJoCo is concerned. A scene holds a hand by one subtree, the one it mounts on the simulated
wrist, so :func:`gather_roots` moves the world's bodies that carry the palm and the fingers' tip
bodies below one new body, :data:`ROOT`, at the world's origin: every pose stays as it was.

Nothing is gathered when the palm moves relative to the world (a joint between them: fingers
beside it would not follow it), and a body on a free joint stays where it is (MuJoCo allows free
joints on the world's children only); the descriptor checks then say which finger is not attached.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import mujoco

from ogcp.planner.hands.descriptor import HandDescriptor

#: Name of the body that gathers a hand's roots.
ROOT = "ogcp_hand_root"


def gather_roots(spec: mujoco.MjSpec, descriptor: HandDescriptor) -> mujoco.MjSpec:
    """``spec``, or a copy whose palm and fingers hang below one body of the world.

    Args:
        spec: The hand's model as parsed (MJCF).
        descriptor: The hand; its palm and tip bodies say which of the world's bodies belong to it.

    Returns:
        ``spec`` itself when the palm's root already holds every tip body, when a name is unknown
        (the checks that follow say why), or when nothing can be gathered.
    """
    palm = spec.body(descriptor.palm)
    tips = [spec.body(f.tip_body) for f in descriptor.fingers]
    if palm is None or any(t is None for t in tips):
        return spec
    path = _path_to_world(spec, palm)
    if any(len(body.joints) for body in path):  # the palm moves: a sibling would not follow it
        return spec
    roots: list[mujoco.MjsBody] = []
    for tip in tips:
        root = _path_to_world(spec, tip)[-1]
        floating = any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in root.joints)
        if not floating and all(root != known for known in [path[-1], *roots]):
            roots.append(root)
    if not roots:
        return spec
    for k, body in enumerate([path[-1], *roots]):  # the copy finds the roots by name
        if not body.name:
            body.name = f"ogcp_root{k}"
    names = {body.name for body in [path[-1], *roots]}
    try:
        tree = ET.fromstring(spec.to_xml())
    except (ValueError, ET.ParseError):
        return spec
    world = tree.find("worldbody")
    if world is None:
        return spec
    gathered = ET.Element("body", {"name": ROOT})
    # A root may sit in a frame on the world: the frame moves with it, keeping its pose.
    for child in list(world):
        if child.tag in ("body", "frame") and _holds(child, names):
            world.remove(child)
            gathered.append(child)
    world.append(gathered)
    for keys in tree.findall("keyframe"):  # their qpos follow the old order of the bodies
        tree.remove(keys)
    for size in tree.findall("size"):  # the copy would keep empty keyframes, which attaching refuses
        size.attrib.pop("nkey", None)
    try:
        copy = mujoco.MjSpec.from_string(ET.tostring(tree, encoding="unicode"))
    except ValueError:
        return spec
    copy.modelfiledir = str(descriptor.model_path.parent) + os.sep  # meshes stay where the file says
    return copy


def _path_to_world(spec: mujoco.MjSpec, body: mujoco.MjsBody) -> list[mujoco.MjsBody]:
    """``body`` and its ancestors below the world, last the world's child."""
    path = [body]
    while path[-1].parent is not None and path[-1].parent != spec.worldbody:
        path.append(path[-1].parent)
    return path


def _holds(element: ET.Element, names: set[str]) -> bool:
    """Whether ``element`` is, or (a frame) directly holds, a body named in ``names``."""
    if element.tag == "body":
        return element.get("name") in names
    return any(_holds(child, names) for child in element if child.tag in ("body", "frame"))
