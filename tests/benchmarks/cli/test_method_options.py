"""``ogcp plan``'s method flags come from the method configurations, and plan as a suite cell does."""

from __future__ import annotations

import argparse
import json
import textwrap

import pytest

from ogcp.benchmarks.cli import build_parser
from ogcp.benchmarks.cli.method_options import config_from_args, declared_options, flag
from ogcp.benchmarks.suite.cells import contact_set, plan_record
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.planner.config.methods import DEFAULT_FINGERS, DEFAULT_METHOD
from ogcp.planner.methods import METHODS, method_spec
from tests.cli_run import run_cli


def _plan_args(*argv: str):
    return build_parser().parse_args(["plan", "box", *argv])


def _help(option_flag: str) -> str:
    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return next(a.help for a in commands.choices["plan"]._actions if option_flag in a.option_strings)


@pytest.mark.parametrize("method", list(METHODS))
def test_no_flags_give_the_configuration_defaults(method):
    spec = method_spec(method)
    assert config_from_args(spec, _plan_args("--method", method)) == spec.config()


def test_plan_defaults_and_help_come_from_the_configurations():
    args = _plan_args()
    assert (args.method, args.fingers) == (DEFAULT_METHOD, DEFAULT_FINGERS)
    for field, declared in declared_options().items():
        defaults = {d.default for d in declared.values()} - {None, False}
        text = _help(flag(field))
        for default in defaults:
            shown = f"{default:g}" if isinstance(default, float) else str(default)
            assert shown in text.partition("(default ")[2], (field, text)
        for choice in {c for d in declared.values() for c in d.choices}:
            assert choice in text, (field, text)
    assert _help("--heuristic").endswith("(default fc; none for dijkstra)")
    assert _help("--eps").endswith("(default 0.4 for wastar)")


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--method", "es", "--branching", "3"], "--branching applies to methods astar, dijkstra, wastar only"),
        (["--method", "hfts", "--max-spread", "0.1"], "--max-spread applies to methods astar, dijkstra, wastar, es"),
        (["--method", "es-pruned", "--bins", "7"], "--bins applies to method 'es' only"),
        (["--method", "astar", "--runs", "3"], "--runs applies to method 'hfts' only"),
        (["--method", "astar", "--backend", "dask"], "--backend applies to methods es, es-pruned, hfts only"),
        (["--method", "es", "--no-optimum"], "--no-optimum applies to method 'hfts' only"),
        (["--method", "astar", "--hand-threshold", "0.2"], "hand_threshold: applies only with a hand"),
        (["--method", "hfts", "--runs", "0"], "runs: expected an integer >= 1, got 0"),
    ],
)
def test_flags_are_checked_against_the_method(argv, message):
    status, out, err = run_cli(["plan", "box", "-n", "8", *argv])
    assert status == 2 and out == ""
    assert err.startswith("ogcp: error: ") and message in err and len(err.splitlines()) == 1


def _comparable(value):
    """A record without what legitimately differs between runs: timings and the machine's provenance."""
    if isinstance(value, dict):
        return {
            k: _comparable(v)
            for k, v in value.items()
            if not k.endswith("_seconds") and k not in ("trace", "peak_rss_bytes")
        }
    if isinstance(value, list):
        return [_comparable(v) for v in value]
    return value


CASES = [
    ("astar", {}, []),
    ("wastar", {"eps": 0.2, "branching": 3}, ["--eps", "0.2", "--branching", "3"]),
    ("dijkstra", {"successor": "ru"}, ["--successor", "ru"]),
    ("astar", {"max_spread": 0.15, "record_tree": True}, ["--max-spread", "0.15", "--record-tree"]),
    ("es", {"chunk": 100}, ["--chunk", "100"]),
    ("es-pruned", {"max_spread": 0.15}, ["--max-spread", "0.15"]),
    ("hfts", {"runs": 3, "iterations": 5, "seed": 2}, ["--runs", "3", "--iterations", "5", "--no-optimum"]),
]


@pytest.mark.parametrize("method, params, flags", CASES, ids=[c[0] for c in CASES])
def test_cli_and_suite_cell_write_the_same_plan_record(method, params, flags):
    contact_seed = params.get("seed", 0)  # ogcp plan's --seed seeds both the contacts and the method
    entries = "\n".join(f"{key} = {json.dumps(value)}" for key, value in params.items())
    suite = parse_suite(
        textwrap.dedent(f"""
        schema_version = 1
        objects = ["box"]
        contacts = 14
        contact_seeds = [{contact_seed}]
        [[methods]]
        method = "{method}"
        """)
        + entries
    )
    (cell,) = suite.cells
    from_suite = plan_record(cell, contact_set(cell))
    status, out, _ = run_cli(
        ["plan", "box", "-n", "14", "-m", "3", "--method", method, "--seed", str(contact_seed), "--json", *flags]
    )
    assert status == 0
    from_cli = json.loads(out)
    assert _comparable(from_cli) == _comparable(json.loads(json.dumps(from_suite)))
    assert from_cli["config"]["seed"] == contact_seed


def test_cli_and_suite_cell_agree_with_a_hand(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    suite = parse_suite(
        'schema_version = 1\nobjects = ["donut"]\ncontacts = 20\n[[methods]]\nmethod = "astar"\nhand = "sdh"'
    )
    (cell,) = suite.cells
    from_suite = plan_record(cell, contact_set(cell))
    status, out, _ = run_cli(["plan", "donut", "-n", "20", "--hand", "sdh", "--json"])
    assert status == 0 and "hand" in from_suite
    assert _comparable(json.loads(out)) == _comparable(json.loads(json.dumps(from_suite)))
