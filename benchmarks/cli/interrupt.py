"""Ctrl-C as a request: the first one asks a running search to stop and return its best grasp.

A search stopped this way is a result (status ``interrupted``, with its certified bound), so
``ogcp plan`` can still print and write it. A second Ctrl-C aborts as usual.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType


@contextlib.contextmanager
def stop_on_interrupt() -> Iterator[threading.Event]:
    """Within the block, the first SIGINT sets the yielded event instead of raising.

    Outside the main thread (where Python delivers signals) the event is yielded but never
    set by a signal, and the handler in place is left alone.
    """
    event = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield event
        return

    def request_stop(signum: int, frame: FrameType | None) -> None:
        if event.is_set():
            raise KeyboardInterrupt  # the second Ctrl-C: the user does not want to wait
        event.set()
        print("ogcp: stopping; the best grasp so far follows (Ctrl-C again to abort)", file=sys.stderr)

    previous = signal.signal(signal.SIGINT, request_stop)
    try:
        yield event
    finally:
        signal.signal(signal.SIGINT, previous)
