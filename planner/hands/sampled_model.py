"""A hand's sampled configurations: the pads' codes, the k-d tree of a choice of fingers, and how many samples a model needs.

How many: a model the descriptor gives no ``[reachability] samples`` grows until it *recalls* the
hand's own configurations: of :data:`RECALL_PROBES` held-out sampled configurations (collision-free
for the fingers that take a default grasp), at least :data:`AUTO_RECALL` must have a code within
the default threshold of a sample's. It starts at :data:`FIRST_SAMPLES` and doubles, up to
:data:`MAX_AUTO_SAMPLES`. A hand whose fingers sweep a large space for their size (long fingers,
wide ranges) needs many more samples than a compact one before its model comes near the grasps
it can reach.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ogcp.planner.config.methods import DEFAULT_HAND_THRESHOLD
from ogcp.planner.hands.box_index import BoxIndex, boxes_within

if TYPE_CHECKING:
    from ogcp.planner.grasp.contact_set import ContactSet
    from ogcp.planner.hands.kinematics import HandKinematics

#: Smallest spread a code dimension is normalised by, for distances [m] and for normal differences
#: and cosines:
#: a gripper whose pads always face each other has no spread in normal difference, and its
#: tolerance (threshold x spread) must still admit slightly curved surfaces.
DISTANCE_SCALE_FLOOR = 1e-3
NORMAL_SCALE_FLOOR = 0.02
#: How far beyond the sampled span of a finger pair's pad distances a grasp's may lie before it
#: counts against the grasp [m]: the fit lets each of the two pads miss its contact by 1 mm. The
#: span is widened further by twice how much the samples' extreme moved from half the samples to
#: all: a hand of many joints samples its extremes less closely.
SPAN_MARGIN = 2e-3
#: The length [m] beyond the widened span that adds 1 to the residual: a parallel gripper's
#: distance code spreads as widely as its jaws travel (16 mm for the built-in gripper), so within
#: the default threshold the code alone admitted a box 11 mm wider than the jaws open.
SPAN_SCALE = 1e-3
#: Configurations posed per progress step while sampling.
SAMPLE_BATCH = 2_000
#: The first samples of a growing model (and the model of a one-finger hand).
FIRST_SAMPLES = 10_000
#: The recall a growing model stops at. The SDH's and the Shadow hand's models of 10,000 samples
#: recall 51 % and 49 % of their first three fingers' configurations and stay at that size; a LEAP
#: hand's (four joints per finger over wide ranges) recalled 16 % and accepted no grasp of a 6.9 cm
#: sphere, and 62 % with 100,000 samples, where it realised and held every one of five.
AUTO_RECALL = 0.4
#: Most configurations a growing model takes (a minute or two of sampling, once, then cached).
MAX_AUTO_SAMPLES = 320_000
#: Held-out configurations a model's recall is measured on.
RECALL_PROBES = 1_000


def pair_code(positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pairwise rigid invariants of pad tuples, shape (..., 4 C(m, 2)).

    For each pair i < j: the distance ``|p_j - p_i|``, the normal difference ``|n_i - n_j|``, and
    both normals' cosines with the direction ``u = (p_j - p_i) / |p_j - p_i|`` (a parallel gripper
    pinches only points whose line runs along its pads' normals).
    """
    m = positions.shape[-2]
    columns = []
    for i, j in itertools.combinations(range(m), 2):
        line = positions[..., j, :] - positions[..., i, :]
        length = np.linalg.norm(line, axis=-1)
        u = line / np.maximum(length, 1e-12)[..., None]
        columns.append(length)
        columns.append(np.linalg.norm(normals[..., i, :] - normals[..., j, :], axis=-1))
        columns.append(np.einsum("...k,...k->...", normals[..., i, :], u))
        columns.append(np.einsum("...k,...k->...", normals[..., j, :], u))
    return np.stack(columns, axis=-1)


@dataclass(frozen=True, eq=False)
class SampledHand:
    """A hand's sampled configurations: pads in the palm frame and collisions.

    Attributes:
        joint_names: The hand's finger joints.
        angles: Configurations, shape (N, J) [rad or m].
        points: Every finger's pad point in the palm frame, shape (N, F, 3) [m].
        normals: Every finger's pad normal in the palm frame, shape (N, F, 3).
        collisions: Which groups (fingers, then the palm) collide, shape (N, F + 1, F + 1).
        recall: The recall a growing model reached (None for a model of a fixed size).
    """

    joint_names: tuple[str, ...]
    angles: NDArray[np.float64]
    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    collisions: NDArray[np.bool_]
    recall: float | None = None


@dataclass(frozen=True, eq=False)
class FingerModel:
    """The k-d tree of one choice of fingers.

    Attributes:
        rows: The samples in which these fingers and the palm are collision-free, shape (n,).
        scale: Each code dimension's spread, shape (4 C(m, 2),).
        codes: The samples' scaled codes, shape (n, 4 C(m, 2)).
        tree: k-d tree of ``codes``.
        boxes: Leaves of ``codes`` with their bounding boxes.
        spans: Each finger pair's least and greatest pad distance over the samples, widened
            (:data:`SPAN_MARGIN`), shape (C(m, 2), 2) [m].
    """

    rows: NDArray[np.intp]
    scale: NDArray[np.float64]
    codes: NDArray[np.float64]
    tree: Any
    boxes: BoxIndex
    spans: NDArray[np.float64]

    def beyond(self, codes: NDArray[np.float64]) -> NDArray[np.float64]:
        """How far unscaled codes (..., 4 C(m, 2)) put the pads beyond the pairs' spans, in
        :data:`SPAN_SCALE` units (root sum of squares over the pairs), shape (...)."""
        distance = codes[..., 0::4]
        gap = np.maximum(self.spans[:, 0] - distance, 0.0) + np.maximum(distance - self.spans[:, 1], 0.0)
        return np.asarray(np.linalg.norm(gap, axis=-1) / SPAN_SCALE)

    def size_mismatch(self, positions: NDArray[np.float64]) -> str | None:
        """Why no grasp of these contact points (n, 3) [m] can meet the fingers' pads whatever the
        samples: every two contacts lie farther apart than any two pads ever come (an object too
        large for the hand), or all nearer than they ever come (too small); None where neither holds."""
        points = np.asarray(positions, dtype=float).reshape(-1, 3)
        if len(points) < 2:
            return None
        from scipy.spatial import cKDTree  # here, as in finger_model: every plan imports this module

        widest, narrowest = float(self.spans[:, 1].max()), float(self.spans[:, 0].min())
        closest = float(cKDTree(points).query(points, k=2)[0][:, 1].min())
        across = float(np.linalg.norm(np.ptp(points, axis=0)))  # no two points are farther apart
        if closest > widest:
            return (
                f"no two contacts are nearer than {closest:.3g} m, and no two of its pads are ever farther apart "
                f"than {widest:.3g} m: the object is too large for the hand"
            )
        if across < narrowest:
            return (
                f"all contacts lie within {across:.3g} m of each other, and no two of its pads ever come nearer "
                f"than {narrowest:.3g} m: the object is too small for the hand"
            )
        return None


@lru_cache(maxsize=8)
def assignments(m: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Every assignment of m super-contacts to the fingers, shape (m!, m), and the finger pairs
    i < j in :func:`pair_code`'s order, shape (C(m, 2), 2)."""
    orders = np.array(list(itertools.permutations(range(m))), dtype=np.int64)
    pairs = np.array(list(itertools.combinations(range(m), 2)), dtype=np.int64).reshape(-1, 2)
    return orders, pairs


def free_rows(sampled: SampledHand, chosen: Sequence[int]) -> NDArray[np.intp]:
    """The samples in which the ``chosen`` fingers and the palm collide with nothing, shape (n,)."""
    groups = [*chosen, sampled.collisions.shape[1] - 1]
    hits = sampled.collisions[:, groups][:, :, groups]
    return np.flatnonzero(~hits.any(axis=(1, 2)))


def finger_model(sampled: SampledHand, chosen: Sequence[int]) -> FingerModel | None:
    """The tree of the samples where the ``chosen`` fingers and the palm collide with nothing; None if none."""
    rows = free_rows(sampled, chosen)
    if len(rows) == 0:
        return None
    codes = pair_code(sampled.points[rows][:, list(chosen)], sampled.normals[rows][:, list(chosen)])
    floor = np.tile([DISTANCE_SCALE_FLOOR, *[NORMAL_SCALE_FLOOR] * 3], codes.shape[1] // 4)
    scale = np.maximum(codes.std(axis=0), floor)
    from scipy.spatial import cKDTree  # here, not at the top: every plan imports this module

    scaled = codes / scale
    return FingerModel(rows, scale, scaled, cKDTree(scaled), BoxIndex(scaled), _spans(codes[:, 0::4]))


def _spans(distance: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each pair's widened span of pad distances, shape (P, 2) [m], from the samples' (n, P)."""
    low, high = distance.min(axis=0), distance.max(axis=0)
    half = distance[::2]  # the samples are independent: every second one is a random half
    low_moved, high_moved = half.min(axis=0) - low, high - half.max(axis=0)
    return np.stack([low - SPAN_MARGIN - 2.0 * low_moved, high + SPAN_MARGIN + 2.0 * high_moved], axis=1)


def residuals(model: FingerModel, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
    """Normalised code distance of pad tuples (B, m, 3) to the nearest sample, best over assignments, shape (B,).

    A pair of contacts farther apart (or nearer) than its fingers' widened span of pad distances
    adds how far, in :data:`SPAN_SCALE` units, as a further dimension of that distance.
    """
    orders = assignments(positions.shape[1])[0]
    codes = pair_code(positions[:, orders], normals[:, orders])  # (B, m!, codes)
    distance, _ = model.tree.query(codes.reshape(-1, codes.shape[-1]) / model.scale, k=1)
    distance = np.hypot(distance.reshape(len(positions), len(orders)), model.beyond(codes))
    return np.asarray(distance.min(axis=1), dtype=float)


def pose_samples(kinematics: HandKinematics, angles: NDArray[np.float64], bar: tqdm) -> SampledHand:
    """The pads and collisions of configurations (N, J), in batches that advance ``bar``."""
    batches = []
    for start in range(0, len(angles), SAMPLE_BATCH):
        batch = angles[start : start + SAMPLE_BATCH]
        batches.append((*kinematics.pads_many(batch), kinematics.collisions(batch)))
        bar.update(len(batch))
    points, normals, collisions = (np.concatenate(parts) for parts in zip(*batches, strict=True))
    return SampledHand(kinematics.joint_names, angles, points, normals, collisions)


def grow_samples(kinematics: HandKinematics, chosen: Sequence[int], seed: int, desc: str) -> SampledHand:
    """A model that doubles from :data:`FIRST_SAMPLES` until it recalls :data:`AUTO_RECALL` of
    the ``chosen`` fingers' held-out configurations, or holds :data:`MAX_AUTO_SAMPLES`.

    The first samples are those of a model of :data:`FIRST_SAMPLES` with ``seed``; the probes and
    each doubling draw streams of their own (``seed`` with spawn keys 0, 1, 2, ...), so the result
    depends on ``seed`` alone.
    """
    with tqdm(total=FIRST_SAMPLES, desc=desc, unit="pose", disable=None) as bar:
        sampled = pose_samples(kinematics, kinematics.sample(FIRST_SAMPLES, seed), bar)
        if len(chosen) < 2:  # one finger: no pair, no code to recall
            return sampled
        probes = pose_samples(kinematics, kinematics.sample(RECALL_PROBES, _stream(seed, 0)), tqdm(disable=True))
        recall = _recall(sampled, probes, chosen)
        doubling = 1
        while recall < AUTO_RECALL and 2 * len(sampled.angles) <= MAX_AUTO_SAMPLES:
            bar.total += len(sampled.angles)
            bar.refresh()
            more = pose_samples(kinematics, kinematics.sample(len(sampled.angles), _stream(seed, doubling)), bar)
            sampled = _joined(sampled, more)
            recall = _recall(sampled, probes, chosen)
            doubling += 1
    return SampledHand(sampled.joint_names, sampled.angles, sampled.points, sampled.normals, sampled.collisions, recall)


def _stream(seed: int, key: int) -> np.random.SeedSequence:
    # Not [seed, key]: numpy seeds [s, 0] exactly as s.
    return np.random.SeedSequence(seed, spawn_key=(key,))


def _recall(sampled: SampledHand, probes: SampledHand, chosen: Sequence[int]) -> float:
    """Share of the probes (collision-free for ``chosen``) whose code is within the default threshold of a sample's."""
    model = finger_model(sampled, chosen)
    free = free_rows(probes, chosen)
    if model is None or not len(free):
        return 0.0
    points = probes.points[free][:, list(chosen)]
    normals = probes.normals[free][:, list(chosen)]
    return float(np.mean(residuals(model, points, normals) <= DEFAULT_HAND_THRESHOLD))


def _joined(a: SampledHand, b: SampledHand) -> SampledHand:
    return SampledHand(
        a.joint_names,
        np.concatenate([a.angles, b.angles]),
        np.concatenate([a.points, b.points]),
        np.concatenate([a.normals, b.normals]),
        np.concatenate([a.collisions, b.collisions]),
    )


def assignment_codes(
    grasp: Sequence[int], contacts: ContactSet, model: FingerModel
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """Every assignment of a grasp's contacts to the fingers, shape (m!, m), its scaled codes,
    shape (m!, 4 C(m, 2)), and how far beyond the pairs' spans it puts the pads, shape (m!,)."""
    orders = assignments(len(grasp))[0]
    ordered = np.asarray(grasp, dtype=np.intp)[orders]
    codes = pair_code(contacts.positions[ordered], contacts.normals[ordered])
    return orders, codes / model.scale, model.beyond(codes)


def boxes_admit(model: FingerModel, bounds: NDArray[np.float64], threshold: float) -> bool:
    """Whether some sample of ``model`` lies within ``threshold`` of the box of codes that super-contacts
    of those invariant ranges (``bounds``, shape (m, m, 2, 4), of :func:`pair_bounds`) span, under
    some assignment to its fingers."""
    orders, pairs = assignments(len(bounds))
    boxes = model.boxes
    return bool(
        boxes_within(
            np.ascontiguousarray(bounds),
            orders,
            pairs,
            model.scale,
            threshold * threshold,
            model.spans,
            SPAN_SCALE,
            boxes.low,
            boxes.high,
            boxes.points,
            boxes.starts,
        )
    )
