"""One look for every figure: fonts, sizes, the method colours, and saving.

Figures are built on :class:`matplotlib.figure.Figure` directly (never ``pyplot``), so
nothing here depends on the interactive backend or leaks global figure state. Saving
writes a vector PDF with TrueType (Type 42) fonts for papers and a PNG for the README.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.methods.registry import METHODS

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.typing import RcKeyType

#: IEEE two-column widths [in].
SINGLE_COLUMN = 3.5
DOUBLE_COLUMN = 7.16
DEFAULT_DPI = 200
#: Height of one legend row [in] (8 pt text plus spacing).
LEGEND_ROW = 0.17
FORMATS = ("pdf", "png")
SAVE_FORMATS = ("pdf", "png", "svg")

STYLE: dict[RcKeyType, Any] = {
    # Type 42 keeps text as embedded TrueType: editable, searchable, accepted by IEEE/PDF-A checks.
    "pdf.fonttype": 42,
    "ps.fonttype": 42,
    "font.family": "DejaVu Sans",
    "mathtext.fontset": "dejavusans",
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "legend.fontsize": 8,
    "legend.frameon": False,
    "legend.handlelength": 1.6,
    "axes.linewidth": 0.6,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.4,
    "savefig.dpi": DEFAULT_DPI,
    "svg.hashsalt": "ogcp",  # stable element ids: reruns give identical SVG files
    "figure.dpi": 100,
}

# Okabe-Ito: distinguishable with the common colour-vision deficiencies and in greyscale print.
METHOD_COLOURS: dict[str, str] = {
    "astar": "#D55E00",
    "wastar": "#009E73",
    "dijkstra": "#CC79A7",
    "es": "#0072B2",
    "es-pruned": "#56B4E9",
    "hfts": "#E69F00",
    "external": "#000000",  # another planner's grasps (suites' method = "external")
}
#: Method name -> its title in labels and legends (the registry's).
METHOD_TITLES: dict[str, str] = {name: spec.title for name, spec in METHODS.items()} | {"external": "external"}
#: Qualitative colours for series that are not methods (objects, successor variants).
SERIES_COLOURS = (
    "#0072B2",
    "#D55E00",
    "#009E73",
    "#CC79A7",
    "#E69F00",
    "#56B4E9",
    "#000000",
    "#F0E442",
    "#7F7F7F",
    "#8C510A",
)
#: Largest eps of the WA* shading: eps above it get the darkest shade.
EPS_SHADE_MAX = 1.5

P = ParamSpec("P")
R = TypeVar("R")


def _mix(colour: str, target: str, amount: float) -> str:
    from matplotlib.colors import to_hex, to_rgb

    red, green, blue = ((1 - amount) * x + amount * y for x, y in zip(to_rgb(colour), to_rgb(target), strict=True))
    return to_hex((red, green, blue))


def method_colour(method: str, eps: float | None = None, constraint: str = "") -> str:
    """The colour of a method in every figure.

    Args:
        method: ``astar``, ``wastar``, ``dijkstra``, ``es``, ``es-pruned`` or ``hfts``
            (anything else is grey).
        eps: WA* inflation: larger eps, darker green (clipped at ``EPS_SHADE_MAX``).
        constraint: Name of the constraint of a constrained variant (``""``: none); hand
            constraints are darker, other constraints lighter than the method's colour.

    Returns:
        A hex colour.
    """
    colour = METHOD_COLOURS.get(method, "#7F7F7F")
    if method == "wastar" and eps is not None and math.isfinite(eps):
        share = min(max(eps, 0.0), EPS_SHADE_MAX) / EPS_SHADE_MAX
        colour = _mix(_mix(colour, "#FFFFFF", 0.45), "#003322", share)
    if constraint:
        hand = constraint.lower().startswith(("sdh", "hand"))
        colour = _mix(colour, "#000000", 0.45) if hand else _mix(colour, "#FFFFFF", 0.45)
    return colour


def series_colour(index: int) -> str:
    """Colour of the ``index``-th series that is not a method (cycles)."""
    return SERIES_COLOURS[index % len(SERIES_COLOURS)]


def variant_colours(methods: Sequence[str]) -> list[str]:
    """Colours of series that are variants of methods: a method's first variant gets its colour."""
    colours: list[str | None] = []
    seen: set[str] = set()
    for method in methods:
        first = method not in seen and method in METHOD_COLOURS
        seen.add(method)
        colours.append(METHOD_COLOURS[method] if first else None)
    spare = iter(c for c in SERIES_COLOURS if c not in colours)
    return [c if c is not None else next(spare, "#7F7F7F") for c in colours]


@contextmanager
def style() -> Iterator[None]:
    """Apply :data:`STYLE` to figures created and saved inside the block."""
    import matplotlib

    with matplotlib.rc_context(STYLE):
        yield


def styled(function: Callable[P, R]) -> Callable[P, R]:
    """Build the decorated function's figure under :func:`style`."""

    @functools.wraps(function)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        from matplotlib.figure import Figure

        with style():
            result = function(*args, **kwargs)
            if isinstance(result, Figure):
                untangle_tick_labels(result)
            return result

    return wrapper


def untangle_tick_labels(figure: Figure, rounds: int = 8) -> None:
    """Thin the ticks of every axis whose tick labels overlap once drawn (narrow panels, long numbers).

    Minor labels go first (a log axis spanning less than a decade labels its minor ticks), then
    the major ticks are thinned by a third at a time until no two labels touch; x labels still
    touching with three ticks or fewer are turned upright.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.ticker import LogLocator, MaxNLocator, NullFormatter

    if not hasattr(figure.canvas, "get_renderer"):
        FigureCanvasAgg(figure)
    for _ in range(rounds):
        figure.canvas.draw()
        renderer = figure.canvas.get_renderer()  # type: ignore[attr-defined]
        tangled = [axis for ax in figure.axes for axis in (ax.xaxis, ax.yaxis) if _overlapping(axis, renderer)]
        if not tangled:
            return
        for axis in tangled:
            if _drawn_labels(axis, minor=True):
                axis.set_minor_formatter(NullFormatter())
                continue
            shown = len(_drawn_labels(axis, minor=False))
            if shown <= 3:  # too few to thin: labels across the axis take less room along it
                axis.set_tick_params(labelrotation=90 if axis.axis_name == "x" else 0)
                continue
            count = max(2, shown * 2 // 3)
            locator = LogLocator(numticks=count) if axis.get_scale() == "log" else MaxNLocator(nbins=count - 1)
            axis.set_major_locator(locator)


def _overlapping(axis: Any, renderer: Any) -> bool:
    """Whether two drawn tick labels of an axis (major or minor) overlap."""
    boxes = [label.get_window_extent(renderer) for minor in (False, True) for label in _drawn_labels(axis, minor)]
    return any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])


def _drawn_labels(axis: Any, minor: bool) -> list[Any]:
    """The tick labels an axis draws: with text, at ticks inside the view (the others are never drawn)."""
    low, high = sorted(axis.get_view_interval())
    margin = 1e-9 * max(abs(low), abs(high), 1e-300)
    locations = axis.get_minorticklocs() if minor else axis.get_majorticklocs()
    return [
        label
        for location, label in zip(locations, axis.get_ticklabels(minor=minor), strict=False)
        if label.get_visible() and label.get_text() and low - margin <= location <= high + margin
    ]


def new_figure(
    panels: int, width: float | None = None, panel_height: float = 1.9, max_columns: int = 3, polar: bool = False
) -> tuple[Figure, list[Axes]]:
    """A figure with ``panels`` axes in a grid at a paper column width.

    Args:
        panels: Number of axes (>= 1).
        width: Figure width [in]; default: one column for a single panel, else two.
        panel_height: Height of one row [in].
        max_columns: Most panels per row.
        polar: Polar axes.

    Returns:
        The figure (constrained layout) and its axes, row by row; surplus grid cells are removed.
    """
    from matplotlib.figure import Figure

    columns = min(panels, max_columns)
    rows = math.ceil(panels / columns)
    width = width or (SINGLE_COLUMN if panels == 1 else DOUBLE_COLUMN)
    figure = Figure(figsize=(width, panel_height * rows), layout="constrained")
    grid = figure.subplots(rows, columns, squeeze=False, subplot_kw={"projection": "polar"} if polar else None)
    axes = [ax for row in grid for ax in row]
    for ax in axes[panels:]:
        ax.remove()
    return figure, axes[:panels]


def shared_legend(figure: Figure, axes: Sequence[Axes], columns: int = 4) -> None:
    """One legend below the panels with every distinct labelled series of ``axes``."""
    handles: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    if handles:
        add_legend(figure, list(handles.values()), list(handles), columns)


def add_legend(figure: Figure, handles: Sequence[Any], labels: Sequence[str], columns: int) -> None:
    """A legend below the panels; the figure grows by the legend's height so the panels keep theirs."""
    ncols = legend_columns(figure, labels, columns)
    rows = math.ceil(len(labels) / ncols)
    figure.set_figheight(figure.get_figheight() + LEGEND_ROW * rows + 0.05)
    figure.legend(list(handles), list(labels), loc="outside lower center", ncols=ncols)


def legend_columns(figure: Figure, labels: Sequence[str], most: int) -> int:
    """As many legend columns (up to ``most``) as fit the figure's width with the longest label."""
    size = float(STYLE["legend.fontsize"])
    # Average glyph ~0.55 em; handle, padding and column spacing ~4.5 em per entry.
    entry = size * (0.55 * max(len(label) for label in labels) + 4.5)
    fit = int(figure.get_figwidth() * 72 // entry)
    return max(1, min(most, len(labels), fit))


def save_figure(
    figure: Figure, out: str | Path, name: str, formats: Sequence[str] = FORMATS, dpi: int = DEFAULT_DPI
) -> list[Path]:
    """Write ``figure`` as ``out/name.<format>`` for each format.

    Raises:
        OgcpError: For an unknown format or a file that cannot be written.
    """
    unknown = sorted(set(formats) - set(SAVE_FORMATS))
    if unknown:
        raise OgcpError(f"unknown figure format {unknown[0]!r}; valid choices: {', '.join(SAVE_FORMATS)}")
    out = Path(out)
    written = []
    with style():
        for fmt in formats:
            path = out / f"{name}.{fmt}"
            try:
                out.mkdir(parents=True, exist_ok=True)
                # Fixed metadata keeps reruns byte-comparable (no creation date in the PDF).
                metadata = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}.get(fmt)
                figure.savefig(path, format=fmt, dpi=dpi, metadata=metadata)
            except OSError as exc:
                raise OgcpError(f"cannot write {path}: {exc.strerror or exc}") from exc
            written.append(path)
    return written
