"""Validated configurations of the planning methods: every default, range and choice written once.

:mod:`ogcp.planner.config.options` declares one parameter (:class:`Option`) and the validated base
class; :mod:`ogcp.planner.config.methods` holds one frozen configuration per method. The engines
(search, baselines, hands) read their defaults here; the CLI's options and the suites'
parameter table are generated from the same declarations.
"""

from ogcp.planner.config.methods import (
    AStarConfig,
    DijkstraConfig,
    ESConfig,
    ESPrunedConfig,
    HFTSConfig,
    WAStarConfig,
)
from ogcp.planner.config.options import ConfigError, MethodConfig, Option, options_of

__all__ = [
    "AStarConfig",
    "ConfigError",
    "DijkstraConfig",
    "ESConfig",
    "ESPrunedConfig",
    "HFTSConfig",
    "MethodConfig",
    "Option",
    "WAStarConfig",
    "options_of",
]
