"""Method configurations and the registry: validation, resolved defaults, one default per parameter."""

from __future__ import annotations

import dataclasses
import inspect

import pytest

from ogcp.planner.baselines import HFTS, ExhaustiveSearch
from ogcp.planner.config import ConfigError, Option, options_of
from ogcp.planner.config.methods import (
    DEFAULT_HAND_THRESHOLD,
    HANDS,
    AStarConfig,
    DijkstraConfig,
    ESConfig,
    ESPrunedConfig,
    HFTSConfig,
    WAStarConfig,
)
from ogcp.planner.hands.reachability import SDHReachability
from ogcp.planner.hands.registry import BUILTIN_HANDS
from ogcp.planner.infra import OgcpError
from ogcp.planner.methods.registry import EXHAUSTIVE_METHODS, METHODS, OPTIMAL_METHODS, SEARCH_METHODS, method_spec
from ogcp.planner.search import GraspPlanner

INVALID = [
    (AStarConfig, {"successor": "xx"}, "unknown successor 'xx'; valid choices: fc, ru"),
    (AStarConfig, {"heuristic": "xx"}, "unknown heuristic 'xx'; valid choices: fc, none, ru"),
    (AStarConfig, {"branching": 1}, "branching: expected an integer >= 2, got 1"),
    (AStarConfig, {"branching": 2.5}, "branching: expected an integer >= 2, got 2.5"),
    (AStarConfig, {"branching": True}, "branching: expected an integer >= 2, got True"),
    (AStarConfig, {"heuristic_branching": 1}, "heuristic_branching: expected an integer >= 2"),
    (AStarConfig, {"symmetry": 1}, "symmetry: expected true or false, got 1"),
    (AStarConfig, {"seed": -1}, "seed: expected an integer >= 0, got -1"),
    (AStarConfig, {"kmeans_iterations": 0}, "kmeans_iterations: expected an integer >= 1"),
    (AStarConfig, {"position_weight": 0.0}, "position_weight: expected a number > 0, got 0.0"),
    (AStarConfig, {"position_weight": float("nan")}, "position_weight: expected a number > 0"),
    (AStarConfig, {"max_spread": -1.0}, "max_spread: expected a number > 0, got -1.0"),
    (
        AStarConfig,
        {"hand": "allegro"},
        "unknown hand 'allegro'; built-in hands are sdh, shadow_hand, parallel_gripper, or give FILE.toml",
    ),
    (AStarConfig, {"hand_threshold": 0.2}, "hand_threshold: applies only with a hand"),
    (AStarConfig, {"hand_fingers": ["thumb"]}, "hand_fingers: applies only with a hand"),
    (AStarConfig, {"hand": "sdh", "hand_fingers": ["a", "a"]}, "hand_fingers: names a value twice: a, a"),
    (AStarConfig, {"hand": "sdh", "hand_fingers": []}, "hand_fingers: expected a list of 1 to 64 non-empty names"),
    (AStarConfig, {"hand": ""}, "hand: expected a non-empty string"),
    (AStarConfig, {"hand": "sdh", "hand_threshold": 0}, "hand_threshold: expected a number > 0, got 0"),
    (WAStarConfig, {"eps": -1}, "eps: expected a number >= 0, got -1"),
    (DijkstraConfig, {"heuristic": "fc"}, "method 'dijkstra' uses no heuristic (got heuristic 'fc'); valid: none"),
    (ESConfig, {"chunk": 0}, "chunk: expected an integer >= 1, got 0"),
    (ESConfig, {"bins": 0}, "bins: expected an integer >= 1, got 0"),
    (ESPrunedConfig, {"max_spread": 0}, "max_spread: expected a number > 0, got 0"),
    (HFTSConfig, {"runs": 0}, "runs: expected an integer >= 1, got 0"),
    (HFTSConfig, {"iterations": -3}, "iterations: expected an integer >= 1, got -3"),
    (HFTSConfig, {"hand_threshold": 0.5}, "hand_threshold: applies only with a hand"),
]


@pytest.mark.parametrize("config, values, message", INVALID)
def test_invalid_values_name_the_field_and_the_valid_values(config, values, message):
    with pytest.raises(OgcpError) as info:
        config(**values)
    assert message in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize(
    "config, values", [(AStarConfig, {"eps": 0.4}), (ESPrunedConfig, {"bins": 5}), (HFTSConfig, {"max_spread": 0.1})]
)
def test_a_parameter_of_another_method_is_not_accepted(config, values):
    with pytest.raises(TypeError):
        config(**values)


def test_dependent_defaults_are_resolved_and_values_canonical():
    assert AStarConfig().heuristic_branching == 2 and AStarConfig(branching=4).heuristic_branching == 4
    assert AStarConfig(branching=4, heuristic_branching=3).heuristic_branching == 3
    assert DijkstraConfig().heuristic == "none" and AStarConfig().heuristic == "fc"
    assert WAStarConfig().eps == 0.4
    eps = WAStarConfig(eps=1).eps
    assert eps == 1.0 and isinstance(eps, float)  # a suite's integer 1 hashes as 1.0
    assert AStarConfig().hand_threshold is None and AStarConfig(hand="sdh").hand_threshold == DEFAULT_HAND_THRESHOLD
    assert HFTSConfig(hand="sdh", hand_threshold=0.5).hand_threshold == 0.5
    with pytest.raises(dataclasses.FrozenInstanceError):
        AStarConfig().branching = 3  # type: ignore[misc]


def test_canonical_form_is_every_parameter_sorted():
    canonical = WAStarConfig(eps=0.2).canonical()
    assert list(canonical) == sorted(options_of(WAStarConfig)) and canonical["eps"] == 0.2
    assert "bins" in ESConfig().canonical() and "bins" not in ESPrunedConfig().canonical()
    assert set(HFTSConfig().canonical()) == {
        "hand",
        "hand_fingers",
        "hand_threshold",
        "iterations",
        "position_weight",
        "runs",
        "seed",
    }


def test_every_option_is_declared_with_a_valid_default_and_help():
    for spec in METHODS.values():
        for name, declared in spec.options().items():
            assert isinstance(declared, Option) and declared.help, name
            if declared.default is not None:
                assert declared.check(name, declared.default) == declared.default
        spec.config()  # every default configuration is valid


def test_registry_names_titles_and_guarantees():
    assert list(METHODS) == ["astar", "dijkstra", "wastar", "es", "es-pruned", "hfts"]
    assert SEARCH_METHODS == ("astar", "dijkstra", "wastar")
    assert OPTIMAL_METHODS == ("astar", "dijkstra", "es", "es-pruned") and EXHAUSTIVE_METHODS == ("es", "es-pruned")
    assert {name: spec.title for name, spec in METHODS.items()}["es-pruned"] == "ES (pruned)"
    assert all(spec.config.method == name for name, spec in METHODS.items())
    with pytest.raises(
        OgcpError, match="unknown method 'bfs'; valid choices: astar, dijkstra, es, es-pruned, hfts, wastar"
    ):
        method_spec("bfs")


def test_a_spec_runs_only_its_own_configuration(object_contacts):
    with pytest.raises(TypeError, match="AStarConfig"):
        method_spec("astar").run(DijkstraConfig(), object_contacts("box", 8, 0), 3)


def _default(function, name):
    return inspect.signature(function).parameters[name].default


def test_engine_constructors_take_their_defaults_from_the_configurations():
    for name in ("branching", "successor", "symmetry", "ordered", "seed", "kmeans_iterations", "position_weight"):
        assert _default(GraspPlanner, name) == getattr(AStarConfig(), name), name
    assert _default(GraspPlanner, "record_tree") is AStarConfig().record_tree
    assert _default(GraspPlanner, "method") == "astar"
    assert GraspPlanner(method="dijkstra").resolved_config()["heuristic"] == DijkstraConfig().heuristic
    assert GraspPlanner(method="wastar").resolved_config()["eps"] == WAStarConfig().eps
    assert (_default(ExhaustiveSearch, "chunk"), _default(ExhaustiveSearch, "bins")) == (
        ESConfig().chunk,
        ESConfig().bins,
    )
    for name in ("runs", "iterations", "seed", "position_weight"):
        assert _default(HFTS, name) == getattr(HFTSConfig(), name), name
    assert _default(SDHReachability, "threshold") == AStarConfig(hand="sdh").hand_threshold
    assert set(BUILTIN_HANDS) == set(HANDS)


def test_config_errors_carry_the_field_for_callers_that_prefix_a_key_path():
    with pytest.raises(ConfigError) as info:
        ESConfig(hand_threshold=0.2)
    assert info.value.field == "hand_threshold" and info.value.problem.startswith("applies only with a hand")
