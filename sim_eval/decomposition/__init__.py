"""Convex decomposition of object meshes for MuJoCo: CoACD in a child process, cached by content.

The names below load their modules on first use (PEP 562), so that reading the settings never loads
trimesh, scipy or CoACD.
"""

from __future__ import annotations

import sys
import types
from typing import TYPE_CHECKING, Any

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.sim_eval.decomposition.decompose import (
        CacheWriteWarning,
        Decomposition,
        cache_key,
        coacd_version,
        decompose,
    )
    from ogcp.sim_eval.decomposition.settings import DecompositionSettings

#: Public name -> the module that defines it.
_EXPORTS = {
    "CacheWriteWarning": "ogcp.sim_eval.decomposition.decompose",
    "Decomposition": "ogcp.sim_eval.decomposition.decompose",
    "DecompositionSettings": "ogcp.sim_eval.decomposition.settings",
    "cache_key": "ogcp.sim_eval.decomposition.decompose",
    "coacd_version": "ogcp.sim_eval.decomposition.decompose",
    "decompose": "ogcp.sim_eval.decomposition.decompose",
}

__all__ = [
    "CacheWriteWarning",
    "Decomposition",
    "DecompositionSettings",
    "cache_key",
    "coacd_version",
    "decompose",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)


class _Package(types.ModuleType):
    """This package, whose name ``decompose`` stays the function, never the submodule.

    The import system binds a submodule to its package's attribute of the same name when it first
    loads it; the submodule ``decompose`` would then hide the function that the package exports
    (as it did when it imported its names eagerly, and the function won).
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _EXPORTS and isinstance(value, types.ModuleType):
            return  # __getattr__ resolves the exported name instead
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
