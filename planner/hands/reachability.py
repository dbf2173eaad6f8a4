"""Fingertip reachability of the Schunk SDH as a grasp constraint P(g) (paper Sec. V-E).

The model samples joint configurations (seeded, self-collisions rejected), encodes each
fingertip triple by the pairwise code ``[|p_i - p_j|, |n_i - n_j|]`` for the finger pairs
(1,2), (1,3), (2,3), normalises every dimension by its spread over the samples, and keeps
a k-d tree. A grasp of three contacts (positions, inward normals: a fingertip pushes
along the inward normal, which is its pad normal) is reachable when, for some assignment
of contacts to fingers, its code lies within ``threshold`` of a sample; the distance to
the nearest sample is the *residual*.

Pruning super-contact states is sound: over a state every pairwise distance and normal
difference lies in an interval, so every grasp's code lies in a box, and the state is
pruned only if no sample lies within ``threshold`` of that box (exact point-to-box
distances) under any assignment. A state that holds a reachable grasp is never pruned.
The sampled model is cached on disk (``$OGCP_CACHE``, default ``~/.cache/ogcp``) as the entry
``sdh_reach_<key>/`` of :mod:`ogcp.planner.infra.cache`, under a key of its parameters.
"""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.config.methods import DEFAULT_HAND_THRESHOLD
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.hands.sdh import (
    BASE_ROTATION_SIGN,
    DISTAL_LENGTH,
    FINGER_BASES,
    FINGER_YAWS,
    JOINT_NAMES,
    PROXIMAL_LENGTH,
    PROXIMAL_OFFSET,
    random_configurations,
)
from ogcp.planner.infra.cache import cache_dir as default_cache_dir
from ogcp.planner.infra.cache import read_entry, write_entry
from ogcp.planner.infra.errors import OgcpError

MODEL_VERSION = 1
#: The sampled model's file in its cache entry: arrays ``q`` (N, 7) [rad] and ``codes`` (N, 6).
MODEL_FILE = "model.npz"
PAIRS = ((0, 1), (0, 2), (1, 2))
ASSIGNMENTS = tuple(itertools.permutations(range(3)))
#: Links of different fingers closer than this are in collision (twice the capsule radius) [m].
LINK_CLEARANCE = 0.019
POINTS_PER_LINK = 8


def finger_chain(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Proximal axis, distal axis and tip of every finger, shape (..., 3 fingers, 3 points, 3) [m]."""
    q = np.atleast_2d(q)
    yaw = FINGER_YAWS[None, :] + BASE_ROTATION_SIGN[None, :] * q[:, :1]
    u = np.stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)], axis=-1)  # toward the palm axis
    z = np.array([0.0, 0.0, 1.0])
    proximal, distal = q[:, 1::2], q[:, 2::2]
    d1 = np.sin(proximal)[..., None] * u + np.cos(proximal)[..., None] * z
    d2 = np.sin(proximal + distal)[..., None] * u + np.cos(proximal + distal)[..., None] * z
    a = np.broadcast_to(FINGER_BASES + PROXIMAL_OFFSET * z, d1.shape)
    b = a + PROXIMAL_LENGTH * d1
    tip = b + DISTAL_LENGTH * d2
    return np.stack([a, b, tip], axis=2)


def pad_normals(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pad normal of every fingertip (distal link's local +x), shape (..., 3, 3)."""
    q = np.atleast_2d(q)
    yaw = FINGER_YAWS[None, :] + BASE_ROTATION_SIGN[None, :] * q[:, :1]
    u = np.stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)], axis=-1)
    angle = (q[:, 1::2] + q[:, 2::2])[..., None]
    return np.cos(angle) * u - np.sin(angle) * np.array([0.0, 0.0, 1.0])


def self_collision_free(q: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether links of different fingers keep :data:`LINK_CLEARANCE`, shape (...,)."""
    chain = finger_chain(q)
    t = np.linspace(0.0, 1.0, POINTS_PER_LINK)[:, None]
    points = np.concatenate(
        [
            chain[:, :, 0:1] + t * (chain[:, :, 1:2] - chain[:, :, 0:1]),
            chain[:, :, 1:2] + t * (chain[:, :, 2:3] - chain[:, :, 1:2]),
        ],
        axis=2,
    )  # (N, 3, 2P, 3)
    ok = np.ones(len(points), dtype=bool)
    for i, j in PAIRS:
        gap = np.linalg.norm(points[:, i, :, None, :] - points[:, j, None, :, :], axis=-1).min(axis=(1, 2))
        ok &= gap >= LINK_CLEARANCE
    return ok


def pair_code(positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pairwise code of fingertip triples, shape (..., 6): distance and normal difference per pair."""
    columns = []
    for i, j in PAIRS:
        columns.append(np.linalg.norm(positions[..., i, :] - positions[..., j, :], axis=-1))
        columns.append(np.linalg.norm(normals[..., i, :] - normals[..., j, :], axis=-1))
    return np.stack(columns, axis=-1)


@dataclass(frozen=True)
class Reach:
    """Reachability of one grasp: residual, the nearest sample's joint angles, the assignment."""

    residual: float
    joint_angles: tuple[float, ...]
    fingers: tuple[int, ...]  # fingers[k] = index of the grasp contact that finger k touches


class SDHReachability:
    """Constraint P(g): the SDH can place its three fingertips on the grasp's contacts.

    Args:
        samples: Joint configurations to sample (before self-collision rejection).
        seed: Sampling seed.
        threshold: Largest residual (normalised code distance) that counts as reachable.
            Residuals shrink as samples grow; with the default 10,000 samples about 5 % of
            random contact triples on the built-in objects fall within 0.3.
        cache_dir: Where the sampled model is cached; default ``$OGCP_CACHE`` or
            ``~/.cache/ogcp``.
    """

    name = "sdh"

    def __init__(
        self,
        samples: int = 10_000,
        seed: int = 0,
        threshold: float = DEFAULT_HAND_THRESHOLD,
        cache_dir: str | Path | None = None,
    ) -> None:
        if not isinstance(samples, int) or samples < 1:
            raise OgcpError(f"hand samples must be an integer >= 1, got {samples!r}")
        if not (np.isfinite(threshold) and threshold > 0):
            raise OgcpError(f"reachability threshold must be a positive number, got {threshold!r}")
        self.samples, self.seed, self.threshold = samples, seed, float(threshold)
        self.cache_dir = Path(cache_dir) if cache_dir else default_cache_dir()
        self.q, codes = self._load_or_sample()
        self.scale = np.maximum(codes.std(axis=0), 1e-9)
        self.codes = codes / self.scale
        from scipy.spatial import cKDTree  # here, not at the top: every plan imports this module

        self._tree = cKDTree(self.codes)

    def _load_or_sample(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        key = hashlib.sha256(repr((MODEL_VERSION, self.samples, self.seed, LINK_CLEARANCE)).encode()).hexdigest()[:16]
        folder = self.cache_dir / f"sdh_reach_{key}"
        cached = read_entry(folder, self._read_model)
        if cached is not None:
            return cached
        q = random_configurations(self.samples, self.seed)
        q = q[self_collision_free(q)]
        if len(q) == 0:
            raise OgcpError("no collision-free SDH configuration was sampled; raise the number of samples")
        codes = pair_code(finger_chain(q)[:, :, 2], pad_normals(q))
        try:
            write_entry(folder, lambda stage: np.savez(stage / MODEL_FILE, q=q, codes=codes))
        except OgcpError:
            pass  # a read-only cache only costs the sampling time next run
        return q, codes

    def _read_model(self, folder: Path) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The sampled model of a cache entry, checked against this model's parameters.

        Raises:
            ValueError: For arrays of the wrong shape or with non-finite values.
        """
        with np.load(folder / MODEL_FILE, allow_pickle=False) as data:
            q, codes = data["q"], data["codes"]
        if not (q.ndim == 2 and q.shape[1] == len(JOINT_NAMES) and 0 < len(q) <= self.samples):
            raise ValueError(f"joint configurations of shape {q.shape}")
        if codes.shape != (len(q), 6) or not (np.isfinite(q).all() and np.isfinite(codes).all()):
            raise ValueError(f"pair codes of shape {codes.shape} or non-finite values")
        return q, codes

    def residuals(self, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
        """Residuals of fingertip target triples, best over finger assignments, shape (B,).

        Args:
            positions: Target points, shape (B, 3, 3) [m].
            normals: Inward normals at the targets (the pad normals needed), shape (B, 3, 3).
        """
        codes = np.stack([pair_code(positions[:, list(a)], normals[:, list(a)]) for a in ASSIGNMENTS], axis=1)
        distance, _ = self._tree.query(codes.reshape(-1, 6) / self.scale, k=1)
        return distance.reshape(len(positions), len(ASSIGNMENTS)).min(axis=1)

    def reach(self, grasp: Sequence[int], contacts: ContactSet) -> Reach:
        """Residual of a 3-contact grasp over all finger assignments, with the nearest sample."""
        if len(grasp) != 3:
            raise OgcpError(f"the SDH has 3 fingers; a grasp of {len(grasp)} contacts cannot be assigned")
        p, n = contacts.positions[list(grasp)], contacts.normals[list(grasp)]
        codes = np.array([pair_code(p[list(a)], n[list(a)]) for a in ASSIGNMENTS]) / self.scale
        distance, nearest = self._tree.query(codes, k=1)
        best = int(np.argmin(distance))
        return Reach(float(distance[best]), tuple(float(v) for v in self.q[nearest[best]]), ASSIGNMENTS[best])

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """P(g): the residual is within the threshold."""
        return self.reach(grasp, contacts).residual <= self.threshold

    def accepts_many(self, grasps: NDArray[np.intp], contacts: ContactSet) -> NDArray[np.bool_]:
        """P(g) for many 3-contact grasps at once, shape (B,)."""
        if grasps.shape[1] != 3:
            raise OgcpError(f"the SDH has 3 fingers; grasps of {grasps.shape[1]} contacts cannot be assigned")
        return self.residuals(contacts.positions[grasps], contacts.normals[grasps]) <= self.threshold

    def admits(self, super_contacts: Sequence[NDArray[np.intp]], contacts: ContactSet) -> bool:
        """Sound: False only if no grasp drawn from the super-contacts is reachable."""
        if len(super_contacts) != 3:
            raise OgcpError(f"the SDH has 3 fingers; m = {len(super_contacts)} cannot be assigned")
        from scipy.spatial.distance import cdist

        lo, hi = np.zeros((3, 3, 2)), np.zeros((3, 3, 2))
        for i, j in itertools.combinations(range(3), 2):
            pi, pj = contacts.positions[super_contacts[i]], contacts.positions[super_contacts[j]]
            ni, nj = contacts.normals[super_contacts[i]], contacts.normals[super_contacts[j]]
            d, e = cdist(pi, pj), cdist(ni, nj)
            lo[i, j] = lo[j, i] = d.min(), e.min()
            hi[i, j] = hi[j, i] = d.max(), e.max()
        for a in ASSIGNMENTS:
            box_lo = np.concatenate([lo[a[i], a[j]] for i, j in PAIRS]) / self.scale
            box_hi = np.concatenate([hi[a[i], a[j]] for i, j in PAIRS]) / self.scale
            gap = np.maximum(box_lo - self.codes, 0.0) + np.maximum(self.codes - box_hi, 0.0)
            if np.min(np.einsum("ij,ij->i", gap, gap)) <= self.threshold**2:
                return True
        return False

    def describe(self) -> dict[str, object]:
        """JSON-ready description."""
        return {
            "name": self.name,
            "samples": self.samples,
            "kept": len(self.q),
            "seed": self.seed,
            "threshold": self.threshold,
        }
