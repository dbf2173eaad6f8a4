"""The planning kernels compiled before a command's timed work, with a line saying so on first use."""

from __future__ import annotations

import sys
from collections.abc import Iterable


def compile_kernels(methods: Iterable[str]) -> float | None:
    """Compile (first use) the kernels the methods call, announcing it on stderr.

    Nothing happens when numba's cache already holds them (loading takes well under a second
    and happens at the first call anyway).

    Returns:
        Seconds spent compiling, None when the cache was warm.
    """
    from ogcp.planner.methods.warm_up import cold_kernels, families_for, warm_up

    chosen = tuple(methods)
    if not cold_kernels(families_for(chosen)):
        return None
    seconds = warm_up(chosen, announce=lambda line: print(f"ogcp: {line}", file=sys.stderr, flush=True))
    print(f"ogcp: compiled in {seconds:.0f} s; later runs load them from numba's cache", file=sys.stderr, flush=True)
    return seconds
