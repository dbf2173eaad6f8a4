"""Processes that ogcp starts end with their parent, and temporary folders outlive no killed run.

A parent killed by SIGTERM or SIGKILL runs none of its Python cleanup, and neither loky nor a
plain subprocess ends its children then: measured, the loky workers of a killed
``ogcp suite --jobs 2`` ran on for over 30 minutes (about 300 MB each), and a killed
``decompose`` left its CoACD child running and its ``ogcp-coacd-*`` folder behind. Two guards:

* :func:`watch_parent`: a daemon thread ends the process (``os._exit``) within
  :data:`WATCH_INTERVAL_S` of its parent's death (the process is then re-parented, so its
  parent pid changes). Portable; each check needs the GIL for a moment, which CoACD releases
  (measured) and the planner's numpy and numba calls hold only briefly.
* :func:`set_parent_death_signal`: Linux ``PR_SET_PDEATHSIG``; the kernel kills the process at
  once, even inside native code. The signal follows the *thread* that started the process, so
  it is safe only where that thread waits for the child (the CoACD runner). Loky starts workers
  from whichever thread submits work and from its manager thread: its workers get the watchdog
  alone (:func:`guard_worker`), since a PDEATHSIG there would kill idle workers of a live parent.

Both run from their source in a child that imports nothing of ogcp (see
:mod:`ogcp.sim_eval.decomposition.coacd_child`), so they import what they use themselves and read no
module globals. :func:`owned_tempdir` names a folder after its owner's pid and locks it while in
use, so that a later run removes the folders of killed runs.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TypeVar

__all__ = [
    "STALE_AGE_S",
    "WATCH_INTERVAL_S",
    "call_in_worker",
    "guard_worker",
    "owned_tempdir",
    "pid_alive",
    "remove_stale_tempdirs",
    "set_parent_death_signal",
    "watch_parent",
]

T = TypeVar("T")

#: [s] How often a watched process checks its parent (the default of :func:`watch_parent`).
WATCH_INTERVAL_S = 0.5
#: [s] A dead owner's folder younger than this is left alone: it closes the moment between a
#: folder's creation and its lock, for an owner whose pid this process cannot see (another pid
#: namespace sharing /tmp).
STALE_AGE_S = 60.0
_LOCK_NAME = ".owner.lock"

# The process whose watchdog runs: a forked copy inherits this value but not the thread.
_watched_in: int | None = None
_watch_lock = threading.Lock()


def watch_parent(parent_pid: int, interval_s: float = 0.5) -> None:
    """End this process soon after ``parent_pid`` stops being its parent.

    Starts a daemon thread that checks the parent pid every ``interval_s`` and calls
    ``os._exit(1)`` once it has changed (the parent died and the process was re-parented);
    exits at once if ``parent_pid`` is no longer the parent. Self-contained (a child runs it
    from its source): the default repeats :data:`WATCH_INTERVAL_S`.

    Args:
        parent_pid: The pid of the process whose death ends this one.
        interval_s: Seconds between checks.
    """
    import os
    import threading
    import time

    if os.getppid() != parent_pid:
        os._exit(1)  # the parent died before the watch began: nobody will read our result

    def watch() -> None:
        while True:
            time.sleep(interval_s)
            if os.getppid() != parent_pid:
                os._exit(1)  # no cleanup: the parent that wanted the work is gone

    threading.Thread(target=watch, name="ogcp-parent-watch", daemon=True).start()


def set_parent_death_signal() -> bool:
    """Linux: have the kernel SIGKILL this process when the thread that started it ends.

    Only for a child whose starting thread waits for it (see the module docstring). The parent
    may have died before this call: follow it with :func:`watch_parent`, which then exits.
    Self-contained (a child runs it from its source).

    Returns:
        Whether the signal is set (False off Linux or where ``prctl`` cannot be called).
    """
    import ctypes
    import signal
    import sys

    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1  # from <linux/prctl.h>
        zero = ctypes.c_ulong(0)
        return bool(libc.prctl(pr_set_pdeathsig, ctypes.c_ulong(int(signal.SIGKILL)), zero, zero, zero) == 0)
    except (OSError, AttributeError):
        return False


def guard_worker(parent_pid: int) -> None:
    """In a worker process of ``parent_pid``: start :func:`watch_parent`, once per process.

    Nothing happens in ``parent_pid`` itself (serial or threaded work) or in a process that is
    not its child while it lives (a pool that is not ours); a worker whose parent is already
    dead exits.

    Args:
        parent_pid: The pid of the process that hands out the work.
    """
    global _watched_in
    pid = os.getpid()
    if pid == parent_pid or _watched_in == pid:
        return
    with _watch_lock:
        if _watched_in == pid:
            return
        _watched_in = pid
        if os.getppid() == parent_pid or not pid_alive(parent_pid):
            watch_parent(parent_pid, WATCH_INTERVAL_S)


def call_in_worker(parent_pid: int, function: Callable[..., T], *args: object) -> T:
    """``function(*args)`` in a worker that ends with ``parent_pid`` (see :func:`guard_worker`).

    Args:
        parent_pid: The pid of the process that hands out the work.
        function: The task.
        *args: Its arguments.

    Returns:
        What ``function`` returns.
    """
    guard_worker(parent_pid)
    return function(*args)


def pid_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (a zombie or another user's process counts; POSIX only).

    Args:
        pid: Process id (> 0).

    Returns:
        False only when no such process exists.
    """
    if pid <= 0:
        return True  # not a process id: never treat it as a dead owner
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _try_lock(handle: IO[bytes], blocking: bool) -> bool:
    import fcntl  # POSIX; callers skip the locks elsewhere

    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
    except BlockingIOError:
        return False
    return True


def _remove_if_stale(folder: Path, owner: int, min_age_s: float) -> bool:
    try:
        info = folder.lstat()
    except OSError:
        return False
    # Only our own real folders (not a link planted in a shared /tmp), old enough, whose owner is gone.
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.getuid():
        return False
    if time.time() - info.st_mtime < min_age_s or pid_alive(owner):
        return False
    try:
        with open(folder / _LOCK_NAME, "rb") as handle:
            if not _try_lock(handle, blocking=False):
                return False  # held: a live owner this process cannot see (another pid namespace)
            shutil.rmtree(folder, ignore_errors=True)
    except FileNotFoundError:
        shutil.rmtree(folder, ignore_errors=True)  # killed before it took its lock
    except OSError:
        return False
    return not folder.exists()


def remove_stale_tempdirs(prefix: str, root: Path | None = None, min_age_s: float = STALE_AGE_S) -> list[Path]:
    """Remove the folders ``<prefix><pid>-*`` of :func:`owned_tempdir` whose owner is dead.

    A folder is kept while its owner pid lives, while its lock is held, while it is younger than
    ``min_age_s`` and when it is not ours; POSIX only (elsewhere nothing is removed).

    Args:
        prefix: The prefix given to :func:`owned_tempdir`.
        root: Folder to scan; default the system temporary folder.
        min_age_s: Seconds since the folder last changed before it may be removed.

    Returns:
        The folders removed.
    """
    if os.name != "posix":
        return []  # os.kill(pid, 0) would terminate the process on Windows
    root = Path(root) if root is not None else Path(tempfile.gettempdir())
    pattern = re.compile(re.escape(prefix) + r"(\d+)-")
    removed = []
    try:
        candidates = [path for path in root.iterdir() if path.name.startswith(prefix)]
    except OSError:
        return []
    for folder in candidates:
        match = pattern.match(folder.name)
        if match and _remove_if_stale(folder, int(match.group(1)), min_age_s):
            removed.append(folder)
    return removed


@contextlib.contextmanager
def owned_tempdir(prefix: str) -> Iterator[Path]:
    """A temporary folder named ``<prefix><pid>-<random>``, locked while in use, removed on exit.

    First removes the folders that killed runs left (:func:`remove_stale_tempdirs`): a process
    killed by a signal cannot remove its own.

    Args:
        prefix: Folder name prefix, e.g. ``"ogcp-coacd-"``.

    Yields:
        The folder.
    """
    remove_stale_tempdirs(prefix)
    with tempfile.TemporaryDirectory(prefix=f"{prefix}{os.getpid()}-") as tmp:
        folder = Path(tmp)
        if sys.platform == "win32":
            yield folder
            return
        # The lock (released by the kernel when this process dies) tells a scanner in another pid
        # namespace that the owner lives; the file is not inherited by children (PEP 446).
        with open(folder / _LOCK_NAME, "wb") as handle:
            _try_lock(handle, blocking=True)
            yield folder
