"""Argument types shared by the ``ogcp`` sub-commands: each rejects bad text with a clear message.

A flag with a declared range takes its type from the declaration (:func:`typed`), so the command
line, the suites and the Python API refuse the same values with the same words, and ``--help``
shows the range (:func:`valid`).
"""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ogcp.planner.config.options import ConfigError, Option
from ogcp.planner.grasp.defaults import (
    CONTACT_MODELS,
    DEFAULT_TORSIONAL_FRICTION,
    DIAGONAL,
    TORSIONAL_FRICTION,
)
from ogcp.planner.infra.errors import OgcpError


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


def typed(declared: Option) -> Callable[[str], Any]:
    """An argument type that reads a number and checks it against an option's declared range.

    Args:
        declared: The option (kind ``int`` or ``float``).

    Returns:
        A function for ``add_argument(type=...)``: text -> the checked value, or an
        ``ArgumentTypeError`` naming the valid range (argparse prefixes the flag).
    """

    def convert(text: str) -> Any:
        value: Any
        try:
            value = int(text) if declared.kind == "int" else float(text)
        except ValueError:
            value = text  # reported by check() below, with the valid range
        try:
            return declared.check("value", value)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(exc.problem) from None

    return convert


def valid(declared: Option) -> str:
    """``valid: 3 to 64`` for a flag's help text."""
    return f"valid: {declared.bounds()}"


def check_output(path: Path | None) -> None:
    """Refuse an output file that can never be written, before the work that fills it.

    The write itself still reports its own failure (a full disk, a file system that refuses);
    this only spares a long simulation whose result has nowhere to go.

    Raises:
        OgcpError: For a folder given as the file, or a path under a file or an unwritable folder.
    """
    if path is None:
        return
    if path.is_dir():
        raise OgcpError(f"cannot write {path}: it is a folder; give a file name")
    check_folder(path.parent, what=f"cannot write {path}")


def check_folder(folder: Path, what: str | None = None) -> None:
    """Refuse a folder that can neither be used nor created (the writers create missing ones).

    Args:
        folder: The folder.
        what: The start of the message (default ``cannot write in FOLDER``).

    Raises:
        OgcpError: For a file in the folder's place or on its path, or an unwritable ancestor.
    """
    what = what or f"cannot write in {folder}"
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise OgcpError(f"{what}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OgcpError(f"{what}: the folder {existing} is not writable")


def add_diagonal_option(parser: argparse.ArgumentParser, default: float) -> None:
    """``--diagonal``: the object's bounding-box diagonal [m], for named objects and mesh files alike.

    Args:
        parser: The sub-command's parser.
        default: The named objects' diagonal [m] (``ogcp.planner.objects.DEFAULT_DIAGONAL``), for the help.
    """
    parser.add_argument(
        "--diagonal",
        type=typed(DIAGONAL),
        default=None,
        metavar="METRES",
        help=f"scale the object to this bounding-box diagonal [m], {DIAGONAL.bounds()} (default {default:g} for "
        "built-in and fetched objects; mesh files keep their size unless given)",
    )


def add_contact_model_options(parser: argparse.ArgumentParser | Any) -> None:
    """``--contact-model`` and ``--torsional-friction`` (read with :func:`torsion_from_args`)."""
    # None, not the defaults, so that inputs with a model of their own can refuse them.
    parser.add_argument(
        "--contact-model",
        choices=CONTACT_MODELS,
        default=None,
        help="hard: point contacts with Coulomb friction; soft: they also resist a moment about the normal "
        "(torsional friction, MuJoCo's condim 4), in Q1, the search's bounds and the simulation (default hard)",
    )
    parser.add_argument(
        "--torsional-friction",
        type=typed(TORSIONAL_FRICTION),
        default=None,
        metavar="METRES",
        help=f"torsional friction coefficient of soft fingers [m], MuJoCo's (default {DEFAULT_TORSIONAL_FRICTION:g} "
        f"with --contact-model soft; {valid(TORSIONAL_FRICTION)}); implies --contact-model soft",
    )


def contact_model_given(args: argparse.Namespace) -> bool:
    """Whether ``--contact-model`` or ``--torsional-friction`` was given."""
    return args.contact_model is not None or args.torsional_friction is not None


def torsion_from_args(args: argparse.Namespace) -> float:
    """The torsional friction coefficient [m] of the flags: 0 = hard fingers.

    Raises:
        OgcpError: For a coefficient with ``--contact-model hard``, or 0 with ``soft``.
    """
    from ogcp.planner.grasp.contact_model import torsion_of

    return torsion_of(args.contact_model, args.torsional_friction, "--contact-model", "--torsional-friction")
