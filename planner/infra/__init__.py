"""What every part of ogcp shares: errors, tolerances, atomic writes, the cache folder, data files, provenance.

The parallel runner (:mod:`ogcp.planner.infra.parallel`) is imported from its module: it loads joblib.
"""

from ogcp.planner.infra.assets import asset_path, assets_dir
from ogcp.planner.infra.atomic import write_atomic, write_bytes_atomic, write_json_atomic, write_text_atomic
from ogcp.planner.infra.cache import cache_dir
from ogcp.planner.infra.errors import NoGraspError, OgcpError, SearchTimeout, choice_error
from ogcp.planner.infra.provenance import provenance
from ogcp.planner.infra.tolerance import TOL, Tolerances

__all__ = [
    "TOL",
    "NoGraspError",
    "OgcpError",
    "SearchTimeout",
    "Tolerances",
    "asset_path",
    "assets_dir",
    "cache_dir",
    "choice_error",
    "provenance",
    "write_atomic",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_text_atomic",
]
