"""Every figure and table of a suite run into one folder, skipping what the run lacks."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ogcp.planner.infra.errors import OgcpError

from .data import RunData, SkipFigure, load_run
from .figures import fig4_q1_histograms, fig6_states_per_level, fig7_iterations_f, fig8_wastar_tradeoff
from .grasp_figures import NoGraspCells, fig3_grasps
from .hand_figures import fig10_hand_grasps
from .names import FIGURE_NAMES, NAMES, TABLE
from .protocol import sim_protocol
from .sim_figures_3d import sim_grasps
from .simulation import sim_fidelity, sim_q1_vs_resistance, sim_survival
from .style import DEFAULT_DPI, FORMATS, SAVE_FORMATS, save_figure
from .tables import time_table
from .tree import fig5_search_tree

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FigureBuilder = Callable[[RunData, "list[str] | None"], "Figure"]

#: File stem -> builder, in the order they are drawn. The stems are written once, in
#: :mod:`ogcp.benchmarks.plots.names`, which ``ogcp plot --help`` reads without these modules.
FIGURES: dict[str, FigureBuilder] = dict(
    zip(
        FIGURE_NAMES,
        (
            fig3_grasps,
            fig4_q1_histograms,
            fig5_search_tree,
            fig6_states_per_level,
            fig7_iterations_f,
            fig8_wastar_tradeoff,
            sim_q1_vs_resistance,
            sim_fidelity,
            sim_survival,
            sim_protocol,
            fig10_hand_grasps,
            sim_grasps,
        ),
        strict=True,
    )
)


@dataclass(frozen=True)
class PlotReport:
    """What :func:`plot_run` did.

    Attributes:
        written: Every file written, in order.
        notes: One line per skipped record, cell, figure or panel.
    """

    written: tuple[Path, ...]
    notes: tuple[str, ...]


def plot_run(
    run: str | Path | RunData,
    out: str | Path,
    only: Sequence[str] | None = None,
    formats: Sequence[str] = FORMATS,
    dpi: int = DEFAULT_DPI,
    unit: str | None = None,
) -> PlotReport:
    """Draw every figure the run has data for and write the time table.

    Args:
        run: A suite output folder (``results.jsonl``, ``manifest.json``) or its loaded data.
        out: Folder for the files (created).
        only: Names from :data:`NAMES` to draw (default: all).
        formats: Figure formats (``pdf``, ``png``, ``svg``).
        dpi: Resolution of raster formats.
        unit: Time unit of the table (``s``, ``min``; default: by magnitude).

    Returns:
        The files written and the notes.

    Raises:
        OgcpError: For a folder without results, an unknown name or format, or an unwritable file.
    """
    unknown = sorted(set(only or ()) - set(NAMES))
    if unknown:
        raise OgcpError(f"unknown figure {unknown[0]!r}; valid choices: {', '.join(NAMES)}")
    if dpi < 10:
        raise OgcpError(f"dpi must be at least 10, got {dpi}")
    bad = sorted(set(formats) - set(SAVE_FORMATS)) or ([] if formats else ["(none)"])
    if bad:
        raise OgcpError(f"unknown figure format {bad[0]!r}; valid choices: {', '.join(SAVE_FORMATS)}")
    if unit not in (None, "s", "min"):
        raise OgcpError(f"unknown time unit {unit!r}; valid choices: min, s")
    data = run if isinstance(run, RunData) else load_run(run)
    notes = list(data.notes)
    written: list[Path] = []
    selected = [name for name in NAMES if only is None or name in only]
    for name in selected:
        if name == TABLE:
            try:
                table = time_table(data, unit)
            except SkipFigure as skip:
                notes.append(f"{name}: skipped, {skip}")
                continue
            written += table.write(out, name)
            continue
        try:
            figure = FIGURES[name](data, notes)
        except SkipFigure as skip:
            # The object pictures (Fig. 3, Fig. 10, sim_grasps) are extras of runs with A*, SDH or
            # simulated cells (NoGraspCells and its subclasses): a note only when asked for.
            if not (isinstance(skip, NoGraspCells) and only is None):
                notes.append(f"{name}: skipped, {skip}")
            continue
        except (ArithmeticError, IndexError, KeyError, TypeError, ValueError) as exc:
            # A record with an unexpected shape costs its figure, not the other figures.
            message = (str(exc).splitlines() or [""])[0]
            notes.append(f"{name}: skipped, could not draw it from these records ({type(exc).__name__}: {message})")
            continue
        written += save_figure(figure, out, name, formats, dpi)
    return PlotReport(tuple(written), tuple(notes))
