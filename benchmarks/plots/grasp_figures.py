"""Fig. 3: the optimal grasp on each object, drawn on the shaded mesh.

One panel per problem (object, m, ...) for its A* cell, or failing that its best cell of a
certified method (:attr:`ogcp.planner.methods.registry.MethodSpec.optimal`), each followed by a panel
per external cell on its object (another planner's best grasp, placed by :mod:`.external`): the
mesh rendered by the z-buffer rasteriser (:mod:`ogcp.benchmarks.plots.raster`), the contact set as
small yellow points and
the grasp's contacts with force arrows along the inward normals (or friction cones). Marks the
mesh hides are left out, piece by piece, from the rasteriser's depth buffer. The mesh is a raster
image inside a matplotlib axes, so titles, fonts and the saved formats match the other figures.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numpy.typing import NDArray

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import METHODS
from ogcp.sim_eval.inputs.plan_input import PlanInput, plan_input

from .data import CellData, RunData, SkipFigure
from .external import by_problem_with_external, host_problems, is_external
from .raster import Raster, fit_view, look, render_mesh
from .style import DOUBLE_COLUMN, SINGLE_COLUMN, method_colour, new_figure, styled

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

T = TypeVar("T")

#: Okabe-Ito yellow, as the paper draws the contact set.
CONTACT_COLOUR = "#F0E442"
#: Candidate cameras [deg] (azimuth around the mesh's up axis, elevation above its plane), in order
#: of preference: the first that shows the most grasp contacts is taken, so ties keep the usual view.
VIEWS = tuple((azimuth, elevation) for elevation in (25.0, -25.0) for azimuth in (35.0, 125.0, 215.0, 305.0))
#: Side of the small test render that scores each candidate view [px].
SCORE_PIXELS = 96
#: Least surface share of a flat base, more than on the opposite side, that makes its axis "up".
BASE_SHARE = 0.02
#: Rendered pixels per inch of panel: above the 300 dpi of print, so the PDF stays sharp.
PIXELS_PER_INCH = 400
#: Arrow length as a fraction of the object's bounding-box diagonal.
ARROW_LENGTH = 0.3
#: Depth slack of marks on the surface, as a fraction of the diagonal.
SURFACE_TOLERANCE = 0.005
#: Seconds spent rendering each panel of the last figure (for the report and the README).
RENDER_SECONDS: list[float] = []


class NoGraspCells(SkipFigure):
    """The run has no cell this figure draws: left out without a note unless asked for by name."""


def grasp_cells(data: RunData) -> list[CellData]:
    """The cells drawn per problem: its plain A* cell, else its best cell of a certified method, then its external cells.

    Args:
        data: The run.

    Returns:
        Cells in panel order, problems in order of first appearance; an external cell follows
        the cell of the planner problem on its object (:func:`.external.host_problems`).
    """
    chosen = []
    for cells in by_problem_with_external(data).values():
        astar = [c for c in cells if c.method == "astar" and c.plain and c.plan_view.grasp is not None]
        certified = [
            c
            for c in cells
            if c.method in METHODS
            and METHODS[c.method].optimal
            and not c.variant.get("symmetry")
            # The hand / spread constraints change the problem: their optimum is not the object's.
            and not c.constraint
            and c.q1 is not None
            and c.plan_view.grasp is not None
        ]
        pick = astar[:1] or sorted(certified, key=lambda c: -(c.q1 or 0.0))[:1]
        chosen += pick + [c for c in cells if is_external(c) and c.plan_view.grasp is not None]
    return chosen


@styled
def fig3_grasps(data: RunData, notes: list[str] | None = None, cones: bool = False) -> Figure:
    """Fig. 3: the optimal grasp of each problem on its shaded object.

    Args:
        data: The run.
        notes: Gets one line per cell whose object or contact set cannot be rebuilt.
        cones: Draw friction cones at the grasp's contacts instead of force arrows.

    Returns:
        The figure, one panel per drawn problem, at most three per row.

    Raises:
        NoGraspCells: No problem has an A* or certified cell.
        SkipFigure: No cell's plan could be rebuilt.
    """
    cells = grasp_cells(data)
    if not cells:
        raise NoGraspCells("needs an A* cell, a cell of another certified method or an external cell")
    names = data.problem_names()
    hosts = host_problems(data)
    inputs = rebuilt_panels(data, [(cell, None) for cell in cells], "fig3_grasps", notes)
    if not inputs:
        raise SkipFigure("no A*, certified or external cell's object and contact set could be rebuilt")
    figure, axes, pixels = panel_grid(len(inputs))
    RENDER_SECONDS.clear()
    for ax, (cell, _, rebuilt) in zip(axes, inputs, strict=True):
        started = time.perf_counter()
        draw_grasp(ax, rebuilt, rebuilt.grasps[0], method_colour(cell.method), pixels, cones)
        RENDER_SECONDS.append(time.perf_counter() - started)
        quality = f", $Q_1$={cell.q1:.3f}" if cell.q1 is not None else ""
        problem = names[hosts.get(cell.id, cell.problem)]
        m = f" m={len(rebuilt.grasps[0])}" if " m=" not in problem else ""
        label = f"{cell.label} (external)" if is_external(cell) and cell.label != cell.method else cell.label
        ax.set_title(f"{problem}{m}: {label}{quality}")
    return figure


def rebuilt_panels(
    data: RunData, picks: Sequence[tuple[CellData, T]], figure: str, notes: list[str] | None
) -> list[tuple[CellData, T, PlanInput]]:
    """Each picked cell with its rebuilt object and contact set; a cell that cannot be rebuilt is noted.

    Args:
        data: The run.
        picks: (cell, what the figure draws of it) pairs.
        figure: The figure's name, for the notes.
        notes: Gets one line per cell left out (None: no notes).
    """
    names = data.problem_names()
    rebuilt: list[tuple[CellData, T, PlanInput]] = []
    for cell, item in picks:
        try:
            rebuilt.append((cell, item, plan_input(cell.plan)))
        except OgcpError as exc:
            if notes is not None:
                notes.append(f"{figure}: {names[cell.problem]} {cell.label} left out: {exc}")
    return rebuilt


def panel_grid(count: int) -> tuple[Figure, Sequence[Axes], int]:
    """A figure of ``count`` square panels, at most three per row; returns it, its axes and the panel side [px]."""
    columns = min(count, 3)
    width = SINGLE_COLUMN if columns == 1 else DOUBLE_COLUMN
    figure, axes = new_figure(count, width=width, panel_height=width / columns, max_columns=3)
    return figure, axes, round(PIXELS_PER_INCH * width / columns)


def draw_grasp(
    ax: Axes,
    rebuilt: PlanInput,
    grasp: Sequence[int],
    colour: str,
    pixels: int = 800,
    cones: bool = False,
) -> Raster:
    """Draw the object, its contact set and one grasp into ``ax``.

    Args:
        ax: The panel (its axis frame is switched off).
        rebuilt: Mesh and contact set of the plan (:func:`ogcp.sim_eval.inputs.plan_input.plan_input`).
        grasp: Contact indices of the grasp, length m.
        colour: Colour of the grasp's contacts and arrows.
        pixels: Side of the square rendered image [px].
        cones: Friction cones (half-angle atan(mu)) instead of force arrows.

    Returns:
        The rendered mesh with its depth buffer.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.patches import FancyArrowPatch

    mesh, contacts = rebuilt.mesh, rebuilt.contacts
    diagonal = float(np.linalg.norm(mesh.bounds[1] - mesh.bounds[0]))
    length = ARROW_LENGTH * diagonal
    index = np.asarray(grasp, dtype=int)
    heads = contacts.positions[index]
    tails = heads - length * contacts.normals[index]  # outside the object, pushing inwards
    rotation = best_view(mesh.vertices, mesh.faces, heads, contacts.normals[index])
    view = fit_view(np.vstack([mesh.vertices, tails]), rotation, pixels, pixels)
    raster = render_mesh(mesh.vertices, mesh.faces, view)
    ax.imshow(raster.rgba, extent=(0, pixels, pixels, 0), interpolation="antialiased", zorder=1)
    tolerance = SURFACE_TOLERANCE * diagonal
    shown = _facing(raster, contacts.normals) & raster.visible(contacts.positions, tolerance)
    others = np.setdiff1d(np.flatnonzero(shown), index)
    where = view.project(contacts.positions)
    ax.scatter(where[others, 0], where[others, 1], s=3, c=CONTACT_COLOUR, edgecolors="#555555", linewidths=0.2)
    ax.scatter(where[index[shown[index]], 0], where[index[shown[index]], 1], s=9, c=colour, zorder=4, linewidths=0)
    lines = []
    for head, normal in zip(heads, contacts.normals[index], strict=True):
        if cones:
            lines += _cone_pieces(raster, head, normal, contacts.mu, 0.6 * length, tolerance)
            continue
        runs = raster.visible_runs(head - length * normal, head, tolerance)
        for first, last in runs:
            if np.allclose(last, view.project(head)[0, :2]):
                arrow = FancyArrowPatch(
                    (float(first[0]), float(first[1])),
                    (float(last[0]), float(last[1])),
                    arrowstyle="-|>",
                    mutation_scale=6,
                    shrinkA=0,
                    shrinkB=0,
                )
                arrow.set(color=colour, linewidth=1.0, zorder=3)
                ax.add_patch(arrow)
            else:
                lines.append((first, last))
    ax.add_collection(LineCollection(lines, colors=colour, linewidths=0.8 if cones else 1.0, zorder=3))
    ax.set_xlim(0, pixels)
    ax.set_ylim(pixels, 0)
    ax.set_aspect("equal")
    ax.axis("off")
    return raster


def upright(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """The world axis a mesh stands on: the side with a flat base that its opposite side lacks.

    Scanned meshes are often y-up (the bunny); drawn z-up they lie on their side. A base is the
    area of faces facing down within 2 % of the diagonal of the lowest point; a box or a ball has
    the same on both sides of every axis and keeps z.

    Args:
        vertices: Mesh vertices, shape (v, 3) [m].
        faces: Triangles, shape (f, 3).

    Returns:
        Unit up direction, shape (3,): a signed coordinate axis, +z unless a base says otherwise.
    """
    corners = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=np.int64)]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(area, 1e-30)[:, None]
    centre = corners.mean(axis=1)
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    share = np.zeros((3, 2))
    for axis, (k, sign) in itertools.product(range(3), enumerate((1.0, -1.0))):
        lowest = float((sign * np.asarray(vertices, dtype=float)[:, axis]).min())
        base = (sign * normal[:, axis] < -0.95) & (sign * centre[:, axis] - lowest < 0.02 * diagonal)
        share[axis, k] = area[base].sum() / max(area.sum(), 1e-30)
    lead = share[:, 0] - share[:, 1]  # + side's base over the - side's, per axis
    axis = int(np.argmax(np.abs(lead)))
    up = np.array([0.0, 0.0, 1.0])
    if abs(lead[axis]) >= BASE_SHARE:
        up = np.zeros(3)
        up[axis] = np.sign(lead[axis])
    return up


def best_view(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    occluder: tuple[NDArray[np.float64], NDArray[np.int64]] | None = None,
) -> NDArray[np.float64]:
    """The candidate camera (:data:`VIEWS` around :func:`upright`) that shows the most grasp contacts.

    Args:
        vertices: Mesh vertices, shape (v, 3) [m].
        faces: Triangles, shape (f, 3).
        points: The grasp's contacts, shape (m, 3) [m].
        normals: Their inward normals, shape (m, 3).
        occluder: Another mesh in the picture (a hand): vertices (w, 3) [m] and faces (g, 3). It
            may hide contacts, and among views that show as many, the one where it hides the
            least of the object wins.

    Returns:
        Camera rotation for :func:`~ogcp.benchmarks.plots.raster.fit_view`, shape (3, 3).
    """
    up = upright(vertices, faces)
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    everything = vertices if occluder is None else np.vstack([vertices, occluder[0]])
    best, chosen = (-1, -1), look(*VIEWS[0], up=up)
    for azimuth, elevation in VIEWS:
        rotation = look(azimuth, elevation, up=up)
        view = fit_view(everything, rotation, SCORE_PIXELS, SCORE_PIXELS)
        raster = render_mesh(vertices, faces, view, outline=False)
        shown = _facing(raster, normals)
        scene = raster if occluder is None else raster.over(render_mesh(*occluder, view, outline=False))
        shown &= scene.visible(points, SURFACE_TOLERANCE * diagonal)
        # Object pixels the occluder leaves in sight; without one, ties keep the preferred view.
        seen = 0 if occluder is None else int(np.sum(np.isfinite(raster.depth) & (raster.depth <= scene.depth)))
        if (int(shown.sum()), seen) > best:
            best, chosen = (int(shown.sum()), seen), rotation
    return chosen


def _facing(raster: Raster, normals: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Contacts whose surface faces the camera (inward normal along the view's forward axis)."""
    # The depth test alone lets through points on the back of thin parts (a wing, an ear).
    return np.asarray(normals @ raster.view.rotation[2] > 0.0)


def _cone_pieces(
    raster: Raster, apex: NDArray[np.float64], normal: NDArray[np.float64], mu: float, height: float, tolerance: float
) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Visible pixel pieces of a friction cone's generators and rim, opening outwards from ``apex``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    angles = np.linspace(0, 2 * np.pi, 25)
    rim = apex - height * normal + height * mu * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    pieces = []
    for point in rim[:-1:3]:  # eight generators
        pieces += raster.visible_runs(apex, point, tolerance, samples=24)
    for a, b in itertools.pairwise(rim):
        pieces += raster.visible_runs(a, b, tolerance, samples=4)
    return pieces
