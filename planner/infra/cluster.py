"""Tasks on a Dask cluster: checked before they go out, each result handed back as it is done.

:func:`run_on_cluster` submits one Dask task per task through a ``distributed.Client`` (not
joblib's Dask backend: joblib runs everything in the calling process when the cluster has one
thread in all, and sends tasks in batches, so a lost scheduler would take finished results with
it). Before any task goes out, every worker must import the tasks' module, or the run stops
naming the worker. Large arguments (a contact set) are scattered once, and tasks go out a
window at a time, so a generator of tasks is never listed in full.

Faults: a worker that dies mid-task has the task run again elsewhere (the scheduler's own
rescheduling, up to ``distributed.scheduler.allowed-failures`` deaths); the caller records each
result once, as it arrives. A scheduler that goes away ends the run with one line; the caller
keeps what it recorded, and a rerun (a suite with ``--resume``, exhaustive search with its
``--checkpoint``) does the rest.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import pickle
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ogcp.planner.infra.errors import OgcpError

#: Seconds the client waits for the scheduler, when connecting and after losing it.
CONNECT_TIMEOUT = "10s"
#: Arguments larger than this [bytes] (pickled) are scattered once and shared by the tasks.
SCATTER_BYTES = 1_000
#: Tasks in flight per worker thread (and at least :data:`MIN_WINDOW` in all): enough to keep
#: every thread busy while results travel back.
TASKS_PER_THREAD = 2
MIN_WINDOW = 4


def run_on_cluster(address: str, function: Callable[..., Any], tasks: Iterable[tuple[Any, ...]]) -> Iterator[Any]:
    """``function(*task)`` for every task on the cluster at ``address``, yielded as each finishes.

    Raises:
        OgcpError: Without the dask extra, for a scheduler that cannot be reached, has no
            workers or goes away, and for a worker that cannot import ``function``'s module.
    """
    try:
        from dask.distributed import Client, as_completed  # lazy: Dask is an optional extra
    except ImportError as exc:
        raise OgcpError("backend 'dask' needs the dask extra: pip install 'ogcp[dask]'") from exc
    # A lost scheduler makes the client log its reconnection attempts with tracebacks; the one
    # line raised below says it instead.
    quiet = logging.getLogger("distributed.client")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)
    try:
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT)
        except OSError as exc:
            raise OgcpError(f"cannot reach the Dask scheduler at {address}: {exc}") from exc
        live: set[Any] = set()
        try:
            _check_workers(client, address, function.__module__)
            scatter = _Scatter(client)
            pending = iter(tasks)
            # A window of tasks in flight rather than all at once: the tasks may be a generator
            # too long to list (exhaustive search's chunks) or one that stops at a deadline.
            window = max(MIN_WINDOW, TASKS_PER_THREAD * sum(client.nthreads().values()))
            finished = as_completed()

            def submit(task: tuple[Any, ...]) -> None:
                future = client.submit(function, *scatter(task), pure=False)
                live.add(future)
                finished.add(future)

            for task in itertools.islice(pending, window):
                submit(task)
            for future in finished:
                result = future.result()
                live.discard(future)
                following = next(pending, None)
                if following is not None:
                    submit(following)
                yield result
        except OgcpError:
            raise
        except Exception as exc:  # whatever a lost cluster raises, said in one line
            if _scheduler_alive(client):
                if type(exc).__name__ == "KilledWorker":
                    raise OgcpError(f"Dask workers kept dying on one task ({exc}); the finished work is kept") from exc
                raise
            raise OgcpError(
                f"the Dask scheduler at {address} went away ({type(exc).__name__}); the finished work is kept: "
                "start a scheduler and run again to finish the rest (a suite with --resume, exhaustive "
                "search with the same --checkpoint)"
            ) from exc
        finally:
            with contextlib.suppress(Exception):  # a client of a dead scheduler may fail to cancel or close
                client.cancel(list(live))
            with contextlib.suppress(Exception):
                client.close(timeout=5)
    finally:
        quiet.setLevel(level)


def _check_workers(client: Any, address: str, module: str) -> None:
    """Refuse a cluster where some worker cannot import ``module`` (the tasks' code), naming it."""
    # exec is a builtin, so the check itself needs nothing of ogcp on the workers.
    answers = client.run(exec, f"import {module}", on_error="return")
    if not answers:
        raise OgcpError(f"the Dask scheduler at {address} has no workers; start some with `dask worker {address}`")
    for worker, answer in sorted(answers.items()):
        if isinstance(answer, BaseException):
            raise OgcpError(
                f"Dask worker {worker} cannot import {module} ({type(answer).__name__}: {answer}); install ogcp "
                "in every worker's environment"
            )


class _Scatter:
    """Replaces each large argument of a task with a future scattered once (a contact set shared
    by every task travels once, not with each task)."""

    def __init__(self, client: Any) -> None:
        self.client = client
        # id -> (the argument, its future); the argument is held so that its id is never reused.
        self.known: dict[int, tuple[Any, Any]] = {}

    def __call__(self, task: tuple[Any, ...]) -> tuple[Any, ...]:
        return tuple(self._one(arg) for arg in task)

    def _one(self, arg: Any) -> Any:
        # Collections are scattered element by element; they stay as they are.
        if arg is None or isinstance(arg, (bool, int, float, str, list, tuple, dict, set)):
            return arg
        known = self.known.get(id(arg))
        if known is not None:
            return known[1]
        if len(pickle.dumps(arg)) <= SCATTER_BYTES:
            return arg
        future = self.client.scatter(arg, hash=False)
        self.known[id(arg)] = (arg, future)
        return future


def _scheduler_alive(client: Any) -> bool:
    """Whether the client still reaches its scheduler."""
    try:
        client.scheduler_info()
        return bool(client.status == "running")
    except Exception:  # noqa: BLE001 - any failure to reach it means it is gone
        return False
