"""Progress lines of a suite run off a terminal (CI, nohup): one at the start, then at least every 30 s.

A terminal gets tqdm's bar; a log gets lines, so that whoever watches it knows at once that the
run started and, during long cells or the first compilation, that it is still alive.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator

from ogcp.benchmarks.suite.record import CellRecord

#: [s] The longest silence of a run's progress lines (modes ``periodic`` and ``each``).
HEARTBEAT_S = 30.0


def number(value: float | None) -> str:
    """A Q1 or bound for a progress line: six decimals, ``-`` for none."""
    return "-" if value is None else f"{value:.6f}"


def duration(seconds: float) -> str:
    """``1h02m03s``, ``2m05s`` or ``7s``: a duration for a progress line."""
    whole = round(seconds)
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours}h{minutes:02d}m{secs:02d}s"
    return f"{minutes}m{secs:02d}s" if minutes else f"{secs}s"


class Meter:
    """Progress lines of one run: see :class:`ogcp.benchmarks.suite.runner.SuiteRunner` ``lines``.

    Args:
        name: The suite's name.
        total: Cells of the suite.
        skipped: Cells done before this run.
        todo: Cells this run will run.
        mode: ``none``, ``periodic`` or ``each``.
        interval: Least seconds between two ``periodic`` lines of finished cells.
        say: Where a line goes.
    """

    def __init__(
        self, name: str, total: int, skipped: int, todo: int, mode: str, interval: float, say: Callable[[str], None]
    ) -> None:
        self.name, self.total, self.skipped, self.todo = name, total, skipped, todo
        self.mode, self.interval, self.say = mode, interval, say
        self.ran = 0
        self.errors = 0
        self.start = time.monotonic()
        self.last: float | None = None
        self._spoke = self.start
        self._lock = threading.Lock()

    def _line(self, text: str) -> None:
        with self._lock:
            self._spoke = time.monotonic()
            self.say(text)

    def started(self) -> None:
        """The opening line: how much there is to do."""
        if self.mode != "none":
            self._line(f"ogcp: {self.name}: {self.todo} cells to run, {self.skipped} of {self.total} done before")

    @contextlib.contextmanager
    def heartbeat(self) -> Iterator[None]:
        """While inside, a line whenever :data:`HEARTBEAT_S` passes without one (long cells, compiling)."""
        if self.mode == "none":
            yield
            return
        stop = threading.Event()
        every = HEARTBEAT_S

        def beat() -> None:
            while not stop.wait(min(every, 1.0)):
                if time.monotonic() - self._spoke >= every:
                    done = f"{self.skipped + self.ran}/{self.total}"
                    elapsed = duration(time.monotonic() - self.start)
                    self._line(f"ogcp: {self.name}: {done} cells, {self.errors} errors, {elapsed} elapsed, running")

        thread = threading.Thread(target=beat, name="ogcp-suite-heartbeat", daemon=True)
        thread.start()
        try:
            yield
        finally:
            stop.set()
            thread.join()

    def finished(self, record: CellRecord) -> None:
        """Count one finished cell and print its line if one is due."""
        self.ran += 1
        self.errors += record.status in ("error", "stopped")
        now = time.monotonic()
        done = f"{self.skipped + self.ran}/{self.total}"
        if self.mode == "each":
            view = record.plan_view
            q1 = number(view.q1 if view is not None else None)
            wall = "-" if record.wall_seconds is None else f"{record.wall_seconds:.2f}"
            self._line(f"ogcp: [{done}] {record.describe()} {record.status}: Q1 {q1}, {wall} s")
        elif self.mode == "periodic" and (
            self.ran == self.todo or self.last is None or now - self.last >= self.interval
        ):
            self.last = now
            elapsed = now - self.start
            eta = elapsed / self.ran * (self.todo - self.ran)
            self._line(
                f"ogcp: {self.name}: {done} cells, {self.errors} errors, "
                f"{duration(elapsed)} elapsed, ETA {duration(eta)}"
            )
