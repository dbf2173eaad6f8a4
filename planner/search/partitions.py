"""Successor functions Γ_b: partitions of a super-contact into b disjoint parts.

* :class:`RandomPartitioner` (Γ^ru): a random, near-equal split.
* :class:`KMeansPartitioner` (Γ^fc): t iterations of k-means (k = b) in the feature
  space ``[w * p / rho, n]`` (position scaled by the torque scale, so the weight ``w`` is
  dimensionless and object-size independent).

Both are deterministic functions of the super-contact's content and the seed, so a
super-contact is always split the same way wherever it appears in the search, and every
super-contact of the search is a node of one hierarchy (:class:`PartitionTree`). Both
are reducing and preserving (paper Thm. IV.1): every part is non-empty, parts are
disjoint and cover the super-contact, and a super-contact of size >= 2 yields >= 2 parts.
"""

from __future__ import annotations

import hashlib
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.config.methods import SUCCESSORS, SearchConfig
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.infra.errors import OgcpError, choice_error

Indices = NDArray[np.intp]


def content_seed(seed: int, indices: Indices) -> list[int]:
    """Seed sequence entropy for a super-contact: the global seed plus a content digest."""
    digest = hashlib.blake2b(np.ascontiguousarray(indices, dtype=np.int64).tobytes(), digest_size=8).digest()
    return [int(seed), int.from_bytes(digest, "little")]


class Partitioner(Protocol):
    """A deterministic split of a super-contact into disjoint parts."""

    name: str
    branching: int

    def split(self, indices: Indices) -> list[Indices]:
        """Split sorted contact indices into ``min(b, len)`` sorted, disjoint, covering parts."""
        ...


def _canonical(parts: list[Indices]) -> list[Indices]:
    parts = [np.sort(p) for p in parts if len(p) > 0]
    parts.sort(key=lambda p: int(p[0]))
    return parts


class RandomPartitioner:
    """Γ_b^ru: random near-equal split (sizes differ by at most one)."""

    name = "ru"

    def __init__(self, branching: int = SearchConfig.branching, seed: int = SearchConfig.seed) -> None:
        self.branching = branching
        self.seed = seed

    def split(self, indices: Indices) -> list[Indices]:
        """Split ``indices`` into near-equal random parts."""
        if len(indices) <= 1:
            return [indices]
        rng = np.random.default_rng(content_seed(self.seed, indices))
        shuffled = rng.permutation(indices)
        return _canonical(np.array_split(shuffled, min(self.branching, len(indices))))


class KMeansPartitioner:
    """Γ_b^fc: t iterations of k-means on ``[w * p / rho, n]`` features.

    Initialisation is k-means++ seeded by the content; empty clusters are re-seeded with
    the point farthest from its centre; identical features fall back to an index split.
    Lloyd's loop ends early once an assignment repeats the one the centres are the means
    of: the remaining iterations would change nothing, so the split is that of all t.
    """

    name = "fc"

    def __init__(
        self,
        contacts: ContactSet,
        branching: int = SearchConfig.branching,
        iterations: int = SearchConfig.kmeans_iterations,
        position_weight: float = SearchConfig.position_weight,
        seed: int = SearchConfig.seed,
    ) -> None:
        self.branching = branching
        self.iterations = iterations
        self.position_weight = position_weight
        self.seed = seed
        scaled = position_weight * (contacts.positions - contacts.com) / contacts.torque_scale
        self._features = np.hstack([scaled, contacts.normals])

    def split(self, indices: Indices) -> list[Indices]:
        """Cluster ``indices`` into at most ``b`` non-empty parts."""
        n = len(indices)
        if n <= 1:
            return [indices]
        k = min(self.branching, n)
        x = self._features[indices]
        rng = np.random.default_rng(content_seed(self.seed, indices))
        centres = self._kmeans_pp(x, k, rng)
        labels = np.zeros(n, dtype=np.intp)
        settled: NDArray[np.intp] | None = None  # labels whose means the centres are
        for _ in range(max(1, self.iterations)):
            dist = ((x[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
            labels = np.argmin(dist, axis=1)
            if settled is not None and np.array_equal(labels, settled):
                break  # converged: every later iteration would repeat this one exactly
            reseeded = False
            for j in range(k):
                members = labels == j
                if members.any():
                    centres[j] = x[members].mean(axis=0)
                else:
                    far = int(np.argmax(dist[np.arange(n), labels]))
                    centres[j] = x[far]
                    labels[far] = j
                    reseeded = True
            settled = None if reseeded else labels
        parts = [indices[labels == j] for j in range(k)]
        parts = [p for p in parts if len(p) > 0]
        # Duplicate features can leave clusters empty; contacts with identical features
        # are interchangeable, so the largest part is halved until there are k parts.
        while len(parts) < k:
            largest = max(range(len(parts)), key=lambda i: (len(parts[i]), -i))
            parts[largest : largest + 1] = np.array_split(parts[largest], 2)
        return _canonical(parts)

    @staticmethod
    def _kmeans_pp(x: NDArray[np.float64], k: int, rng: np.random.Generator) -> NDArray[np.float64]:
        centres = [x[int(rng.integers(len(x)))]]
        for _ in range(1, k):
            d2 = np.min(((x[:, None, :] - np.array(centres)[None]) ** 2).sum(axis=2), axis=1)
            total = d2.sum()
            pick = int(rng.choice(len(x), p=d2 / total)) if total > 0 else int(rng.integers(len(x)))
            centres.append(x[pick])
        return np.array(centres, dtype=float)


def make_partitioner(
    kind: str,
    contacts: ContactSet,
    branching: int,
    seed: int,
    iterations: int = SearchConfig.kmeans_iterations,
    position_weight: float = SearchConfig.position_weight,
) -> Partitioner:
    """Build a partitioner by name.

    Args:
        kind: ``"fc"`` (k-means) or ``"ru"`` (random uniform).
        contacts: The contact set (features for k-means).
        branching: b >= 2.
        seed: Seed for the content-derived random streams.
        iterations: k-means iterations t (``fc`` only).
        position_weight: Weight of positions against normals (``fc`` only).

    Raises:
        OgcpError: For an unknown kind or invalid parameters.
    """
    if kind not in SUCCESSORS:
        raise choice_error("successor function", kind, SUCCESSORS)
    if int(branching) != branching or branching < 2:
        raise OgcpError(f"branching factor b must be an integer >= 2, got {branching!r}")
    if kind == "ru":
        return RandomPartitioner(int(branching), seed)
    if int(iterations) != iterations or iterations < 1:
        raise OgcpError(f"k-means iterations must be an integer >= 1, got {iterations!r}")
    if not (np.isfinite(position_weight) and position_weight >= 0):
        raise OgcpError(f"position weight must be a non-negative number, got {position_weight!r}")
    return KMeansPartitioner(contacts, int(branching), int(iterations), float(position_weight), seed)


class PartitionTree:
    """The hierarchy of super-contacts that one partitioner induces on C, built lazily.

    Node 0 is C. A node of one contact is a leaf whose only "child" is itself, so a state
    whose other super-contacts still split keeps it unchanged.
    """

    def __init__(self, n_contacts: int, partitioner: Partitioner) -> None:
        self.partitioner = partitioner
        self.n_contacts = n_contacts
        self.members: list[Indices] = [np.arange(n_contacts, dtype=np.intp)]
        self.masks: list[NDArray[np.uint8]] = [self._mask(self.members[0])]
        self.depth: list[int] = [0]
        #: Nodes of one contact (the search's hot test for terminal states).
        self.leaves: set[int] = {0} if n_contacts == 1 else set()
        self._children: dict[int, tuple[int, ...]] = {}

    def _mask(self, indices: Indices) -> NDArray[np.uint8]:
        flags = np.zeros(self.n_contacts, dtype=bool)
        flags[indices] = True
        return np.packbits(flags)

    def size(self, node: int) -> int:
        """Number of contacts in a node."""
        return len(self.members[node])

    def children(self, node: int) -> tuple[int, ...]:
        """Child nodes (the node itself for a single contact)."""
        cached = self._children.get(node)
        if cached is not None:
            return cached
        if self.size(node) == 1:
            result: tuple[int, ...] = (node,)
        else:
            ids = []
            for part in self.partitioner.split(self.members[node]):
                if len(part) == 1:
                    self.leaves.add(len(self.members))
                ids.append(len(self.members))
                self.members.append(part)
                self.masks.append(self._mask(part))
                self.depth.append(self.depth[node] + 1)
            result = tuple(ids)
        self._children[node] = result
        return result
