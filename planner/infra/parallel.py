"""The one place where ogcp runs work in parallel: joblib's local processes, or a Dask cluster.

Tasks are independent and their results are merged by the caller in a deterministic
order, so the serial path (``jobs=1``), local processes (``loky``) and a Dask cluster give
identical answers.

Local workers end with the process that started them (:mod:`ogcp.planner.infra.lifetime`): a suite
killed by SIGTERM or SIGKILL leaves no worker computing for nobody. Dask workers belong to their
cluster and are left alone; :mod:`ogcp.planner.infra.cluster` runs the tasks there and says
what happens when a worker or the scheduler dies.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ogcp.planner.infra.cluster import run_on_cluster
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.infra.lifetime import call_in_worker, guard_worker

BACKENDS = ("dask", "loky")
DEFAULT_BACKEND = "loky"
DEFAULT_JOBS = 1
#: The first joblib that passes a worker initializer through ``Parallel`` to loky.
_INITIALIZER_SINCE = (1, 5)


#: Local worker processes per CPU core at most: every worker loads numpy and the Q1 kernels
#: (~150 MB) and more workers than cores only take turns; 10^5 of them stall the machine
#: while they start.
JOBS_PER_CORE = 4


def max_jobs() -> int:
    """The most local worker processes: :data:`JOBS_PER_CORE` per CPU core of this machine."""
    return JOBS_PER_CORE * (os.cpu_count() or 1)


def validate_backend(backend: str, address: str | None, jobs: int) -> None:
    """Check the parallel settings, raising :class:`OgcpError` with the valid choices."""
    if backend not in BACKENDS:
        raise choice_error("backend", backend, BACKENDS)
    if not isinstance(jobs, int) or jobs < 1:
        raise OgcpError(f"jobs must be an integer >= 1, got {jobs!r}")
    if backend == "loky" and jobs > max_jobs():
        raise OgcpError(f"jobs must be at most {max_jobs()} ({JOBS_PER_CORE} per CPU core), got {jobs}")
    if backend == "dask" and not address:
        raise OgcpError("backend 'dask' needs --address HOST:PORT of a running Dask scheduler")
    if backend == "loky" and address:
        raise OgcpError("--address applies to backend 'dask' only")


def run_tasks(
    function: Callable[..., Any],
    tasks: Iterable[tuple[Any, ...]],
    jobs: int = DEFAULT_JOBS,
    backend: str = DEFAULT_BACKEND,
    address: str | None = None,
) -> Iterator[Any]:
    """Run ``function(*task)`` for every task, yielding results as they finish.

    Args:
        function: A picklable function.
        tasks: Argument tuples, taken as workers are free for them: a generator may stop
            yielding (a deadline) and is never listed in full.
        jobs: Worker processes (ignored by Dask, whose cluster decides).
        backend: ``loky`` (local processes) or ``dask``.
        address: Dask scheduler ``HOST:PORT``.

    Yields:
        Results in completion order (callers merge them deterministically).
    """
    validate_backend(backend, address, jobs)
    if backend == "loky" and jobs == 1:
        for task in tasks:
            yield function(*task)
        return
    if backend == "dask":
        yield from run_on_cluster(str(address), function, tasks)
        return
    # Lazy: the backends and defaults above are read where joblib would be wasted (``ogcp --help``).
    import joblib

    parent = os.getpid()
    # Every task starts the parent watchdog in its worker; the initializer (where joblib has
    # it) also covers a worker that gets no task before the parent dies, which would otherwise
    # idle for loky's 300 s before it exits. No backend is named, so that a nested call keeps
    # joblib's choice (threads inside a worker); those backends ignore the initializer.
    options = {"initializer": guard_worker, "initargs": (parent,)} if _has_initializer(joblib.__version__) else {}
    parallel = joblib.Parallel(n_jobs=jobs, return_as="generator_unordered", **options)
    yield from parallel(joblib.delayed(call_in_worker)(parent, function, *task) for task in tasks)


def _has_initializer(version: str) -> bool:
    """Whether this joblib version passes ``Parallel(initializer=...)`` on to loky."""
    try:
        major, minor = (int(part) for part in version.split(".")[:2])
    except ValueError:
        return False
    return (major, minor) >= _INITIALIZER_SINCE
