"""The kernels that ship with ogcp: current with their sources, loaded instead of compiled on a fresh
install, and skipped (never trusted, never deleted) when damaged or stale."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numba
import numpy as np
import pytest

from ogcp.planner.grasp.kernel import shipped
from ogcp.planner.grasp.kernel.jit import cached_njit
from ogcp.planner.infra.cache import CacheEntryWarning
from ogcp.planner.methods import warm_up as warm
from ogcp.planner.search import open_list

TAG = f".py{sys.version_info.major}{sys.version_info.minor}."
HERE = sorted(shipped.SHIPPED.glob(f"*{TAG}*"))
#: The numba that built them (each file's header names it); another numba ignores them.
BUILT_BY = HERE[0].read_bytes().split(b"\n", 1)[0].split(b" ")[1].decode() if HERE else None
needs_shipped = pytest.mark.skipif(
    not HERE or not shipped.enabled() or BUILT_BY != numba.__version__,
    reason=f"no shipped kernels for this Python ({TAG.strip('.')}) and numba {numba.__version__} (built by "
    f"{BUILT_BY}), or this CPU lacks {shipped.SHIPPED_CPU}",
)


def _stamp(index: Path) -> object:
    body = index.read_bytes().split(b"\n", 1)[1]
    import pickle

    return pickle.loads(body)[0]


@pytest.mark.skipif(not HERE, reason=f"no shipped kernels for this Python ({TAG.strip('.')})")
def test_the_shipped_kernels_are_current_and_cover_every_entry_kernel() -> None:
    stale = [p.name for p in HERE if p.suffix == ".nbi" and _stamp(p) != shipped.shipped_stamp()]
    assert not stale, (
        f"shipped kernels older than their sources: run python -m ogcp.benchmarks.perf.ship_kernels ({stale})"
    )
    for family in warm.FAMILIES:
        for name, dispatcher in warm.kernel_dispatchers(family).items():
            if name in warm.ENTRY_KERNELS[family]:
                assert shipped.shipped_index(dispatcher._cache._impl.filename_base).is_file(), name


_CHILD = """
import json, sys
from numba.core import event
from ogcp.planner import builtin_mesh, sample_contacts
from ogcp.planner.methods import warm_up as warm
from ogcp.planner.methods.registry import METHODS
from ogcp.planner.methods.runners import RunOptions
compiled = []
with event.install_recorder("numba:compile") as recorder:
    cold = warm.cold_kernels(("q1", "search"))
    warm.warm_up()
    contacts = sample_contacts(builtin_mesh("box"), n=24, seed=5)
    plans = {name: spec.run(spec.config(), contacts, 3, RunOptions()).record for name, spec in METHODS.items()}
compiled = sorted({ev.data["dispatcher"].py_func.__qualname__ for _, ev in recorder.buffer if "dispatcher" in ev.data})
print(json.dumps({"cold": cold, "compiled": compiled, "q1": {k: v["q1"] for k, v in plans.items()},
                  "grasps": {k: v["grasp"] for k, v in plans.items()}}))
"""


@needs_shipped
def test_a_fresh_install_plans_with_every_method_without_compiling(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "OGCP_CACHE": str(tmp_path / "ogcp")}
    env.pop("OGCP_SHIPPED_KERNELS", None)
    out = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, check=True).stdout
    child = json.loads(out)
    assert child["cold"] == [] and child["compiled"] == []  # before: about 30 s of compiling
    assert not list((tmp_path / "numba").rglob("*.nb[ic]"))
    # The shipped code gives this process's answers (compiled here or loaded from its own cache).
    from ogcp.planner import builtin_mesh, sample_contacts
    from ogcp.planner.methods.registry import METHODS
    from ogcp.planner.methods.runners import RunOptions

    contacts = sample_contacts(builtin_mesh("box"), n=24, seed=5)
    for name, spec in METHODS.items():
        record = spec.run(spec.config(), contacts, 3, RunOptions()).record
        assert record["grasp"] == child["grasps"][name] and record["q1"] == child["q1"][name], name


@pytest.fixture
def shipped_copy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The shipped folder copied where a test may damage it, and an empty local numba cache."""
    copy = tmp_path / "shipped"
    shutil.copytree(shipped.SHIPPED, copy)
    monkeypatch.setattr(shipped, "SHIPPED", copy)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    return copy


def _pop_top():  # a fresh dispatcher of a small shipped kernel, as a new process would make
    return cached_njit()(open_list._pop_top.py_func)


def _call(kernel) -> tuple:
    values = np.array([[2.0, 2.0, 0.0], [1.0, 1.0, 0.0]])
    order = np.array([[-1, 0, 4], [-1, 1, 8]], dtype=np.int64)
    return kernel(values, order, 2)


@needs_shipped
def test_a_shipped_kernel_loads_without_compiling(shipped_copy: Path) -> None:
    kernel = _pop_top()
    assert kernel._cache.ships
    result = _call(kernel)
    assert sum(kernel.stats.cache_hits.values()) == 1 and sum(kernel.stats.cache_misses.values()) == 0
    assert result == _call(open_list._pop_top)


@needs_shipped
def test_a_damaged_shipped_file_is_skipped_with_one_line_and_kept(shipped_copy: Path) -> None:
    (data,) = shipped_copy.glob(f"open_list._pop_top-*{TAG}ogcp.1.nbc")
    damaged = data.read_bytes()[:-1] + bytes([data.read_bytes()[-1] ^ 0x40])
    data.write_bytes(damaged)
    kernel = _pop_top()
    with pytest.warns(CacheEntryWarning, match=r"shipped kernel file .* is damaged .*skipped, the kernel is compiled"):
        result = _call(kernel)
    assert result == _call(open_list._pop_top) and sum(kernel.stats.cache_misses.values()) == 1
    assert data.read_bytes() == damaged  # part of the installation: reported, never removed


@needs_shipped
def test_shipped_kernels_of_other_sources_or_turned_off_are_not_used(
    shipped_copy: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(shipped, "shipped_stamp", lambda: ("ogcp-shipped/1", "another source"))
    stale = _pop_top()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # stale, not damaged: no warning, one compilation
        _call(stale)
    assert not stale._cache.ships and sum(stale.stats.cache_misses.values()) == 1
    monkeypatch.undo()
    monkeypatch.setenv("OGCP_SHIPPED_KERNELS", "0")
    assert cached_njit()(open_list._pop_top.py_func)._cache._shipped is None
