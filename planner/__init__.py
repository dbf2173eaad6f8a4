"""ogcp planner: contact sets, exact Q1 and optimal / bounded-suboptimal grasp search.

Typical use::

    from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts

    contacts = sample_contacts(builtin_mesh("box"), n=100, seed=0)
    result = GraspPlanner(method="astar").plan(contacts, m=3)
    print(result.grasp, result.q1)

The names below load their modules on first use (PEP 562): importing one light module of the
package (an error class, a configuration, a default) must not load numpy, trimesh, scipy and the
numba kernels, so that ``ogcp --help`` answers at once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp import __version__ as __version__  # the distribution's version, re-exported as before
from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.baselines.es import ESResult, ExhaustiveSearch
    from ogcp.planner.baselines.hfts import HFTS, HFTSResult
    from ogcp.planner.grasp.constraints import DistinctContacts, MaxFingerSpread
    from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
    from ogcp.planner.grasp.quality import Q1Certificate, q1, q1_certificate
    from ogcp.planner.hands.reachability import HandReachability, SDHReachability
    from ogcp.planner.infra.errors import OgcpError, SearchTimeout
    from ogcp.planner.infra.tolerance import TOL
    from ogcp.planner.objects import BUILTIN_OBJECTS, builtin_mesh, load_mesh, resolve_object
    from ogcp.planner.search.grasp_planner import GraspPlanner
    from ogcp.planner.search.result import SearchResult, SearchStats

#: Public name -> the module that defines it.
_EXPORTS = {
    "BUILTIN_OBJECTS": "ogcp.planner.objects",
    "TOL": "ogcp.planner.infra.tolerance",
    "ContactSet": "ogcp.planner.grasp.contact_set",
    "DistinctContacts": "ogcp.planner.grasp.constraints",
    "ESResult": "ogcp.planner.baselines.es",
    "ExhaustiveSearch": "ogcp.planner.baselines.es",
    "GraspPlanner": "ogcp.planner.search.grasp_planner",
    "HFTS": "ogcp.planner.baselines.hfts",
    "HFTSResult": "ogcp.planner.baselines.hfts",
    "MaxFingerSpread": "ogcp.planner.grasp.constraints",
    "OgcpError": "ogcp.planner.infra.errors",
    "Q1Certificate": "ogcp.planner.grasp.quality",
    "HandReachability": "ogcp.planner.hands.reachability",
    "SDHReachability": "ogcp.planner.hands.reachability",
    "SearchResult": "ogcp.planner.search.result",
    "SearchStats": "ogcp.planner.search.result",
    "SearchTimeout": "ogcp.planner.infra.errors",
    "builtin_mesh": "ogcp.planner.objects",
    "load_mesh": "ogcp.planner.objects",
    "q1": "ogcp.planner.grasp.quality",
    "q1_certificate": "ogcp.planner.grasp.quality",
    "resolve_object": "ogcp.planner.objects",
    "sample_contacts": "ogcp.planner.grasp.contact_set",
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
    "HandReachability",
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
