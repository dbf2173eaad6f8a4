"""Every compiled kernel a planning method calls, compiled (or loaded from numba's cache) before any timed work.

numba compiles a kernel at its first call, once per signature (argument types). The first plan
of a fresh install compiles about 140 signatures (about 40 s on two cores), most of it in two
independent families:

* ``q1``: the exact Q1 kernel (:mod:`ogcp.planner.grasp.kernel`): single sets, batches exact
  and with a cut, and the canonical refit; every method and the simulation's prediction call it.
* ``search``: the best-first searches' kernels (:mod:`ogcp.planner.search`): the open list,
  the children, the branch and bound and the ray bounds; A*, WA* and Dijkstra call them.

:func:`warm_up` runs each family the chosen methods need on a small fixed problem, through the
same calls the planners make, so later calls find their signatures compiled. On a cold cache
with more than one core, the search family compiles in a child process (which writes numba's
cache) while this one compiles the Q1 family; this process then loads the search kernels from
the cache. A child that fails or is killed costs only time: this process compiles whatever it
did not write.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ogcp.planner.infra.errors import OgcpError

__all__ = ["ENTRY_KERNELS", "FAMILIES", "cold_kernels", "compiled_signatures", "kernel_dispatchers", "warm_up"]

#: Kernel family -> the modules whose compiled kernels it holds.
FAMILIES: dict[str, tuple[str, ...]] = {
    "q1": (
        "ogcp.planner.grasp.kernel.batch",
        "ogcp.planner.grasp.kernel.certify",
        "ogcp.planner.grasp.kernel.epa",
        "ogcp.planner.grasp.kernel.geometry",
        "ogcp.planner.grasp.kernel.refit",
    ),
    "search": (
        "ogcp.planner.grasp.kernel.ray_bound",
        "ogcp.planner.hands.box_index",
        "ogcp.planner.search.children_kernel",
        "ogcp.planner.search.expansion",
        "ogcp.planner.search.open_list",
        "ogcp.planner.search.refine_kernel",
    ),
}
#: Family -> the kernels Python calls directly (the others are compiled into them): each gets
#: an index in numba's cache, so a missing index means a cold cache.
ENTRY_KERNELS: dict[str, tuple[str, ...]] = {
    "q1": (
        "ogcp.planner.grasp.kernel.batch._batch_kernel",
        "ogcp.planner.grasp.kernel.epa._q1_kernel",
        "ogcp.planner.grasp.kernel.refit._canonical_plane",
    ),
    "search": (
        "ogcp.planner.hands.box_index._box_within",
        "ogcp.planner.hands.box_index.boxes_within",
        "ogcp.planner.hands.box_index.pair_bounds",
        "ogcp.planner.search.children_kernel.decode_children",
        "ogcp.planner.search.children_kernel.shared_tree_children",
        "ogcp.planner.search.children_kernel.stale_children",
        "ogcp.planner.search.expansion.settled_entries",
        "ogcp.planner.search.open_list._pop_top",
        "ogcp.planner.search.refine_kernel.branch_and_bound",
        "ogcp.planner.search.refine_kernel.state_bound",
    ),
}
#: Methods that need the search family (the others need the Q1 family only).
_SEARCH_METHODS = frozenset({"astar", "wastar", "dijkstra"})
#: Contacts of the warm-up problem: enough that the search reaches its branch and bound.
WARM_UP_CONTACTS = 40


def kernel_dispatchers(family: str) -> dict[str, Any]:
    """The compiled kernels (numba dispatchers) of a family: qualified name -> dispatcher.

    Raises:
        OgcpError: For an unknown family, listing the valid ones.
    """
    if family not in FAMILIES:
        raise OgcpError(f"unknown kernel family {family!r}; valid: {', '.join(FAMILIES)}")
    import importlib

    from numba.core.registry import CPUDispatcher

    found: dict[str, Any] = {}
    for name in FAMILIES[family]:
        module = importlib.import_module(name)
        for attribute, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name:
                found[f"{name}.{attribute}"] = value
    return found


def compiled_signatures() -> dict[str, int]:
    """How many signatures each kernel of every family has compiled or loaded in this process."""
    return {name: len(d.signatures) for family in FAMILIES for name, d in kernel_dispatchers(family).items()}


def families_for(methods: Iterable[str]) -> tuple[str, ...]:
    """The kernel families the named methods call (the Q1 family always)."""
    return ("q1", "search") if _SEARCH_METHODS.intersection(methods) else ("q1",)


def cold_kernels(families: Iterable[str]) -> list[str]:
    """Entry kernels of the families with no cache index on disk, local or shipped: the ones a first call will compile.

    A kernel whose index exists may still compile (another numba, an edited source); this is
    the cheap check that decides whether to say that compiling is coming, not a promise.
    """
    cold = []
    for family in families:
        dispatchers = kernel_dispatchers(family)
        for name in ENTRY_KERNELS[family]:
            dispatcher = dispatchers[name]
            cache = getattr(dispatcher, "_cache", None)
            index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
            ships = bool(getattr(cache, "ships", False))  # shipped with ogcp for these sources
            if not dispatcher.signatures and not ships and (index is None or not os.path.exists(index)):
                cold.append(name)
    return cold


def _run_q1() -> None:
    from ogcp.planner.grasp.kernel import warm_up as warm_q1

    warm_q1()


def _run_search() -> None:
    from ogcp.planner.grasp.contact_set import sample_contacts
    from ogcp.planner.objects.builtin import builtin_mesh
    from ogcp.planner.search.grasp_planner import GraspPlanner

    contacts = sample_contacts(builtin_mesh("box"), n=WARM_UP_CONTACTS, seed=0)
    GraspPlanner(method="astar").plan(contacts, 2)
    _run_open_list()
    _run_hand_boxes(contacts)


def _run_hand_boxes(contacts: Any) -> None:
    """A hand's reachability test of a search state (:meth:`HandReachability.admits`), on a made-up
    index: loading a real hand needs MuJoCo and minutes of sampling."""
    import numpy as np

    from ogcp.planner.hands.box_index import BoxIndex, boxes_within, pair_bounds

    index = BoxIndex(np.random.default_rng(0).normal(size=(100, 12)))
    index.any_within(np.zeros((1, 12)), np.ones((1, 12)), 0.5)
    members, offsets = np.arange(6, dtype=np.int64), np.array([0, 2, 4, 6], dtype=np.int64)
    bounds = pair_bounds(contacts.positions, contacts.normals, members, offsets)
    assignments = np.array([[0, 1, 2], [2, 1, 0]], dtype=np.int64)
    pairs = np.array([[0, 1], [0, 2], [1, 2]], dtype=np.int64)
    spans = np.array([[0.0, 1.0]] * 3)
    boxes_within(
        bounds, assignments, pairs, np.ones(12), 0.25, spans, 1e-3, index.low, index.high, index.points, index.starts
    )


def _run_open_list() -> None:
    """What a search too short to meet its memory limit or a better grasp's cutoff never calls:
    the open list's purge and forgetting (a long search calls them)."""
    from ogcp.planner.search.open_list import OpenList

    entries = OpenList()
    for ident in range(4):
        entries.push(float(ident), -1, float(ident), 0, 0.0, ident)
    entries.purge(2.5)
    entries.forget(1.5)


def _run_search_alone() -> None:
    """The search family without compiling the Q1 family (what a helper process runs).

    The warm-up search asks for Q1 values; here the compiled Q1 entry points answer "not
    settled", so the values come from the qhull paths (same values, slower, nothing compiled)
    while the process that started this one compiles the Q1 family.
    """
    import numpy as np

    from ogcp.planner.grasp import quality
    from ogcp.planner.grasp.kernel import FALLBACK

    def unsettled_q1(w: Any, certify: bool = True) -> tuple[bool, float, Any]:
        return False, float("nan"), np.full(6, np.nan)

    def unsettled_batch(w: Any, g: Any, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
        return np.full(len(g), np.nan), np.full(len(g), FALLBACK, dtype=np.int64)

    quality.kernel_q1 = unsettled_q1  # type: ignore[assignment]
    quality.evaluate_batch = unsettled_batch  # type: ignore[assignment]
    quality.last_active = lambda n: np.arange(n)
    _run_search()


_RUNS: dict[str, Callable[[], None]] = {"q1": _run_q1, "search": _run_search, "search-alone": _run_search_alone}


def warm_up(
    methods: Iterable[str] = ("astar", "es", "hfts"),
    *,
    announce: Callable[[str], None] | None = None,
    parallel: bool = True,
) -> float:
    """Compile, or load from numba's cache, every kernel the named methods call; idempotent.

    Args:
        methods: Planning methods (``astar``, ``wastar``, ``dijkstra``, ``es``, ``es-pruned``,
            ``hfts``); the default covers every family.
        announce: Called with one line when kernels are about to compile (a cold cache), so
            a command line can say why its first run waits (a timer then runs on stderr if it
            is a terminal); None: silent.
        parallel: Compile the search family in a child process while this one compiles the
            Q1 family (cold cache and more than one core only).

    Returns:
        Wall time of the warm-up [s].
    """
    start = time.perf_counter()
    families = families_for(methods)
    cold = cold_kernels(families)
    if cold and announce is not None:
        announce(f"compiling the planning kernels, first use only: about {_estimate(families)} s")
    helper = None
    if parallel and (os.cpu_count() or 1) > 1 and any(_family_of(k) == "search" for k in cold):
        helper = _start_child("search-alone")
    with _ticker(announce is not None and bool(cold) and sys.stderr.isatty()):
        for family in families:
            if family == "search" and helper is not None:
                _wait(helper)
            _RUNS[family]()
    return time.perf_counter() - start


def _family_of(kernel: str) -> str:
    module = kernel.rsplit(".", 1)[0]
    return next(family for family, modules in FAMILIES.items() if module in modules)


#: [s] Compile time of each family measured on two cores (numba 0.68, ``benchmarks/perf/first_run.py``):
#: the announcement's estimate.
_COMPILE_SECONDS = {"q1": 15, "search": 26}
#: [s] Longest wait for the helper process; past it, it is killed and this process compiles alone.
HELPER_TIMEOUT_S = 600.0


def _estimate(families: tuple[str, ...]) -> int:
    seconds = [_COMPILE_SECONDS[f] for f in families]
    return max(seconds) + 5 if (os.cpu_count() or 1) > 1 and len(seconds) > 1 else sum(seconds)


def _start_child(family: str) -> subprocess.Popen[bytes] | None:
    """A process compiling one family into numba's cache; it ends with its parent."""
    code = (
        "import sys\n"
        "from ogcp.planner.infra.lifetime import set_parent_death_signal, watch_parent\n"
        f"set_parent_death_signal(); watch_parent({os.getpid()})\n"
        "from ogcp.planner.methods.warm_up import _RUNS\n"
        f"_RUNS[{family!r}]()\n"
    )
    try:
        return subprocess.Popen(
            [sys.executable, "-c", code],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:
        return None


def _wait(child: subprocess.Popen[bytes]) -> None:
    """Wait for the child; killed if it outlasts :data:`HELPER_TIMEOUT_S` or this process is interrupted first."""
    try:
        child.wait(timeout=HELPER_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        pass  # compiled here instead, from whatever it wrote
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


@contextlib.contextmanager
def _ticker(show: bool) -> Iterator[None]:
    """A progress bar on stderr counting the seconds while kernels compile."""
    if not show:
        yield
        return
    from tqdm import tqdm

    done = threading.Event()
    bar = tqdm(desc="compiling", unit="s", bar_format="{desc}: {elapsed}", file=sys.stderr, leave=False)

    def tick() -> None:
        while not done.wait(0.5):
            bar.refresh()

    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
        bar.close()
