"""Object meshes: the built-in procedural objects, mesh files, and the paper's fetchable meshes.

:func:`resolve_object` turns what a user names (a built-in, a fetched object or a mesh
path) into a mesh and the source record that results carry.

The names below load their modules on first use (PEP 562), so that the built-in objects' names
and the fetchable objects' manifest are read (``ogcp --help``) without loading trimesh.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.infra.cache import file_sha256
    from ogcp.planner.objects.builtin import BUILTIN_OBJECTS, DEFAULT_DIAGONAL, builtin_mesh, normalise_scale
    from ogcp.planner.objects.fetch import ObjectStatus, fetch_objects, is_cached, list_objects, load_fetched
    from ogcp.planner.objects.fetchable import FETCH_GROUPS, FETCHABLE_OBJECTS, PAPER_OBJECTS, FetchableObject
    from ogcp.planner.objects.loading import MESH_SUFFIXES, load_mesh
    from ogcp.planner.objects.repair import repair_mesh
    from ogcp.planner.objects.resolve import resolve_object

#: Public name -> the module that defines it.
_EXPORTS = {
    "BUILTIN_OBJECTS": "ogcp.planner.objects.builtin",
    "DEFAULT_DIAGONAL": "ogcp.planner.objects.builtin",
    "FETCHABLE_OBJECTS": "ogcp.planner.objects.fetchable",
    "FETCH_GROUPS": "ogcp.planner.objects.fetchable",
    "MESH_SUFFIXES": "ogcp.planner.objects.loading",
    "PAPER_OBJECTS": "ogcp.planner.objects.fetchable",
    "FetchableObject": "ogcp.planner.objects.fetchable",
    "ObjectStatus": "ogcp.planner.objects.fetch",
    "builtin_mesh": "ogcp.planner.objects.builtin",
    "fetch_objects": "ogcp.planner.objects.fetch",
    "file_sha256": "ogcp.planner.infra.cache",
    "is_cached": "ogcp.planner.objects.fetch",
    "list_objects": "ogcp.planner.objects.fetch",
    "load_fetched": "ogcp.planner.objects.fetch",
    "load_mesh": "ogcp.planner.objects.loading",
    "normalise_scale": "ogcp.planner.objects.builtin",
    "repair_mesh": "ogcp.planner.objects.repair",
    "resolve_object": "ogcp.planner.objects.resolve",
}

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


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
