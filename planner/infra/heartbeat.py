"""A progress line every so often for work that reports nothing while it runs (off a terminal).

The best-first searches report from their own loop; exhaustive search and HFTS hand their
work to worker processes, so a thread of the calling process says how far they got.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from types import TracebackType
from typing import Self

#: [s] Least time between two progress lines of long work run off a terminal.
LINE_SECONDS = 30.0


class Heartbeat:
    """Calls ``say(describe())`` every ``every`` seconds while the ``with`` block runs.

    Args:
        say: Where a line goes (a log); None: nothing is started.
        describe: The line, built when it is due (it reads counters the work updates).
        every: Seconds between lines, the first after as long [s]; None: :data:`LINE_SECONDS`.
    """

    def __init__(
        self, say: Callable[[str], None] | None, describe: Callable[[], str], every: float | None = None
    ) -> None:
        self.say = say
        self.describe = describe
        self.every = LINE_SECONDS if every is None else every
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> Self:
        if self.say is not None:
            self._thread = threading.Thread(target=self._beat, name="ogcp-heartbeat", daemon=True)
            self._thread.start()
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self._done.set()
        if self._thread is not None:
            self._thread.join()

    def _beat(self) -> None:
        assert self.say is not None
        while not self._done.wait(self.every):
            try:
                line = self.describe()
            except Exception:  # noqa: BLE001 - a progress line is not worth a traceback; the work goes on
                return
            self.say(line)
