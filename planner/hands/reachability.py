"""Fingertip reachability of any hand as a grasp constraint P(g) (paper Sec. V-E).

The model samples joint configurations of the hand (seeded, uniform within the joint limits,
joint equalities kept), computes every finger's pad point and pad normal in the palm frame with
MuJoCo (:class:`ogcp.planner.hands.kinematics.HandKinematics`) and records which fingers collide
in each. For a grasp of m contacts the m chosen fingers (``fingers``, default the first m of the
descriptor) are used: each sample in which they and the palm are collision-free is encoded by the
pairwise code ``[|p_i - p_j|, |n_i - n_j|, n_i . u_ij, n_j . u_ij]`` over the finger pairs
(``u_ij`` the unit direction from p_i to p_j), every dimension is normalised
by its spread over the samples, and a k-d tree is kept. A grasp (positions, inward normals: a pad
pushes along the inward normal, its pad normal) is reachable when, for some assignment of its
contacts to the fingers, its code lies within ``threshold`` of a sample; the distance to the
nearest sample is the *residual*. The code's distance dimension is normalised by its spread, which
for a parallel gripper is as wide as its jaws travel: a pair of contacts farther apart (or nearer)
than the span of its fingers' sampled pad distances, widened by the fit's tolerance and the
sampling's uncertainty, adds how far (in millimetres) to the residual as one more dimension.

What pruning guarantees: over a super-contact state every pairwise distance and normal difference
lies in an interval, so every grasp's code lies in a box, and the state is pruned only if no
sample lies within ``threshold`` of that box (exact point-to-box distances, the distance
intervals' from the spans included) under any assignment.
A state that holds a grasp accepted by the *sampled* model is never pruned. The model is a sample:
a grasp the real hand reaches but no sample comes near is rejected, and more samples (``samples``)
shrink that gap; the fit in simulation is what finally decides.

The sampled model is cached (``$OGCP_CACHE``) as the entry ``hand_reach_<name>_<key>/`` of
:mod:`ogcp.planner.infra.cache`, keyed by the descriptor's and the model's sha256 and the
sampling parameters, and rebuilt when damaged.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ogcp.planner.config.methods import DEFAULT_HAND_THRESHOLD
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.hands.box_index import pair_bounds
from ogcp.planner.hands.descriptor import HandDescriptor
from ogcp.planner.hands.many_fingers import TRIPLE_SLACK, ManyFingers
from ogcp.planner.hands.model_file import MODEL_FILE, read_model, save_model
from ogcp.planner.hands.registry import resolve_hand
from ogcp.planner.hands.sampled_model import (
    AUTO_RECALL,
    MAX_AUTO_SAMPLES,
    FingerModel,
    SampledHand,
    assignment_codes,
    boxes_admit,
    finger_model,
    grow_samples,
    pair_code,
    pose_samples,
    residuals,
)
from ogcp.planner.infra.cache import cache_dir as default_cache_dir
from ogcp.planner.infra.cache import read_entry, write_entry
from ogcp.planner.infra.errors import OgcpError

__all__ = ["HandReachability", "Reach", "SDHReachability", "pair_code"]

MODEL_VERSION = 6  # 6: a coupled joint's driver sampled only where the coupled joint stays in its range
#: Most contacts a grasp may have: the residual is a minimum over m! finger assignments.
MAX_FINGERS = 6
#: Fingers whose configurations a growing model must recall, when none are named: a default grasp's.
RECALLED_FINGERS = 3
#: Most fingers one code covers: a grasp of more is judged by every three of its fingers
#: (:mod:`~ogcp.planner.hands.many_fingers`).
CODED_FINGERS = 3


@dataclass(frozen=True)
class Reach:
    """Reachability of one grasp.

    Attributes:
        residual: Normalised code distance to the nearest sample.
        joint_angles: That sample's configuration (the hand's finger joints) [rad or m].
        fingers: ``fingers[k]`` = index in the grasp of the contact that chosen finger k touches.
        finger_names: The chosen fingers, in order.
    """

    residual: float
    joint_angles: tuple[float, ...]
    fingers: tuple[int, ...]
    finger_names: tuple[str, ...] = ()


#: How many times the samples of the last model a search tries when it finds no grasp under a hand.
DENSER_FACTOR = 4
#: A denser model is tried only where some grasp's residual is within this many thresholds: the
#: Allegro hand's best grasp of a 7 cm sphere is at 1.27 with 10,000 samples and 0.98 with 80,000;
#: the SDH's of a 2 m box at 5.0.
NEAR_MISS = 1.5
#: Grasps whose residuals :meth:`HandReachability.near_miss` takes (about 0.3 s).
NEAR_MISS_GRASPS = 2_000


class HandReachability:
    """Constraint P(g): the hand can place the chosen fingers' pads on the grasp's contacts.

    Args:
        hand: A built-in hand name, a descriptor path, or a loaded descriptor.
        fingers: Names of the fingers that take the contacts, in order; None: the first m.
        samples: Joint configurations to sample (before collision rejection); None: the
            descriptor's ``[reachability] samples``, or where it gives none as many as the model
            needs to recall the hand's own configurations (:mod:`~ogcp.planner.hands.sampled_model`).
        seed: Sampling seed.
        threshold: Largest residual (normalised code distance) that counts as reachable.
        cache_dir: Where the sampled model is cached; default ``$OGCP_CACHE`` or ``~/.cache/ogcp``.

    Raises:
        OgcpError: For an unknown hand, a bad descriptor or model, or bad parameters.
    """

    def __init__(
        self,
        hand: str | Path | HandDescriptor = "sdh",
        fingers: Sequence[str] | None = None,
        samples: int | None = None,
        seed: int = 0,
        threshold: float = DEFAULT_HAND_THRESHOLD,
        cache_dir: str | Path | None = None,
    ) -> None:
        if samples is not None and (isinstance(samples, bool) or not isinstance(samples, int) or samples < 1):
            raise OgcpError(f"hand samples must be an integer >= 1, got {samples!r}")
        if not (isinstance(threshold, int | float) and math.isfinite(threshold) and threshold > 0):
            raise OgcpError(f"reachability threshold must be a positive number, got {threshold!r}")
        self.descriptor = hand if isinstance(hand, HandDescriptor) else resolve_hand(hand)
        samples = self.descriptor.reach_samples if samples is None else samples
        self.name = self.descriptor.name
        self.fingers = tuple(fingers) if fingers is not None else None
        if self.fingers is not None:
            self.descriptor.choose_fingers(len(self.fingers), self.fingers)
        self.seed, self.threshold = seed, float(threshold)
        #: The fixed size asked for; None: grown until it recalls the hand (then the size reached).
        self.samples: int | None = samples
        #: Whether a search that finds no grasp under this model may try a denser one
        #: (:meth:`denser`): the size was not fixed, by the caller or the descriptor.
        self.growable = samples is None
        self.cache_dir = Path(cache_dir) if cache_dir else default_cache_dir()
        self.sampled = self._load_or_sample()
        self.samples = len(self.sampled.angles)
        self._models: dict[tuple[int, ...], FingerModel] = {}
        self._threes: dict[tuple[int, ...], ManyFingers] = {}

    # ----- the sampled model -------------------------------------------------------------------

    def _recalled(self) -> tuple[int, ...]:
        """The fingers whose configurations a growing model must recall: the named ones, else a default grasp's."""
        count = len(self.descriptor.fingers)
        if self.fingers is not None:
            return self.descriptor.choose_fingers(len(self.fingers), self.fingers)
        return tuple(range(min(RECALLED_FINGERS, count)))

    def _key(self) -> str:
        size = self.samples if self.samples is not None else ("grown", AUTO_RECALL, MAX_AUTO_SAMPLES, self._recalled())
        parts = (MODEL_VERSION, self.descriptor.sha256, self.descriptor.model_sha256, size, self.seed)
        return hashlib.sha256(repr(parts).encode()).hexdigest()[:16]

    def _load_or_sample(self) -> SampledHand:
        slug = re.sub(r"[^A-Za-z0-9_-]+", "_", self.name)[:40]
        folder = self.cache_dir / f"hand_reach_{slug}_{self._key()}"
        cached = read_entry(folder, self._read_model)
        if cached is not None:
            return cached
        from ogcp.planner.hands.kinematics import HandKinematics  # MuJoCo only when sampling

        kinematics = HandKinematics(self.descriptor)
        desc = f"sampling the {self.name} hand"
        if self.samples is None:
            sampled = grow_samples(kinematics, self._recalled(), self.seed, desc)
        else:
            with tqdm(total=self.samples, desc=desc, unit="pose", disable=None) as bar:
                sampled = pose_samples(kinematics, kinematics.sample(self.samples, self.seed), bar)

        try:
            write_entry(folder, lambda stage: save_model(stage / MODEL_FILE, sampled))
        except OgcpError:
            pass  # a read-only cache only costs the sampling time next run
        return sampled

    def _read_model(self, folder: Path) -> SampledHand:
        """The sampled model of a cache entry, checked against this hand (:func:`read_model`)."""
        recalls = len(self._recalled()) >= 2  # a one-finger hand has no pair to recall: it keeps its first samples
        return read_model(folder / MODEL_FILE, len(self.descriptor.fingers), self.samples, recalls)

    def chosen(self, m: int) -> tuple[int, ...]:
        """Indices of the fingers that take an m-contact grasp.

        Raises:
            OgcpError: If m exceeds the hand's fingers or :data:`MAX_FINGERS`, or differs from the
                number of named fingers.
        """
        if m > MAX_FINGERS:
            raise OgcpError(f"hand constraints take grasps of at most {MAX_FINGERS} contacts; got m = {m}")
        if m < 2:
            raise OgcpError(f"a hand grasp needs at least 2 contacts; got m = {m}")
        return self.descriptor.choose_fingers(m, self.fingers)

    def _model(self, m: int) -> FingerModel:
        return self._model_of(self.chosen(m))

    def _many(self, m: int) -> ManyFingers:
        """The m > :data:`CODED_FINGERS` chosen fingers as the models of their threes."""
        chosen = self.chosen(m)
        if chosen not in self._threes:
            self._threes[chosen] = ManyFingers(chosen, self._model_of)
        return self._threes[chosen]

    def _model_of(self, chosen: tuple[int, ...]) -> FingerModel:
        if chosen not in self._models:
            model = finger_model(self.sampled, chosen)
            if model is None:
                names = ", ".join(self.descriptor.finger_names[f] for f in chosen)
                raise OgcpError(
                    f"no collision-free configuration of the {self.name} hand's fingers {names} was sampled "
                    f"in {self.samples}; raise the number of samples or check the model's geoms"
                )
            self._models[chosen] = model
        return self._models[chosen]

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The hand's finger joints, in the order of every configuration."""
        return self.sampled.joint_names

    @property
    def q(self) -> NDArray[np.float64]:
        """Every sampled configuration, shape (N, J)."""
        return self.sampled.angles

    # ----- the constraint ----------------------------------------------------------------------

    def residuals(self, positions: NDArray[np.float64], normals: NDArray[np.float64]) -> NDArray[np.float64]:
        """Residuals of target tuples, best over assignments of contacts to fingers, shape (B,).

        Args:
            positions: Target points, shape (B, m, 3) [m].
            normals: Inward normals at the targets (the pad normals needed), shape (B, m, 3).
        """
        m = positions.shape[1]
        if m > CODED_FINGERS:
            return self._many(m).residuals(positions, normals)
        return residuals(self._model(m), positions, normals)

    def reach(self, grasp: Sequence[int], contacts: ContactSet) -> Reach:
        """Residual of a grasp over all finger assignments, with the nearest sample."""
        m = len(grasp)
        if m > CODED_FINGERS:
            return self._many_starts(grasp, contacts, 1)[0]
        model = self._model(m)
        orders, codes, beyond = assignment_codes(grasp, contacts, model)
        distance, nearest = model.tree.query(codes, k=1)
        distance = np.hypot(distance, beyond)
        best = int(np.argmin(distance))
        angles = self.sampled.angles[model.rows[nearest[best]]]
        names = tuple(self.descriptor.finger_names[f] for f in self.chosen(m))
        order = tuple(int(f) for f in orders[best])
        return Reach(float(distance[best]), tuple(float(v) for v in angles), order, names)

    def starts(self, grasp: Sequence[int], contacts: ContactSet, count: int) -> list[Reach]:
        """``count`` near samples, each assignment's nearest first: starts for a fit.

        A fit from the single nearest sample can end in a local minimum (a finger through the
        object, a pad a few millimetres short); the sampled code is approximate, so the nearest
        samples of one assignment often share its failure. The starts therefore take every
        assignment's nearest sample (assignments by that distance), then every second nearest, etc.
        """
        m = len(grasp)
        if m > CODED_FINGERS:
            return self._many_starts(grasp, contacts, count)
        model = self._model(m)
        orders, codes, beyond = assignment_codes(grasp, contacts, model)
        k = min(count, len(model.rows))
        distance, nearest = model.tree.query(codes, k=k)
        distance, nearest = np.hypot(distance.reshape(len(orders), k), beyond[:, None]), nearest.reshape(len(orders), k)
        ranked = np.argsort(distance[:, 0], kind="stable")
        order = [int(a) * k + j for j in range(k) for a in ranked][:count]
        names = tuple(self.descriptor.finger_names[f] for f in self.chosen(m))
        found = []
        for flat in order:
            a, j = divmod(int(flat), k)
            angles = self.sampled.angles[model.rows[nearest[a, j]]]
            fingers = tuple(int(f) for f in orders[a])
            found.append(Reach(float(distance[a, j]), tuple(float(v) for v in angles), fingers, names))
        return found

    def _many_starts(self, grasp: Sequence[int], contacts: ContactSet, count: int) -> list[Reach]:
        """:meth:`starts` of a grasp of more than :data:`CODED_FINGERS` contacts: the assignments by
        residual, and within one the nearest samples of its threes of fingers by theirs."""
        members = np.asarray(grasp, dtype=np.intp)
        ranked = self._many(len(grasp)).ranked_starts(contacts.positions[members], contacts.normals[members])
        names = tuple(self.descriptor.finger_names[f] for f in self.chosen(len(grasp)))
        return [
            Reach(residual, tuple(float(v) for v in self.sampled.angles[row]), tuple(int(f) for f in order), names)
            for residual, row, order in ranked[:count]
        ]

    def accepts(self, grasp: Sequence[int], contacts: ContactSet) -> bool:
        """P(g): the residual is within the threshold.

        Asked as :meth:`admits` asks it of single contacts (some assignment's code within the
        threshold of some sample's), compiled: the nearest sample that :meth:`reach` finds in the
        k-d tree is not needed, and took 0.6 ms of every grasp a search met.
        """
        members = np.asarray(grasp, dtype=np.int64)
        if len(members) > CODED_FINGERS:
            residual = self.residuals(contacts.positions[members][None], contacts.normals[members][None])[0]
            return bool(residual <= self.threshold)
        return self._within(contacts, members, np.arange(len(members) + 1, dtype=np.int64))

    def accepts_many(self, grasps: NDArray[np.intp], contacts: ContactSet) -> NDArray[np.bool_]:
        """P(g) for many grasps of one size at once, shape (B,)."""
        return self.residuals(contacts.positions[grasps], contacts.normals[grasps]) <= self.threshold

    def admits(self, super_contacts: Sequence[NDArray[np.intp]], contacts: ContactSet) -> bool:
        """Sound: False only if no grasp drawn from the super-contacts is accepted."""
        members = np.concatenate([np.asarray(s, dtype=np.int64) for s in super_contacts])
        offsets = np.zeros(len(super_contacts) + 1, dtype=np.int64)
        offsets[1:] = np.cumsum([len(s) for s in super_contacts])
        return self._within(contacts, members, offsets)

    def _within(self, contacts: ContactSet, members: NDArray[np.int64], offsets: NDArray[np.int64]) -> bool:
        """Whether some sample's code lies within the threshold of the box of codes that super-contacts
        ``members[offsets[x]:offsets[x + 1]]`` span, under some assignment to the fingers."""
        m = len(offsets) - 1
        # bounds[x, y]: the interval of every code dimension of contact x (finger i) and y (finger j).
        bounds = pair_bounds(contacts.positions, contacts.normals, members, offsets)
        if m > CODED_FINGERS:
            widened = TRIPLE_SLACK * self.threshold
            return self._many(m).admits(
                lambda model, three: boxes_admit(model, bounds[np.ix_(three, three)], widened), m
            )
        return boxes_admit(self._model(m), bounds, self.threshold)

    def near_miss(self, contacts: ContactSet, m: int, seed: int = 0) -> float:
        """The least residual of up to :data:`NEAR_MISS_GRASPS` of the contacts' m-grasps (all, when
        there are no more; else drawn with ``seed``): how near the model came to accepting one."""
        n = len(contacts)
        if n < m:
            return math.inf
        if math.comb(n, m) <= NEAR_MISS_GRASPS:
            grasps = np.array(list(itertools.combinations(range(n), m)), dtype=np.intp)
        else:  # rows with a repeated contact dropped (few: there are more grasps than drawn)
            drawn = np.sort(np.random.default_rng(seed).integers(0, n, (NEAR_MISS_GRASPS, m)), axis=1)
            grasps = drawn[np.all(np.diff(drawn, axis=1) > 0, axis=1)]
        return float(self.residuals(contacts.positions[grasps], contacts.normals[grasps]).min())

    def denser(self, contacts: ContactSet, m: int) -> HandReachability | None:
        """The same hand's model with :data:`DENSER_FACTOR` times the samples (at most
        :data:`~ogcp.planner.hands.sampled_model.MAX_AUTO_SAMPLES`), for a search on ``contacts``
        that found no m-grasp under this one; None where the size was fixed or is at that limit, or
        where no grasp came within :data:`NEAR_MISS` thresholds (a 2 m box for a 20 cm hand).

        A grown model stops once it recalls the hand's own poses on average; a grasp the hand
        reaches only in a narrow family of poses (three pads on one sphere: their normals must meet
        in one point) can still lie just beyond every sample. Sampled once, then cached like this one.
        """
        count = len(self.sampled.angles)
        if not self.growable or count >= MAX_AUTO_SAMPLES:
            return None
        if self.near_miss(contacts, m) > NEAR_MISS * self.threshold:
            return None
        size = min(DENSER_FACTOR * count, MAX_AUTO_SAMPLES)
        model = HandReachability(self.descriptor, self.fingers, size, self.seed, self.threshold, self.cache_dir)
        model.growable = True
        return model

    def why_none(self, m: int | None = None, contacts: ContactSet | None = None) -> str:
        """What may change a search's finding that no m-grasp of ``contacts`` satisfies this constraint (one line)."""
        recall = "" if self.sampled.recall is None else f", recalling {self.sampled.recall:.0%} of its poses"
        mismatch = self._model(m).size_mismatch(contacts.positions) if m and contacts is not None else None
        if mismatch is not None:  # no sample, threshold or choice of fingers changes that
            return f"the {self.name} hand's reach accepts none of these contacts' grasps: {mismatch}; scale it (--diagonal)"
        many = ""
        if m is not None and m > CODED_FINGERS:
            many = (
                f"; with {m} fingers a grasp is accepted where every {CODED_FINGERS} of them accept their contacts "
                f"within {TRIPLE_SLACK:g} thresholds, under one assignment; or plan {CODED_FINGERS} of them "
                f"(-m {CODED_FINGERS}, --hand-fingers)"
            )
        return (
            f"the {self.name} hand's reachability model ({self.samples:,} sampled configurations{recall}) accepts "
            f"none of these contacts' grasps; more [reachability] samples in its descriptor, a larger "
            f"--hand-threshold (now {self.threshold:g}) or other --hand-fingers may find one{many}"
        )

    def describe(self) -> dict[str, object]:
        """JSON-ready description (the same whatever grasps were asked about before)."""
        return {
            "name": self.name,
            "descriptor_sha256": self.descriptor.sha256,
            "model_sha256": self.descriptor.model_sha256,
            "fingers": list(self.fingers) if self.fingers is not None else None,
            "samples": self.samples,
            "recall": self.sampled.recall,
            "seed": self.seed,
            "threshold": self.threshold,
        }


class SDHReachability(HandReachability):
    """:class:`HandReachability` of the built-in Schunk SDH (three fingers)."""

    def __init__(
        self,
        samples: int | None = None,
        seed: int = 0,
        threshold: float = DEFAULT_HAND_THRESHOLD,
        cache_dir: str | Path | None = None,
    ) -> None:
        super().__init__("sdh", None, samples, seed, threshold, cache_dir)
