"""Exception types raised by ogcp for invalid user input."""

from __future__ import annotations

from collections.abc import Iterable


class OgcpError(ValueError):
    """Invalid input: a file, a parameter or a configuration that ogcp cannot use.

    The message is a single line meant for the user; the CLI prints it without a
    traceback and exits with status 2.
    """


class NoGraspError(OgcpError):
    """A search that ran to its end found no grasp that satisfies the constraints."""


class SearchTimeout(OgcpError):
    """A search stopped (time limit, memory limit or stop request) before it had a grasp to return.

    A search that has a grasp when it stops returns it, with status ``stopped``, ``memory``
    or ``interrupted`` and its certified bound; this is raised only when it has none.

    Attributes:
        seconds: The time limit that was reached [s]; None when stopped otherwise.
        visited: States expanded until then.
        best_q1: Best exact Q1 of a grasp seen so far (None if no grasp was evaluated) [-].
        upper_bound: Certified upper bound on the optimal Q1 at that moment [-].
        memory: Stopped at its memory limit.
    """

    def __init__(
        self,
        method: str,
        seconds: float | None,
        visited: int,
        best_q1: float | None,
        upper_bound: float,
        memory: bool = False,
    ) -> None:
        best = "no grasp evaluated yet" if best_q1 is None else f"best Q1 found {best_q1:.6f}"
        why = "by request" if seconds is None else f"at its time limit of {seconds:g} s"
        if memory:
            why = "at its memory limit"
        super().__init__(
            f"{method} stopped {why} after {visited} expansions ({best}; the optimum is at most {upper_bound:.6f})"
        )
        self.seconds = seconds
        self.visited = visited
        self.best_q1 = best_q1
        self.upper_bound = upper_bound
        self.memory = memory


def choice_error(what: str, given: object, valid: Iterable[str]) -> OgcpError:
    """Build the error for an unknown name, listing the valid choices.

    Args:
        what: What was being chosen, e.g. ``"method"``.
        given: The value the user gave.
        valid: The accepted values.

    Returns:
        An :class:`OgcpError` whose message lists the valid choices.
    """
    choices = ", ".join(sorted(valid))
    return OgcpError(f"unknown {what} {given!r}; valid choices: {choices}")
