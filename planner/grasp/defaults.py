"""Defaults and valid ranges of the contact sampling, in a module that imports nothing heavy.

They are read where loading numpy, trimesh and the Q1 kernels would be wasted: the command
line's ``--help`` and argument checks, the suites' validation and the simulation's settings.
:mod:`ogcp.planner.grasp.contact_set` and :mod:`ogcp.planner.grasp.reach` take them from here, so each
value is written once. The ranges are :class:`~ogcp.planner.config.options.Option` declarations
(the command line shows them in ``--help``); the number of contacts has no fixed maximum but a
memory estimate (:func:`check_contact_memory`) that is checked before anything is allocated.
"""

from __future__ import annotations

import os
from pathlib import Path

from ogcp.planner.config.options import MAX_SEED, Option
from ogcp.planner.infra.errors import OgcpError

#: Friction coefficient mu of a contact set when none is given.
DEFAULT_MU = 0.5
#: Friction-cone edges k of a contact set when none is given.
DEFAULT_CONE_EDGES = 8
#: Contacts sampled from a mesh when no count is given.
DEFAULT_CONTACTS = 100
#: Default fingertip radius as a fraction of the object's bounding-box diagonal: the one
#: default of both the contact sampling and the simulation, so that a plan made with the
#: defaults only holds contacts the simulated fingertip can touch.
DEFAULT_TIP_RADIUS_RATIO = 0.04

#: Largest friction coefficient. Cone edges are n + mu t, not normalised, so Q1 grows with mu:
#: up to ~10^6 it stays exact, at 10^8 the hull of a box's contacts already collapses to Q1 = 0
#: (reported as certified), at 10^308 the wrenches overflow. Measured coefficients of grasping
#: stay below about 2 (rubber on rough surfaces); 10 is generous and keeps wrenches near unit size.
MAX_MU = 10.0
#: Most friction-cone edges. Q1 hulls hold m k wrenches and Q_OWS n k: k = 64 approximates the
#: circular cone to 0.1 % (1 - cos(pi / k)) at 16x the default's cost; k = 10^5 never finishes.
MAX_CONE_EDGES = 64
#: Smallest and largest object diagonal [m]. ogcp is checked from 5 cm to 2 m; the range is
#: 50x wider on both ends, finite and far from where the geometry loses precision (10^-9 m
#: already leaves sampled normals of zero length, 10^-300 m divides by zero).
MIN_DIAGONAL = 1e-3
MAX_DIAGONAL = 100.0

#: Contact models: point contacts with Coulomb friction, or soft fingers that also resist a
#: moment about the normal (torsional friction).
CONTACT_MODELS = ("hard", "soft")
#: Torsional friction coefficient [m] of soft fingers when none is given: DexGraspBench's
#: value (MuJoCo's own default is 0.005). Like MuJoCo's, it is a length, not scaled with the object.
DEFAULT_TORSIONAL_FRICTION = 0.02
#: Largest torsional friction coefficient [m]: the largest object's diagonal (a moment per unit
#: normal force beyond the object's size has no physical meaning).
MAX_TORSIONAL_FRICTION = MAX_DIAGONAL

#: Friction coefficient mu.
MU = Option("float", DEFAULT_MU, "friction coefficient mu", minimum=0, exclusive=True, maximum=MAX_MU)
#: Friction-cone edges k.
CONE_EDGES = Option("int", DEFAULT_CONE_EDGES, "friction-cone edges k", minimum=3, maximum=MAX_CONE_EDGES)
#: Contact model.
CONTACT_MODEL = Option("choice", "hard", "contact model", choices=CONTACT_MODELS)
#: Torsional friction coefficient gamma [m] of soft fingers (0 = hard fingers).
TORSIONAL_FRICTION = Option(
    "float", None, "torsional friction coefficient [m] of soft fingers", minimum=0, maximum=MAX_TORSIONAL_FRICTION
)
#: Contacts sampled from the surface; their memory is checked by :func:`check_contact_memory`.
CONTACTS = Option("int", DEFAULT_CONTACTS, "number of contacts sampled from the surface", minimum=1)
#: Seed of the contact sampling (the methods' seeds have the same range).
CONTACT_SEED = Option("int", 0, "seed of the contact sampling", minimum=0, maximum=MAX_SEED)
#: The object's bounding-box diagonal [m] (scales built-in, fetched and, when given, mesh objects).
DIAGONAL = Option("float", None, "the object's bounding-box diagonal [m]", minimum=MIN_DIAGONAL, maximum=MAX_DIAGONAL)
#: Fingertip radius [m] the contacts are kept for: 0 = plain sampling; at most the largest object.
TIP_RADIUS = Option("float", None, "fingertip radius [m]", minimum=0, maximum=MAX_DIAGONAL)

#: Memory of planning on n contacts with k cone edges: ``BASE + n (PER_CONTACT + PER_EDGE k)``
#: bytes. Measured as the peak RSS of ``ogcp plan box -n N --cone-edges K --time-limit 20``
#: (A*; n = 1000 to 300 000 at k = 8, and k = 32 and 64 at n = 30 000): 21 kB per contact at
#: k = 8, 69 kB at k = 32, 136 kB at k = 64, over a 270 MB interpreter with numpy, trimesh and
#: the kernels. Sampling alone takes about 1.2 kB per contact; exhaustive search took 4x the
#: estimate at n = 30 000 (so the estimate is a floor: it refuses only what cannot fit).
MEMORY_BASE = 300 * 2**20
MEMORY_PER_CONTACT = 5 * 2**10
MEMORY_PER_EDGE = 2 * 2**10
#: Bytes per grasp of an exhaustive-search chunk, per contact of the grasp: its int64 indices,
#: plus the constraint masks, sort orders and gathered bounds made from them.
MEMORY_PER_CHUNK_INDEX = 4 * 8
#: Fraction of the machine's memory an estimate may take: the rest is the system's, and a
#: search's open list grows past the estimate while it runs.
MEMORY_FRACTION = 0.8


def planning_memory(n: int, k: int, m: int | None = None, chunk: int | None = None) -> int:
    """Estimated peak memory of sampling ``n`` contacts with ``k`` cone edges and planning on them [bytes].

    Args:
        n: Number of contacts.
        k: Friction-cone edges.
        m: Contacts per grasp (with ``chunk``: exhaustive search's chunks).
        chunk: Grasps per chunk of exhaustive search; None for the other methods.
    """
    total = MEMORY_BASE + n * (MEMORY_PER_CONTACT + MEMORY_PER_EDGE * k)
    if chunk is not None and m is not None:
        total += chunk * m * MEMORY_PER_CHUNK_INDEX
    return total


def memory_size() -> int | None:
    """This machine's memory [bytes]: physical memory, or a smaller container (cgroup v2) limit; None if unknown."""
    sizes = []
    try:
        sizes.append(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        pass
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit.isdigit():
            sizes.append(int(limit))
    except OSError:
        pass
    return min(sizes) if sizes else None


def check_contact_memory(n: int, k: int, m: int | None = None, chunk: int | None = None) -> None:
    """Refuse a problem whose estimated memory (:func:`planning_memory`) exceeds this machine's.

    Called before anything of the size of ``n`` is allocated, so that an impossible request
    ends at once with the estimate instead of swapping or being killed minutes later.

    Raises:
        OgcpError: With the estimate, the limit and the largest n that fits.
    """
    size = memory_size()
    if size is None:
        return
    limit = MEMORY_FRACTION * size
    need = planning_memory(n, k, m, chunk)
    if need <= limit:
        return
    fits = max(0, int((limit - planning_memory(0, k, m, chunk)) // (MEMORY_PER_CONTACT + MEMORY_PER_EDGE * k)))
    raise OgcpError(
        f"{n} contacts with {k} cone edges need about {_gib(need)} to sample and plan on "
        f"({_kib(MEMORY_PER_CONTACT + MEMORY_PER_EDGE * k)} per contact); this machine's limit is {_gib(limit)} "
        f"({100 * MEMORY_FRACTION:g} % of {_gib(size)}): use at most about {fits} contacts"
    )


def _gib(size: float) -> str:
    return f"{size / 2**30:.3g} GiB"


def _kib(size: float) -> str:
    return f"{size / 2**10:.3g} kiB"
