"""Grasps on a contact set: contacts, friction cones and wrenches, the exact Q1, bounds, constraints.

Contacts can be restricted to where a fingertip sphere reaches (:mod:`planner.grasp.reach`,
on the exact point-to-mesh distance of :mod:`planner.grasp.mesh_distance`).

Everything here is a value or a pure function of a contact set; the search
(:mod:`planner.search`) and the baselines (:mod:`planner.baselines`) build on it. The
compiled exact-Q1 kernel lives in :mod:`planner.grasp.kernel`.
"""

from planner.grasp.constraints import Constraint, DistinctContacts, MaxFingerSpread, accepts_many
from planner.grasp.contact_set import (
    DEFAULT_CONE_EDGES,
    DEFAULT_MU,
    ContactSet,
    NonWatertightWarning,
    mass_properties,
    sample_contacts,
)
from planner.grasp.mesh_distance import Nearest, SurfaceIndex
from planner.grasp.quality import Q1Certificate, exact_q1_batch, q1, q1_certificate, signed_q1
from planner.grasp.reach import DEFAULT_TIP_RADIUS_RATIO, REACH_TOLERANCE, default_tip_radius, reachable
from planner.grasp.subset_quality import GraspQuality
from planner.grasp.support_bound import SupportBound
from planner.grasp.wrench import cone_edges, contact_wrenches, tangent_basis

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
