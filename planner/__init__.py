"""ogcp planner: contact sets, exact Q1 and optimal / bounded-suboptimal grasp search.

Typical use::

    from planner import GraspPlanner, builtin_mesh, sample_contacts

    contacts = sample_contacts(builtin_mesh("box"), n=100, seed=0)
    result = GraspPlanner(method="astar").plan(contacts, m=3)
    print(result.grasp, result.q1)
"""

from planner.grasp.constraints import DistinctContacts, MaxFingerSpread
from planner.grasp.contact_set import ContactSet, sample_contacts
from planner.grasp.quality import Q1Certificate, q1, q1_certificate
from planner.infra.errors import OgcpError, SearchTimeout
from planner.infra.tolerance import TOL
from planner.objects import BUILTIN_OBJECTS, builtin_mesh, load_mesh, resolve_object
from planner.search.grasp_planner import GraspPlanner
from planner.search.result import SearchResult, SearchStats

__version__ = "0.1.0"

__all__ = [
    "BUILTIN_OBJECTS",
    "TOL",
    "ContactSet",
    "DistinctContacts",
    "GraspPlanner",
    "MaxFingerSpread",
    "OgcpError",
    "Q1Certificate",
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
