"""A descriptor's fingers checked against the hand's compiled model.

A finger's tip body must be carried by joints relative to the palm: it hangs below the palm, or
below a body the palm is fixed to (a finger beside the palm on a common base, as a URDF's tree
often has it). Its joints are those on that chain, or the descriptor's, which must lie on it and be
hinges or slides.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.descriptor import HandDescriptor
from ogcp.planner.infra.errors import OgcpError

#: The joint types a finger moves on.
MOVABLE = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))


@dataclass(frozen=True)
class Finger:
    """A finger resolved against the compiled model.

    Attributes:
        name: The descriptor's name.
        body: Id of the tip body.
        joints: Ids of the joints that move it, and of the loops it closes (model order).
        offset: Pad contact point in the tip body's frame, shape (3,) [m].
        normal: Unit pad normal in the tip body's frame, shape (3,).
        radius: Pad rounding [m].
        width: A flat pad's width [m]; 0 for a rounded pad.
    """

    name: str
    body: int
    joints: tuple[int, ...]
    offset: NDArray[np.float64]
    normal: NDArray[np.float64]
    radius: float
    width: float = 0.0


def body_id(descriptor: HandDescriptor, model: mujoco.MjModel, name: str, field: str) -> int:
    """The id of the body ``name`` that the descriptor's ``field`` names, or one line listing the model's bodies."""
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
    if body < 0:
        names = [model.body(i).name for i in range(1, model.nbody)]
        raise OgcpError(
            f"{descriptor.path}: {field} = {name!r} is not a body of {descriptor.model_path.name}; "
            f"its bodies are {', '.join(names)}"
        )
    return int(body)


def finger_chain(model: mujoco.MjModel, palm: int, body: int) -> list[int]:
    """Bodies that carry ``body`` relative to the palm, down to ``body`` (included): those below
    the palm, or below the nearest ancestor of the palm it is fixed to (a finger beside the palm
    on a common base); [] if neither."""
    fixed_to = [palm]  # the palm and the ancestors no joint moves it relative to
    while model.body_jntnum[fixed_to[-1]] == 0 and model.body_parentid[fixed_to[-1]] != 0:
        fixed_to.append(int(model.body_parentid[fixed_to[-1]]))
    chain = []
    while body not in fixed_to:
        if body == 0:
            return []
        chain.append(body)
        body = int(model.body_parentid[body])
    return chain[::-1]


def resolve_finger(descriptor: HandDescriptor, model: mujoco.MjModel, palm: int, k: int) -> Finger:
    """Finger ``k`` of the descriptor checked against the compiled model (one line per problem)."""
    spec = descriptor.fingers[k]
    where = f"{descriptor.path}: fingers[{k}] ({spec.name})"
    body = body_id(descriptor, model, spec.tip_body, f"fingers[{k}].tip_body")
    chain = finger_chain(model, palm, body)
    if not chain:
        raise OgcpError(
            f"{where}: tip_body {spec.tip_body!r} is not below the palm {descriptor.palm!r}, "
            "nor on a body the palm is fixed to"
        )
    on_chain = [j for b in chain for j in range(model.njnt) if model.jnt_bodyid[j] == b]
    if spec.joints is None:
        joints = on_chain
    else:
        joints = []
        for name in spec.joints:
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j < 0:
                raise OgcpError(f"{where}: joint {name!r} is not a joint of {descriptor.model_path.name}")
            if j not in on_chain:
                raise OgcpError(f"{where}: joint {name!r} is not on the chain from the palm to {spec.tip_body!r}")
            joints.append(j)
    if not joints:
        raise OgcpError(f"{where}: no joint moves {spec.tip_body!r} relative to the palm {descriptor.palm!r}")
    for j in joints:
        if model.jnt_type[j] not in MOVABLE:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
            raise OgcpError(
                f"{where}: joint {name!r} must be a hinge or a slide (ball and free joints are not fingers)"
            )
    return Finger(spec.name, body, tuple(sorted(joints)), spec.offset(), spec.normal(), spec.tip_radius, spec.pad_width)
