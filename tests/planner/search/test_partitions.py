"""Successor functions (random and k-means partitions) and the partition tree."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, sample_contacts
from ogcp.planner.infra import OgcpError
from ogcp.planner.search import KMeansPartitioner, PartitionTree, RandomPartitioner, make_partitioner
from ogcp.planner.search.partitions import content_seed

N = 60


@pytest.fixture(scope="module")
def contacts() -> ContactSet:
    return sample_contacts(builtin_mesh("amphora"), N, seed=1)


def _index_sets(rng: np.random.Generator) -> list[np.ndarray]:
    sets = [
        np.arange(N, dtype=np.intp),
        np.array([4], dtype=np.intp),
        np.array([2, 9], dtype=np.intp),
        np.array([0, 1, 2], dtype=np.intp),
    ]
    for size in (4, 5, 11, 30, 59):
        sets.append(np.sort(rng.choice(N, size, replace=False)).astype(np.intp))
    return sets


def _check_partition(parts, indices, b):
    assert len(parts) == min(b, len(indices))
    assert all(len(p) > 0 for p in parts)
    for p in parts:
        assert np.array_equal(p, np.sort(p))
    joined = np.concatenate(parts)
    assert len(joined) == len(set(joined.tolist()))  # pairwise disjoint
    assert np.array_equal(np.sort(joined), np.sort(indices))
    if len(indices) >= 2:
        assert len(parts) >= 2


@pytest.mark.parametrize("kind", ["ru", "fc"])
@pytest.mark.parametrize("b", [2, 3, 4])
def test_split_is_a_reducing_partition(contacts, kind, b):
    partitioner = make_partitioner(kind, contacts, b, seed=3)
    assert isinstance(partitioner, RandomPartitioner if kind == "ru" else KMeansPartitioner)
    assert partitioner.branching == b
    fresh = make_partitioner(kind, contacts, b, seed=3)
    for indices in _index_sets(np.random.default_rng(b)):
        parts = partitioner.split(indices)
        _check_partition(parts, indices, b)
        again = partitioner.split(indices)
        other = fresh.split(indices)
        assert len(again) == len(other) == len(parts)
        for p, q, r in zip(parts, again, other):
            assert np.array_equal(p, q) and np.array_equal(p, r)


def test_random_split_depends_on_seed(contacts):
    indices = np.arange(N, dtype=np.intp)
    first = make_partitioner("ru", contacts, 2, seed=0).split(indices)
    second = make_partitioner("ru", contacts, 2, seed=1).split(indices)
    assert not all(np.array_equal(p, q) for p, q in zip(first, second))


@pytest.mark.parametrize("b", [2, 3, 4])
def test_random_split_sizes_near_equal(contacts, b):
    partitioner = make_partitioner("ru", contacts, b, seed=0)
    for indices in _index_sets(np.random.default_rng(10 + b)):
        sizes = [len(p) for p in partitioner.split(indices)]
        assert max(sizes) - min(sizes) <= 1


def _two_clusters() -> ContactSet:
    rng = np.random.default_rng(0)
    near0 = rng.normal(0.0, 0.01, (10, 3))
    near1 = np.array([1.0, 0.0, 0.0]) + rng.normal(0.0, 0.01, (10, 3))
    normals = np.vstack([np.tile([0.0, 0.0, 1.0], (10, 1)), np.tile([0.0, 0.0, -1.0], (10, 1))])
    return ContactSet(np.vstack([near0, near1]), normals, np.zeros(3), 1.0)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_kmeans_separates_two_clusters(seed):
    contacts = _two_clusters()
    parts = make_partitioner("fc", contacts, 2, seed=seed).split(np.arange(20, dtype=np.intp))
    assert [p.tolist() for p in parts] == [list(range(10)), list(range(10, 20))]


def _lloyd_every_iteration(partitioner: KMeansPartitioner, indices: np.ndarray) -> list[np.ndarray]:
    """The split as ``t`` full Lloyd iterations compute it (no stop at convergence)."""
    x = partitioner._features[indices]
    k = min(partitioner.branching, len(indices))
    rng = np.random.default_rng(content_seed(partitioner.seed, indices))
    centres = partitioner._kmeans_pp(x, k, rng)
    labels = np.zeros(len(indices), dtype=np.intp)
    for _ in range(partitioner.iterations):
        dist = ((x[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
        labels = np.argmin(dist, axis=1)
        for j in range(k):
            members = labels == j
            if members.any():
                centres[j] = x[members].mean(axis=0)
            else:
                far = int(np.argmax(dist[np.arange(len(indices)), labels]))
                centres[j] = x[far]
                labels[far] = j
    return sorted((np.sort(indices[labels == j]) for j in range(k) if (labels == j).any()), key=lambda p: int(p[0]))


@pytest.mark.parametrize("iterations", [1, 2, 10, 100])
@pytest.mark.parametrize("b", [2, 3, 5])
def test_kmeans_stopping_at_convergence_changes_no_split(contacts, iterations, b):
    partitioner = KMeansPartitioner(contacts, b, iterations, position_weight=2.0, seed=3)
    rng = np.random.default_rng(iterations * 10 + b)
    for indices in _index_sets(rng)[3:]:
        expected = _lloyd_every_iteration(partitioner, indices)
        if len(expected) < min(b, len(indices)):
            continue  # duplicate features: the split halves parts after Lloyd's loop, alike either way
        got = partitioner.split(indices)
        assert [p.tolist() for p in got] == [p.tolist() for p in expected]


@pytest.mark.parametrize("b", [2, 3, 4])
def test_kmeans_identical_features_still_splits(b):
    contacts = ContactSet(np.tile([0.1, 0.2, 0.3], (7, 1)), np.tile([0.0, 1.0, 0.0], (7, 1)), np.zeros(3), 1.0)
    indices = np.arange(7, dtype=np.intp)
    parts = make_partitioner("fc", contacts, b, seed=0).split(indices)
    assert len(parts) >= 2
    assert np.array_equal(np.sort(np.concatenate(parts)), indices)
    assert all(len(p) > 0 for p in parts)


def test_kmeans_partially_duplicated_features_gives_min_b_len_parts():
    positions = np.array([[0.0, 0, 0], [0, 0, 0], [0, 0, 0], [1, 0, 0]])
    contacts = ContactSet(positions, np.tile([0.0, 0, 1], (4, 1)), np.zeros(3), 1.0)
    parts = make_partitioner("fc", contacts, 4, seed=0).split(np.arange(4, dtype=np.intp))
    assert len(parts) == 4


@pytest.mark.parametrize("kind", ["ru", "fc"])
def test_partition_tree(contacts, kind):
    tree = PartitionTree(N, make_partitioner(kind, contacts, 3, seed=0))
    assert tree.size(0) == N and tree.depth[0] == 0
    root_children = tree.children(0)
    assert tree.children(0) == root_children  # cached
    _check_partition([tree.members[c] for c in root_children], tree.members[0], 3)
    leaves: list[int] = []
    frontier = [0]
    while frontier:
        node = frontier.pop()
        kids = tree.children(node)
        if tree.size(node) == 1:
            assert kids == (node,)
            leaves.append(node)
            continue
        _check_partition([tree.members[k] for k in kids], tree.members[node], 3)
        for k in kids:
            assert tree.depth[k] == tree.depth[node] + 1
            flags = np.unpackbits(tree.masks[k])[:N].astype(bool)
            assert np.array_equal(np.flatnonzero(flags), tree.members[k])
        frontier.extend(kids)
    members = np.sort(np.concatenate([tree.members[leaf] for leaf in leaves]))
    assert np.array_equal(members, np.arange(N))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"kind": "kmeans"}, "fc, ru"),
        ({"branching": 1}, "branching factor b must be an integer >= 2"),
        ({"branching": 2.5}, "branching factor b must be an integer >= 2"),
        ({"iterations": 0}, "k-means iterations must be an integer >= 1"),
        ({"position_weight": -1.0}, "position weight must be a non-negative number"),
        ({"position_weight": float("nan")}, "position weight must be a non-negative number"),
    ],
)
def test_make_partitioner_errors(contacts, kwargs, match):
    args = {"kind": "fc", "branching": 2, "seed": 0, "iterations": 10, "position_weight": 1.0}
    args.update(kwargs)
    with pytest.raises(OgcpError, match=match):
        make_partitioner(args.pop("kind"), contacts, **args)
