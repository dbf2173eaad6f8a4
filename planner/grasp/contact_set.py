"""Contact sets C: point contacts (position, inward normal) plus the Q1 conventions.

A :class:`ContactSet` carries everything Q1 needs, so every method that receives the same
set computes the same quality: positions, inward unit normals, the wrench reference
(centre of mass), the torque scale rho, the friction coefficient mu, the number of
cone edges k and the contact model (hard fingers, or soft fingers with a torsional
friction coefficient; see :mod:`ogcp.planner.grasp.wrench`).
"""

from __future__ import annotations

import json
import logging
import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from numbers import Real
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

# The defaults live in a module without numpy and trimesh, for readers that need nothing else.
from ogcp.planner.grasp.defaults import (
    CONTACT_SEED,
    DEFAULT_CONE_EDGES,
    DEFAULT_MU,
    MAX_CONE_EDGES,
    MAX_DIAGONAL,
    MAX_MU,
    MIN_DIAGONAL,
    TIP_RADIUS,
    TORSIONAL_FRICTION,
    check_contact_memory,
)
from ogcp.planner.grasp.wrench import contact_wrenches, primitives_per_contact
from ogcp.planner.infra.atomic import write_json_atomic
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.tolerance import TOL

if TYPE_CHECKING:
    # Sampling imports trimesh where it is used: planning from a contact file needs no mesh library.
    import trimesh

SCHEMA = "ogcp.contacts/1"
#: ``source["sampling"]`` of a set from :func:`sample_contacts`.
EVEN_SAMPLING = "even"


class NonWatertightWarning(UserWarning):
    """The mesh is not watertight, so its volume centroid is undefined."""


def _readonly(array: NDArray[np.float64]) -> NDArray[np.float64]:
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class ContactSet:
    """A finite set of frictional point contacts on one object.

    Attributes:
        positions: Contact points, shape (n, 3) [m].
        normals: Inward unit surface normals, shape (n, 3).
        com: Wrench reference point (object centre of mass), shape (3,) [m].
        torque_scale: rho [m]; torques are divided by it.
        mu: Coulomb friction coefficient.
        cone_edges: Number of friction-cone edges k.
        source: Provenance of the set (object, sampling seed, ...), JSON-ready.
        torsional_friction: Torsional friction coefficient gamma [m] (MuJoCo's, condim 4):
            0 for hard fingers (point contacts), > 0 for soft fingers that also resist a
            moment of up to gamma times the normal force about the normal.
    """

    positions: NDArray[np.float64]
    normals: NDArray[np.float64]
    com: NDArray[np.float64]
    torque_scale: float
    mu: float = DEFAULT_MU
    cone_edges: int = DEFAULT_CONE_EDGES
    source: dict[str, Any] = field(default_factory=dict)
    torsional_friction: float = 0.0

    def __post_init__(self) -> None:
        try:
            positions = np.asarray(self.positions, dtype=float)
            normals = np.asarray(self.normals, dtype=float)
            com = np.asarray(self.com, dtype=float)
        except (TypeError, ValueError) as exc:
            raise OgcpError(f"contact positions, normals and centre of mass must be numeric arrays ({exc})") from None
        for name in ("torque_scale", "mu"):
            # math.isfinite below would raise a bare TypeError for a string or None.
            if not isinstance(getattr(self, name), Real):
                raise OgcpError(f"{name} must be a number, got {getattr(self, name)!r}")
        if positions.ndim != 2 or positions.shape[1] != 3 or len(positions) == 0:
            raise OgcpError(f"contact positions must have shape (n, 3) with n >= 1, got {positions.shape}")
        if normals.shape != positions.shape:
            raise OgcpError(f"contact normals must have shape {positions.shape}, got {normals.shape}")
        if not np.all(np.isfinite(positions)):
            raise OgcpError("contact positions contain NaN or infinite values")
        if not np.all(np.isfinite(normals)):
            raise OgcpError("contact normals contain NaN or infinite values")
        lengths = np.linalg.norm(normals, axis=1)
        if np.any(lengths < TOL.normal_norm):
            bad = int(np.argmax(lengths < TOL.normal_norm))
            raise OgcpError(f"contact normal {bad} has zero length")
        if com.shape != (3,) or not np.all(np.isfinite(com)):
            raise OgcpError(f"centre of mass must be 3 finite numbers, got {com.tolist()}")
        if not (math.isfinite(self.torque_scale) and self.torque_scale > 0):
            raise OgcpError(f"torque scale rho must be a positive number of metres, got {self.torque_scale!r}")
        _check_friction(self.mu, self.cone_edges)
        TORSIONAL_FRICTION.check("torsional_friction [m]", self.torsional_friction)
        # A loaded set is checked too: its size was never asked for, but planning allocates by it.
        check_contact_memory(len(positions), primitives_per_contact(int(self.cone_edges), self.torsional_friction))
        object.__setattr__(self, "positions", _readonly(positions))
        # Rows that are already unit length are kept bit-for-bit, so a JSON round trip
        # (or re-wrapping a set) reproduces the normals exactly.
        lengths = np.where(np.abs(lengths - 1.0) <= 1e-12, 1.0, lengths)
        object.__setattr__(self, "normals", _readonly(normals / lengths[:, None]))
        object.__setattr__(self, "com", _readonly(com))
        object.__setattr__(self, "torque_scale", float(self.torque_scale))
        object.__setattr__(self, "mu", float(self.mu))
        object.__setattr__(self, "cone_edges", int(self.cone_edges))
        object.__setattr__(self, "torsional_friction", float(self.torsional_friction))

    @property
    def contact_model(self) -> str:
        """``"soft"`` when the contacts resist torsion (``torsional_friction`` > 0), else ``"hard"``."""
        return "soft" if self.torsional_friction > 0 else "hard"

    def __len__(self) -> int:
        return len(self.positions)

    @cached_property
    def wrenches(self) -> NDArray[np.float64]:
        """Wrench primitives of every contact, shape (n, K, 6) [N] (torque / rho).

        K = k cone edges for hard fingers, :func:`~ogcp.planner.grasp.wrench.primitives_per_contact`
        for soft ones.
        """
        w = contact_wrenches(
            self.positions, self.normals, self.com, self.torque_scale, self.mu, self.cone_edges, self.torsional_friction
        )
        w.setflags(write=False)
        return w

    def subset_wrenches(self, indices: NDArray[np.intp]) -> NDArray[np.float64]:
        """Wrenches of the given contacts stacked, shape (len(indices) * K, 6).

        Args:
            indices: Contact indices, shape (m,), each in ``[0, n)``.

        Raises:
            OgcpError: For indices that are not integers, not of shape (m,), or out of range
                (a negative index would silently pick a contact from the end).
        """
        idx = np.asarray(indices)
        if idx.ndim != 1 or not (idx.dtype.kind in "iu" or idx.size == 0):
            raise OgcpError(f"contact indices must be integers of shape (m,), got {idx.dtype} of shape {idx.shape}")
        # The search calls this per Q1 evaluation, mostly with a few indices: a Python min over
        # them costs a fifth of numpy's. Indices past the end fail numpy's own bounds check.
        if idx.size and (min(idx.tolist()) if idx.size < 64 else idx.min()) < 0:
            raise OgcpError(f"contact indices must be in [0, {len(self)}), got {int(idx.min())}")
        try:
            return self.wrenches[idx.astype(np.intp, copy=False)].reshape(-1, 6)
        except IndexError:
            raise OgcpError(f"contact indices must be in [0, {len(self)}), got {int(idx.max())}") from None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (schema ``ogcp.contacts/1``)."""
        return {
            "schema": SCHEMA,
            "positions": self.positions.tolist(),
            "normals": self.normals.tolist(),
            "com": self.com.tolist(),
            "torque_scale": self.torque_scale,
            "mu": self.mu,
            "cone_edges": self.cone_edges,
            **({"torsional_friction": self.torsional_friction} if self.torsional_friction else {}),
            "source": self.source,
        }

    @classmethod
    def from_dict(cls, data: Any, where: str = "contact data") -> ContactSet:
        """Build a set from its JSON form, validating every field.

        Args:
            data: Parsed JSON object.
            where: Name used in error messages (e.g. the file path).

        Raises:
            OgcpError: On a wrong schema, a missing key or an invalid value.
        """
        if not isinstance(data, dict):
            raise OgcpError(f"{where}: expected a JSON object with schema {SCHEMA!r}")
        if data.get("schema") != SCHEMA:
            raise OgcpError(f"{where}: schema is {data.get('schema')!r}, expected {SCHEMA!r}")
        missing = [k for k in ("positions", "normals", "com", "torque_scale") if k not in data]
        if missing:
            raise OgcpError(f"{where}: missing key(s) {', '.join(missing)}")
        try:
            return cls(
                positions=np.asarray(data["positions"], dtype=float),
                normals=np.asarray(data["normals"], dtype=float),
                com=np.asarray(data["com"], dtype=float),
                torque_scale=float(data["torque_scale"]),
                mu=float(data.get("mu", DEFAULT_MU)),
                cone_edges=data.get("cone_edges", DEFAULT_CONE_EDGES),
                source=dict(data.get("source", {})),
                torsional_friction=data.get("torsional_friction", 0.0),
            )
        except OgcpError as exc:
            raise OgcpError(f"{where}: {exc}") from exc
        except (TypeError, ValueError) as exc:
            raise OgcpError(f"{where}: malformed contact data ({exc})") from exc

    def save(self, path: str | Path) -> None:
        """Write the JSON form atomically (a crash never leaves a half-written file).

        Raises:
            OgcpError: If the file cannot be written.
        """
        write_json_atomic(path, self.to_dict())

    @classmethod
    def load(cls, path: str | Path) -> ContactSet:
        """Read a contact JSON file.

        Raises:
            OgcpError: If the file is missing, not JSON, or invalid.
        """
        path = Path(path)
        if not path.is_file():
            raise OgcpError(f"contact file not found: {path}")
        try:
            data = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise OgcpError(f"{path}: not a readable JSON file ({exc})") from exc
        return cls.from_dict(data, where=str(path))


def _real(value: Any) -> float | None:
    """``value`` as a finite float if it is a number (numpy's included, booleans not), else None."""
    if isinstance(value, bool) or not isinstance(value, Real):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _count(value: Any) -> int | None:
    """``value`` as an int if it is a finite whole number (20 and 20.0 alike), else None."""
    number = _real(value)
    return int(number) if number is not None and number.is_integer() else None


def _check_friction(mu: Any, cone_edges: Any) -> None:
    """mu in (0, MAX_MU] and k an integer in [3, MAX_CONE_EDGES] (see ogcp.planner.grasp.defaults for why).

    Raises:
        OgcpError: Naming the value and its valid range.
    """
    friction = _real(mu)
    if friction is None or friction <= 0:
        raise OgcpError(f"friction coefficient mu must be positive, got {mu!r} (valid: > 0 and <= {MAX_MU:g})")
    if friction > MAX_MU:
        raise OgcpError(
            f"friction coefficient mu must be at most {MAX_MU:g}, got {mu!r} (valid: > 0 and <= {MAX_MU:g})"
        )
    # int() of NaN, inf or a string would raise its own error; only a finite whole number is a count.
    edges = _count(cone_edges)
    if edges is None or edges < 3:
        raise OgcpError(f"cone_edges must be an integer >= 3, got {cone_edges!r} (valid: 3 to {MAX_CONE_EDGES})")
    if edges > MAX_CONE_EDGES:
        raise OgcpError(
            f"cone_edges must be at most {MAX_CONE_EDGES}, got {cone_edges!r} (valid: 3 to {MAX_CONE_EDGES})"
        )


def _check_sampling(
    mesh: trimesh.Trimesh, n: Any, seed: Any, mu: Any, cone_edges: Any, tip_radius: float | None, torsion: Any
) -> None:
    """Everything :func:`sample_contacts` is given, checked before it allocates anything of size n.

    Raises:
        OgcpError: For a bad count (or one whose memory exceeds the machine's), seed, friction
            model, tip radius, or an object outside the diagonals ogcp works at.
    """
    count = _count(n)
    if count is None or count < 1:
        raise OgcpError(f"number of contacts must be a positive integer, got {n!r}")
    CONTACT_SEED.check("seed", seed)
    _check_friction(mu, cone_edges)
    if tip_radius is not None:
        TIP_RADIUS.check("tip radius [m]", tip_radius)
    TORSIONAL_FRICTION.check("torsional_friction [m]", torsion)
    check_contact_memory(count, primitives_per_contact(int(cone_edges), float(torsion)))
    diagonal = (
        float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices, dtype=float), axis=0))) if len(mesh.vertices) else 0.0
    )
    if not MIN_DIAGONAL <= diagonal <= MAX_DIAGONAL:
        raise OgcpError(
            f"the object's bounding-box diagonal is {diagonal:.3g} m; ogcp samples objects from {MIN_DIAGONAL:g} m to "
            f"{MAX_DIAGONAL:g} m (scale it with --diagonal METRES, e.g. a mesh in millimetres)"
        )


def mass_properties(mesh: trimesh.Trimesh) -> tuple[NDArray[np.float64], float]:
    """Centre of mass and torque scale of a mesh.

    The COM is the volume centroid of a watertight mesh. For a mesh that is not
    watertight the volume is undefined; the area-weighted surface centroid is used
    instead and a :class:`NonWatertightWarning` is issued.

    Returns:
        ``(com, rho)``: COM, shape (3,) [m], and rho = max distance COM-vertex [m].
    """
    if mesh.is_watertight and mesh.volume > 0:
        com = np.asarray(mesh.center_mass, dtype=float)
    else:
        warnings.warn(
            "mesh is not watertight: using the area-weighted surface centroid as centre of mass",
            NonWatertightWarning,
            stacklevel=2,
        )
        com = np.average(mesh.triangles_center, axis=0, weights=mesh.area_faces)
    rho = float(np.max(np.linalg.norm(mesh.vertices - com, axis=1)))
    return com, rho


def sample_contacts(
    mesh: trimesh.Trimesh,
    n: int,
    seed: int = 0,
    mu: float = DEFAULT_MU,
    cone_edges: int = DEFAULT_CONE_EDGES,
    source: dict[str, Any] | None = None,
    *,
    tip_radius: float | None = None,
    reach_tolerance: float | None = None,
    torsional_friction: float = 0.0,
) -> ContactSet:
    """Sample exactly ``n`` contacts evenly over a mesh surface.

    Even (Poisson-disk-like) sampling may return fewer than ``n`` points; the remainder
    is filled with area-weighted random samples from a seed derived from ``seed``, so the
    result is deterministic and always has ``n`` contacts.

    With a tip radius r > 0, only contacts a fingertip sphere of radius r can touch
    without cutting the object are kept (:func:`ogcp.planner.grasp.reach.reachable`); the
    others are replaced, in order, by reachable area-weighted samples from further seeds
    derived from ``seed`` (:func:`ogcp.planner.grasp.reach.fill_reachable`). Where every contact
    is reachable (a convex object) the set equals the one sampled without r.

    Args:
        mesh: Object surface.
        n: Number of contacts.
        seed: Sampling seed.
        mu: Friction coefficient.
        cone_edges: Number of cone edges k.
        source: Provenance of the mesh, recorded in the set's ``source``.
        tip_radius: Fingertip sphere radius r [m]; None or 0 samples the whole surface.
            A positive r is recorded in ``source["tip_radius"]``.
        reach_tolerance: Cut depth a kept contact's sphere may have [m]; None = 1 % of r
            (:data:`ogcp.planner.grasp.reach.REACH_TOLERANCE`). Recorded with r.
        torsional_friction: Torsional friction coefficient [m] of soft fingers; 0 = hard fingers.

    Returns:
        The contact set; normals are the inward face normals at the samples.

    Raises:
        OgcpError: For a bad n, seed, mu, cone edges, radius or tolerance (each has a finite
            range, see :mod:`ogcp.planner.grasp.defaults`), for n contacts whose estimated memory
            exceeds this machine's, for an object outside the diagonals ogcp works at, or when
            too little of the surface is reachable by the tip to give n contacts. All are
            checked before anything of size n is allocated.
    """
    import trimesh.sample

    from ogcp.planner.grasp.reach import fill_outer, fill_reachable, reach_settings

    _check_sampling(mesh, n, seed, mu, cone_edges, tip_radius, torsional_friction)
    n, seed = int(n), int(seed)
    reach = reach_settings(tip_radius, reach_tolerance)
    # trimesh logs a warning when even sampling falls short; the shortfall is filled below.
    trimesh_log = logging.getLogger("trimesh")
    level = trimesh_log.level
    trimesh_log.setLevel(logging.ERROR)
    try:
        points, faces = trimesh.sample.sample_surface_even(mesh, n, seed=np.random.default_rng([seed, 0]))
    finally:
        trimesh_log.setLevel(level)
    points, faces = np.asarray(points)[:n], np.asarray(faces)[:n]
    if len(points) < n:
        extra_p, extra_f = trimesh.sample.sample_surface(mesh, n - len(points), seed=np.random.default_rng([seed, 1]))
        points = np.vstack([points, extra_p])
        faces = np.concatenate([faces, extra_f])
    if reach is not None:
        points, faces = fill_reachable(mesh, points, faces, seed, *reach)
    else:  # still only where a finger can touch: not on a shell inside another
        points, faces = fill_outer(mesh, points, faces, seed)
    com, rho = mass_properties(mesh)
    record = dict(source or {})
    record.update({"sampling": EVEN_SAMPLING, "n": n, "seed": seed})
    if reach is not None:
        # Only reach-aware sets carry these keys, so records of plain sets are unchanged.
        record.update({"tip_radius": reach[0], "reach_tolerance": reach[1]})
    return ContactSet(points, -mesh.face_normals[faces], com, rho, mu, cone_edges, record, float(torsional_friction))
