"""Fig. 10: the Schunk SDH on the optimal reachable grasp of each object.

The plan record's ``hand`` block holds the joint angles of the reachability model's nearest sample
and the contact each finger takes (:class:`ogcp.planner.records.plan.PlanHand`); it holds no hand pose,
since the model matches the fingertips' *shape* (pairwise distances and normal differences), not
their place. Placed rigidly (:func:`palm_pose`), those angles leave the fingertips 14-24 mm off
their contacts. The figure draws the refined pose instead (:func:`ogcp.planner.hands.fit.fit_hand`):
joint angles within their limits and the palm pose, solved from the recorded angles so that each
finger's end sphere touches its contact from outside, pad towards the surface. Each panel's title
gives the largest distance of a refined fingertip from its contact and the rigid fit's, and
:data:`HAND_FITS` keeps the last figure's fits with the distance of every finger. Fingers and palm
are capsules and a cylinder rasterised with the object (:mod:`ogcp.benchmarks.plots.raster`), so each
hides the other correctly. The fit has no collision terms: the title says when fingers touch each
other, and the hand is not kept out of the object.
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.hands.fit import HandFit, fit_hand, rigid_fit
from ogcp.planner.hands.reachability import LINK_CLEARANCE, finger_chain, pad_normals
from ogcp.planner.hands.sdh import FINGER_BASES, PALM_HEIGHT
from ogcp.planner.records.plan import PlanHand
from ogcp.sim_eval.plan_input import PlanInput

from .data import CellData, RunData, SkipFigure
from .grasp_figures import CONTACT_COLOUR, NoGraspCells, best_view, panel_grid, rebuilt_panels
from .raster import fit_view, merge_meshes, render_mesh, sphere_mesh, tube_mesh
from .style import method_colour, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Radius of the drawn finger links [m]: the reachability model's collision capsules.
LINK_RADIUS = LINK_CLEARANCE / 2
#: Radius of the drawn palm cylinder [m], just around the finger bases.
PALM_RADIUS = 0.048
#: How far along the normals the pose fit also matches the fingertips [m]: it turns the pads
#: towards the surface, not only the tips onto it.
NORMAL_REACH = 0.03
HAND_COLOUR = (0.42, 0.47, 0.56)
#: Seconds spent drawing each panel of the last figure.
RENDER_SECONDS: list[float] = []


@dataclasses.dataclass(frozen=True)
class PanelFit:
    """How one panel's hand was posed.

    Attributes:
        title: The panel's problem and cell.
        rigid_misfit: Largest fingertip distance from its target at the recorded angles, rigidly placed [m].
        fit: The refined pose that is drawn; its ``residuals`` are per finger [m].
    """

    title: str
    rigid_misfit: float
    fit: HandFit


#: The hand fits of the last figure's panels, in panel order.
HAND_FITS: list[PanelFit] = []


class NoHandCells(NoGraspCells):
    """The run has no cell with an SDH record: left out without a note unless asked for by name."""


def hand_cells(data: RunData) -> list[tuple[CellData, PlanHand]]:
    """Per problem, its best-Q1 cell whose plan records an SDH configuration (A* first).

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
            if hand is None or hand.name != "sdh" or cell.plan_view.grasp is None:
                continue
            if len(hand.joint_angles) == 7 and len(hand.finger_contacts) == 3:
                found.append((cell.method != "astar", -(cell.q1 or 0.0), cell.label, cell, hand))
        if found:
            best = min(found, key=lambda f: f[:3])
            chosen.append((best[3], best[4]))
    return chosen


def palm_pose(
    angles: NDArray[np.float64], points: NDArray[np.float64], normals: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """The palm pose that best puts the fingertips on the contacts (least squares, Kabsch).

    Args:
        angles: Joint angles, shape (7,) [rad].
        points: Each finger's contact, fingers in the SDH order, shape (3, 3) [m].
        normals: Their inward normals, shape (3, 3).

    Returns:
        Rotation (3, 3) and translation (3,) from the palm frame to the world [m], and the largest
        distance of a fingertip's sphere centre from where it should be [m].
    """
    tips = finger_chain(angles)[0, :, 2]
    pads = pad_normals(angles)[0]
    # The finger's axis ends one link radius outside the surface, its pad facing along the normal.
    targets = points - LINK_RADIUS * normals
    source = np.vstack([tips, tips + NORMAL_REACH * pads])
    target = np.vstack([targets, targets + NORMAL_REACH * normals])
    rotation, translation = rigid_fit(source, target)
    misfit = float(np.linalg.norm(tips @ rotation.T + translation - targets, axis=1).max())
    return rotation, translation, misfit


def hand_mesh(angles: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Palm cylinder and finger capsules of a configuration, in the palm frame.

    Args:
        angles: Joint angles, shape (7,) [rad].

    Returns:
        Vertices, shape (v, 3) [m], and triangles, shape (f, 3).
    """
    chain = finger_chain(angles)[0]  # (finger, [proximal axis, distal axis, tip], 3)
    parts = [tube_mesh([0.0, 0.0, 0.0], [0.0, 0.0, PALM_HEIGHT], PALM_RADIUS, sides=24)]
    for base, (proximal, distal, tip) in zip(FINGER_BASES, chain, strict=True):
        for start, end in ((base, proximal), (proximal, distal), (distal, tip)):
            parts.append(tube_mesh(start, end, LINK_RADIUS))
        for joint in (proximal, distal, tip):
            parts.append(sphere_mesh(joint, LINK_RADIUS))
    return merge_meshes(parts)


@styled
def fig10_sdh_grasps(data: RunData, notes: list[str] | None = None) -> Figure:
    """Fig. 10: the SDH, its recorded joint angles refined, on each object's best reachable grasp.

    Args:
        data: The run.
        notes: Gets one line per cell whose object or contact set cannot be rebuilt.

    Returns:
        The figure, one panel per problem with an SDH cell, at most three per row.

    Raises:
        NoHandCells: No cell records an SDH configuration.
        SkipFigure: No such cell's plan could be rebuilt.
    """
    cells = hand_cells(data)
    if not cells:
        raise NoHandCells('needs cells planned with hand = "sdh"')
    names = data.problem_names()
    inputs = rebuilt_panels(data, cells, "fig10_sdh_grasps", notes)
    if not inputs:
        raise SkipFigure("no SDH cell's object and contact set could be rebuilt")
    figure, axes, pixels = panel_grid(len(inputs))
    RENDER_SECONDS.clear()
    HAND_FITS.clear()
    for ax, (cell, hand, rebuilt) in zip(axes, inputs, strict=True):
        started = time.perf_counter()
        posed = draw_hand(ax, rebuilt, hand, method_colour(cell.method), pixels)
        RENDER_SECONDS.append(time.perf_counter() - started)
        HAND_FITS.append(dataclasses.replace(posed, title=f"{names[cell.problem]}: {cell.label}"))
        quality = f", $Q_1$={cell.q1:.3f}" if cell.q1 is not None else ""
        ax.set_title(f"{names[cell.problem]}: {cell.label}{quality}\n{fit_caption(posed)}")
    return figure


def fit_caption(posed: PanelFit) -> str:
    """One short line on the drawn pose: the largest fingertip distance from its contact, and the rigid fit's."""
    clash = ", fingers touch" if not posed.fit.collision_free else ""
    return f"tips within {posed.fit.max_residual * 1e3:.1f} mm (rigid: {posed.rigid_misfit * 1e3:.0f} mm){clash}"


def draw_hand(ax: Axes, rebuilt: PlanInput, hand: PlanHand, colour: str, pixels: int = 800) -> PanelFit:
    """Draw the object, the grasp's contacts and the hand in its refined pose into ``ax``.

    Args:
        ax: The panel (its axis frame is switched off).
        rebuilt: Mesh and contact set of the plan.
        hand: The plan's hand block (7 joint angles, 3 finger contacts).
        colour: Colour of the grasp's contacts.
        pixels: Side of the square rendered image [px].

    Returns:
        The drawn pose (title left empty) with the recorded angles' rigid misfit.
    """
    mesh, contacts = rebuilt.mesh, rebuilt.contacts
    angles = np.asarray(hand.joint_angles, dtype=float)
    index = np.asarray(hand.finger_contacts, dtype=int)
    points, normals = contacts.positions[index], contacts.normals[index]
    _, _, misfit = palm_pose(angles, points, normals)
    fit = fit_hand(points, normals, angles, offset=LINK_RADIUS)
    vertices, faces = hand_mesh(fit.joint_angles)
    vertices = fit.to_world(vertices)
    camera = best_view(mesh.vertices, mesh.faces, points, normals, occluder=(vertices, faces))
    view = fit_view(np.vstack([mesh.vertices, vertices]), camera, pixels, pixels)
    scene = render_mesh(mesh.vertices, mesh.faces, view).over(render_mesh(vertices, faces, view, HAND_COLOUR))
    ax.imshow(scene.rgba, extent=(0, pixels, pixels, 0), interpolation="antialiased", zorder=1)
    diagonal = float(np.linalg.norm(mesh.bounds[1] - mesh.bounds[0]))
    # Contacts under a fingertip are hidden by it, as they should be; the others show.
    shown = scene.visible(points, 0.005 * diagonal)
    where = view.project(points)
    ax.scatter(where[shown, 0], where[shown, 1], s=12, c=colour, edgecolors=CONTACT_COLOUR, linewidths=0.6, zorder=4)
    ax.set_xlim(0, pixels)
    ax.set_ylim(pixels, 0)
    ax.set_aspect("equal")
    ax.axis("off")
    return PanelFit("", misfit, fit)
