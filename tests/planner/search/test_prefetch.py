"""Threaded Q1 prefetch (OGCP_Q1_THREADS): the same search as a sequential run, bit for bit."""

from __future__ import annotations

import dataclasses

import pytest

from planner.grasp import subset_quality
from planner.search import GraspPlanner


def _summary(result):
    """Everything a run decides: grasp, values, and the counters that follow its order."""
    stats = dataclasses.asdict(result.stats)
    for timing in ("wall_seconds", "cpu_seconds", "peak_rss_bytes"):
        stats.pop(timing)
    return result.grasp, result.q1, result.bound, result.status, stats


@pytest.mark.parametrize(("name", "method", "eps", "m"), [("box", "astar", None, 3), ("donut", "wastar", 0.4, 3)])
def test_prefetch_gives_the_sequential_search(object_contacts, monkeypatch, name, method, eps, m):
    contacts = object_contacts(name, 150, 0)
    sequential = GraspPlanner(method=method, eps=eps).plan(contacts, m)
    monkeypatch.setattr(subset_quality, "PREFETCH_THREADS", 2)
    started = []
    original = subset_quality.GraspQuality._prefetch

    def counting(self, union, key):
        before = len(self._started)
        original(self, union, key)
        started.append(len(self._started) - before)

    monkeypatch.setattr(subset_quality.GraspQuality, "_prefetch", counting)
    threaded = GraspPlanner(method=method, eps=eps).plan(contacts, m)
    assert sum(started) > 0  # the threads did take part
    assert _summary(threaded) == _summary(sequential)


def test_prefetch_threads_from_the_environment(monkeypatch):
    monkeypatch.setenv("OGCP_Q1_THREADS", "1")
    assert subset_quality._prefetch_threads() == 1
    for text in ("", "two", "-2", "0"):
        monkeypatch.setenv("OGCP_Q1_THREADS", text)
        with pytest.warns(UserWarning, match="OGCP_Q1_THREADS"):
            assert subset_quality._prefetch_threads() == 1
    monkeypatch.setenv("OGCP_Q1_THREADS", "2")
    assert 1 <= subset_quality._prefetch_threads() <= 2


def test_a_forked_child_gets_its_own_threads(monkeypatch):
    monkeypatch.setattr(subset_quality, "PREFETCH_THREADS", 2)
    parent = subset_quality._pool()
    assert subset_quality._pool() is parent
    monkeypatch.setattr(subset_quality.os, "getpid", lambda: -1)  # as in a forked child
    child = subset_quality._pool()
    assert child is not parent and child.submit(abs, -3).result(timeout=10) == 3
