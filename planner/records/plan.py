"""The ``ogcp.plan/1`` record: what every planning method writes and the simulation reads.

This module owns the schema: it builds the record (:func:`plan_record` and its blocks)
and reads it back (:func:`load_plan`, :func:`recorded_contacts`, :func:`contact_sampling`,
:func:`plan_grasps`, :class:`PlanView`). Later stages (simulation, suites, comparisons, figures) read it only
through these, so every key is named here. Fields are only ever added.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import DEFAULT_CONE_EDGES, DEFAULT_MU, EVEN_SAMPLING, ContactSet
from ogcp.planner.infra.atomic import read_json
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.provenance import provenance
from ogcp.planner.infra.tolerance import TOL

if TYPE_CHECKING:
    from ogcp.planner.hands.reachability import HandReachability

PLAN_SCHEMA = "ogcp.plan/1"
#: Keys of a contact set's ``source`` that say how it was sampled (the rest describe the object).
SAMPLING_KEYS = ("sampling", "n", "seed", "tip_radius", "reach_tolerance")
#: Relative slack of :func:`check_result`: Q1 of a grasp and Q_OWS come from different hulls,
#: so a grasp that holds every contact may round a last bit above Q_OWS.
RESULT_RTOL = 1e-9


def check_result(method: str, q1: float, q_ows: float, bound: float) -> None:
    """Refuse a result that cannot be: 0 <= Q1 <= bound <= Q_OWS, all finite.

    The Q1 of a grasp is at most the Q1 of all contacts (its hull lies inside theirs), and a
    certified bound lies between the grasp it certifies and Q_OWS. A result outside that order
    comes from a bug or from tampered input (a checkpoint), never from a search: it is refused
    rather than written.

    Args:
        method: Method name, for the message.
        q1: Q1 of the returned grasp [-].
        q_ows: Q1 of the whole contact set [-].
        bound: Certified upper bound on the optimum [-].

    Raises:
        OgcpError: One line naming the values that break the order.
    """
    values = {"Q1": q1, "Q_OWS": q_ows, "bound": bound}
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
            raise OgcpError(f"impossible {method} result: {name} is {value!r}, not a number")
        if not math.isfinite(value) or value < 0:
            raise OgcpError(f"impossible {method} result: {name} = {value!r} (expected finite and >= 0)")
    slack = RESULT_RTOL * max(q1, q_ows, bound)
    for (low, a), (high, b) in (
        (("Q1", q1), ("Q_OWS", q_ows)),
        (("Q1", q1), ("bound", bound)),
        (("bound", bound), ("Q_OWS", q_ows)),
    ):
        if a > b + slack:
            raise OgcpError(f"impossible {method} result: {low} {a:.12g} > {high} {b:.12g}")


def plan_record(
    method: str,
    grasp: tuple[int, ...],
    q1: float,
    q_ows: float,
    bound: float,
    positions: NDArray[np.float64],
    normals: NDArray[np.float64],
    stats: dict[str, Any],
    config: dict[str, Any],
    contact_set: dict[str, Any] | None = None,
    **extra: Any,
) -> dict[str, Any]:
    """The ``ogcp.plan/1`` record shared by every planning method.

    Args:
        method: Method name.
        grasp: Sorted contact indices.
        q1: Q1 of the grasp [-].
        q_ows: Q1 of the whole contact set [-].
        bound: Certified upper bound on the optimum [-].
        positions: Contact points of the grasp, shape (m, 3) [m].
        normals: Inward normals of the grasp, shape (m, 3).
        stats: Method-specific statistics.
        config: Method parameters.
        contact_set: Description of the contact set (COM, rho, mu, k, source).
        **extra: Further method-specific top-level fields.

    Raises:
        OgcpError: For values that cannot be (see :func:`check_result`).
    """
    check_result(method, q1, q_ows, bound)
    return {
        "schema": PLAN_SCHEMA,
        "method": method,
        "grasp": list(grasp),
        "q1": q1,
        "q_ows": q_ows,
        "bound": bound,
        "force_closure": q1 > 0,
        "contacts": {"positions": positions.tolist(), "normals": normals.tolist()},
        "contact_set": contact_set or {},
        **extra,
        "stats": stats,
        "config": config,
        "tolerances": TOL.as_dict(),
        "provenance": provenance(),
    }


def contact_set_record(contacts: ContactSet) -> dict[str, Any]:
    """What a plan records about its contact set: the set itself, and how and on what it was made.

    The contacts are recorded in full (``positions`` (n, 3) [m] and inward unit ``normals``
    (n, 3), at full float precision: about 100 kB for n = 1000), so a plan evaluates the same
    set on any machine; re-sampling from ``source`` can differ across trimesh versions. For a
    mesh file, ``mesh`` records its sha256 and its path twice: as given (relative to the folder
    planned in) and absolute; :func:`add_plan_path` adds it relative to the plan file.
    """
    record: dict[str, Any] = {
        "size": len(contacts),
        "com": contacts.com.tolist(),
        "torque_scale": contacts.torque_scale,
        "mu": contacts.mu,
        "cone_edges": contacts.cone_edges,
        "contact_model": contacts.contact_model,
        "torsional_friction": contacts.torsional_friction,
        "source": contacts.source,
        "positions": contacts.positions.tolist(),
        "normals": contacts.normals.tolist(),
    }
    source = contacts.source
    if source.get("kind") == "mesh" and isinstance(source.get("path"), str):
        record["mesh"] = {
            "sha256": source.get("sha256"),
            "path": source["path"],
            "absolute_path": str(Path(source["path"]).resolve()),
        }
    return record


def add_plan_path(record: dict[str, Any], plan_file: str | Path) -> dict[str, Any]:
    """``record`` with its mesh file's path relative to ``plan_file``, where the plan is about to be written.

    A plan moved to another folder together with its mesh (keeping their relative layout) then
    still finds it. Unchanged for plans on built-in or fetched objects, or on contact files.
    """
    mesh = (record.get("contact_set") or {}).get("mesh")
    if isinstance(mesh, dict) and isinstance(mesh.get("absolute_path"), str):
        folder = Path(plan_file).resolve().parent
        mesh["path_from_plan"] = Path(os.path.relpath(mesh["absolute_path"], folder)).as_posix()
    return record


def hand_record(hand: HandReachability, grasp: Sequence[int], contacts: ContactSet) -> dict[str, Any]:
    """The ``"hand"`` block of a result: the hand's identity, the nearest sampled configuration
    (joint names and angles), its residual, and which finger takes which contact."""
    reach = hand.reach(grasp, contacts)
    return {
        **hand.descriptor.to_dict(),
        "fingers": list(reach.finger_names),
        "joint_names": list(hand.joint_names),
        "joint_angles": list(reach.joint_angles),
        "residual": reach.residual,
        "reachable": reach.residual <= hand.threshold,
        "finger_contacts": [grasp[i] for i in reach.fingers],
        "samples": hand.samples,
    }


def add_hand(record: dict[str, Any], hand: HandReachability | None, contacts: ContactSet) -> dict[str, Any]:
    """``record`` with the :func:`hand_record` of its best grasp (unchanged without a hand)."""
    if hand is not None:
        record["hand"] = hand_record(hand, record["grasp"], contacts)
    return record


def add_optimum(
    record: dict[str, Any],
    method: str,
    grasp: Sequence[int],
    q1: float,
    status: str = "optimal",
    bound: float | None = None,
) -> dict[str, Any]:
    """``record`` with the ``"optimum"`` block: grasp and Q1 [-] an exact ``method`` found (HFTS shows its gap).

    Args:
        record: The plan record (changed in place and returned).
        method: The exact method.
        grasp: Its grasp's contact indices.
        q1: Its grasp's Q1 [-].
        status: ``optimal``, or how it stopped short (``stopped``: its time ran out).
        bound: Its certified upper bound on the optimum [-]; None: ``q1`` (optimal).
    """
    record["optimum"] = {
        "method": method,
        "grasp": list(grasp),
        "q1": q1,
        "status": status,
        "bound": q1 if bound is None else bound,
    }
    return record


def histogram_record(
    bin_edges: NDArray[np.float64], counts: NDArray[np.int64], zero: int | None, force_closure_fraction: float | None
) -> dict[str, Any]:
    """The ``"histogram"`` block of an exhaustive search: Q1 of every admissible grasp, binned.

    Args:
        bin_edges: Bin edges over (0, Q_OWS] [-], one more than ``counts``.
        counts: Grasps per bin.
        zero: Grasps with Q1 = 0 (not in force closure).
        force_closure_fraction: Fraction of the admissible grasps in force closure.
    """
    return {
        "bin_edges": bin_edges.tolist(),
        "counts": counts.tolist(),
        "zero": zero,
        "force_closure_fraction": force_closure_fraction,
    }


# -- reading ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContactSampling:
    """How a plan's contact set was sampled: enough to sample it again.

    Attributes:
        object: The object's description (``kind``, ``name`` or ``path``, ``diagonal``, ``sha256``).
        n: Number of contacts.
        seed: Sampling seed.
        mu: Friction coefficient.
        cone_edges: Friction-cone edges k.
        com: Recorded centre of mass [m], None if the plan has none.
        torsional_friction: Torsional friction coefficient [m]; 0 = hard fingers.
        tip_radius: Fingertip radius the contacts were kept for [m]; None = plain sampling
            (plans made before reach-aware sampling, or with tip radius 0).
        reach_tolerance: Cut depth allowed with it [m]; None with ``tip_radius``.
    """

    object: dict[str, Any]
    n: int
    seed: int
    mu: float
    cone_edges: int
    com: tuple[float, ...] | None
    tip_radius: float | None = None
    reach_tolerance: float | None = None
    torsional_friction: float = 0.0


def load_plan(path: str | Path) -> dict[str, Any]:
    """Read and check a plan JSON file (schema ``ogcp.plan/1``).

    Raises:
        OgcpError: For a missing or unreadable file, invalid JSON or another schema.
    """
    path = Path(path)
    record = read_json(path, "plan", "ogcp.plan")
    if not isinstance(record, dict) or record.get("schema") != PLAN_SCHEMA:
        found = record.get("schema") if isinstance(record, dict) else type(record).__name__
        other = " or grasps with schema 'ogcp.grasps/1'" if str(found).startswith("ogcp.grasps/") else ""
        raise OgcpError(f"{path}: expected a plan with schema {PLAN_SCHEMA!r}{other}, got {found!r}")
    return record


def contact_sampling(record: dict[str, Any]) -> ContactSampling:
    """How the plan's contact set was sampled, from its ``contact_set`` block.

    Raises:
        OgcpError: When the plan does not record it (e.g. it was planned on a contact file).
    """
    block = record.get("contact_set") or {}
    source = dict(block.get("source") or record.get("source") or {})
    if source.get("sampling") != EVEN_SAMPLING or "n" not in source or "seed" not in source:
        raise OgcpError("the plan does not record how its contacts were sampled (object, n, seed): cannot rebuild them")
    com = block.get("com")
    tip, tolerance = source.get("tip_radius"), source.get("reach_tolerance")
    return ContactSampling(
        object={k: v for k, v in source.items() if k not in SAMPLING_KEYS},
        n=int(source["n"]),
        seed=int(source["seed"]),
        mu=float(block.get("mu", DEFAULT_MU)),
        cone_edges=int(block.get("cone_edges", DEFAULT_CONE_EDGES)),
        com=None if com is None else tuple(float(c) for c in com),
        # Absent in plain-sampled sets: they are sampled again without a tip, as before.
        tip_radius=None if tip is None else float(tip),
        reach_tolerance=None if tip is None or tolerance is None else float(tolerance),
        # Absent in plans made before soft fingers: they were all hard.
        torsional_friction=float(block.get("torsional_friction") or 0.0),
    )


def plan_grasps(record: dict[str, Any], n: int) -> tuple[tuple[tuple[int, ...], ...], tuple[str, ...]]:
    """The plan's distinct grasps, best first, and where each came from.

    The best grasp is labelled ``best``; a plan's ``top`` list gives ``top-<i>`` and
    HFTS's ``runs`` give ``hfts-run-<i>``. A grasp listed twice keeps its first label.

    Args:
        record: The plan.
        n: Size of the contact set the grasps index.

    Raises:
        OgcpError: For a grasp that is not a list of contact indices below ``n``.
    """
    found: dict[tuple[int, ...], str] = {}
    candidates = [("best", record.get("grasp"))]
    candidates += [
        (f"top-{i}", t.get("grasp") if isinstance(t, dict) else t) for i, t in enumerate(record.get("top") or [])
    ]
    candidates += [(f"hfts-run-{i}", r.get("grasp")) for i, r in enumerate(record.get("runs") or [])]
    for label, grasp in candidates:
        if not isinstance(grasp, list) or not all(isinstance(i, int) for i in grasp):
            raise OgcpError(f"plan grasp {label!r} must be a list of contact indices, got {grasp!r}")
        if any(i < 0 or i >= n for i in grasp):
            raise OgcpError(f"plan grasp {label!r} {grasp} indexes outside the {n}-contact set")
        found.setdefault(tuple(grasp), label)
    return tuple(found), tuple(found.values())


def recorded_contacts(record: dict[str, Any]) -> ContactSet | None:
    """The contact set the plan records in full, None for plans made before contacts were recorded.

    Raises:
        OgcpError: For recorded contacts that do not make a valid set (shapes, NaN, zero normals).
    """
    block = record.get("contact_set") or {}
    if not isinstance(block, dict) or "positions" not in block:
        return None
    source = block.get("source") or record.get("source") or {}
    try:
        return ContactSet(
            np.asarray(block.get("positions"), dtype=float),
            np.asarray(block.get("normals"), dtype=float),
            np.asarray(block.get("com"), dtype=float),
            block.get("torque_scale"),  # type: ignore[arg-type]  # checked by ContactSet
            block.get("mu", DEFAULT_MU),
            block.get("cone_edges", DEFAULT_CONE_EDGES),
            dict(source),
            block.get("torsional_friction") or 0.0,
        )
    except (TypeError, ValueError) as exc:
        raise OgcpError(f"plan field contact_set: the recorded contacts are not a contact set ({exc})") from None
    except OgcpError as exc:
        raise OgcpError(f"plan field contact_set: the recorded contacts are not a contact set: {exc}") from None


def recorded_positions(record: dict[str, Any]) -> NDArray[np.float64]:
    """Contact points of the plan's best grasp as recorded, shape (m, 3) [m] (empty if none)."""
    return np.asarray((record.get("contacts") or {}).get("positions", []), dtype=float)


@dataclass(frozen=True, eq=False)
class PlanHistogram:
    """The Q1 histogram of an exhaustive search read back (see :func:`histogram_record`); None: not recorded."""

    bin_edges: NDArray[np.float64]
    counts: NDArray[np.float64]
    zero: int | None
    force_closure_fraction: float | None


@dataclass(frozen=True)
class PlanHand:
    """The ``"hand"`` block read back (see :func:`hand_record`): joint angles [rad], residual, contact per finger.

    Plans written before hands had descriptors carry no ``descriptor``, ``fingers`` or
    ``joint_names`` (then None or empty).
    """

    name: str | None
    joint_angles: tuple[float, ...]
    residual: float | None
    finger_contacts: tuple[int, ...]
    descriptor: str | None = None
    descriptor_sha256: str | None = None
    fingers: tuple[str, ...] = ()
    joint_names: tuple[str, ...] = ()
    samples: int | None = None


@dataclass(frozen=True)
class PlanOptimum:
    """The ``"optimum"`` block read back (see :func:`add_optimum`); None: not recorded."""

    method: str | None
    grasp: tuple[int, ...] | None
    q1: float | None
    status: str = "optimal"
    bound: float | None = None


@dataclass(frozen=True, eq=False)
class PlanView:
    """Typed, lenient read access to an ``ogcp.plan/1`` record.

    Comparisons and figures read records of any method and of partial or older runs, so
    nothing here raises: a value that is missing or of the wrong type reads as None (or an
    empty value), and the reader skips what the record lacks. NaN, written to JSON as null,
    reads as None too.

    Attributes:
        record: The record as written (not copied).
    """

    record: Mapping[str, Any]

    @property
    def method(self) -> str | None:
        """The method name."""
        method = self.record.get("method")
        return None if method is None else str(method)

    @property
    def grasp(self) -> tuple[int, ...] | None:
        """The best grasp's contact indices."""
        return _indices(self.record.get("grasp"))

    @property
    def q1(self) -> float | None:
        """Q1 of the best grasp [-]."""
        return _number(self.record.get("q1"))

    @property
    def q_ows(self) -> float | None:
        """Q1 of the whole contact set [-]."""
        return _number(self.record.get("q_ows"))

    @property
    def bound(self) -> float | None:
        """Certified upper bound on the optimum [-]."""
        return _number(self.record.get("bound"))

    @property
    def eps(self) -> float | None:
        """The search's inflation eps (searches and exhaustive search)."""
        return _number(self.record.get("eps"))

    @property
    def eps_bound(self) -> float | None:
        """The bound that eps guarantees (searches)."""
        return _number(self.record.get("eps_bound"))

    @property
    def stats(self) -> dict[str, Any]:
        """The method's statistics (their keys are the method's own; empty when absent)."""
        stats = self.record.get("stats")
        return stats if isinstance(stats, dict) else {}

    @property
    def cpu_seconds(self) -> float | None:
        """The method's CPU time, summed over workers where it records them [s]."""
        return _number(self.stats.get("cpu_seconds"))

    @property
    def wall_seconds(self) -> float | None:
        """The method's wall time [s]."""
        return _number(self.stats.get("wall_seconds"))

    @property
    def histogram(self) -> PlanHistogram | None:
        """The Q1 histogram (``es``), None when absent or its arrays do not fit together."""
        block = self.record.get("histogram")
        if not isinstance(block, dict):
            return None
        try:
            edges = np.asarray(block.get("bin_edges"), dtype=float)
            counts = np.asarray(block.get("counts"), dtype=float)
        except (TypeError, ValueError):
            return None
        if edges.ndim != 1 or counts.ndim != 1 or len(edges) != len(counts) + 1 or len(counts) == 0:
            return None
        zero = block.get("zero")
        return PlanHistogram(
            edges,
            counts,
            zero if isinstance(zero, int) and not isinstance(zero, bool) else None,
            _number(block.get("force_closure_fraction")),
        )

    @property
    def run_q1s(self) -> tuple[float | None, ...]:
        """Q1 of every recorded run (HFTS's ``runs``) [-]; empty for other methods."""
        return tuple(_number(run.get("q1")) for run in _runs(self.record))

    @property
    def tree(self) -> dict[str, Any] | None:
        """The recorded search tree (parallel lists; see ``SearchTree.to_dict``), None when not recorded."""
        tree = self.record.get("tree")
        return tree if isinstance(tree, dict) else None

    @property
    def hand(self) -> PlanHand | None:
        """The hand's joint angles and finger assignment, None for a plan without a hand."""
        block = self.record.get("hand")
        if not isinstance(block, dict):
            return None
        name, angles = block.get("name"), block.get("joint_angles")
        descriptor, digest = block.get("descriptor"), block.get("descriptor_sha256")
        samples = block.get("samples")
        return PlanHand(
            name=None if name is None else str(name),
            joint_angles=tuple(float(a) for a in angles if _is_number(a)) if isinstance(angles, list) else (),
            residual=_number(block.get("residual")),
            finger_contacts=_indices(block.get("finger_contacts")) or (),
            descriptor=descriptor if isinstance(descriptor, str) else None,
            descriptor_sha256=digest if isinstance(digest, str) else None,
            fingers=_names(block.get("fingers")),
            joint_names=_names(block.get("joint_names")),
            samples=samples if isinstance(samples, int) and not isinstance(samples, bool) and samples > 0 else None,
        )

    @property
    def optimum(self) -> PlanOptimum | None:
        """The optimum recorded next to an approximate method's result, None when not recorded."""
        block = self.record.get("optimum")
        if not isinstance(block, dict):
            return None
        method, status = block.get("method"), block.get("status", "optimal")
        return PlanOptimum(
            None if method is None else str(method),
            _indices(block.get("grasp")),
            _number(block.get("q1")),
            status if isinstance(status, str) else "optimal",  # older records: always the optimum
            _number(block.get("bound", block.get("q1"))),
        )


def _names(value: Any) -> tuple[str, ...]:
    return tuple(v for v in value if isinstance(v, str)) if isinstance(value, list) else ()


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(value: Any) -> float | None:
    """A finite float, else None (JSON writes NaN as null; a bool is not a number)."""
    return float(value) if _is_number(value) and math.isfinite(value) else None


def _indices(value: Any) -> tuple[int, ...] | None:
    """A JSON list of contact indices as a tuple, else None."""
    if not isinstance(value, list) or not all(isinstance(i, int) and not isinstance(i, bool) for i in value):
        return None
    return tuple(value)


def _runs(record: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The recorded runs (HFTS) that are JSON objects."""
    runs = record.get("runs")
    return [run for run in runs if isinstance(run, dict)] if isinstance(runs, list) else []
