"""What every part of ogcp shares: errors, tolerances, atomic writes, the cache folder, data files, provenance.

The parallel runner (:mod:`planner.infra.parallel`) is imported from its module: it loads joblib.
"""

from planner.infra.assets import asset_path, assets_dir
from planner.infra.atomic import write_atomic, write_bytes_atomic, write_json_atomic, write_text_atomic
from planner.infra.cache import cache_dir
from planner.infra.errors import OgcpError, SearchTimeout, choice_error
from planner.infra.provenance import provenance
from planner.infra.tolerance import TOL, Tolerances

__all__ = [
    "TOL",
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
