"""Hands written for the tests, as a user would write them: MJCF or URDF plus an ogcp.hand/1 descriptor."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import trimesh

#: A three-finger hand nobody here described before: mesh links, no actuator, a palm that sits
#: off the world origin and turned, every finger a two-hinge chain.
MESH_HAND = """<mujoco model="claw">
  <compiler angle="radian" meshdir="meshes"/>
  <asset><mesh name="link" file="link.stl"/><mesh name="tip" file="tip.stl"/></asset>
  <worldbody>
    <body name="base" pos="0.3 -0.2 0.5" euler="0.4 0.2 1.0">
      <geom type="box" size="0.03 0.03 0.01"/>
      <body name="palm" pos="0 0 0.02">
        {fingers}
      </body>
    </body>
  </worldbody>
</mujoco>
"""
FINGER = """<body name="f{k}" pos="{x} {y} 0" euler="0 0 {yaw}">
          <joint name="f{k}_a" axis="0 1 0" range="-0.3 1.4"/>
          <geom type="mesh" mesh="link" pos="0 0 0.025"/>
          <body name="f{k}_tip" pos="0 0 0.05">
            <joint name="f{k}_b" axis="0 1 0" range="0 1.4"/>
            <geom type="mesh" mesh="tip" pos="0 0 0.02"/>
          </body>
        </body>"""
MESH_HAND_DESCRIPTOR = """schema = "ogcp.hand/1"
name = "claw"
mjcf = "claw.xml"
palm = "palm"
{fingers}
[actuation]
kp = 4.0
force_range = 1.5
"""
FINGER_ENTRY = """[[fingers]]
name = "f{k}"
tip_body = "f{k}_tip"
tip_offset = [0.008, 0.0, 0.03]
pad_normal = [1.0, 0.0, 0.0]
tip_radius = 0.008
"""


def write_mesh_hand(folder: Path) -> Path:
    """The three-finger mesh hand and its descriptor in ``folder``; returns the descriptor's path."""
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(extents=(0.016, 0.016, 0.05)).export(folder / "meshes" / "link.stl")
    trimesh.creation.capsule(height=0.024, radius=0.008).export(folder / "meshes" / "tip.stl")
    spots = ((0.035, 0.0, 3.14159), (-0.02, 0.03, -0.9), (-0.02, -0.03, 0.9))
    fingers = "\n        ".join(FINGER.format(k=k, x=x, y=y, yaw=yaw) for k, (x, y, yaw) in enumerate(spots))
    (folder / "claw.xml").write_text(MESH_HAND.format(fingers=fingers))
    entries = "\n".join(FINGER_ENTRY.format(k=k) for k in range(3))
    path = folder / "claw.toml"
    path.write_text(MESH_HAND_DESCRIPTOR.format(fingers=entries))
    return path


URDF_GRIPPER = """<robot name="urdf_gripper">
  <link name="palm">
    <inertial><mass value="0.2"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><mesh filename="package://urdf_gripper/meshes/palm.stl"/></geometry></collision>
  </link>
  <link name="left">
    <inertial><mass value="0.02"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.035"/><geometry><box size="0.02 0.008 0.07"/></geometry></collision>
  </link>
  <link name="right">
    <inertial><mass value="0.02"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.035"/><geometry><box size="0.02 0.008 0.07"/></geometry></collision>
  </link>
  <link name="left_pad"/>
  <link name="right_pad"/>
  <joint name="left" type="prismatic"><parent link="palm"/><child link="left"/><origin xyz="0 0.045 0.01"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="20" velocity="0.1"/></joint>
  <joint name="right" type="prismatic"><parent link="palm"/><child link="right"/><origin xyz="0 -0.045 0.01"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="20" velocity="0.1"/></joint>
  <joint name="left_pad" type="fixed"><parent link="left"/><child link="left_pad"/><origin xyz="0 -0.004 0.06"/></joint>
  <joint name="right_pad" type="fixed"><parent link="right"/><child link="right_pad"/><origin xyz="0 0.004 0.06"/></joint>
</robot>
"""
URDF_DESCRIPTOR = """schema = "ogcp.hand/1"
name = "urdf_gripper"
mjcf = "urdf_gripper.urdf"
palm = "palm"
[[fingers]]
name = "left"
tip_body = "left_pad"
tip_offset = [0.0, 0.0, 0.0]
pad_normal = [0.0, -1.0, 0.0]
tip_radius = 0.004
[[fingers]]
name = "right"
tip_body = "right_pad"
tip_offset = [0.0, 0.0, 0.0]
pad_normal = [0.0, 1.0, 0.0]
tip_radius = 0.004
[actuation]
kp = 20000.0
force_range = 15.0
"""


def write_urdf_gripper(folder: Path) -> Path:
    """A URDF parallel gripper (mesh palm found through package://, pads on fixed links); the descriptor's path."""
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(extents=(0.04, 0.11, 0.02)).export(folder / "meshes" / "palm.stl")
    (folder / "urdf_gripper.urdf").write_text(URDF_GRIPPER)
    path = folder / "urdf_gripper.toml"
    path.write_text(URDF_DESCRIPTOR)
    return path


#: A hand as light as an Allegro hand's model and as stiffly servoed: three two-hinge fingers of
#: 5-8 g capsule links, joint damping, and position actuators with no force limit (kp 10 N·m/rad):
#: its distal servos would ring at the simulation's step without the armature the scene adds.
LIGHT_HAND = """<mujoco model="light">
  <compiler angle="radian" autolimits="true"/>
  <default><joint axis="0 1 0" damping="1"/><position kp="10"/><geom density="800"/></default>
  <worldbody>
    <body name="palm">
      <geom type="box" size="0.035 0.035 0.008"/>
      {fingers}
    </body>
  </worldbody>
  {tendons}<actuator>{actuators}</actuator>
</mujoco>
"""
LIGHT_FINGER = """<body name="f{k}" pos="{x} {y} 0.01" euler="0 0 {yaw}">
        <joint name="f{k}_a" range="-0.3 1.4"/>
        <geom type="capsule" size="0.008" fromto="0 0 0 0 0 0.045"/>
        <body name="f{k}_tip" pos="0 0 0.05">
          <joint name="f{k}_b" range="0 1.4"/>
          <geom type="capsule" size="0.008" fromto="0 0 0.005 0 0 0.03"/>
        </body>
      </body>"""
LIGHT_ACTUATORS = """<position joint="f{k}_a" ctrlrange="-0.3 1.4"/><position joint="f{k}_b" ctrlrange="0 1.4"/>"""
#: The same hand with each distal joint driven through a fixed tendon (as Menagerie's Shadow hand drives its J0).
LIGHT_TENDON_ACTUATORS = (
    """<position joint="f{k}_a" ctrlrange="-0.3 1.4"/><position tendon="t{k}" ctrlrange="0 1.4"/>"""
)
LIGHT_TENDON = """<fixed name="t{k}"><joint joint="f{k}_b" coef="1"/></fixed>"""
LIGHT_DESCRIPTOR = """schema = "ogcp.hand/1"
name = "light"
mjcf = "light.xml"
palm = "palm"
{fingers}"""


def write_light_hand(folder: Path, tendons: bool = False) -> Path:
    """The light, stiffly servoed hand and its descriptor in ``folder``; returns the descriptor's path.

    With ``tendons``, each distal joint's servo drives it through a fixed tendon.
    """
    folder.mkdir(parents=True, exist_ok=True)
    spots = ((0.03, 0.0, 3.14159), (-0.02, 0.025, -0.9), (-0.02, -0.025, 0.9))
    fingers = "\n      ".join(LIGHT_FINGER.format(k=k, x=x, y=y, yaw=yaw) for k, (x, y, yaw) in enumerate(spots))
    servos = LIGHT_TENDON_ACTUATORS if tendons else LIGHT_ACTUATORS
    actuators = "".join(servos.format(k=k) for k in range(3))
    coupling = "<tendon>" + "".join(LIGHT_TENDON.format(k=k) for k in range(3)) + "</tendon>" if tendons else ""
    text = LIGHT_HAND.format(fingers=fingers, actuators=actuators, tendons=coupling)
    (folder / "light.xml").write_text(text)
    entries = "\n".join(FINGER_ENTRY.format(k=k) for k in range(3))
    path = folder / "light.toml"
    path.write_text(LIGHT_DESCRIPTOR.format(fingers=entries))
    return path


def write_gripper_variant(
    folder: Path, edit_model: Callable[[str], str], edit_descriptor: Callable[[str], str] = lambda text: text
) -> Path:
    """The built-in parallel gripper with its MJCF (and optionally its descriptor) edited, in ``folder``.

    Returns:
        The descriptor's path (``g.toml``, beside ``g.xml``).
    """
    from ogcp.planner.hands import resolve_hand

    source = resolve_hand("parallel_gripper")
    (folder / "g.xml").write_text(edit_model(source.model_path.read_text()))
    descriptor = source.path.read_text().replace('"parallel_gripper.xml"', '"g.xml"')
    (folder / "g.toml").write_text(edit_descriptor(descriptor))
    return folder / "g.toml"


#: The palm of the two-jaw loop grippers below, with their jaws in it.
TWO_JAW_PALM = """  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="palm">
      <geom name="palm" type="box" size="0.015 0.06 0.008" pos="0 0 -0.008"/>
      {jaws}
    </body>
  </worldbody>
"""

#: A parallelogram gripper: each jaw hangs from a driven link and a passive follower link whose
#: tip a ``connect`` pins to the jaw, so the jaw stays upright (a four-bar loop, as the Robotiq
#: 2F-85 closes its own). Only the drivers have servos; the loops are made stiff, as a real
#: model's must be for light links under a squeeze.
FOURBAR = (
    """<mujoco model="fourbar">
"""
    + TWO_JAW_PALM
    + """  <contact>
    <exclude body1="l_pad" body2="l_follower"/>
    <exclude body1="r_pad" body2="r_follower"/>
  </contact>
  <equality>
    <connect body1="l_follower" body2="l_pad" anchor="0 0 0.05" solref="0.004 1" solimp="0.9999 0.9999 0.001"/>
    <connect body1="r_follower" body2="r_pad" anchor="0 0 0.05" solref="0.004 1" solimp="0.9999 0.9999 0.001"/>
  </equality>
  <actuator>
    <position name="l" joint="l_driver" kp="5" forcerange="-1 1"/>
    <position name="r" joint="r_driver" kp="5" forcerange="-1 1"/>
  </actuator>
</mujoco>
"""
)
JAW = """<body name="{s}_driver" pos="0 {y} 0">
        <joint name="{s}_driver" axis="{ax} 0 0" range="-0.3 0.9" damping="0.05"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.004"/>
        <body name="{s}_pad" pos="0 0 0.05">
          <joint name="{s}_pad" axis="{ax} 0 0" range="-1 1" damping="0.01"/>
          <geom name="{s}_pad" type="box" pos="0 {inward} 0.02" size="0.01 0.004 0.025"/>
        </body>
      </body>
      <body name="{s}_follower" pos="0 {y2} 0">
        <joint name="{s}_follower" axis="{ax} 0 0" range="-0.3 0.9" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.003"/>
      </body>"""
FOURBAR_DESCRIPTOR = """schema = "ogcp.hand/1"
name = "fourbar"
mjcf = "fourbar.xml"
palm = "palm"

[[fingers]]
name = "left"
tip_body = "l_pad"
tip_offset = [0.0, -0.010, 0.03]
pad_normal = [0.0, -1.0, 0.0]
tip_radius = 0.004

[[fingers]]
name = "right"
tip_body = "r_pad"
tip_offset = [0.0, 0.010, 0.03]
pad_normal = [0.0, 1.0, 0.0]
tip_radius = 0.004
"""


def write_fourbar_gripper(folder: Path) -> Path:
    """The parallelogram (four-bar) gripper and its descriptor in ``folder``; returns the descriptor's path."""
    folder.mkdir(parents=True, exist_ok=True)
    jaws = "\n      ".join(
        JAW.format(s=s, y=sign * 0.03, y2=sign * 0.045, ax=sign, inward=-sign * 0.006)
        for s, sign in (("l", 1), ("r", -1))
    )
    (folder / "fourbar.xml").write_text(FOURBAR.format(jaws=jaws))
    path = folder / "fourbar.toml"
    path.write_text(FOURBAR_DESCRIPTOR)
    return path


#: An adaptive (underactuated) gripper, as the Robotiq 2F-85 is built: each jaw's pad hangs from a
#: passive chain (a base link, an elbow, the pad's hinge) that a ``connect`` pins to the tip of a
#: driven link beside it, a five-bar loop with two degrees of freedom and one servo. A spring
#: holds each elbow on its stop, so the jaws close parallel until something pushes them out of
#: it. One general affine servo (a 0-255 command, as grippers take) drives both driven links
#: through a tendon, and a joint equality keeps them together.
ADAPTIVE = (
    """<mujoco model="adaptive">
"""
    + TWO_JAW_PALM
    + """  <contact>
    <exclude body1="l_pad" body2="l_drive"/>
    <exclude body1="r_pad" body2="r_drive"/>
    <exclude body1="l_elbow" body2="l_drive"/>
    <exclude body1="r_elbow" body2="r_drive"/>
  </contact>
  <tendon>
    <fixed name="split"><joint joint="l_drive" coef="0.5"/><joint joint="r_drive" coef="0.5"/></fixed>
  </tendon>
  <equality>
    <connect body1="l_drive" body2="l_pad" anchor="0 0 0.05" {loop}/>
    <connect body1="r_drive" body2="r_pad" anchor="0 0 0.05" {loop}/>
    <joint joint1="r_drive" joint2="l_drive" solref="0.004 1" solimp="0.9999 0.9999 0.001"/>
  </equality>
  <actuator>
    <general name="squeeze" tendon="split" gainprm="{gain}" biastype="affine" biasprm="0 -20 -0.5"
      ctrlrange="0 255" forcerange="-0.6 0.6"/>
  </actuator>
</mujoco>
"""
)
ADAPTIVE_JAW = """<body name="{s}_base" pos="0 {y} 0">
        <joint name="{s}_base" axis="{ax} 0 0" range="-0.3 0.9" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.025" size="0.004"/>
        <body name="{s}_elbow" pos="0 0 0.025">
          <joint name="{s}_elbow" axis="{ax} 0 0" range="{elbow}" stiffness="0.02" springref="{spring}" damping="0.01"
            solreflimit="0.004 1" solimplimit="0.95 0.99 0.001"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.025" size="0.004"/>
          <body name="{s}_pad" pos="0 0 0.025">
            <joint name="{s}_pad" axis="{ax} 0 0" range="-1 1" damping="0.01"/>
            <geom name="{s}_pad" type="box" pos="0 {inward} 0.02" size="0.01 0.004 0.025"/>
          </body>
        </body>
      </body>
      <body name="{s}_drive" pos="0 {y2} 0">
        <joint name="{s}_drive" axis="{ax} 0 0" range="-0.3 0.9" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.05" size="0.003"/>
      </body>"""


#: Stiff loops: a model's light links need them under a squeeze (MuJoCo's default lets them give).
STIFF_LOOP = 'solref="0.004 1" solimp="0.9999 0.9999 0.001"'


def write_adaptive_gripper(folder: Path, elbow: str = "0 1", spring: float = -1.0, loop: str = STIFF_LOOP) -> Path:
    """The adaptive gripper and its descriptor in ``folder``; returns the descriptor's path.

    ``elbow`` is the elbows' range [rad] and ``spring`` their spring's reference [rad]: by default the
    spring presses each elbow on its lower stop, 0, where the jaw stands parallel. ``loop`` holds the
    ``connect`` equalities' softness attributes.
    """
    folder.mkdir(parents=True, exist_ok=True)
    jaws = "\n      ".join(
        ADAPTIVE_JAW.format(
            s=s, y=sign * 0.03, y2=sign * 0.045, ax=sign, inward=-sign * 0.006, elbow=elbow, spring=spring
        )
        for s, sign in (("l", 1), ("r", -1))
    )
    (folder / "adaptive.xml").write_text(ADAPTIVE.format(jaws=jaws, gain=20 * 0.9 / 255, loop=loop))
    path = folder / "adaptive.toml"
    path.write_text(FOURBAR_DESCRIPTOR.replace('"fourbar"', '"adaptive"').replace('"fourbar.xml"', '"adaptive.xml"'))
    return path


def write_scaled_gripper(folder: Path, factor: float, kp: float, force: float, pad_width: float | None = None) -> Path:
    """The built-in parallel gripper with every length times ``factor`` (its MJCF's positions, sizes
    and slide ranges, the pads' offsets and rounding), servos of ``kp`` [N/m] and ``force`` [N], and
    optionally flat pads ``pad_width`` [m] wide; the descriptor's path."""
    import re

    def scaled(match: re.Match[str]) -> str:
        values = " ".join(f"{float(v) * factor:.9g}" for v in match.group(2).split())
        return f'{match.group(1)}="{values}"'

    def edit_descriptor(text: str) -> str:
        text = re.sub(
            r"tip_offset = \[([^\]]+)\]",
            lambda m: "tip_offset = [" + ", ".join(f"{float(v) * factor:.9g}" for v in m.group(1).split(",")) + "]",
            text,
        )
        flat = f"\npad_width = {pad_width:g}" if pad_width else ""
        text = re.sub(r"tip_radius = ([0-9.]+)", lambda m: f"tip_radius = {float(m.group(1)) * factor:.9g}{flat}", text)
        text = re.sub(r"kp = [0-9.]+", f"kp = {kp:g}", text)
        return re.sub(r"force_range = [0-9.]+", f"force_range = {force:g}", text)

    return write_gripper_variant(
        folder, lambda text: re.sub(r'\b(pos|size|range)="([^"]+)"', scaled, text), edit_descriptor
    )


def _spread_finger(n: int, pos: str, euler: str, spread: bool) -> str:
    """One finger of :func:`write_spread_hand`: an optional spread hinge, then two flexion hinges."""
    axis = "1" if n == 1 else "-1"
    joint = f'<joint name="j{n}1" axis="0 0 {axis}" range="0 1.57"/>' if spread else ""
    return f"""
      <body name="f{n}_base" pos="{pos}" euler="{euler}">{joint}
        <geom type="box" size="0.012 0.012 0.008" pos="0 0 0.008"/>
        <body name="f{n}_prox" pos="0 0 0.016">
          <joint name="j{n}2" axis="0 -1 0" range="-0.9 2.44"/>
          <geom type="capsule" fromto="0 0 0.005 0 0 0.06" size="0.01"/>
          <body name="f{n}_dist" pos="0 0 0.07">
            <joint name="j{n}3" axis="0 -1 0" range="0 2.0"/>
            <geom type="capsule" fromto="0 0 0.005 0 0 0.045" size="0.009"/>
            <body name="f{n}_tip" pos="-0.009 0 0.035"/>
          </body>
        </body>
      </body>"""


def write_spread_hand(folder: Path) -> Path:
    """A Barrett-like hand in primitives, no actuators: two fingers whose spread hinges one joint
    equality ties, a third opposite, each with two flexion hinges; the descriptor's path."""
    fingers = (
        _spread_finger(1, "0.025 0.025 0.06", "0 0 0", True)
        + _spread_finger(2, "0.025 -0.025 0.06", "0 0 0", True)
        + _spread_finger(3, "-0.025 0 0.06", "0 0 3.14159", False)
    )
    tie = '<equality><joint joint1="j21" joint2="j11" polycoef="0 1 0 0 0"/></equality>'
    return _primitive_hand(folder, "spread", 0.045, fingers, (3, 1, 2), tie)


def _primitive_hand(
    folder: Path, name: str, palm: float, fingers: str, order: tuple[int, ...], extra: str = ""
) -> Path:
    """A cylinder palm of radius ``palm`` [m] holding ``fingers`` (:func:`_spread_finger`), no actuators;
    the descriptor (fingers in ``order``, [actuation] servos) beside it; the descriptor's path."""
    (folder / f"{name}.xml").write_text(
        f'<mujoco model="{name}"><compiler angle="radian" autolimits="true"/>'
        '<default><joint damping="0.05" armature="0.001"/><geom density="1500"/></default>'
        f'<worldbody><body name="palm"><geom type="cylinder" size="{palm} 0.03" pos="0 0 0.03"/>{fingers}'
        f"</body></worldbody>{extra}</mujoco>"
    )
    entries = "".join(
        f'[[fingers]]\nname = "f{n}"\ntip_body = "f{n}_tip"\ntip_offset = [0.0, 0.0, 0.0]\n'
        "pad_normal = [-1.0, 0.0, 0.0]\ntip_radius = 0.009\n"
        for n in order
    )
    path = folder / f"{name}.toml"
    path.write_text(
        f'schema = "ogcp.hand/1"\nname = "{name}"\nmjcf = "{name}.xml"\npalm = "palm"\n{entries}'
        "[actuation]\nkp = 5.0\nforce_range = 1.5\n"
    )
    return path


#: The built-in gripper's jaws, as its MJCF writes them (inside the palm, relative to it).
LEFT_JAW = """<joint name="left" type="slide" axis="0 -1 0" range="0 0.04" damping="2"/>
  <geom name="left" type="box" pos="0 0 0.035" size="0.01 0.004 0.035"/>"""
RIGHT_JAW = LEFT_JAW.replace("left", "right").replace("0 -1 0", "0 1 0")
PALM = '<geom name="palm" type="box" size="0.02 0.055 0.01"/>'
#: The same gripper with its palm at (0.1, 0, 0.2) and its jaws on the world beside it: the left
#: one directly, the right one in a frame on the world; a keyframe too.
SIDE_BY_SIDE = f"""<mujoco><compiler angle="radian" autolimits="true"/><worldbody>
  <body name="palm" pos="0.1 0 0.2">{PALM}</body>
  <body name="left" pos="0.1 0.045 0.21">{LEFT_JAW}</body>
  <frame pos="0.1 0 0.2"><body name="right" pos="0 -0.045 0.01">{RIGHT_JAW}</body></frame>
</worldbody><keyframe><key name="k" qpos="0.01 0.02"/></keyframe></mujoco>"""
#: The gripper as a URDF's tree would have it: a base, the palm fixed below it, the jaws beside the palm.
ON_A_BASE = f"""<mujoco><compiler angle="radian" autolimits="true"/><worldbody><body name="base">
  <body name="palm">{PALM}</body>
  <body name="left" pos="0 0.045 0.01">{LEFT_JAW}</body>
  <body name="right" pos="0 -0.045 0.01">{RIGHT_JAW}</body>
</body></worldbody></mujoco>"""


def write_side_by_side_gripper(folder: Path) -> Path:
    """The built-in gripper with its palm and jaws on the world side by side (:data:`SIDE_BY_SIDE`); the descriptor's path."""
    return write_gripper_variant(folder, lambda text: SIDE_BY_SIDE)


def write_four_finger_hand(folder: Path) -> Path:
    """Four fingers of two flexion hinges round a cylinder palm, two facing two; the descriptor's path."""
    fingers = (
        _spread_finger(1, "0.025 0.025 0.06", "0 0 0", False)
        + _spread_finger(2, "0.025 -0.025 0.06", "0 0 0", False)
        + _spread_finger(3, "-0.025 0.025 0.06", "0 0 3.14159", False)
        + _spread_finger(4, "-0.025 -0.025 0.06", "0 0 3.14159", False)
    )
    return _primitive_hand(folder, "four", 0.05, fingers, (1, 2, 3, 4))
