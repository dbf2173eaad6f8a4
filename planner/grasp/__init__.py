"""Grasps on a contact set: contacts, friction cones and wrenches, the exact Q1, bounds, constraints.

Contacts can be restricted to where a fingertip sphere reaches (:mod:`planner.grasp.reach`,
on the exact point-to-mesh distance of :mod:`planner.grasp.mesh_distance`).

Everything here is a value or a pure function of a contact set; the search
(:mod:`planner.search`) and the baselines (:mod:`planner.baselines`) build on it. The
compiled exact-Q1 kernel lives in :mod:`planner.grasp.kernel`.

The names below load their modules on first use (PEP 562), so that reading a light module of this
package (:mod:`planner.grasp.defaults`) never loads numpy, trimesh or the kernels.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from planner.grasp.constraints import Constraint, DistinctContacts, MaxFingerSpread, accepts_many
    from planner.grasp.contact_set import ContactSet, NonWatertightWarning, mass_properties, sample_contacts
    from planner.grasp.defaults import DEFAULT_CONE_EDGES, DEFAULT_MU, DEFAULT_TIP_RADIUS_RATIO
    from planner.grasp.mesh_distance import Nearest, SurfaceIndex
    from planner.grasp.quality import Q1Certificate, exact_q1_batch, q1, q1_certificate, signed_q1
    from planner.grasp.reach import REACH_TOLERANCE, default_tip_radius, reachable
    from planner.grasp.subset_quality import GraspQuality
    from planner.grasp.support_bound import SupportBound
    from planner.grasp.wrench import cone_edges, contact_wrenches, tangent_basis

#: Public name -> the module that defines it.
_EXPORTS = {
    "DEFAULT_CONE_EDGES": "planner.grasp.defaults",
    "DEFAULT_MU": "planner.grasp.defaults",
    "DEFAULT_TIP_RADIUS_RATIO": "planner.grasp.defaults",
    "REACH_TOLERANCE": "planner.grasp.reach",
    "Constraint": "planner.grasp.constraints",
    "ContactSet": "planner.grasp.contact_set",
    "DistinctContacts": "planner.grasp.constraints",
    "GraspQuality": "planner.grasp.subset_quality",
    "MaxFingerSpread": "planner.grasp.constraints",
    "Nearest": "planner.grasp.mesh_distance",
    "NonWatertightWarning": "planner.grasp.contact_set",
    "Q1Certificate": "planner.grasp.quality",
    "SupportBound": "planner.grasp.support_bound",
    "SurfaceIndex": "planner.grasp.mesh_distance",
    "accepts_many": "planner.grasp.constraints",
    "cone_edges": "planner.grasp.wrench",
    "contact_wrenches": "planner.grasp.wrench",
    "default_tip_radius": "planner.grasp.reach",
    "exact_q1_batch": "planner.grasp.quality",
    "mass_properties": "planner.grasp.contact_set",
    "q1": "planner.grasp.quality",
    "q1_certificate": "planner.grasp.quality",
    "reachable": "planner.grasp.reach",
    "sample_contacts": "planner.grasp.contact_set",
    "signed_q1": "planner.grasp.quality",
    "tangent_basis": "planner.grasp.wrench",
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
