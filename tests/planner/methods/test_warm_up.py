"""The warm-up compiles every kernel the methods call: planning after it compiles nothing."""

from __future__ import annotations

import numpy as np
import pytest

from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.grasp.kernel import default_directions, support_table
from ogcp.planner.grasp.quality import exact_q1_batch, q1_certificate
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods import warm_up as warm
from ogcp.planner.methods.registry import METHODS
from ogcp.planner.methods.runners import RunOptions
from ogcp.planner.search.open_list import OpenList


def test_planning_with_every_method_after_the_warm_up_compiles_nothing() -> None:
    warm.warm_up()
    before = warm.compiled_signatures()
    assert all(before[name] > 0 for family in warm.ENTRY_KERNELS.values() for name in family)
    contacts = sample_contacts(builtin_mesh("box"), n=30, seed=3)
    for name, spec in METHODS.items():
        for m in (2, 3) if name != "hfts" else (2,):
            spec.run(spec.config(), contacts, m, RunOptions())
    # The public Q1 entry points with read-only (a contact set's) and writeable inputs alike.
    union = contacts.wrenches[[0, 7, 15]].reshape(-1, 6)
    q1_certificate(union)
    q1_certificate(np.array(union))
    table = support_table(contacts.wrenches, default_directions())
    exact_q1_batch(contacts.wrenches, np.array([[0, 7, 15], [1, 2, 3]]), table)
    exact_q1_batch(np.array(contacts.wrenches), np.array([[0, 7, 15]]), table, cut=0.1)
    # What only a long search calls: a purge after a better grasp, forgetting at the memory limit.
    entries = OpenList()
    for ident in range(6):
        entries.push(0.5 * ident, -2, 0.5 * ident, 1, 0.1, ident)
    entries.purge(1.2)
    entries.forget(0.7, keep=0)
    grown = {name: count - before[name] for name, count in warm.compiled_signatures().items() if count != before[name]}
    assert grown == {}, f"compiled after the warm-up: {grown}"


def test_the_families_follow_the_methods() -> None:
    assert warm.families_for(["es"]) == ("q1",)
    assert warm.families_for(["hfts", "wastar"]) == ("q1", "search")
    with pytest.raises(OgcpError, match="valid: q1, search"):
        warm.kernel_dispatchers("nope")


def test_a_cold_cache_is_announced_once_and_a_warm_one_not(monkeypatch: pytest.MonkeyPatch) -> None:
    lines: list[str] = []
    monkeypatch.setattr(warm, "cold_kernels", lambda families: ["ogcp.planner.search.open_list._pop_top"])
    warm.warm_up(["astar"], announce=lines.append, parallel=False)
    assert len(lines) == 1 and lines[0].startswith("compiling the planning kernels, first use only: about ")
    monkeypatch.setattr(warm, "cold_kernels", lambda families: [])
    warm.warm_up(["astar"], announce=lines.append)
    assert len(lines) == 1
