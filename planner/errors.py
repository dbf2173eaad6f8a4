"""Exception types raised by ogcp for invalid user input."""

from __future__ import annotations

from collections.abc import Iterable


class OgcpError(ValueError):
    """Invalid input: a file, a parameter or a configuration that ogcp cannot use.

    The message is a single line meant for the user; the CLI prints it without a
    traceback and exits with status 2.
    """


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
