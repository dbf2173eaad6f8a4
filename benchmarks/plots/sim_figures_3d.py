"""Per-object picture of a simulated grasp: where the tips settled and which push broke the grasp.

For each problem, its simulated A* cell (else its first simulated cell) and that cell's grasp
labelled ``best`` (else its valid grasp of largest measured minimum): the mesh, the fingertips as
shaded spheres where they sat after preload and settling (``realized.settled_centres`` of an
``ogcp.sim/2`` record, :class:`ogcp.sim_eval.result.SimGraspRecord`: the state every disturbance trial
starts from), and the disturbance direction of least measured resistance as an arrow from the
centre of mass: straight for a force, an arc around the axis for a torque. Older records draw what
they have, and the title says so: records without settled centres put the spheres where the tips
started (on the realized contacts, ``tips at start positions``), ``ogcp.sim/1`` records without
realized contacts on the planned contacts (``tips at planned contacts``). The arrow's part inside
the object is drawn dashed.
"""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.sim_eval.inputs.plan_input import PlanInput
from ogcp.sim_eval.result import SimGraspRecord

from .data import CellData, RunData, SkipFigure
from .grasp_figures import NoGraspCells, best_view, panel_grid, rebuilt_panels
from .raster import Raster, fit_view, merge_meshes, render_mesh, sphere_mesh
from .style import method_colour, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Arrow length (and twice the torque arc's radius) as a fraction of the bounding-box diagonal.
ARROW_LENGTH = 0.45
ARROW_COLOUR = "#D55E00"
TIP_COLOUR = (0.90, 0.62, 0.0)
#: Title suffix per source of the drawn tip positions (see :func:`tip_centres`).
TIP_CAPTIONS = {"settled": "", "start": " (tips at start positions)", "planned": " (tips at planned contacts)"}


class NoSimulatedCells(NoGraspCells):
    """The run has no simulated grasp: left out without a note unless asked for by name."""


def simulated_grasps(data: RunData) -> list[tuple[CellData, SimGraspRecord]]:
    """Per problem, the simulated grasp to draw (see the module docstring).

    Args:
        data: The run.

    Returns:
        (cell, grasp record) per problem with a simulated grasp that has measured directions.
    """
    chosen = []
    for cells in data.by_problem().values():
        found = []
        for cell in cells:
            for g in cell.simulation.grasps if cell.simulation is not None else ():
                if g.grasp is None or not np.isfinite(g.measured).any() or len(g.directions) != len(g.measured):
                    continue
                key = (cell.method != "astar", g.label != "best", g.valid is not True, -(g.measured_min or 0.0))
                found.append((key, cell.label, cell, g))
        if found:
            best = min(found, key=lambda f: f[:2])
            chosen.append((best[2], best[3]))
    return chosen


@styled
def sim_grasps(data: RunData, notes: list[str] | None = None) -> Figure:
    """Settled fingertips and the weakest measured disturbance of one simulated grasp per object.

    Args:
        data: The run.
        notes: Gets one line per cell whose object cannot be rebuilt.

    Returns:
        The figure, one panel per problem with a simulated grasp, at most three per row.

    Raises:
        NoSimulatedCells: No cell has a simulated grasp with measured resistance.
        SkipFigure: No such cell's plan could be rebuilt.
    """
    picks = simulated_grasps(data)
    if not picks:
        raise NoSimulatedCells("needs simulated cells ([simulation] enabled = true) with measured resistance")
    names = data.problem_names()
    inputs = rebuilt_panels(data, picks, "sim_grasps", notes)
    if not inputs:
        raise SkipFigure("no simulated cell's object and contact set could be rebuilt")
    figure, axes, pixels = panel_grid(len(inputs))
    for ax, (cell, grasp, rebuilt) in zip(axes, inputs, strict=True):
        tips = draw_sim_grasp(ax, rebuilt, grasp, _tip_radius(cell, rebuilt), method_colour(cell.method), pixels)
        weakest = int(np.nanargmin(grasp.measured))
        bound = "≥" if len(grasp.censored) > weakest and grasp.censored[weakest] else "="
        where = TIP_CAPTIONS[tips]
        label = grasp.direction_labels[weakest]
        ax.set_title(
            f"{names[cell.problem]}: {cell.label} {grasp.label}{where}\n"
            f"weakest: {direction_name(label)} {bound} {grasp.measured[weakest]:.3g} {_unit(label)}"
        )
    return figure


def direction_name(label: str) -> str:
    """What a disturbance direction's label means, in words (``+fx`` -> ``force +x``, ``s22`` -> ``sphere dir. 22``)."""
    if len(label) == 3 and label[0] in "+-" and label[1] in "ft" and label[2] in "xyz":
        return f"{'force' if label[1] == 'f' else 'torque'} {label[0]}{label[2]}"
    if label == "q1-weakest":
        return "Q1's weakest direction"
    if label[:1] == "s" and label[1:].isdigit():
        return f"sphere dir. {int(label[1:])}"
    return label


def _unit(label: str) -> str:
    """Forces in N; any other direction's load is the size of a scaled wrench (torques / rho)."""
    return "N" if label[:2] in ("+f", "-f") else "N (scaled wrench)"


def _tip_radius(cell: CellData, rebuilt: PlanInput) -> float:
    """The simulated tip radius [m]: the record's setting, else its ratio of the diagonal."""
    settings = cell.simulation.settings if cell.simulation is not None else {}
    radius, ratio = settings.get("tip_radius"), settings.get("tip_radius_ratio")
    if isinstance(radius, (int, float)) and not isinstance(radius, bool) and radius > 0:
        return float(radius)
    if isinstance(ratio, (int, float)) and not isinstance(ratio, bool) and ratio > 0:
        return default_tip_radius(rebuilt.mesh, float(ratio))
    return default_tip_radius(rebuilt.mesh)


def tip_centres(
    grasp: SimGraspRecord, contacts: ContactSet, radius: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], str]:
    """Where to draw a simulated grasp's tips, and the contacts that aim the camera.

    Args:
        grasp: The simulated grasp (``grasp`` indices present).
        contacts: The plan's contact set.
        radius: Fingertip radius [m].

    Returns:
        Tip sphere centres (m, 3) [m], contact points (m, 3) [m], their inward normals (m, 3), and
        where the centres come from: ``settled`` (after preload and settling), ``start`` (on the
        realized contacts, before settling) or ``planned`` (on the planned contacts).
    """
    index = np.asarray(grasp.grasp, dtype=int)
    points = np.asarray(grasp.realized.get("points") or [], dtype=float).reshape(-1, 3)
    normals = np.asarray(grasp.realized.get("normals") or [], dtype=float).reshape(-1, 3)
    if points.shape != (len(index), 3) or normals.shape != points.shape:
        points, normals = contacts.positions[index], contacts.normals[index]
        return points - radius * normals, points, normals, "planned"
    settled = np.asarray(grasp.realized.get("settled_centres") or [], dtype=float).reshape(-1, 3)
    if settled.shape == points.shape and np.isfinite(settled).all():
        return settled, points, normals, "settled"
    return points - radius * normals, points, normals, "start"  # inward normals: the tip sits outside


def draw_sim_grasp(
    ax: Axes, rebuilt: PlanInput, grasp: SimGraspRecord, radius: float, colour: str, pixels: int = 800
) -> str:
    """Draw the object, the tip spheres and the weakest disturbance into ``ax``.

    Args:
        ax: The panel (its axis frame is switched off).
        rebuilt: Mesh and contact set of the plan.
        grasp: The simulated grasp (``grasp`` indices and measured directions present).
        radius: Fingertip radius [m].
        colour: Unused by the spheres (they keep one colour); outlines the arrow's head.
        pixels: Side of the square rendered image [px].

    Returns:
        Where the tips were drawn: ``settled``, ``start`` or ``planned`` (see :func:`tip_centres`).
    """
    mesh = rebuilt.mesh
    centres, points, normals, source = tip_centres(grasp, rebuilt.contacts, radius)
    diagonal = float(np.linalg.norm(mesh.bounds[1] - mesh.bounds[0]))
    com = np.asarray(mesh.center_mass if mesh.is_watertight else mesh.bounds.mean(axis=0), dtype=float)
    path = _arrow_path(grasp.directions[int(np.nanargmin(grasp.measured))], com, ARROW_LENGTH * diagonal)
    tips = merge_meshes([sphere_mesh(c, radius, rings=12) for c in centres])
    camera = best_view(mesh.vertices, mesh.faces, points, normals)
    view = fit_view(np.vstack([mesh.vertices, tips[0], path]), camera, pixels, pixels)
    scene = render_mesh(mesh.vertices, mesh.faces, view).over(render_mesh(*tips, view, TIP_COLOUR))
    ax.imshow(scene.rgba, extent=(0, pixels, pixels, 0), interpolation="antialiased", zorder=1)
    _draw_path(ax, scene, path, colour)
    ax.set_xlim(0, pixels)
    ax.set_ylim(pixels, 0)
    ax.set_aspect("equal")
    ax.axis("off")
    return source


def _arrow_path(direction: NDArray[np.float64], com: NDArray[np.float64], length: float) -> NDArray[np.float64]:
    """Points of the disturbance arrow, shape (k, 3) [m]: a segment for a force, an arc for a torque.

    A direction mixes force and (scaled) torque; the larger part decides which is drawn.
    """
    force, torque = direction[:3], direction[3:]
    if np.linalg.norm(force) >= np.linalg.norm(torque):
        return np.vstack([com, com + length * force / np.linalg.norm(force)])
    axis = torque / np.linalg.norm(torque)
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)  # u, v, axis right-handed: the arc turns positively about the torque
    angle = np.linspace(0.0, 1.5 * math.pi, 28)
    return com + 0.5 * length * (np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * v)


def _draw_path(ax: Axes, scene: Raster, path: NDArray[np.float64], colour: str) -> None:
    """The arrow along ``path``: solid where nothing hides it, dashed inside, a head at its end."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import FancyArrowPatch

    pixels = scene.view.project(path)[:, :2]
    ax.plot(pixels[:, 0], pixels[:, 1], color=ARROW_COLOUR, linewidth=0.8, linestyle=(0, (2, 2)), zorder=3)
    solid = []
    for a, b in itertools.pairwise(path):
        solid += scene.visible_runs(a, b, samples=16)
    ax.add_collection(LineCollection(solid, colors=ARROW_COLOUR, linewidths=1.6, zorder=3))
    head = FancyArrowPatch(tuple(pixels[-2]), tuple(pixels[-1]), arrowstyle="-|>", mutation_scale=10, shrinkA=0)
    head.set(color=ARROW_COLOUR, edgecolor=colour, linewidth=0.6, zorder=5)
    ax.add_patch(head)
