"""Settings of a convex decomposition: CoACD's parameters, validated, plus method and timeout."""

from __future__ import annotations

import math
import numbers
import sys
from dataclasses import asdict, dataclass, fields
from typing import Any

from ogcp.planner.infra.errors import OgcpError, choice_error

__all__ = ["METHODS", "PREPROCESS_MODES", "DecompositionSettings"]

METHODS = ("coacd", "convex_hull")
PREPROCESS_MODES = ("if_open", "auto", "on", "off")

#: Integer settings and their ranges; CoACD rejects a preprocess resolution outside 5-1000 and
#: takes an unsigned 32-bit seed. The search's upper bounds are 50-100x CoACD's defaults
#: (2000 samples, 20 nodes, 150 iterations, depth 3): past them one decomposition runs for
#: hours, and the timeout would end it with nothing to show.
_INT_RANGES = {
    "preprocess_resolution": (5, 1000),
    "resolution": (1, 200_000),
    "mcts_nodes": (1, 1000),
    "mcts_iterations": (1, 10_000),
    "mcts_max_depth": (1, 20),
    "max_ch_vertex": (4, 100_000),
    "seed": (0, 2**32 - 1),
}


#: Settings that never change the parts of one CoACD run.
_NOT_IN_KEY = ("timeout_s", "contact_tolerance", "refine_thresholds")


def _number(value: object, integral: bool) -> bool:
    kind = numbers.Integral if integral else numbers.Real
    return isinstance(value, kind) and not isinstance(value, bool)


def _boolean(value: object) -> bool:
    # A numpy bool exists only once numpy is loaded, so the check never imports it: the settings'
    # defaults are read where numpy would be wasted (``ogcp --help``).
    numpy = sys.modules.get("numpy")
    return isinstance(value, bool) or (numpy is not None and isinstance(value, numpy.bool_))


@dataclass(frozen=True)
class DecompositionSettings:
    """How to split a mesh into convex parts (CoACD's parameters plus method and timeout).

    Attributes:
        method: ``"coacd"`` (approximate convex decomposition) or ``"convex_hull"`` (one part,
            the hull of the mesh: exact for convex objects, fast for tests).
        threshold: CoACD concavity threshold, 0.01-1 (smaller: more, tighter parts).
        max_convex_hull: Most parts CoACD may return; -1 = no limit.
        preprocess_mode: ``"if_open"`` (remesh only meshes that are not closed and consistently
            oriented by ogcp's edge test), ``"auto"`` (remesh what fails CoACD's own manifold
            check, which also rejects closed meshes with a pinched vertex), ``"on"`` (always
            remesh) or ``"off"`` (never; the mesh must be closed). Remeshing moves the surface
            outward by about a voxel (the diagonal / ``preprocess_resolution``).
        preprocess_resolution: Voxel resolution of the remeshing, 5-1000.
        resolution: Surface samples per part for CoACD's concavity metric.
        mcts_nodes: Children per node of CoACD's cutting-plane tree search.
        mcts_iterations: Iterations of the tree search.
        mcts_max_depth: Depth of the tree search.
        merge: Merge parts afterwards when the merge keeps concavity below threshold.
        decimate: Limit the vertices of every part to ``max_ch_vertex``.
        max_ch_vertex: Vertex limit per part when ``decimate`` is on.
        seed: CoACD's random seed (fixed, so results repeat).
        timeout_s: Wall-clock limit of one CoACD run [s]; not part of the cache key.
        contact_tolerance: Largest distance between the mesh and the collision surface along a
            contact's normal that a grasp accepts, as a fraction of the object's bounding-box
            diagonal; beyond it the grasp is simulated on a finer decomposition.
        refine_thresholds: The finer CoACD thresholds tried in turn (each below ``threshold``
            counts; empty: never refine). Neither refinement field is part of the cache key.
    """

    method: str = "coacd"
    threshold: float = 0.05
    max_convex_hull: int = -1
    preprocess_mode: str = "if_open"
    preprocess_resolution: int = 50
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 150
    mcts_max_depth: int = 3
    merge: bool = True
    decimate: bool = False
    max_ch_vertex: int = 256
    seed: int = 0
    timeout_s: float = 300.0
    contact_tolerance: float = 0.0025
    refine_thresholds: tuple[float, ...] = (0.02,)

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise choice_error("decomposition method", self.method, METHODS)
        if self.preprocess_mode not in PREPROCESS_MODES:
            raise choice_error("CoACD preprocess mode", self.preprocess_mode, PREPROCESS_MODES)
        if not (_number(self.threshold, False) and 0.01 <= self.threshold <= 1.0):
            raise OgcpError(f"CoACD threshold must be a number from 0.01 to 1, got {self.threshold!r}")
        if not (_number(self.timeout_s, False) and 0 < self.timeout_s < math.inf):
            raise OgcpError(f"decomposition timeout must be a positive number of seconds, got {self.timeout_s!r}")
        if not (_number(self.max_convex_hull, True) and (self.max_convex_hull == -1 or self.max_convex_hull >= 1)):
            raise OgcpError(f"max_convex_hull must be -1 (no limit) or an integer >= 1, got {self.max_convex_hull!r}")
        for name, (low, high) in _INT_RANGES.items():
            value = getattr(self, name)
            if not (_number(value, True) and low <= value and (high is None or value <= high)):
                bounds = f"from {low} to {high}" if high is not None else f">= {low}"
                raise OgcpError(f"decomposition {name} must be an integer {bounds}, got {value!r}")
            object.__setattr__(self, name, int(value))  # plain ints keep to_dict() JSON-ready
        for name in ("merge", "decimate"):
            if not _boolean(getattr(self, name)):
                raise OgcpError(f"decomposition {name} must be true or false, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        if not (_number(self.contact_tolerance, False) and 0 < self.contact_tolerance <= 0.1):
            raise OgcpError(
                f"contact_tolerance must be a fraction of the diagonal above 0 and at most 0.1, "
                f"got {self.contact_tolerance!r}"
            )
        thresholds = self.refine_thresholds
        if not (
            isinstance(thresholds, (tuple, list)) and all(_number(t, False) and 0.01 <= t <= 1.0 for t in thresholds)
        ):
            raise OgcpError(f"refine_thresholds must be a list of CoACD thresholds from 0.01 to 1, got {thresholds!r}")
        object.__setattr__(self, "refine_thresholds", tuple(sorted({float(t) for t in thresholds}, reverse=True)))
        object.__setattr__(self, "contact_tolerance", float(self.contact_tolerance))
        object.__setattr__(self, "max_convex_hull", int(self.max_convex_hull))
        object.__setattr__(self, "threshold", float(self.threshold))
        object.__setattr__(self, "timeout_s", float(self.timeout_s))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> DecompositionSettings:
        """Settings from a mapping of field names (e.g. :meth:`to_dict` output or user JSON)."""
        known = {f.name for f in fields(cls)}
        for name in data:
            if name not in known:
                raise choice_error("decomposition setting", name, known)
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        """JSON form: every field."""
        data = asdict(self)
        data["refine_thresholds"] = list(self.refine_thresholds)
        return data

    @property
    def ladder(self) -> tuple[float, ...]:
        """The CoACD thresholds a grasp may be simulated with, coarse to fine (one for the hull)."""
        if self.method == "convex_hull":
            return (self.threshold,)
        return (self.threshold, *(t for t in self.refine_thresholds if t < self.threshold))

    def key_dict(self) -> dict[str, Any]:
        """The fields that determine the parts: the hull ignores CoACD's; the timeout never counts."""
        if self.method == "convex_hull":
            return {"method": self.method}
        return {k: v for k, v in self.to_dict().items() if k not in _NOT_IN_KEY}
