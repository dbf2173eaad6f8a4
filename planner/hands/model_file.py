"""A hand's sampled model on disk: one ``.npz`` in its cache entry, checked whole when read.

The file holds ``joint_names`` (J,), ``angles`` (N, J), ``points`` and ``normals`` (N, F, 3) in the
palm frame, ``collisions`` (N, F + 1, F + 1), and for a grown model its ``recall`` (). A file
that fails a check raises ``ValueError``; :func:`~ogcp.planner.infra.cache.read_entry` then
reports it in one line and the model is sampled again.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.sampled_model import FIRST_SAMPLES, MAX_AUTO_SAMPLES, SampledHand

#: The sampled model's file in its cache entry.
MODEL_FILE = "model.npz"


def save_model(path: Path, sampled: SampledHand) -> None:
    """Write a sampled model to ``path`` (an ``.npz``)."""
    arrays: dict[str, NDArray] = {
        "joint_names": np.array(sampled.joint_names),
        "angles": sampled.angles,
        "points": sampled.points,
        "normals": sampled.normals,
        "collisions": sampled.collisions,
    }
    if sampled.recall is not None:
        arrays["recall"] = np.array(sampled.recall)
    np.savez(path, **arrays)  # type: ignore[arg-type]


def read_model(path: Path, fingers: int, samples: int | None, recalls: bool) -> SampledHand:
    """A sampled model read back and checked against its hand.

    Args:
        path: The ``.npz``.
        fingers: The hand's fingers F.
        samples: The size asked for; None: a grown model (between the first size and the cap,
            with its recall where it has a pair of fingers to recall).
        recalls: Whether a grown model of this hand records a recall.

    Raises:
        ValueError: For arrays of the wrong shape or with non-finite values.
    """
    keys = ("joint_names", "angles", "points", "normals", "collisions")
    with np.load(path, allow_pickle=False) as data:
        names, angles, points, normals, collisions = (data[k] for k in keys)
        recall = float(data["recall"]) if "recall" in data.files else None
    count = samples if samples is not None else len(angles)
    if samples is None and not (FIRST_SAMPLES <= count <= MAX_AUTO_SAMPLES and (recall is not None or not recalls)):
        raise ValueError(f"a grown model of {count} configurations and recall {recall}")
    if names.ndim != 1 or names.dtype.kind != "U" or angles.shape != (count, len(names)):
        raise ValueError(f"{len(names)} joint names and configurations of shape {angles.shape}, expected {count} rows")
    if points.shape != (count, fingers, 3) or normals.shape != points.shape:
        raise ValueError(f"pads of shape {points.shape} and {normals.shape}")
    if collisions.shape != (count, fingers + 1, fingers + 1) or collisions.dtype != np.bool_:
        raise ValueError(f"collisions of shape {collisions.shape} and type {collisions.dtype}")
    if not all(np.isfinite(a).all() for a in (angles, points, normals)):
        raise ValueError("non-finite values")
    return SampledHand(tuple(str(n) for n in names), angles, points, normals, collisions, recall)
