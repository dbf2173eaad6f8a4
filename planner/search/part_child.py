"""Entry point of a search part's child process: ``python -m ogcp.planner.search.part_child FOLDER RANK PARENT_PID``.

Started by :func:`ogcp.planner.search.parts.search_in_parts`, which reads the pickled outcome from
this process's stdout; anything else the child prints goes to stderr.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path


def main() -> int:
    from ogcp.planner.infra.lifetime import set_parent_death_signal, watch_parent

    folder, rank, parent = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    set_parent_death_signal()  # the caller's thread that started this process waits for it
    watch_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the caller, which stops every part
    out = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # stray prints must not corrupt the outcome
    from ogcp.planner.search.parts import child_main

    out.write(child_main(folder, rank))
    out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
