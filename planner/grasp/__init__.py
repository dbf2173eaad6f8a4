"""Grasps on a contact set: contacts, friction cones and wrenches, the exact Q1, bounds, constraints.

Contacts can be restricted to where a fingertip sphere reaches (:mod:`ogcp.planner.grasp.reach`,
on the exact point-to-mesh distance of :mod:`ogcp.planner.grasp.mesh_distance`).

Everything here is a value or a pure function of a contact set; the search
(:mod:`ogcp.planner.search`) and the baselines (:mod:`ogcp.planner.baselines`) build on it. The
compiled exact-Q1 kernel lives in :mod:`ogcp.planner.grasp.kernel`.

The names below load their modules on first use (PEP 562), so that reading a light module of this
package (:mod:`ogcp.planner.grasp.defaults`) never loads numpy, trimesh or the kernels.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.grasp.constraints import Constraint, DistinctContacts, MaxFingerSpread, accepts_many
    from ogcp.planner.grasp.contact_set import ContactSet, NonWatertightWarning, mass_properties, sample_contacts
    from ogcp.planner.grasp.defaults import DEFAULT_CONE_EDGES, DEFAULT_MU, DEFAULT_TIP_RADIUS_RATIO
    from ogcp.planner.grasp.mesh_distance import Nearest, SurfaceIndex
    from ogcp.planner.grasp.quality import Q1Certificate, exact_q1_batch, q1, q1_certificate, signed_q1
    from ogcp.planner.grasp.reach import REACH_TOLERANCE, default_tip_radius, reachable
    from ogcp.planner.grasp.subset_quality import GraspQuality
    from ogcp.planner.grasp.support_bound import SupportBound
    from ogcp.planner.grasp.wrench import cone_edges, contact_wrenches, tangent_basis

#: Public name -> the module that defines it.
_EXPORTS = {
    "DEFAULT_CONE_EDGES": "ogcp.planner.grasp.defaults",
    "DEFAULT_MU": "ogcp.planner.grasp.defaults",
    "DEFAULT_TIP_RADIUS_RATIO": "ogcp.planner.grasp.defaults",
    "REACH_TOLERANCE": "ogcp.planner.grasp.reach",
    "Constraint": "ogcp.planner.grasp.constraints",
    "ContactSet": "ogcp.planner.grasp.contact_set",
    "DistinctContacts": "ogcp.planner.grasp.constraints",
    "GraspQuality": "ogcp.planner.grasp.subset_quality",
    "MaxFingerSpread": "ogcp.planner.grasp.constraints",
    "Nearest": "ogcp.planner.grasp.mesh_distance",
    "NonWatertightWarning": "ogcp.planner.grasp.contact_set",
    "Q1Certificate": "ogcp.planner.grasp.quality",
    "SupportBound": "ogcp.planner.grasp.support_bound",
    "SurfaceIndex": "ogcp.planner.grasp.mesh_distance",
    "accepts_many": "ogcp.planner.grasp.constraints",
    "cone_edges": "ogcp.planner.grasp.wrench",
    "contact_wrenches": "ogcp.planner.grasp.wrench",
    "default_tip_radius": "ogcp.planner.grasp.reach",
    "exact_q1_batch": "ogcp.planner.grasp.quality",
    "mass_properties": "ogcp.planner.grasp.contact_set",
    "q1": "ogcp.planner.grasp.quality",
    "q1_certificate": "ogcp.planner.grasp.quality",
    "reachable": "ogcp.planner.grasp.reach",
    "sample_contacts": "ogcp.planner.grasp.contact_set",
    "signed_q1": "ogcp.planner.grasp.quality",
    "tangent_basis": "ogcp.planner.grasp.wrench",
}

__all__ = [
    "DEFAULT_CONE_EDGES",
    "DEFAULT_MU",
    "DEFAULT_TIP_RADIUS_RATIO",
    "REACH_TOLERANCE",
    "Constraint",
    "ContactSet",
    "DistinctContacts",
    "GraspQuality",
    "MaxFingerSpread",
    "Nearest",
    "NonWatertightWarning",
    "Q1Certificate",
    "SupportBound",
    "SurfaceIndex",
    "accepts_many",
    "cone_edges",
    "contact_wrenches",
    "default_tip_radius",
    "exact_q1_batch",
    "mass_properties",
    "q1",
    "q1_certificate",
    "reachable",
    "sample_contacts",
    "signed_q1",
    "tangent_basis",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
