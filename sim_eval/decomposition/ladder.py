"""A decomposition faithful where each grasp's fingers touch: measured per contact, refined when it is not.

CoACD's parts are convex hulls of pieces of the mesh, so where a piece is concave they stand
proud of the surface, and a fingertip meets them before it meets the mesh. For every grasp the
offset of the collision surface along each contact's normal is measured
(:meth:`~ogcp.sim_eval.scene.collision.CollisionSurface.offsets`); when one exceeds the tolerance
(``contact_tolerance`` x the object's diagonal) the next, finer CoACD threshold of
:attr:`~ogcp.sim_eval.decomposition.settings.DecompositionSettings.ladder` is tried, each computed
once per object and cached on disk like any decomposition. A grasp gets the coarsest level that
meets the tolerance at all its contacts, else the level with the smallest worst offset, and a
one-line note of what could not be met.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.decomposition.decompose import Decomposition, decompose
from ogcp.sim_eval.decomposition.settings import DecompositionSettings
from ogcp.sim_eval.scene.collision import CollisionSurface

#: How far along the normal the offset is looked for, in fingertip radii on either side.
OFFSET_REACH_RADII = 2.0


@dataclass(frozen=True, eq=False)
class ContactFit:
    """The decomposition a grasp is simulated on, and how far it lies from the mesh at the contacts.

    Attributes:
        decomposition: The parts.
        surface: The same parts, prepared for distance queries.
        threshold: The CoACD threshold of these parts (the hull's nominal one for ``convex_hull``).
        offsets: Collision surface offset along each contact's inward normal, shape (m,) [m]:
            negative where the parts stand proud of the mesh; NaN where no part lies within reach.
        tolerance: The largest accepted ``|offset|`` [m].
        tried: The thresholds measured for this grasp, coarse to fine.
        refine_error: Why a finer level could not be made (CoACD failed or timed out), if so.
    """

    decomposition: Decomposition
    surface: CollisionSurface
    threshold: float
    offsets: NDArray[np.float64]
    tolerance: float
    tried: tuple[float, ...]
    refine_error: str | None = None

    @property
    def errors(self) -> NDArray[np.float64]:
        """``|offset|`` per contact [m], inf where no collision surface is near, shape (m,)."""
        return np.where(np.isnan(self.offsets), np.inf, np.abs(self.offsets))

    @property
    def within_tolerance(self) -> bool:
        """Whether every contact's offset is known and within the tolerance."""
        return bool(np.all(self.errors <= self.tolerance))

    @property
    def worst(self) -> float:
        """The largest ``|offset|`` [m] (inf when some contact has no collision surface near it)."""
        return float(self.errors.max())

    def note(self, diagonal: float) -> str | None:
        """One line when the tolerance was not met (None when it was)."""
        if self.within_tolerance:
            return None
        finger = int(np.argmax(self.errors))
        if math.isinf(self.worst):
            where = f"finger {finger} finds no collision surface within reach of its contact"
        else:
            where = (
                f"the collision surface is {self.worst * 1e3:.3g} mm ({100 * self.worst / diagonal:.2g} % of the "
                f"diagonal) from the mesh at finger {finger}"
            )
        remedy = (
            f"refining failed: {self.refine_error}"
            if self.refine_error
            else "a smaller threshold in refine_thresholds may help"
        )
        return (
            f"{where}, over the tolerance of {self.tolerance * 1e3:.3g} mm even at CoACD threshold "
            f"{self.threshold:g}; the tips start on the parts, so the simulated grasp differs from the plan "
            f"(see its realized contacts); {remedy}"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the ``collision`` entry of a simulated grasp)."""
        return {
            "threshold": self.threshold,
            "offsets": [None if math.isnan(v) else float(v) for v in self.offsets],
            "tolerance": self.tolerance,
            "within_tolerance": self.within_tolerance,
            "tried": list(self.tried),
            "hull_count": self.decomposition.hull_count,
            "refine_error": self.refine_error,
        }


class DecompositionLadder:
    """The decompositions of one object from coarse to fine, computed when first needed.

    Args:
        mesh: The object's mesh [m].
        settings: Decomposition settings; their ``ladder`` gives the levels.
        diagonal: The object's bounding-box diagonal [m] (the tolerance's unit).
        tip_radius: Fingertip radius [m] (the offsets' search reach).
        cache: Decomposition cache folder (default ``$OGCP_CACHE/decompositions``).
        progress: Show CoACD's progress bar.
        first: A decomposition to use for the coarsest level instead of computing it.
    """

    def __init__(
        self,
        mesh: trimesh.Trimesh,
        settings: DecompositionSettings,
        diagonal: float,
        tip_radius: float,
        cache: Path | None = None,
        progress: bool = False,
        first: Decomposition | None = None,
    ) -> None:
        self.mesh = mesh
        self.settings = settings
        self.tolerance = settings.contact_tolerance * diagonal
        self.reach = OFFSET_REACH_RADII * tip_radius
        self.cache = cache
        self.progress = progress
        self._levels: dict[float, tuple[Decomposition, CollisionSurface]] = {}
        if first is not None:
            self._levels[settings.ladder[0]] = (first, CollisionSurface.from_parts(first.parts))

    def level(self, threshold: float) -> tuple[Decomposition, CollisionSurface]:
        """The decomposition at one threshold of the ladder (computed, or read from the cache, once)."""
        if threshold not in self._levels:
            parts = decompose(
                self.mesh, replace(self.settings, threshold=threshold), cache=self.cache, progress=self.progress
            )
            self._levels[threshold] = (parts, CollisionSurface.from_parts(parts.parts))
        return self._levels[threshold]

    @property
    def used(self) -> dict[float, Decomposition]:
        """The levels computed so far, by threshold."""
        return {t: parts for t, (parts, _) in self._levels.items()}

    def fit(self, positions: ArrayLike, inward_normals: ArrayLike) -> ContactFit:
        """The coarsest level within tolerance at these contacts, else the one with the smallest worst offset.

        Args:
            positions: One grasp's contacts, shape (m, 3) [m].
            inward_normals: Their inward normals, shape (m, 3).
        """
        best: ContactFit | None = None
        tried: list[float] = []
        failure = None
        for k, threshold in enumerate(self.settings.ladder):
            try:
                parts, surface = self.level(threshold)
            except OgcpError as exc:
                if k == 0:
                    raise  # without the coarsest level there is nothing to simulate on
                failure = str(exc)
                break
            tried.append(threshold)
            offsets = surface.offsets(positions, inward_normals, self.reach)
            fit = ContactFit(parts, surface, threshold, offsets, self.tolerance, tuple(tried))
            if best is None or fit.worst < best.worst:
                best = fit
            if fit.within_tolerance:
                break
        assert best is not None
        return replace(best, tried=tuple(tried), refine_error=failure)
