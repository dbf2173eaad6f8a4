"""Argument types shared by the ``ogcp`` sub-commands: each rejects bad text with a clear message."""

from __future__ import annotations

import argparse
import math


def integer(text: str) -> int:
    """Any integer."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def positive_int(text: str) -> int:
    """An integer >= 1 (a count of things that must exist: contacts, jobs, runs)."""
    value = integer(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def nonnegative_int(text: str) -> int:
    """An integer >= 0 (a count that may be zero: extra directions, threads where 0 means default)."""
    value = integer(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def number(text: str) -> float:
    """Any float (range checks belong to the API that receives it)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def finite_number(text: str) -> float:
    """A finite float."""
    value = number(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def add_diagonal_option(parser: argparse.ArgumentParser, default: float) -> None:
    """``--diagonal``: the object's bounding-box diagonal [m], for named objects and mesh files alike.

    Args:
        parser: The sub-command's parser.
        default: The named objects' diagonal [m] (``planner.objects.DEFAULT_DIAGONAL``), for the help.
    """
    parser.add_argument(
        "--diagonal",
        type=number,
        default=None,
        metavar="METRES",
        help=f"scale the object to this bounding-box diagonal [m] (default {default:g} for built-in and fetched "
        "objects; mesh files keep their size unless given)",
    )
