"""The planning methods behind one interface: runners and the registry by name.

* :mod:`ogcp.planner.methods.runners`: run a method's configuration on a contact set and return
  the result with its complete ``ogcp.plan/1`` record.
* :mod:`ogcp.planner.methods.registry`: method name -> title, configuration class and runner.

The configurations themselves live one layer down, in :mod:`ogcp.planner.config`, because the
engines (search, baselines, hands) read their defaults from them and the registry imports
the engines.

The names below load their modules on first use (PEP 562): the registry is read (``ogcp --help``)
without loading the engines, which load when a method runs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.methods.registry import METHODS, MethodSpec, method_spec
    from ogcp.planner.methods.runners import MethodRun, RunOptions

#: Public name -> the module that defines it.
_EXPORTS = {
    "METHODS": "ogcp.planner.methods.registry",
    "MethodRun": "ogcp.planner.methods.runners",
    "MethodSpec": "ogcp.planner.methods.registry",
    "RunOptions": "ogcp.planner.methods.runners",
    "method_spec": "ogcp.planner.methods.registry",
}

__all__ = [
    "METHODS",
    "MethodRun",
    "MethodSpec",
    "RunOptions",
    "method_spec",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
