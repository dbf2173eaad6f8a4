"""Shared inputs for the speed benchmarks: fixed seeds, so runs are comparable."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.grasp.contact_set import ContactSet


@pytest.fixture(scope="session")
def box1000() -> ContactSet:
    return sample_contacts(builtin_mesh("box"), 1000, seed=0)


@pytest.fixture(scope="session")
def box200() -> ContactSet:
    return sample_contacts(builtin_mesh("box"), 200, seed=0)


@pytest.fixture(scope="session")
def small_grasps(box1000: ContactSet) -> list[np.ndarray]:
    """100 random 3-contact grasps from the 1000-contact box, as wrench arrays (24, 6)."""
    rng = np.random.default_rng(0)
    return [box1000.subset_wrenches(rng.choice(1000, 3, replace=False)) for _ in range(100)]


@pytest.fixture(scope="session")
def super_contact(box1000: ContactSet) -> np.ndarray:
    """A 100-contact super-contact (800 wrenches)."""
    return box1000.subset_wrenches(np.random.default_rng(1).choice(1000, 100, replace=False))


@pytest.fixture(scope="session")
def sphere1000() -> ContactSet:
    return sample_contacts(builtin_mesh("sphere"), 1000, seed=0)


@pytest.fixture(scope="session")
def mid_unions(sphere1000: ContactSet) -> list[tuple[np.ndarray, np.ndarray]]:
    """200 random 12-contact unions of the 1000-contact sphere (96 wrenches each), with a
    random unit start direction each: the size the search's exact values mostly have."""
    rng = np.random.default_rng(2)
    unions = []
    for _ in range(200):
        start = rng.normal(size=6)
        unions.append((sphere1000.subset_wrenches(rng.choice(1000, 12, replace=False)), start / np.linalg.norm(start)))
    return unions
