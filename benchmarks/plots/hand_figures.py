"""Fig. 10: each plan's hand on its best reachable grasp, for any hand: as it settled in simulation, else fitted.

A cell simulated with its hand (a suite with ``simulate``) records the hand as it settled on the
object (``hand.settled_joint_angles`` and the palm pose): the figure draws that. Where the
simulation's fit, which keeps the hand's links out of the object, found the grasp unreachable, the
figure draws that fit's pose (``hand.fit``) and says so. Otherwise the plan
record's ``hand`` block holds the reachability model's nearest sampled configuration and
the contact each finger takes (:class:`ogcp.planner.records.plan.PlanHand`); it holds no palm pose,
since the model matches the pads' rigid invariants, not their place. The figure fits the hand to
the contacts (:func:`ogcp.sim_eval.hand.fit.fit_hand`: joint angles within their limits and the
palm pose, from the recorded configuration and the next nearest samples) and draws every
colliding geom of the hand's MuJoCo model in that pose, rasterised with the object
(:mod:`ogcp.benchmarks.plots.raster`), so each hides the other correctly. Each panel's title gives
the largest pad residual; :data:`HAND_FITS` keeps the last figure's fits. The fit here checks the
hand against itself but not against the object (that needs the object's convex decomposition;
the simulation's fit does).
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.reachability import HandReachability
from ogcp.planner.hands.registry import resolve_hand
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.records.plan import PlanHand
from ogcp.sim_eval.hand.fit import HandFit, fit_hand, measure_pose
from ogcp.sim_eval.hand.fit_result import LINK_TOLERANCE, RESIDUAL_TOLERANCE
from ogcp.sim_eval.hand.fit_scene import FitScene
from ogcp.sim_eval.hand.geometry import posed_triangles
from ogcp.sim_eval.inputs.plan_input import PlanInput

from .data import CellData, RunData, SkipFigure
from .grasp_figures import CONTACT_COLOUR, NoGraspCells, best_view, panel_grid, rebuilt_panels
from .raster import fit_view, render_mesh
from .style import method_colour, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Sampled configurations a panel's fit starts from, nearest first, until one is realised.
FIT_STARTS = 8
HAND_COLOUR = (0.42, 0.47, 0.56)
#: Seconds spent drawing each panel of the last figure.
RENDER_SECONDS: list[float] = []


@dataclasses.dataclass(frozen=True)
class PanelFit:
    """How one panel's hand was posed.

    Attributes:
        title: The panel's problem and cell.
        fit: The pose that is drawn; its ``residuals`` are per chosen finger [m].
        how: ``settled`` (as the hand settled in simulation), ``unreachable`` (the simulation's fit
            of a grasp it found unreachable) or ``fitted`` (fitted here, the object left out).
        inside: How deep the simulation's fit put a link inside the object [m] (``unreachable``).
    """

    title: str
    fit: HandFit
    how: str = "fitted"
    inside: float = 0.0

    @property
    def settled(self) -> bool:
        """Whether the pose is the one the hand settled in, in simulation."""
        return self.how == "settled"


#: The hand fits of the last figure's panels, in panel order.
HAND_FITS: list[PanelFit] = []


class NoHandCells(NoGraspCells):
    """The run has no cell with a hand record: left out without a note unless asked for by name."""


def hand_cells(data: RunData) -> list[tuple[CellData, PlanHand]]:
    """Per problem, its best-Q1 cell whose plan records a hand configuration (A* first).

    Args:
        data: The run.

    Returns:
        (cell, hand block) per problem that has one, problems in order of first appearance.
    """
    chosen = []
    for cells in data.by_problem().values():
        found = []
        for cell in cells:
            hand = cell.plan_view.hand
            if hand is None or cell.plan_view.grasp is None or not hand.joint_angles or not hand.finger_contacts:
                continue
            found.append((cell.method != "astar", -(cell.q1 or 0.0), cell.label, cell, hand))
        if found:
            best = min(found, key=lambda f: f[:3])
            chosen.append((best[3], best[4]))
    return chosen


def hand_of(record: PlanHand) -> HandKinematics:
    """The recorded hand, compiled: its descriptor path, else its built-in name (older plans).

    Raises:
        OgcpError: If the hand cannot be found, or its descriptor changed since the plan.
    """
    source = record.descriptor or record.name
    if source is None:
        raise OgcpError("the plan's hand block names no hand")
    descriptor = resolve_hand(source)
    if record.descriptor_sha256 is not None and descriptor.sha256 != record.descriptor_sha256:
        raise OgcpError(f"hand descriptor {descriptor.path} changed since the plan (its sha256 differs)")
    return HandKinematics(descriptor)


@styled
def fig10_hand_grasps(data: RunData, notes: list[str] | None = None) -> Figure:
    """Fig. 10: each problem's hand, fitted to its best reachable grasp.

    Args:
        data: The run.
        notes: Gets one line per cell whose object, contact set or hand cannot be rebuilt.

    Returns:
        The figure, one panel per problem with a hand cell, at most three per row.

    Raises:
        NoHandCells: No cell records a hand configuration.
        SkipFigure: No such cell's plan could be rebuilt.
    """
    cells = hand_cells(data)
    if not cells:
        raise NoHandCells('needs cells planned with a hand (hand = "sdh" or a descriptor)')
    names = data.problem_names()
    inputs = rebuilt_panels(data, cells, "fig10_hand_grasps", notes)
    hands = []
    for cell, hand, rebuilt in inputs:
        try:
            hands.append((cell, hand, rebuilt, hand_of(hand)))
        except OgcpError as exc:
            if notes is not None:
                notes.append(f"fig10_hand_grasps: {cell.label}: {exc}")
    if not hands:
        raise SkipFigure("no hand cell's object, contact set and hand could be rebuilt")
    figure, axes, pixels = panel_grid(len(hands))
    RENDER_SECONDS.clear()
    HAND_FITS.clear()
    for ax, (cell, hand, rebuilt, kinematics) in zip(axes, hands, strict=True):
        started = time.perf_counter()
        settled = simulated_pose(cell, hand)
        posed = draw_hand(ax, rebuilt, hand, kinematics, method_colour(cell.method), pixels, settled)
        RENDER_SECONDS.append(time.perf_counter() - started)
        HAND_FITS.append(dataclasses.replace(posed, title=f"{names[cell.problem]}: {cell.label}"))
        quality = f", $Q_1$={cell.q1:.3f}" if cell.q1 is not None else ""
        ax.set_title(f"{names[cell.problem]}: {cell.label}{quality}\n{fit_caption(posed)}")
    return figure


def fit_caption(posed: PanelFit) -> str:
    """One short line on the drawn pose: settled, unreachable or fitted, the largest pad distance
    from its contact, collisions."""
    clash = ", links touch" if posed.fit.self_penetration > 0 else ""
    if posed.inside > 0:
        clash = f", a link {posed.inside * 1e3:.1f} mm in the object{clash}"
    how = {"unreachable": "unreachable in simulation"}.get(posed.how, posed.how)
    return f"{how}, pads within {posed.fit.residuals.max() * 1e3:.1f} mm{clash}"


@dataclasses.dataclass(frozen=True, eq=False)
class SettledHand:
    """The hand as the simulation left it: settled, or fitted to a grasp it found unreachable.

    Attributes:
        pose: Joint angles (J,), palm rotation (3, 3) and palm position (3,) [m].
        finger_contacts: The contact each chosen finger took, in the fingers' order.
        how: ``settled`` or ``unreachable``.
        inside: How deep the simulation's fit put a link inside the object [m] (0 when settled).
    """

    pose: tuple[np.ndarray, np.ndarray, np.ndarray]
    finger_contacts: tuple[int, ...]
    how: str = "settled"
    inside: float = 0.0


def simulated_pose(cell: CellData, hand: PlanHand) -> SettledHand | None:
    """The hand as the simulation left the cell's grasp: as it settled, or, for a grasp it found
    unreachable, as its fit (with the object) posed it; None when the cell was not simulated with
    its hand (or its record lacks the pose)."""
    if cell.simulation is None:
        return None
    wanted = sorted(int(i) for i in hand.finger_contacts)
    for grasp in cell.simulation.grasps:
        block = grasp.hand or {}
        if grasp.grasp is None or sorted(grasp.grasp) != wanted:
            continue
        recorded = block.get("fit")
        fit: dict[str, Any] = recorded if isinstance(recorded, dict) else {}
        if "settled_joint_angles" in block:
            keys, source, how = ("settled_joint_angles", "palm_rotation", "palm_position"), dict(block), "settled"
        elif fit.get("realised") is False and "joint_angles" in fit:
            keys, source, how = ("joint_angles", "palm_rotation", "palm_position"), fit, "unreachable"
        else:
            continue
        try:
            angles, rotation, position = (np.asarray(source[k], dtype=float) for k in keys)
            order = tuple(int(i) for i in block.get("finger_contacts") or hand.finger_contacts)
            inside = float(fit.get("penetration") or 0.0) if how == "unreachable" else 0.0
        except (KeyError, TypeError, ValueError):
            return None
        tolerance = fit.get("tolerance")
        if isinstance(tolerance, (int, float)) and inside <= LINK_TOLERANCE * tolerance / RESIDUAL_TOLERANCE:
            inside = 0.0  # within the fit's link tolerance: not what made it unreachable
        if (
            rotation.shape == (3, 3)
            and position.shape == (3,)
            and np.isfinite(np.concatenate([angles, position, [inside]])).all()
        ):
            return SettledHand((angles, rotation, position), order, how, inside)
    return None


def fitted(kinematics: HandKinematics, hand: PlanHand, rebuilt: PlanInput) -> HandFit:
    """The hand fitted to the plan's contacts: from its recorded configuration, then the next nearest
    samples of the reachability model (:data:`FIT_STARTS` in all), until one fit is realised."""
    contacts = rebuilt.contacts
    grasp = tuple(int(i) for i in hand.finger_contacts)
    names = hand.fingers or kinematics.descriptor.finger_names[: len(grasp)]
    fingers = kinematics.descriptor.choose_fingers(len(grasp), names)
    scene = FitScene(kinematics)
    starts: list[tuple[tuple[int, ...], tuple[float, ...]]] = []
    if len(hand.joint_angles) == len(kinematics.joint_names):
        starts.append((grasp, hand.joint_angles))
    model = HandReachability(kinematics.descriptor, names)
    starts += [(tuple(grasp[i] for i in s.fingers), s.joint_angles) for s in model.starts(grasp, contacts, FIT_STARTS)]
    best: HandFit | None = None
    for order, angles in starts[:FIT_STARTS]:
        index = list(order)
        fit = fit_hand(scene, fingers, contacts.positions[index], contacts.normals[index], angles)
        if best is None or fit.residuals.max() < best.residuals.max():
            best = fit
        if fit.realised:
            break
    assert best is not None
    return best


def draw_hand(
    ax: Axes,
    rebuilt: PlanInput,
    hand: PlanHand,
    kinematics: HandKinematics,
    colour: str,
    pixels: int = 800,
    settled: SettledHand | None = None,
) -> PanelFit:
    """Draw the object, the grasp's contacts and the fitted hand into ``ax``.

    Args:
        ax: The panel (its axis frame is switched off).
        rebuilt: Mesh and contact set of the plan.
        hand: The plan's hand block (configuration, finger contacts).
        kinematics: The hand, compiled.
        colour: Colour of the grasp's contacts.
        pixels: Side of the square rendered image [px].
        settled: The hand as the simulation left it (:func:`simulated_pose`); None: fitted here.

    Returns:
        The drawn pose (title left empty).
    """
    mesh, contacts = rebuilt.mesh, rebuilt.contacts
    points, normals = contacts.positions[list(hand.finger_contacts)], contacts.normals[list(hand.finger_contacts)]
    if settled is not None and len(settled.pose[0]) == len(kinematics.joint_names):
        names = hand.fingers or kinematics.descriptor.finger_names[: len(points)]
        fingers = kinematics.descriptor.choose_fingers(len(points), names)
        order = list(settled.finger_contacts)
        fit = measure_pose(
            FitScene(kinematics), fingers, contacts.positions[order], contacts.normals[order], settled.pose
        )
    else:
        settled, fit = None, fitted(kinematics, hand, rebuilt)
    scene = FitScene(kinematics)
    scene.pose(fit.joint_angles, fit.rotation, fit.translation)
    vertices, faces = posed_triangles(scene.model, scene.data, scene.hand.geoms)
    camera = best_view(mesh.vertices, mesh.faces, points, normals, occluder=(vertices, faces))
    view = fit_view(np.vstack([mesh.vertices, vertices]), camera, pixels, pixels)
    image = render_mesh(mesh.vertices, mesh.faces, view).over(render_mesh(vertices, faces, view, HAND_COLOUR))
    ax.imshow(image.rgba, extent=(0, pixels, pixels, 0), interpolation="antialiased", zorder=1)
    diagonal = float(np.linalg.norm(mesh.bounds[1] - mesh.bounds[0]))
    # Contacts under a pad are hidden by it, as they should be; the others show.
    shown = image.visible(points, 0.005 * diagonal)
    where = view.project(points)
    ax.scatter(where[shown, 0], where[shown, 1], s=12, c=colour, edgecolors=CONTACT_COLOUR, linewidths=0.6, zorder=4)
    ax.set_xlim(0, pixels)
    ax.set_ylim(pixels, 0)
    ax.set_aspect("equal")
    ax.axis("off")
    if settled is None:
        return PanelFit("", fit)
    return PanelFit("", fit, settled.how, settled.inside)
