"""Evaluate grasps from any planner (``ogcp.grasps/1``) with ogcp's Q1, physics and metrics.

The grasps' contacts become one :class:`~ogcp.planner.grasp.contact_set.ContactSet` (the union of
every grasp's contacts, in the record's order) with ogcp's conventions: the COM and the torque
scale rho of :func:`~ogcp.planner.grasp.contact_set.mass_properties` (as
:func:`~ogcp.planner.grasp.contact_set.sample_contacts` sets them), the record's mu and cone edges.
Each grasp indexes its own contacts there, and :class:`~ogcp.sim_eval.evaluate.GraspEvaluator`
simulates them exactly as it simulates a plan's, so an ogcp plan exported with
:func:`~ogcp.sim_eval.inputs.external_export.export_grasps` and evaluated here gives the plan's own numbers.

Contacts need not lie on the mesh exactly. Each one's signed distance from the surface and the
angle of its normal from the surface's inward normal there are measured and recorded; one
farther than :data:`SURFACE_TOLERANCE` of the fingertip radius is projected onto the surface
(with a warning) or refused (``on_surface="refuse"``). A contact farther than the tip radius
itself, or whose normal points out of the object, is refused either way: that is a unit, frame
or sign error, not a rounding.

Typical use::

    from ogcp.sim_eval import evaluate_grasps, load_grasps

    result = evaluate_grasps(None, load_grasps("mine.json"))  # the object named in the file
    print(result.to_dict()["object"]["external"]["grasps"][0])
"""

from __future__ import annotations

import dataclasses
import itertools
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.grasp.contact_set import DEFAULT_CONE_EDGES, DEFAULT_MU, ContactSet, mass_properties
from ogcp.planner.grasp.mesh_distance import SurfaceIndex
from ogcp.planner.grasp.quality import q1_certificate
from ogcp.planner.grasp.reach import REACH_TOLERANCE
from ogcp.planner.infra.errors import OgcpError, choice_error
from ogcp.planner.records.grasps import GRASPS_SCHEMA, ExternalGrasps
from ogcp.sim_eval.decomposition.decompose import DecompositionSettings
from ogcp.sim_eval.evaluate import GraspEvaluator, object_diagonal, tip_radius
from ogcp.sim_eval.hand.given import GivenPose, resolve_pose
from ogcp.sim_eval.result import SimResult
from ogcp.sim_eval.settings import SimSettings

if TYPE_CHECKING:
    from ogcp.planner.hands.kinematics import HandKinematics

#: ``on_surface`` choices: what happens to a contact off the mesh's surface.
ON_SURFACE = ("project", "refuse")
#: A contact may lie this fraction of the fingertip radius off the surface and is simulated where
#: given: the cut depth reach-aware sampling allows (1 %, 0.08 mm at the default 8 mm tip).
SURFACE_TOLERANCE = REACH_TOLERANCE
#: Farther than this fraction of the tip radius, a contact is refused even by ``project``.
PROJECT_LIMIT = 1.0
#: ``source["sampling"]`` of a contact set built from external grasps.
EXTERNAL_SAMPLING = "external"


class OffSurfaceWarning(UserWarning):
    """Contacts of external grasps were off the object's surface and were projected onto it."""


@dataclass(frozen=True, eq=False)
class SurfaceFit:
    """Where given contacts lie relative to the object's surface.

    Attributes:
        positions: The contacts as simulated (projected where they were moved), shape (N, 3) [m].
        distance: Signed distance of each given contact from the surface, > 0 outside, shape (N,) [m].
        normal_angle: Angle between each given normal and the surface's inward normal at the
            nearest surface point, shape (N,) [deg].
        projected: Whether each contact was moved onto the surface, shape (N,).
        tolerance: Distance a contact may have and stay where given [m].
    """

    positions: NDArray[np.float64]
    distance: NDArray[np.float64]
    normal_angle: NDArray[np.float64]
    projected: NDArray[np.bool_]
    tolerance: float


def surface_fit(
    mesh: trimesh.Trimesh,
    positions: ArrayLike,
    normals: ArrayLike,
    radius: float,
    on_surface: str = "project",
    names: Sequence[str] | None = None,
) -> SurfaceFit:
    """Measure contacts against the surface; project or refuse those off it.

    Args:
        mesh: The object, outward faces [m].
        positions: Contact points, shape (N, 3) [m].
        normals: Inward unit normals, shape (N, 3).
        radius: The simulated fingertip radius [m]; the tolerances are fractions of it.
        on_surface: ``project`` or ``refuse`` contacts farther than the tolerance.
        names: Name of each contact in messages (default ``contact <i>``).

    Returns:
        The distances, angles and the positions to simulate.

    Raises:
        OgcpError: For an unknown ``on_surface``; a normal pointing out of the object; a contact
            farther than the tip radius; with ``refuse``, one farther than the tolerance.
    """
    if on_surface not in ON_SURFACE:
        raise choice_error("on_surface", on_surface, ON_SURFACE)
    points, inward = np.asarray(positions, dtype=float), np.asarray(normals, dtype=float)
    names = list(names) if names is not None else [f"contact {i}" for i in range(len(points))]
    nearest = SurfaceIndex(mesh).nearest(points)
    distance = np.where(nearest.outside, nearest.distance, -nearest.distance) + 0.0  # no -0.0 on the surface
    surface = -np.asarray(mesh.face_normals)[nearest.face]
    cosine = np.einsum("ij,ij->i", inward, surface) / np.linalg.norm(inward, axis=1)
    angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
    tolerance = SURFACE_TOLERANCE * radius

    def where(i: int) -> str:
        side = "outside" if distance[i] > 0 else "inside"
        return f"{names[i]}.position is {abs(distance[i]) * 1e3:.4g} mm {side} the object's surface"

    far = np.abs(distance) > tolerance
    i = int(np.argmax(np.abs(distance)))
    count = f"{int(far.sum())} contact(s) beyond {tolerance * 1e3:.4g} mm"
    # First the distance beyond any rounding: with the wrong units or frame, the normals are
    # compared with faces that have nothing to do with them.
    if abs(distance[i]) > PROJECT_LIMIT * radius:
        raise OgcpError(
            f"{where(i)}, beyond the {radius * 1e3:.4g} mm fingertip radius ({count}): not a rounding of the "
            f"surface; {_units_hint(mesh, points, PROJECT_LIMIT * radius)}"
        )
    if (outward := np.flatnonzero(angle > 90.0)).size:
        j = int(outward[np.argmax(angle[outward])])
        raise OgcpError(
            f"{names[j]}.normal points out of the object ({angle[j]:.1f} deg from the surface's inward normal; "
            f"{outward.size} such contact(s)): ogcp.grasps/1 normals point into the object, negate them"
        )
    if far.any() and on_surface == "refuse":
        raise OgcpError(
            f"{where(i)} (tolerance {tolerance * 1e3:.4g} mm, {SURFACE_TOLERANCE:.0%} of the {radius * 1e3:.4g} mm "
            f"fingertip radius; {count}); on_surface='project' moves contacts within the tip radius onto it"
        )
    if far.any():
        warnings.warn(
            f"projected {int(far.sum())} of {len(points)} contacts onto the object's surface; farthest: {where(i)} "
            f"(tolerance {tolerance * 1e3:.4g} mm, {SURFACE_TOLERANCE:.0%} of the {radius * 1e3:.4g} mm fingertip "
            "radius); the distances are recorded",
            OffSurfaceWarning,
            stacklevel=2,
        )
    # Contacts within the tolerance are kept bit for bit: an exported ogcp plan stays the plan.
    simulated = np.where(far[:, None], nearest.point, points)
    return SurfaceFit(simulated, distance, angle, far, tolerance)


@dataclass(frozen=True, eq=False)
class ExternalInput:
    """External grasps ready to simulate.

    Attributes:
        mesh: The object [m].
        contacts: Every grasp's contacts in one set, in the record's order.
        grasps: Each grasp's indices into ``contacts``.
        labels: Each grasp's label.
        fit: The contacts' distances and angles from the surface.
        q1: ogcp's Q1 of each grasp at the simulated contacts [-].
        external: The grasps as given.
        radius: The fingertip radius the tolerances are fractions of [m].
        poses: Per grasp, the hand as the record posed it, or None (fingertips, or fitted by ogcp).
    """

    mesh: trimesh.Trimesh
    contacts: ContactSet
    grasps: tuple[tuple[int, ...], ...]
    labels: tuple[str, ...]
    fit: SurfaceFit
    q1: tuple[float, ...]
    external: ExternalGrasps
    radius: float
    poses: tuple[GivenPose | None, ...] = ()

    def record(self, on_surface: str) -> dict[str, Any]:
        """The ``external`` block of the ``ogcp.sim/2`` record's object: per grasp its label,
        method, score, Q1 and contact distances [m] and angles [deg]."""
        entries = []
        for i, (grasp, given) in enumerate(zip(self.grasps, self.external.grasps, strict=True)):
            idx = list(grasp)
            entries.append(
                {
                    "index": i,
                    "label": given.label,
                    "method": self.external.method_of(given),
                    "score": given.score,
                    "q1": self.q1[i],
                    "contacts": idx,
                    "surface_distance": self.fit.distance[idx].tolist(),
                    "normal_angle": self.fit.normal_angle[idx].tolist(),
                    "projected": self.fit.projected[idx].tolist(),
                }
            )
        return {
            "mu": self.contacts.mu,
            "cone_edges": self.contacts.cone_edges,
            "contact_model": self.contacts.contact_model,
            "torsional_friction": self.contacts.torsional_friction,
            "on_surface": on_surface,
            "tip_radius": self.radius,
            "surface_tolerance": self.fit.tolerance,
            "max_surface_distance": float(np.max(np.abs(self.fit.distance))),
            "max_normal_angle": float(np.max(self.fit.normal_angle)),
            "n_projected": int(self.fit.projected.sum()),
            "grasps": entries,
        }


def external_input(
    mesh: trimesh.Trimesh,
    grasps: ExternalGrasps,
    radius: float,
    on_surface: str = "project",
    source: dict[str, Any] | None = None,
    hand: HandKinematics | None = None,
) -> ExternalInput:
    """Measure, project or refuse the contacts, and build the contact set the grasps index.

    Args:
        mesh: The object, in the grasps' frame [m].
        grasps: The grasps.
        radius: The simulated fingertip radius [m].
        on_surface: ``project`` or ``refuse`` contacts off the surface (see :func:`surface_fit`).
        source: Description of the object, recorded in the set's source.
        hand: The record's hand, compiled (required when a grasp has a ``hand`` block): a grasp
            without contacts gets its chosen pads' points and normals.

    Raises:
        OgcpError: See :func:`surface_fit` and :func:`~ogcp.sim_eval.hand.given.resolve_pose`,
            and for a mesh ogcp cannot take mass properties of.
    """
    poses: list[GivenPose | None] = []
    given_points, given_normals = [], []
    where = "grasps" if grasps.path is None else str(grasps.path)
    for i, g in enumerate(grasps.grasps):
        points, normals_i = g.positions, g.normals
        if g.hand is not None:
            if hand is None:
                raise OgcpError(f"{where}: grasps[{i}].hand: simulating a posed hand needs the record's hand")
            own = g.positions if len(g.positions) else None
            pose, pads, pad_normals = resolve_pose(hand, g.hand, mesh, f"{where}: grasps[{i}].hand", own)
            poses.append(pose)
            if own is None:
                points, normals_i = pads, pad_normals
        else:
            poses.append(None)
        given_points.append(points)
        given_normals.append(normals_i)
    positions = np.vstack(given_points)
    normals = np.vstack(given_normals)
    names = [f"grasps[{i}].contacts[{j}]" for i, p in enumerate(given_points) for j in range(len(p))]
    fit = surface_fit(mesh, positions, normals, radius, on_surface, names)
    com, rho = mass_properties(mesh)
    file = None if grasps.path is None else str(grasps.path)
    origin = {"sampling": EXTERNAL_SAMPLING, "schema": GRASPS_SCHEMA, "file": file}
    contacts = ContactSet(
        fit.positions,
        normals,
        com,
        rho,
        grasps.mu,
        grasps.cone_edges,
        {**(source or {}), **origin},
        grasps.torsional_friction,
    )
    sizes = np.cumsum([0] + [len(p) for p in given_points])
    indices = tuple(tuple(range(int(a), int(b))) for a, b in itertools.pairwise(sizes.tolist()))
    q1 = tuple(q1_certificate(contacts.subset_wrenches(np.asarray(g, dtype=np.intp))).q1 for g in indices)
    labels = tuple(g.label for g in grasps.grasps)
    return ExternalInput(mesh, contacts, indices, labels, fit, q1, grasps, radius, tuple(poses))


def evaluate_grasps(
    mesh: trimesh.Trimesh | None,
    grasps: ExternalGrasps | Sequence[tuple[ArrayLike, ArrayLike]],
    settings: SimSettings | dict[str, Any] | None = None,
    decomposition: DecompositionSettings | dict[str, Any] | None = None,
    *,
    mu: float | None = None,
    cone_edges: int | None = None,
    labels: Sequence[str] | None = None,
    on_surface: str = "project",
    progress: bool = False,
    max_grasps: int | None = None,
    source: dict[str, Any] | None = None,
    tips: bool = False,
) -> SimResult:
    """Simulate grasps from any planner, with ogcp's Q1 conventions and physics.

    Args:
        mesh: The object [m], in the grasps' frame; None: the object the record names.
        grasps: A loaded ``ogcp.grasps/1`` record, or per grasp ``(positions (m, 3) [m],
            inward unit normals (m, 3))``; grasps may differ in m.
        settings: Simulation settings or a mapping of them.
        decomposition: Decomposition settings or a mapping of them.
        mu: Friction coefficient of array grasps (default :data:`DEFAULT_MU`); a record has its own.
        cone_edges: Cone edges k of array grasps (default :data:`DEFAULT_CONE_EDGES`).
        labels: Labels of array grasps (default ``grasp-<i>``).
        on_surface: ``project`` (default; with an :class:`OffSurfaceWarning`) or ``refuse``
            contacts farther from the surface than :data:`SURFACE_TOLERANCE` x the tip radius.
        progress: Show progress bars on stderr.
        max_grasps: Simulate at most this many grasps, in the given order.
        source: Description of a given ``mesh``, recorded as the result's object.
        tips: Simulate fingertip spheres even when the record names a hand (its posed grasps
            then need contacts, or give their pads' points).

    Returns:
        The ``ogcp.sim/2`` result; its ``object["external"]`` holds each grasp's label, method,
        score, ogcp's Q1, and its contacts' surface distances [m] and normal angles [deg].

    Raises:
        OgcpError: For bad grasps or settings, mu, k or labels given next to a record (it has
            its own), an object that cannot be loaded, or contacts off the surface (see
            :func:`surface_fit`).
    """
    if isinstance(grasps, ExternalGrasps):
        if mu is not None or cone_edges is not None or labels is not None:
            raise OgcpError("mu, cone_edges and labels come from the grasps record; do not pass them too")
        external = grasps
    else:
        k = DEFAULT_CONE_EDGES if cone_edges is None else cone_edges
        external = ExternalGrasps.from_arrays(grasps, DEFAULT_MU if mu is None else mu, k, labels)
    if max_grasps is not None:
        if isinstance(max_grasps, bool) or not isinstance(max_grasps, int) or max_grasps < 1:
            raise OgcpError(f"max_grasps must be a positive integer, got {max_grasps!r}")
        external = dataclasses.replace(external, grasps=external.grasps[:max_grasps])
    if mesh is None:
        mesh, described = external.load_object()
        source = {**described, **(source or {})}
    if not isinstance(settings, SimSettings):
        settings = SimSettings.from_dict(settings)
    if decomposition is not None and not isinstance(decomposition, DecompositionSettings):
        decomposition = DecompositionSettings(**dict(decomposition))
    radius = tip_radius(mesh, settings.scaled(object_diagonal(mesh)))
    kinematics = setup = None
    if external.hand_spec is not None:
        from ogcp.planner.hands.kinematics import HandKinematics
        from ogcp.planner.hands.registry import resolve_hand
        from ogcp.sim_eval.hand.setup import HandSetup

        kinematics = HandKinematics(resolve_hand(external.hand_spec))
        setup = None if tips else HandSetup.of(kinematics)
    given = external_input(mesh, external, radius, on_surface, source, kinematics)
    evaluator = GraspEvaluator(settings, decomposition, progress=progress, hand=setup)
    poses = given.poses if setup is not None else None
    result = evaluator.evaluate(mesh, given.contacts, given.grasps, given.labels, poses=poses)
    return dataclasses.replace(result, object={**result.object, "external": given.record(on_surface)})


def _units_hint(mesh: trimesh.Trimesh, points: NDArray[np.float64], reach: float) -> str:
    """What to check when contacts are far off the surface: millimetres, when they fit once divided by 1000."""
    scaled = SurfaceIndex(mesh).nearest(points / 1000.0)
    if float(np.max(scaled.distance)) <= reach:
        return "the positions look like millimetres: ogcp.grasps/1 positions are in metres, divide them by 1000"
    return "are the units metres and the frame the mesh's?"
