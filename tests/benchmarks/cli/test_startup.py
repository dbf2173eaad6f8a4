"""``ogcp --help`` loads no heavy dependency: the parser is built from light modules only.

Start-up time itself is measured by ``benchmarks/perf/cli_startup.py``, never here; these
tests check its cause deterministically, in fresh interpreters: which modules the help of
every command imports.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
#: Dependencies that ``--help`` must not load (numpy is allowed by the issue, but not needed either).
HEAVY = (
    "numpy",
    "scipy",
    "trimesh",
    "numba",
    "llvmlite",
    "mujoco",
    "matplotlib",
    "coacd",
    "joblib",
    "tqdm",
)

# Builds the parser, prints the help of every command and sub-command through main(), as the
# console script does, then reports the top-level packages that were imported.
_HELP_EVERYWHERE = """
import argparse, contextlib, io, json, sys
from ogcp.benchmarks.cli.app import build_parser, main

def paths(parser, prefix=()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield (*prefix, name)
                yield from paths(child, (*prefix, name))

helps = {}
for path in [(), *paths(build_parser())]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        main([*path, "--help"])
    helps[" ".join(path)] = out.getvalue()
print(json.dumps({"helps": helps, "modules": sorted(sys.modules)}))
"""


def _python(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, check=True)


@pytest.fixture(scope="module")
def help_everywhere() -> dict[str, object]:
    """Every command's help text and the modules loaded after printing all of them."""
    found: dict[str, object] = json.loads(_python("-c", _HELP_EVERYWHERE).stdout)
    return found


def _heavy(modules: list[str]) -> list[str]:
    return sorted(m for m in modules if m.split(".")[0] in HEAVY)


def test_help_of_every_command_imports_no_heavy_module(help_everywhere):
    helps = help_everywhere["helps"]
    assert isinstance(helps, dict)
    # The walk reached every command and sub-command, and each printed its usage.
    for command in ("contacts", "plan", "evaluate", "decompose", "assets list", "assets fetch", "suite", "plot"):
        assert helps[command].startswith(f"usage: ogcp {command}")
    modules = help_everywhere["modules"]
    assert isinstance(modules, list)
    assert _heavy(modules) == []
    # Nor the planner's engines, the simulation or the figures, which import them.
    engines = (
        "ogcp.planner.grasp.kernel",
        "ogcp.planner.search",
        "ogcp.planner.baselines",
        "ogcp.sim_eval.evaluate",
        "ogcp.benchmarks.plots.report",
    )
    assert [m for m in modules if m.startswith(engines)] == []


def test_console_entry_point_help_imports_no_heavy_module():
    # The real entry (python -m ogcp.benchmarks.cli, as the console script's import of main):
    # -X importtime lists every module the process imported, on stderr.
    done = _python("-X", "importtime", "-m", "ogcp.benchmarks.cli", "--help")
    assert done.stdout.startswith("usage: ogcp")
    imported = [line.rsplit("|", 1)[-1].strip() for line in done.stderr.splitlines() if line.startswith("import time:")]
    assert "ogcp.benchmarks.cli.app" in imported
    assert _heavy(imported) == []


def test_plan_still_loads_the_engines_it_needs(tmp_path: Path) -> None:
    # The lazy imports move work to the handlers; they do not skip it: a plan runs the kernel,
    # and with an empty contact cache it samples the mesh with trimesh.
    script = (
        "import sys; from ogcp.benchmarks.cli.app import main; status = main(['plan', 'box', '-n', '12', '--json']); "
        "print(status, 'ogcp.planner.grasp.kernel' in sys.modules, 'trimesh' in sys.modules, file=sys.stderr)"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        cwd=ROOT,
        env={**os.environ, "OGCP_CACHE": str(tmp_path / "cache")},
        capture_output=True,
        text=True,
        check=True,
    )
    assert done.stderr.split()[-3:] == ["0", "True", "True"]
    assert json.loads(done.stdout)["schema"] == "ogcp.plan/1"


def test_figure_names_read_by_the_help_match_the_builders():
    from ogcp.benchmarks.plots.names import FIGURE_NAMES, NAMES, TABLE
    from ogcp.benchmarks.plots.report import FIGURES

    assert tuple(FIGURES) == FIGURE_NAMES
    assert all(builder.__name__ == name for name, builder in FIGURES.items())
    assert NAMES == (*FIGURE_NAMES, TABLE)
