"""Object meshes: the built-in procedural objects, mesh files, and the paper's fetchable meshes.

:func:`resolve_object` turns what a user names (a built-in, a fetched object or a mesh
path) into a mesh and the source record that results carry.
"""

from planner.objects.builtin import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, builtin_mesh, normalise_scale
from planner.objects.fetch import ObjectStatus, fetch_objects, is_cached, list_objects, load_fetched
from planner.objects.fetchable import FETCH_GROUPS, FETCHABLE_OBJECTS, PAPER_OBJECTS, FetchableObject
from planner.objects.loading import MESH_SUFFIXES, file_sha256, load_mesh
from planner.objects.repair import repair_mesh
from planner.objects.resolve import resolve_object

__all__ = [
    "BUILTIN_OBJECTS",
    "DEFAULT_DIAGONAL",
    "FETCHABLE_OBJECTS",
    "FETCH_GROUPS",
    "MESH_SUFFIXES",
    "PAPER_OBJECTS",
    "FetchableObject",
    "ObjectStatus",
    "builtin_mesh",
    "fetch_objects",
    "file_sha256",
    "is_cached",
    "list_objects",
    "load_fetched",
    "load_mesh",
    "normalise_scale",
    "repair_mesh",
    "resolve_object",
]
