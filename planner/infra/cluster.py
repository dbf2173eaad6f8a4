"""Tasks on a Dask cluster: checked before they go out, each result handed back as it is done.

:func:`run_on_cluster` submits one Dask task per task through a ``distributed.Client`` (not
joblib's Dask backend: joblib runs everything in the calling process when the cluster has one
thread in all, and sends tasks in batches, so a lost scheduler would take finished results with
it). Before any task goes out, every worker must import the tasks' module, or the run stops
naming the worker. Arguments shared by several tasks (a contact set) are scattered once.

Faults: a worker that dies mid-task has the task run again elsewhere (the scheduler's own
rescheduling, up to ``distributed.scheduler.allowed-failures`` deaths); the caller records each
result once, as it arrives. A scheduler that goes away ends the run with one line; the caller
keeps what it recorded, and a rerun (a suite with ``--resume``, exhaustive search with its
``--checkpoint``) does the rest.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import pickle
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ogcp.planner.infra.errors import OgcpError

#: Seconds the client waits for the scheduler, when connecting and after losing it.
CONNECT_TIMEOUT = "10s"
#: Arguments larger than this [bytes] that several tasks share are scattered once.
SCATTER_BYTES = 1_000


def run_on_cluster(address: str, function: Callable[..., Any], tasks: Sequence[tuple[Any, ...]]) -> Iterator[Any]:
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
        futures: list[Any] = []
        try:
            _check_workers(client, address, function.__module__)
            arguments = _scattered(client, tasks)
            futures = [client.submit(function, *task, pure=False) for task in arguments]
            for future in as_completed(futures):
                yield future.result()
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
                client.cancel(futures)
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


def _scattered(client: Any, tasks: Sequence[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    """The tasks with each large argument that several share replaced by one scattered future."""
    uses = collections.Counter(id(arg) for task in tasks for arg in task)
    futures: dict[int, Any] = {}
    for task in tasks:
        for arg in task:
            # Collections are scattered element by element; they stay as they are.
            shared = uses[id(arg)] > 1 and not isinstance(arg, (list, tuple, dict, set))
            if shared and id(arg) not in futures and len(pickle.dumps(arg)) > SCATTER_BYTES:
                futures[id(arg)] = client.scatter(arg, hash=False)
    return [tuple(futures.get(id(arg), arg) for arg in task) for task in tasks]


def _scheduler_alive(client: Any) -> bool:
    """Whether the client still reaches its scheduler."""
    try:
        client.scheduler_info()
        return bool(client.status == "running")
    except Exception:  # noqa: BLE001 - any failure to reach it means it is gone
        return False
