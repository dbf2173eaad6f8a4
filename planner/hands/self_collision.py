"""Which of a hand's own links count as colliding: its model's geometry, less the overlaps it was built with.

A hand model's collision geometry is often coarser than the hand. MuJoCo collides a mesh as its
convex hull, so a URDF whose links are the CAD meshes (the LEAP hand's, say) gets a hull of a
bracket that swallows the link two joints further on over most of that joint's range. Such a pair
is not a collision of the real hand, whose joint limits keep a chain's own links apart. A geom pair
overlaps *by design* when it

- penetrates in the hand's reference pose (whatever the links, the model was drawn that way);
- lies on one chain (one body below the other, beyond the parent-child pairs MuJoCo never
  collides) and penetrates in more than :data:`OVERLAP_SHARE` of :data:`OVERLAP_SAMPLES` seeded
  poses within the joint limits;
- or joins two bodies the descriptor lists under ``ignore_collisions``.

Designed overlaps are left out of the reachability model's collisions and of the fit's
self-penetration; hand links never collide with each other in the simulated scenes.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Depth beyond which two hand geoms count as colliding [m].
SELF_PENETRATION = 5e-4
#: Share of sampled poses above which two links of one chain overlap by design. The gap is wide:
#: the LEAP hand's hull pairs overlap in 83-85 % of poses, no pair of the SDH's or the Shadow
#: hand's chains in more than 10 %.
OVERLAP_SHARE = 0.5
#: Poses sampled to find a chain's designed overlaps, and their seed.
OVERLAP_SAMPLES = 256
OVERLAP_SEED = 0

GeomPair = tuple[int, int]


def collision_model(model: mujoco.MjModel, hand_geoms: NDArray[np.bool_] | None = None) -> mujoco.MjModel:
    """A copy of a hand's model in which every geom that collides with anything collides with every other.

    ``hand_geoms`` (shape (ngeom,)) marks the hand's own geoms; the others (a floor or a table in the
    file the descriptor names, which no scene takes over) collide with nothing.
    """
    collider = copy.copy(model)
    if hand_geoms is not None:
        collider.geom_contype[~hand_geoms] = 0
        collider.geom_conaffinity[~hand_geoms] = 0
    solid = (collider.geom_contype != 0) | (collider.geom_conaffinity != 0)
    collider.geom_contype[solid] = 1
    collider.geom_conaffinity[solid] = 1
    # The broadphase filters bodies first, by flags the compiler ORed from their geoms.
    collider.body_contype[:] = 1
    collider.body_conaffinity[:] = 1
    return collider


def penetrating_pairs(model: mujoco.MjModel, data: mujoco.MjData) -> set[GeomPair]:
    """Geom pairs (lower id first) deeper than :data:`SELF_PENETRATION` in the posed ``data``."""
    mujoco.mj_collision(model, data)
    return {
        (min(c.geom1, c.geom2), max(c.geom1, c.geom2)) for c in data.contact[: data.ncon] if c.dist < -SELF_PENETRATION
    }


@dataclass(frozen=True)
class DesignedOverlaps:
    """The geom pairs of a hand that are not collisions, and why.

    Attributes:
        pairs: Every designed pair (geom ids of the collision model, lower first).
        at_reference: Pairs that penetrate in the reference pose.
        on_chain: Pairs of one chain that penetrate in more than :data:`OVERLAP_SHARE` of the
            sampled poses, with that share.
        listed: Pairs of the bodies the descriptor lists under ``ignore_collisions``.
    """

    pairs: frozenset[GeomPair]
    at_reference: frozenset[GeomPair]
    on_chain: dict[GeomPair, float]
    listed: frozenset[GeomPair]


def designed_overlaps(
    collider: mujoco.MjModel,
    pose: Callable[[mujoco.MjModel, mujoco.MjData, ArrayLike], None],
    reference: NDArray[np.float64],
    samples: NDArray[np.float64],
    listed_bodies: Iterable[tuple[int, int]] = (),
) -> DesignedOverlaps:
    """Find a hand's designed overlaps (see the module's rules).

    Args:
        collider: The hand's :func:`collision_model`.
        pose: Puts a configuration (J,) into ``data`` and runs the kinematics.
        reference: The reference configuration, shape (J,).
        samples: Configurations within the limits, shape (N, J).
        listed_bodies: Body id pairs whose geoms never count as colliding.

    Returns:
        The designed pairs.
    """
    data = mujoco.MjData(collider)
    pose(collider, data, reference)
    at_reference = frozenset(penetrating_pairs(collider, data))
    counts: dict[GeomPair, int] = {}
    for row in samples:
        pose(collider, data, row)
        for pair in penetrating_pairs(collider, data):
            if pair not in at_reference and _one_chain(collider, *pair):
                counts[pair] = counts.get(pair, 0) + 1
    on_chain = {pair: n / len(samples) for pair, n in counts.items() if n > OVERLAP_SHARE * len(samples)}
    listed = frozenset(_geom_pairs(collider, listed_bodies))
    return DesignedOverlaps(at_reference | frozenset(on_chain) | listed, at_reference, on_chain, listed)


def _one_chain(model: mujoco.MjModel, geom_a: int, geom_b: int) -> bool:
    """Whether the bodies of two geoms lie on one chain: one is the other's ancestor."""
    a, b = int(model.geom_bodyid[geom_a]), int(model.geom_bodyid[geom_b])
    return _below(model, a, b) or _below(model, b, a)


def _below(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    while body != ancestor:
        if body == 0:
            return False
        body = int(model.body_parentid[body])
    return True


def _geom_pairs(model: mujoco.MjModel, bodies: Iterable[tuple[int, int]]) -> set[GeomPair]:
    """Every pair of geoms, one on each body of each body pair."""
    pairs = set()
    for a, b in bodies:
        for g in np.flatnonzero(model.geom_bodyid == a):
            for h in np.flatnonzero(model.geom_bodyid == b):
                pairs.add((int(min(g, h)), int(max(g, h))))
    return pairs
