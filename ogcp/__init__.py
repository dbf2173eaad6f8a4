"""ogcp: optimal grasp contact planning, validated in simulation.

One import name for three layers, each importing only the ones before it:

- :mod:`ogcp.planner`: contact sets, the exact Ferrari-Canny Q1, A*/WA*/Dijkstra over super-contacts,
  exhaustive search and HFTS (no MuJoCo, no matplotlib);
- :mod:`ogcp.sim_eval`: MuJoCo simulation of planned or external grasps against the analytic limit;
- :mod:`ogcp.benchmarks`: suites, regression checks, figures and the ``ogcp`` command line.

The three subpackages load on first use (``import ogcp`` alone imports nothing heavy)::

    import ogcp

    contacts = ogcp.planner.sample_contacts(ogcp.planner.builtin_mesh("box"), n=100, seed=0)

In a checkout the subpackages are the top-level folders ``planner/``, ``sim_eval/`` and
``benchmarks/`` (this folder links to them); a wheel installs them under ``ogcp/``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

_SUBPACKAGES = ("planner", "sim_eval", "benchmarks")


def _installed_version() -> str:
    """ogcp's version as installed (from git by setuptools-scm at install time)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ogcp")
    except PackageNotFoundError:  # a checkout used without installing it
        return "0+unknown"


__version__ = _installed_version()
__all__ = ["__version__", "benchmarks", "planner", "sim_eval"]


def __getattr__(name: str) -> ModuleType:
    if name in _SUBPACKAGES:
        return importlib.import_module(f"ogcp.{name}")
    raise AttributeError(f"module 'ogcp' has no attribute {name!r}; its subpackages are {', '.join(_SUBPACKAGES)}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_SUBPACKAGES))
