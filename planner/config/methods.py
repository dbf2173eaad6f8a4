"""The configuration of every planning method: one frozen, validated dataclass each.

Every default, range, choice list and help line of a method parameter is declared here
once. The engines' constructors (:class:`~ogcp.planner.search.grasp_planner.GraspPlanner`,
:class:`~ogcp.planner.baselines.es.ExhaustiveSearch`, :class:`~ogcp.planner.baselines.hfts.HFTS`)
take their defaults from these classes, and ``ogcp plan``'s flags and the suites'
parameter tables are generated from them. This module imports nothing but the option
machinery, so every engine can import it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ogcp.planner.config.options import ConfigError, MethodConfig, Option, field_of, option

#: Method of ``ogcp plan`` and of :class:`GraspPlanner` when none is named.
DEFAULT_METHOD = "astar"
#: Number of contacts (fingers) m when none is given.
DEFAULT_FINGERS = 3
#: Seed of every random choice when none is given.
DEFAULT_SEED = 0
#: Expansion successor functions: k-means (fc) or random uniform (ru) splits.
SUCCESSORS = ("fc", "ru")
#: Successor functions of the heuristic; ``none`` is h = 0.
HEURISTICS = (*SUCCESSORS, "none")
#: WA*'s inflation eps when none is given (the other searches have eps = 0).
DEFAULT_WASTAR_EPS = 0.4
#: Built-in hands a grasp can be constrained to by name (ogcp.planner.hands.registry has their
#: descriptors); any other hand is named by the path of its ogcp.hand/1 descriptor (*.toml).
HANDS = ("sdh", "shadow_hand", "parallel_gripper")
#: Largest reachability residual of a reachable grasp (normalised code distance).
DEFAULT_HAND_THRESHOLD = 1.0
#: Grasps per chunk of exhaustive search (the unit of parallel work and of checkpoints).
DEFAULT_CHUNK = 200_000
#: Bins of exhaustive search's Q1 histogram over (0, Q_OWS].
DEFAULT_BINS = 50

SEED = Option("int", DEFAULT_SEED, "seed of every random choice", minimum=0)
POSITION_WEIGHT = Option("float", 1.0, "position weight in fc features", minimum=0, exclusive=True)
#: The searches' weight of positions in Γ^fc's k-means features ``[w (p - com) / rho, n]``, which
#: shapes the tree and so how many states A* expands. With 1000 contacts (m = 3-5, t = 10) A*
#: expanded 1.8-6.2x fewer states than at w = 1 on the bunny, homer, plane and amphora, as many
#: (+-7 %) on the sphere and donut, and 1.2-1.6x more on the box (README, "Position weight and
#: converged k-means"). HFTS keeps w = 1.
SEARCH_POSITION_WEIGHT = Option("float", 2.0, "position weight in fc features", minimum=0, exclusive=True)


@dataclass(frozen=True, kw_only=True)
class SpreadOption(MethodConfig):
    """The finger-spread constraint."""

    max_spread: float | None = option(
        "float",
        None,
        "constraint: maximum distance between any two contacts [m]",
        minimum=0,
        exclusive=True,
        metavar="METRES",
    )


@dataclass(frozen=True, kw_only=True)
class HandOptions(MethodConfig):
    """The hand constraint: fingertips reachable by a hand model.

    ``hand_threshold`` is set only together with ``hand``; with a hand and no threshold
    it becomes :data:`DEFAULT_HAND_THRESHOLD`.
    """

    hand: str | None = option(
        "text",
        None,
        f"constraint: the fingers of this hand reach the contacts: {', '.join(HANDS)}, or an ogcp.hand/1 "
        "descriptor (FILE.toml); m <= its fingers",
        metavar="NAME|FILE.toml",
    )
    hand_fingers: tuple[str, ...] | None = option(
        "names",
        None,
        "the hand's fingers that take the m contacts, by name, comma-separated (default: its first m)",
        metavar="A,B,...",
        sweep=False,
    )
    hand_threshold: float | None = option(
        "float",
        None,
        f"largest reachability residual (default {DEFAULT_HAND_THRESHOLD:g})",
        minimum=0,
        exclusive=True,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.hand is None:
            for name in ("hand_threshold", "hand_fingers"):
                if getattr(self, name) is not None:
                    raise ConfigError(name, "applies only with a hand (hand = NAME or FILE.toml)")
        elif not self.hand.lower().endswith(".toml") and self.hand not in HANDS:
            raise ConfigError(
                "hand", f"unknown hand {self.hand!r}; built-in hands are {', '.join(HANDS)}, or give FILE.toml"
            )
        if self.hand is not None and self.hand_threshold is None:
            object.__setattr__(self, "hand_threshold", DEFAULT_HAND_THRESHOLD)


#: Most plans ``realise`` may ask for: each is a full search and a fit.
MAX_REALISE = 50


@dataclass(frozen=True, kw_only=True)
class ConstraintOptions(HandOptions, SpreadOption):
    """Every grasp constraint: finger spread and hand (fields in that order), and how many plans may
    be made to find a grasp the hand realises (:mod:`ogcp.sim_eval.realise`)."""

    realise: int | None = option(
        "int",
        None,
        "with a hand: fit it to the planned grasp as ogcp evaluate does (against the object's convex parts) and, "
        "where it cannot realise it, plan again without it, up to N plans; the record lists the grasps rejected",
        minimum=1,
        maximum=MAX_REALISE,
        metavar="N",
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.realise is not None and self.hand is None:
            raise ConfigError("realise", "applies only with a hand (hand = NAME or FILE.toml): it fits that hand")


@dataclass(frozen=True, kw_only=True)
class SearchConfig(MethodConfig):
    """Parameters shared by the best-first searches (A*, WA*, Dijkstra).

    ``heuristic_branching`` left unset becomes ``branching``.
    """

    branching: int = option("int", 2, "branching factor b >= 2", minimum=2)
    successor: str = option("choice", "fc", "expansion successors: {choices}", choices=SUCCESSORS)
    heuristic: str = option("choice", "fc", "heuristic successors: {choices}", choices=HEURISTICS)
    heuristic_branching: int | None = option("int", None, "b of the heuristic (default: branching)", minimum=2)
    symmetry: bool = option("bool", False, "approximate geometric symmetry removal (may lose optimality)")
    ordered: bool = option("bool", False, "keep finger order (the paper's raw search tree)")
    # A tree is an output switch, not a variant: a suite may not sweep it.
    record_tree: bool = option(
        "bool",
        False,
        "keep the search tree (parent, level, f, visited per state) in the JSON result",
        sweep=False,
    )
    # Lloyd's loop stops once converged (ogcp.planner.search.partitions), so t is a cap: 100 costs no more
    # than 10 did. At w = 2 converged trees took A* from 12 % more (donut m = 3) to 35 % fewer (plane
    # m = 5) expansions than t = 10 (1000 contacts; README, "Position weight and converged k-means").
    kmeans_iterations: int = option("int", 100, "most k-means iterations t for fc", minimum=1)
    position_weight: float = field_of(SEARCH_POSITION_WEIGHT)
    seed: int = field_of(SEED)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.heuristic_branching is None:
            object.__setattr__(self, "heuristic_branching", self.branching)


@dataclass(frozen=True, kw_only=True)
class AStarConfig(ConstraintOptions, SearchConfig):
    """A*: the optimal grasp."""

    method: ClassVar[str] = "astar"


@dataclass(frozen=True, kw_only=True)
class WAStarConfig(AStarConfig):
    """Weighted A*: a grasp whose cost is within 1 + eps of the optimal cost."""

    method: ClassVar[str] = "wastar"
    eps: float = option("float", DEFAULT_WASTAR_EPS, "WA* inflation eps >= 0", minimum=0)


@dataclass(frozen=True, kw_only=True)
class DijkstraConfig(AStarConfig):
    """Dijkstra: uniform-cost search, the optimal grasp without a heuristic."""

    method: ClassVar[str] = "dijkstra"
    heuristic: str = option("choice", "none", "heuristic successors: {choices}", choices=("none",))

    def __post_init__(self) -> None:
        # Checked first: "uses no heuristic" says more than the generic list of one choice.
        if self.heuristic != "none":
            raise ConfigError(
                "heuristic", f"method 'dijkstra' uses no heuristic (got heuristic {self.heuristic!r}); valid: none"
            )
        super().__post_init__()


@dataclass(frozen=True, kw_only=True)
class ChunkOption(MethodConfig):
    """How exhaustive search splits the grasps."""

    chunk: int = option("int", DEFAULT_CHUNK, "grasps per chunk", minimum=1)


@dataclass(frozen=True, kw_only=True)
class ESPrunedConfig(ConstraintOptions, ChunkOption):
    """Exhaustive search that skips grasps whose bound cannot beat the best (no histogram)."""

    method: ClassVar[str] = "es-pruned"


@dataclass(frozen=True, kw_only=True)
class ESConfig(ConstraintOptions, ChunkOption):
    """Exhaustive search: the exact Q1 of every grasp and their histogram."""

    method: ClassVar[str] = "es"
    bins: int = option("int", DEFAULT_BINS, "histogram bins", minimum=1)


@dataclass(frozen=True, kw_only=True)
class HFTSConfig(HandOptions):
    """HFTS, the randomised baseline: R independent seeded runs."""

    method: ClassVar[str] = "hfts"
    runs: int = option("int", 20, "independent runs, seeds S..S+R-1", minimum=1)
    iterations: int = option("int", 40, "moves per level", minimum=1)
    seed: int = field_of(SEED)
    position_weight: float = field_of(POSITION_WEIGHT)


#: The best-first searches by method name.
SEARCH_CONFIGS: dict[str, type[AStarConfig]] = {c.method: c for c in (AStarConfig, DijkstraConfig, WAStarConfig)}
