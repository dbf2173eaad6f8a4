"""ogcp planner: contact sets, exact Q1 and optimal / bounded-suboptimal grasp search.

Typical use::

    from planner import GraspPlanner, builtin_mesh, sample_contacts

    contacts = sample_contacts(builtin_mesh("box"), n=100, seed=0)
    result = GraspPlanner(method="astar").plan(contacts, m=3)
    print(result.grasp, result.q1)

The names below load their modules on first use (PEP 562): importing one light module of the
package (an error class, a configuration, a default) must not load numpy, trimesh, scipy and the
numba kernels, so that ``ogcp --help`` answers at once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from planner.baselines.es import ESResult, ExhaustiveSearch
    from planner.baselines.hfts import HFTS, HFTSResult
    from planner.grasp.constraints import DistinctContacts, MaxFingerSpread
    from planner.grasp.contact_set import ContactSet, sample_contacts
    from planner.grasp.quality import Q1Certificate, q1, q1_certificate
    from planner.hands.reachability import SDHReachability
    from planner.infra.errors import OgcpError, SearchTimeout
    from planner.infra.tolerance import TOL
    from planner.objects import BUILTIN_OBJECTS, builtin_mesh, load_mesh, resolve_object
    from planner.search.grasp_planner import GraspPlanner
    from planner.search.result import SearchResult, SearchStats


def _installed_version() -> str:
    """ogcp's version as installed (from git by setuptools-scm at install time)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ogcp")
    except PackageNotFoundError:  # a checkout used without installing it
        return "0+unknown"


__version__ = _installed_version()

#: Public name -> the module that defines it.
_EXPORTS = {
    "BUILTIN_OBJECTS": "planner.objects",
    "TOL": "planner.infra.tolerance",
    "ContactSet": "planner.grasp.contact_set",
    "DistinctContacts": "planner.grasp.constraints",
    "ESResult": "planner.baselines.es",
    "ExhaustiveSearch": "planner.baselines.es",
    "GraspPlanner": "planner.search.grasp_planner",
    "HFTS": "planner.baselines.hfts",
    "HFTSResult": "planner.baselines.hfts",
    "MaxFingerSpread": "planner.grasp.constraints",
    "OgcpError": "planner.infra.errors",
    "Q1Certificate": "planner.grasp.quality",
    "SDHReachability": "planner.hands.reachability",
    "SearchResult": "planner.search.result",
    "SearchStats": "planner.search.result",
    "SearchTimeout": "planner.infra.errors",
    "builtin_mesh": "planner.objects",
    "load_mesh": "planner.objects",
    "q1": "planner.grasp.quality",
    "q1_certificate": "planner.grasp.quality",
    "resolve_object": "planner.objects",
    "sample_contacts": "planner.grasp.contact_set",
}

__all__ = [
    "BUILTIN_OBJECTS",
    "HFTS",
    "TOL",
    "ContactSet",
    "DistinctContacts",
    "ESResult",
    "ExhaustiveSearch",
    "GraspPlanner",
    "HFTSResult",
    "MaxFingerSpread",
    "OgcpError",
    "Q1Certificate",
    "SDHReachability",
    "SearchResult",
    "SearchStats",
    "SearchTimeout",
    "builtin_mesh",
    "load_mesh",
    "q1",
    "q1_certificate",
    "resolve_object",
    "sample_contacts",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
