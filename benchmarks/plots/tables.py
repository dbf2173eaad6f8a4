"""Fig. 9: CPU time per object and method, as Markdown, CSV and a LaTeX booktabs tabular.

Rows are problems (objects), columns the plain variant of each method: A*, WA* per eps,
Dijkstra, ES, ES (pruned), HFTS, each only where the run has it. A cell is the median CPU
time over the matching cells (several seeds); HFTS's time is the sum over its runs, ES's
the sum over its workers. Minutes when any value reaches ten minutes, else seconds. External
cells (another planner's grasps) have no column: ogcp times only their evaluation, not their
planning; Fig. 3 and the simulation figures show them beside A* (:mod:`.external`).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ogcp.planner.infra.errors import OgcpError

from .data import CellData, RunData, SkipFigure
from .style import METHOD_TITLES

COLUMN_ORDER = ("astar", "wastar", "dijkstra", "es", "es-pruned", "hfts")
MINUTES_FROM = 600.0
LATEX_SPECIAL = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
}


@dataclass(frozen=True)
class TimeTable:
    """Times per problem (rows) and method (columns).

    Attributes:
        rows: Row names (problems).
        columns: Column titles (methods), with eps for WA* as ``WA* (eps=0.4)``.
        values: Times in ``unit``, ``values[row][column]``; None where the run has no cell.
        unit: ``s`` or ``min``.
    """

    rows: tuple[str, ...]
    columns: tuple[str, ...]
    values: tuple[tuple[float | None, ...], ...]
    unit: str

    def _text(self, value: float | None, missing: str) -> str:
        if value is None:
            return missing
        return f"{value:.2f}" if value >= 1 else f"{value:.3g}"

    def markdown(self) -> str:
        """A GitHub Markdown table."""
        header = [f"object (CPU {self.unit})", *self.columns]
        lines = ["| " + " | ".join(header) + " |", "|" + "|".join([":---"] + ["---:"] * len(self.columns)) + "|"]
        for name, row in zip(self.rows, self.values):
            lines.append("| " + " | ".join([name, *(self._text(v, "-") for v in row)]) + " |")
        return "\n".join(lines) + "\n"

    def csv(self) -> str:
        """CSV with a header row; full precision, empty where there is no cell."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(["object", *(f"{c} [{self.unit}]" for c in self.columns)])
        for name, row in zip(self.rows, self.values):
            writer.writerow([name, *("" if v is None else f"{v:.6g}" for v in row)])
        return buffer.getvalue()

    def latex(self) -> str:
        """A booktabs ``tabular`` (needs ``\\usepackage{booktabs}``)."""
        header = [f"Object (CPU {self.unit})", *(_latex_title(c) for c in self.columns)]
        lines = [
            r"\begin{tabular}{l" + "r" * len(self.columns) + "}",
            r"\toprule",
            " & ".join(header) + r" \\",
            r"\midrule",
        ]
        for name, row in zip(self.rows, self.values):
            lines.append(" & ".join([_latex_escape(name), *(self._text(v, "--") for v in row)]) + r" \\")
        lines += [r"\bottomrule", r"\end{tabular}"]
        return "\n".join(lines) + "\n"

    def write(self, out: str | Path, name: str) -> list[Path]:
        """Write ``name.md``, ``name.csv`` and ``name.tex`` into ``out``.

        Raises:
            OgcpError: When a file cannot be written.
        """
        out = Path(out)
        written = []
        for suffix, text in (("md", self.markdown()), ("csv", self.csv()), ("tex", self.latex())):
            path = out / f"{name}.{suffix}"
            try:
                out.mkdir(parents=True, exist_ok=True)
                path.write_text(text, encoding="utf-8")
            except OSError as exc:
                raise OgcpError(f"cannot write {path}: {exc.strerror or exc}") from exc
            written.append(path)
        return written


def _latex_escape(text: str) -> str:
    return "".join(LATEX_SPECIAL.get(ch, ch) for ch in text)


def _latex_title(column: str) -> str:
    if "(eps=" in column:
        head, eps = column.split(" (eps=")
        return _latex_escape(head) + r" ($\varepsilon{=}" + eps.rstrip(")") + "$)"
    return _latex_escape(column)


def _column(cell: CellData) -> tuple[int, float, str] | None:
    """(order, eps, title) of the cell's column, or None when the cell is not a plain method run."""
    if cell.method not in COLUMN_ORDER or not cell.plain:
        return None
    title = METHOD_TITLES[cell.method]
    if cell.method == "wastar":
        if cell.eps is None:
            return None
        return COLUMN_ORDER.index("wastar"), cell.eps, f"{title} (eps={cell.eps:g})"
    return COLUMN_ORDER.index(cell.method), 0.0, title


def time_table(run: RunData, unit: str | None = None) -> TimeTable:
    """The Fig. 9 table of the run.

    Args:
        run: The run.
        unit: ``s`` or ``min``; default: minutes when any time reaches ten minutes.

    Raises:
        SkipFigure: When no cell of a plain method records a time.
        OgcpError: For an unknown unit.
    """
    if unit not in (None, "s", "min"):
        raise OgcpError(f"unknown time unit {unit!r}; valid choices: min, s")
    names = run.problem_names()
    times: dict[tuple[str, tuple[int, float, str]], list[float]] = {}
    for problem, cells in run.by_problem().items():
        for cell in cells:
            column, seconds = _column(cell), cell.cpu_seconds()
            if column is not None and seconds is not None:
                times.setdefault((names[problem], column), []).append(seconds)
    if not times:
        raise SkipFigure("needs cells of A*, WA*, Dijkstra, ES or HFTS without constraints or variants")
    rows = tuple(dict.fromkeys(row for row, _ in times))
    columns = sorted({column for _, column in times})
    median = {key: float(np.median(v)) for key, v in times.items()}
    if unit is None:
        unit = "min" if max(median.values()) >= MINUTES_FROM else "s"
    scale = 60.0 if unit == "min" else 1.0
    values = tuple(tuple(None if (row, c) not in median else median[(row, c)] / scale for c in columns) for row in rows)
    return TimeTable(rows, tuple(c[2] for c in columns), values, unit)
