"""Built-in procedural objects: box, sphere, donut and amphora, and scaling to a diagonal.

Built-in objects are watertight, centred on their bounding-box centre and scaled to a
bounding-box diagonal of ``DEFAULT_DIAGONAL`` (0.2 m).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from ogcp.planner.infra.errors import OgcpError, choice_error

if TYPE_CHECKING:
    import trimesh

# numpy and trimesh are imported in the functions that use them: the names and the default
# diagonal are read where loading them would be wasted (``ogcp --help``, the simulation's settings).

DEFAULT_DIAGONAL = 0.2  # [m]


def _box() -> trimesh.Trimesh:
    import trimesh

    return trimesh.creation.box(extents=(3.0, 2.0, 1.4))


def _sphere() -> trimesh.Trimesh:
    import trimesh

    return trimesh.creation.icosphere(subdivisions=4, radius=1.0)


def _donut() -> trimesh.Trimesh:
    import trimesh

    return trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=64, minor_sections=32)


def _amphora() -> trimesh.Trimesh:
    import numpy as np
    import trimesh

    # Profile (radius, height) of a vase: foot, belly, shoulder, neck and lip, closed on
    # the axis at both ends so the surface of revolution is watertight.
    heights = np.linspace(0.0, 1.0, 41)
    radius = (
        0.16
        + 0.26 * np.exp(-(((heights - 0.38) / 0.2) ** 2))
        - 0.06 * np.exp(-(((heights - 0.8) / 0.06) ** 2))
        + 0.05 * np.exp(-(((heights - 0.98) / 0.03) ** 2))
    )
    profile = np.column_stack([radius, heights * 1.6])
    profile = np.vstack([[0.0, 0.0], profile, [0.0, 1.6]])
    return trimesh.creation.revolve(profile, sections=64)


#: Registry of built-in procedural objects: name -> factory of an unscaled mesh.
BUILTIN_OBJECTS: dict[str, Callable[[], trimesh.Trimesh]] = {
    "amphora": _amphora,
    "box": _box,
    "donut": _donut,
    "sphere": _sphere,
}


def normalise_scale(mesh: trimesh.Trimesh, diagonal: float = DEFAULT_DIAGONAL) -> trimesh.Trimesh:
    """Centre a mesh on its bounding-box centre and scale it to a bounding-box diagonal.

    Args:
        mesh: Input mesh (not modified).
        diagonal: Target bounding-box diagonal [m].

    Returns:
        A scaled copy.
    """
    import numpy as np

    out = mesh.copy()
    lo, hi = out.bounds
    out.apply_translation(-(lo + hi) / 2.0)
    out.apply_scale(diagonal / float(np.linalg.norm(hi - lo)))
    return out


def builtin_mesh(name: str, diagonal: float = DEFAULT_DIAGONAL) -> trimesh.Trimesh:
    """Build a built-in procedural object.

    Args:
        name: One of :data:`BUILTIN_OBJECTS`.
        diagonal: Bounding-box diagonal [m].

    Returns:
        A watertight mesh.

    Raises:
        OgcpError: For an unknown name.
    """
    import numpy as np

    if name not in BUILTIN_OBJECTS:
        raise choice_error("object", name, BUILTIN_OBJECTS)
    if not (np.isfinite(diagonal) and diagonal > 0):
        raise OgcpError(f"object diagonal must be a positive number of metres, got {diagonal!r}")
    return normalise_scale(BUILTIN_OBJECTS[name](), diagonal)
