"""The exhaustive search's checkpoint: finished chunks on disk, each checked before it is reused.

A checkpoint directory holds ``manifest.json`` (the run key: method, m, chunk size, bins,
contact-set digest, constraints) and one ``chunk_<index>.json`` per finished chunk, schema
``ogcp.es-chunk/1``: the chunk's :class:`ChunkResult` and a sha256 over the canonical JSON
of the run key and the chunk, so a chunk is tied to the run that wrote it. Every file is
written atomically.

A chunk read back must pass, in order:

1. **Parsing.** A file that cannot be read or is not JSON (truncated or overwritten on disk:
   writes are atomic, so a crash never leaves one half written) and one without a checksum
   (written before checkpoints had one) are not trusted: one :class:`CheckpointWarning` line
   names the file (or counts them all) and the chunk is recomputed. Recomputing is always
   correct, so nothing read here can reach the result.
2. **Checksum.** Parseable content that does not match its checksum was edited (or damaged
   in a way that still parses, which disk damage rarely does): the checkpoint is refused, as
   one that fails validation must be, rather than silently recomputed around the edit.
3. **Consistency.** Types, the chunk's index and grasp counts, the histogram against the
   chunk's best Q1 (nothing above it), 0 <= best Q1 <= Q_OWS, the best grasp a sorted tuple
   of m distinct contacts of this chunk that satisfies the constraints, and finally the best
   grasp's Q1 evaluated again (one exact Q1 per chunk). Content that matches its checksum
   but fails any of these was written on purpose: the checkpoint is refused.

Refusal is an :class:`OgcpError` of one line naming the file and the fault; deleting the file
recomputes that chunk. The checksum is not a signature (anyone can recompute a sha256), so it
catches damage and careless edits; the consistency checks bound what a deliberate edit can do
(an impossible Q1 is always caught; a smaller chunk best cannot be told from the real one
without evaluating the chunk again).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, fields
from math import comb
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.constraints import Constraint, accepts_many
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel import default_directions, support_table
from ogcp.planner.grasp.quality import exact_q1_batch
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.plan import RESULT_RTOL

CHUNK_SCHEMA = "ogcp.es-chunk/1"
MANIFEST = "manifest.json"


class CheckpointWarning(UserWarning):
    """A checkpoint chunk could not be read (or had no checksum); it is recomputed."""


class _Fault(Exception):
    """What is wrong with a chunk's content (becomes the refusal's message)."""


@dataclass(frozen=True, eq=False)
class ChunkResult:
    """What one chunk contributes: its best grasp, histogram and counts."""

    index: int
    best_q1: float
    best_grasp: tuple[int, ...] | None
    counts: list[int]
    zero: int
    excluded: int
    evaluated: int
    exact_evaluations: int
    cpu_seconds: float

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True, eq=False)
class ChunkSpace:
    """What the chunks of one run must agree with.

    Attributes:
        contacts: The contact set.
        m: Contacts per grasp.
        chunk: Grasps per chunk.
        edges: Histogram bin edges [N], one more than the bins.
        q_ows: Q1 of all contacts [-].
        pruned: ``es-pruned`` (no histogram) rather than ``es``.
        constraints: Constraints every counted grasp satisfies.
    """

    contacts: ContactSet
    m: int
    chunk: int
    edges: NDArray[np.float64]
    q_ows: float
    pruned: bool
    constraints: Sequence[Constraint] = ()

    @property
    def total(self) -> int:
        """Grasps in the run, C(|C|, m)."""
        return comb(len(self.contacts), self.m)

    def size(self, index: int) -> int:
        """Grasps in chunk ``index`` (the last one may be short)."""
        return min(self.chunk, self.total - index * self.chunk)


class ChunkStore:
    """Finished chunks of one run on disk (see the module docstring); None keeps nothing."""

    def __init__(self, directory: str | Path | None, key: dict[str, Any]) -> None:
        self.directory = None if directory is None else Path(directory)
        self.key = key

    def load(self, space: ChunkSpace) -> dict[int, ChunkResult]:
        """The checked chunks of the checkpoint, by index; writes the manifest of a new one.

        Raises:
            OgcpError: For a directory that cannot be created, a manifest that cannot be
                read or belongs to another run, or a chunk that fails its checksum or its
                consistency checks.
        """
        if self.directory is None:
            return {}
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OgcpError(f"cannot create checkpoint directory {self.directory}: {exc.strerror}") from exc
        manifest = self.directory / MANIFEST
        if manifest.exists():
            try:
                stored = json.loads(manifest.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
                raise OgcpError(
                    f"checkpoint manifest {manifest} is unreadable ({type(exc).__name__}); "
                    "delete the checkpoint directory or use another"
                ) from exc
            if stored != self.key:
                raise OgcpError(
                    f"checkpoint {self.directory} belongs to a different run ({stored}); use another directory"
                )
        else:
            write_json_atomic(manifest, self.key, indent=None)
        done, untrusted = {}, []
        for path in sorted(self.directory.glob("chunk_*.json")):
            result = self._read(path, space)
            if isinstance(result, str):
                untrusted.append((path, result))
            else:
                done[result.index] = result
        if len(untrusted) == 1:
            path, reason = untrusted[0]
            warnings.warn(f"checkpoint chunk {path} {reason}; it is recomputed", CheckpointWarning, 3)
        elif untrusted:
            # One line for all: a checkpoint of an older ogcp has no checksum in any chunk.
            path, reason = untrusted[0]
            warnings.warn(
                f"{len(untrusted)} checkpoint chunks in {self.directory} are unreadable or have no checksum "
                f"(the first, {path.name}, {reason}); they are recomputed",
                CheckpointWarning,
                3,
            )
        _check_best_q1(done, space, self.directory)
        return done

    def save(self, result: ChunkResult) -> None:
        """Write one finished chunk with its checksum (atomically)."""
        if self.directory is not None:
            chunk = result.to_dict()
            record = {"schema": CHUNK_SCHEMA, "sha256": self._digest(chunk), "chunk": chunk}
            write_json_atomic(self.directory / _name(result.index), record, indent=None)

    def _digest(self, chunk: dict[str, Any]) -> str:
        canonical = json.dumps({"key": self.key, "chunk": chunk}, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(canonical.encode()).hexdigest()

    def _read(self, path: Path, space: ChunkSpace) -> ChunkResult | str:
        """One chunk file: its checked result, or why it cannot be read (it is recomputed).

        Raises:
            OgcpError: When its checksum or its consistency checks fail.
        """
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            return f"is unreadable ({type(exc).__name__})"
        if not (
            isinstance(record, dict)
            and record.get("schema") == CHUNK_SCHEMA
            and isinstance(record.get("sha256"), str)
            and isinstance(record.get("chunk"), dict)
        ):
            return "has no checksum"
        refuse = f"checkpoint chunk {path} is refused"
        if self._digest(record["chunk"]) != record["sha256"]:
            raise OgcpError(f"{refuse}: its content does not match its checksum; delete it to recompute the chunk")
        try:
            result = _parse(record["chunk"], space)
            if path.name != _name(result.index):
                raise _Fault(f"it holds chunk {result.index}")
        except _Fault as fault:
            raise OgcpError(f"{refuse}: {fault}; delete it to recompute the chunk") from None
        return result


def _name(index: int) -> str:
    return f"chunk_{index:07d}.json"


def _integer(data: dict[str, Any], name: str, low: int, high: int) -> int:
    value = data[name]
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _Fault(f"{name} {value!r} is not an integer in [{low}, {high}]")
    return value


def _number(data: dict[str, Any], name: str, high: float) -> float:
    value = data[name]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value >= 0):
        raise _Fault(f"{name} {value!r} is not a finite number >= 0")
    if value > high:
        raise _Fault(f"{name} {value!r} exceeds {high!r}")
    return float(value)


def _rank(grasp: Sequence[int], n: int) -> int:
    """Lexicographic rank of a sorted combination of range(n) (the inverse of ``combinations_range``)."""
    m = len(grasp)
    return comb(n, m) - 1 - sum(comb(n - 1 - c, m - i) for i, c in enumerate(grasp))


def _parse(data: dict[str, Any], space: ChunkSpace) -> ChunkResult:
    """A chunk's content as a :class:`ChunkResult`, checked against its run.

    Raises:
        _Fault: Naming the first check that fails.
    """
    names = [f.name for f in fields(ChunkResult)]
    if sorted(data) != sorted(names):
        raise _Fault(f"its fields are {sorted(data)}, expected {sorted(names)}")
    n, m, bins = len(space.contacts), space.m, len(space.edges) - 1
    index = _integer(data, "index", 0, -(-space.total // space.chunk) - 1)
    size = space.size(index)
    if _integer(data, "evaluated", 0, size) != size:
        raise _Fault(f"evaluated {data['evaluated']} grasps, the chunk has {size}")
    excluded = _integer(data, "excluded", 0, size)
    admissible = size - excluded
    zero = _integer(data, "zero", 0, admissible)
    _integer(data, "exact_evaluations", 0, admissible)
    cpu = _number(data, "cpu_seconds", math.inf)
    best_q1 = _number(data, "best_q1", space.q_ows * (1 + RESULT_RTOL))
    counts = data["counts"]
    if not (isinstance(counts, list) and len(counts) == bins):
        raise _Fault(f"counts is not a list of {bins} bins")
    counts = [_integer({"counts": c}, "counts", 0, admissible) for c in counts]
    if space.pruned:
        if zero or any(counts):
            raise _Fault("es-pruned keeps no histogram, but the chunk has one")
    elif sum(counts) + zero != admissible:
        raise _Fault(f"its histogram holds {sum(counts) + zero} grasps, {admissible} were admissible")
    elif best_q1 > 0:
        top = min(int(np.searchsorted(space.edges, best_q1, side="right")) - 1, bins - 1)
        if counts[top] == 0 or any(counts[top + 1 :]):
            raise _Fault(f"its histogram does not peak at its best Q1 {best_q1!r}")
    elif any(counts):
        raise _Fault("its histogram counts grasps in force closure, but its best Q1 is 0")
    raw = data["best_grasp"]
    if raw is None:
        if admissible or best_q1:
            raise _Fault("it names no best grasp, yet has admissible grasps")
        grasp = None
    else:
        if admissible == 0:
            raise _Fault("it names a best grasp, but no grasp of it satisfies the constraints")
        ok = isinstance(raw, list) and len(raw) == m
        ok = ok and all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c < n for c in raw)
        if not (ok and all(a < b for a, b in itertools.pairwise(raw))):
            raise _Fault(f"best_grasp {raw!r} is not {m} sorted distinct contacts of {n}")
        grasp = tuple(raw)
        if _rank(grasp, n) // space.chunk != index:
            raise _Fault(f"best_grasp {raw} is not a grasp of chunk {index}")
        for constraint in space.constraints:
            if not accepts_many(constraint, np.array([grasp], dtype=np.intp), space.contacts)[0]:
                raise _Fault(f"best_grasp {raw} fails the constraint {constraint.name}")
    return ChunkResult(index, best_q1, grasp, counts, zero, excluded, size, data["exact_evaluations"], cpu)


def _check_best_q1(done: dict[int, ChunkResult], space: ChunkSpace, directory: Path) -> None:
    """Evaluate every chunk's best grasp again (one exact Q1 each) and compare.

    Raises:
        OgcpError: For a chunk whose best Q1 is not its grasp's.
    """
    named = [r for r in done.values() if r.best_grasp is not None]
    if not named:
        return
    wrenches = np.asarray(space.contacts.wrenches)
    table = support_table(wrenches, default_directions())
    values, _ = exact_q1_batch(wrenches, np.array([r.best_grasp for r in named], dtype=np.int64), table, 0.0)
    for result, value in zip(named, values, strict=True):
        if abs(float(value) - result.best_q1) > RESULT_RTOL * max(space.q_ows, float(value), result.best_q1):
            raise OgcpError(
                f"checkpoint chunk {directory / _name(result.index)} is refused: its best Q1 {result.best_q1!r} "
                f"is not the Q1 {float(value)!r} of its grasp {list(result.best_grasp or ())}; "
                "delete it to recompute the chunk"
            )
