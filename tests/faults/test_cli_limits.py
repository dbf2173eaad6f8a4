"""Every number ogcp takes has a finite range: out of it, one line ``ogcp: error: ...``, exit status 2.

Each flag is tried where it used to hang, exhaust memory or answer wrongly (``--cone-edges
100000`` never finished, ``-n 100000000`` allocated until killed, ``--mu 1e308`` reported Q1 = 0
as certified, ``--diagonal 1e9`` was taken). The same ranges hold in the Python API, and
``--help`` shows them. ``ogcp evaluate``'s plan and settings files are checked field by field.
"""

from __future__ import annotations

import contextlib
import copy
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from ogcp.benchmarks.cli import build_parser
from ogcp.benchmarks.cli.simulate import settings_file, sim_summary
from ogcp.planner import builtin_mesh
from ogcp.planner.config.methods import AStarConfig, HFTSConfig
from ogcp.planner.config.options import ConfigError
from ogcp.planner.grasp import defaults
from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.infra.errors import OgcpError
from ogcp.sim_eval.settings import SimSettings
from tests.faults import run_cli

_run = run_cli


def _one_error(argv: list[str]) -> str:
    status, out, err = _run(argv)
    assert status == 2 and out == "", (argv, status, out, err)
    assert err.startswith("ogcp: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(autouse=True)
def _cache(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OGCP_CACHE", str(cache))


@pytest.fixture(autouse=True)
def _memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """A machine of 16 GiB, so that the memory limits are the same everywhere."""
    monkeypatch.setattr(defaults, "memory_size", lambda: 16 * 2**30)


PLAN = ["plan", "box", "-n", "12"]
LIMITS = {
    "cone edges": (
        PLAN + ["--cone-edges", "100000"],
        "--cone-edges: expected an integer <= 64, got 100000 (valid: 3 to 64)",
    ),
    "mu huge": (PLAN + ["--mu", "1e308"], "--mu: expected a number <= 10, got 1e+308"),
    "mu 100": (PLAN + ["--mu", "100"], "--mu: expected a number <= 10, got 100.0 (valid: > 0 and <= 10)"),
    "mu nan": (PLAN + ["--mu", "nan"], "--mu: expected a number > 0, got nan"),
    "diagonal huge": (PLAN + ["--diagonal", "1e9"], "argument --diagonal: expected a number <= 100, got 1000000000.0"),
    "diagonal tiny": (PLAN + ["--diagonal", "1e-300"], "argument --diagonal: expected a number >= 0.001"),
    "contacts huge": (["plan", "box", "-n", "100000000"], "100000000 contacts with 8 cone edges need about 2e+03 GiB"),
    "contacts file": (["contacts", "box", "-n", "10000000", "-o", "c.json"], "(80 % of 16 GiB): use at most about "),
    "seed": (PLAN + ["--seed", str(2**32)], "seed: expected an integer <= 4294967295, got 4294967296"),
    "tip radius": (PLAN + ["--tip-radius", "1e9"], "--tip-radius: expected a number <= 100"),
    "branching": (PLAN + ["--branching", "1000000000"], "branching: expected an integer <= 64"),
    "kmeans": (PLAN + ["--kmeans-iterations", "1000000000"], "kmeans_iterations: expected an integer <= 1000"),
    "weight": (PLAN + ["--position-weight", "1e308"], "position_weight: expected a number <= 1000"),
    "spread": (PLAN + ["--max-spread", "1e308"], "max_spread: expected a number <= 100"),
    "hand": (PLAN + ["--hand", "sdh", "--hand-threshold", "1e308"], "hand_threshold: expected a number <= 10,"),
    "eps": (PLAN + ["--method", "wastar", "--eps", "1e308"], "eps: expected a number <= 100, got 1e+308"),
    "chunk": (PLAN + ["--method", "es", "--chunk", "1000000000000"], "chunk: expected an integer <= 10000000"),
    "bins": (PLAN + ["--method", "es", "--bins", "1000000000000"], "bins: expected an integer <= 10000,"),
    "runs": (PLAN + ["--method", "hfts", "--runs", "1000000000"], "runs: expected an integer <= 10000,"),
    "iterations": (PLAN + ["--method", "hfts", "--iterations", "1000000000"], "iterations: expected an integer <="),
    "wrong type": (
        PLAN + ["--mu", "abc"],
        "argument --mu: expected a number > 0, got 'abc' (valid: > 0 and <= 10); see ogcp plan --help",
    ),
    "max grasps": (
        ["evaluate", "p.json", "--max-grasps", "0"],
        "argument --max-grasps: expected an integer >= 1, got 0",
    ),
    "directions": (["evaluate", "p.json", "--directions", "1000000000"], "--directions: expected an integer <= 10000"),
    "max force": (["evaluate", "p.json", "--max-force", "1e308"], "--max-force: expected a number <= 10000"),
    "ramp time": (["evaluate", "p.json", "--ramp-time", "1e308"], "--ramp-time: expected a number <= 600"),
    "threads": (["evaluate", "p.json", "--threads", "100000"], "--threads: expected an integer <= 1024"),
    "sim tip": (["evaluate", "p.json", "--tip-radius", "0"], "--tip-radius: expected a number > 0, got 0.0"),
    "decompose": (["decompose", "box", "--diagonal", "1e9"], "--diagonal: expected a number <= 100"),
    "jobs": (["suite", "quick", "--out", "o", "--jobs", "100000"], "argument --jobs: expected an integer <= "),
    "suite time": (
        ["suite", "quick", "--out", "o", "--time-limit", "1e308"],
        "--time-limit: expected a number <= 10000000, got 1e+308",
    ),
    "suite nan": (
        ["suite", "quick", "--out", "o", "--time-limit", "nan"],
        "--time-limit: expected a number > 0, got nan",
    ),
    "dpi": (["plot", "run", "--dpi", "1000000"], "argument --dpi: expected an integer <= 1200, got 1000000"),
    "resistance": (
        ["compare", "a", "b", "--resistance-tolerance", "5"],
        "resistance tolerance is a relative drop from 0",
    ),
}


@pytest.mark.parametrize("case", sorted(LIMITS))
def test_a_number_out_of_range_is_one_error_line(case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv, expected = LIMITS[case]
    assert expected in _one_error(argv)
    assert list(tmp_path.iterdir()) == []  # nothing written, nothing started


@pytest.mark.parametrize(
    ("command", "flag", "shown"),
    [
        ("plan", "--branching", "valid: 2 to 64 (default 2)"),
        ("plan", "--eps", "valid: 0 to 100 (default 0.4 for wastar)"),
        ("plan", "--runs", "valid: 1 to 10000"),
        ("plan", "--diagonal", "0.001 to 100"),
        ("evaluate", "--directions", "valid: 0 to 10000"),
        ("evaluate", "--max-grasps", "valid: >= 1"),
        ("evaluate", "--max-force", "valid: > 0 and <= 10000"),
        ("suite", "--jobs", "valid: 1 to "),
        ("suite", "--time-limit", "> 0 and <= 10000000"),
        ("plot", "--dpi", "valid: 10 to 1200"),
        ("compare", "--resistance-tolerance", "0 to 1"),
    ],
)
def test_help_shows_the_range(command, flag, shown):
    commands = next(a for a in build_parser()._actions if hasattr(a, "choices") and isinstance(a.choices, dict))
    action = next(a for a in commands.choices[command]._actions if flag in a.option_strings)
    assert shown in action.help.replace("%%", "%")


def test_the_api_has_the_same_ranges():
    mesh = builtin_mesh("box")
    with pytest.raises(OgcpError, match="mu must be at most 10"):
        sample_contacts(mesh, 12, mu=1e308)
    with pytest.raises(OgcpError, match="cone_edges must be an integer >= 3, got nan"):
        ContactSet([[0, 0, 0]], [[1, 0, 0]], [0, 0, 0], 1.0, 0.5, float("nan"))
    with pytest.raises(OgcpError, match="diagonal is 1e\\+09 m"):
        sample_contacts(mesh.copy().apply_scale(5e9), 12)
    with pytest.raises(ConfigError, match="branching: expected an integer <= 64, got 65"):
        AStarConfig(branching=65)
    with pytest.raises(ConfigError, match="runs: expected an integer >= 1, got 0 \\(valid: 1 to 10000\\)"):
        HFTSConfig(runs=0)
    with pytest.raises(OgcpError, match="timestep: expected a number >= 1e-05"):
        SimSettings(timestep=1e-12)
    with pytest.raises(OgcpError, match="MuJoCo steps"):
        SimSettings(ramp_time=600, ramp_extent=10, timestep=1e-4)


def test_the_memory_estimate_refuses_before_allocating(monkeypatch):
    def sample(*_: Any, **__: Any) -> None:
        raise AssertionError("sampled although the estimate exceeds the machine")

    monkeypatch.setattr("trimesh.sample.sample_surface_even", sample)
    with pytest.raises(OgcpError) as info:
        sample_contacts(builtin_mesh("box"), 2_000_000, cone_edges=64)
    message = str(info.value)
    assert message.startswith("2000000 contacts with 64 cone edges need about 254 GiB to sample and plan on (133 kiB")
    assert "this machine's limit is 12.8 GiB (80 % of 16 GiB): use at most about 98" in message
    assert (
        defaults.planning_memory(100, 8) < defaults.planning_memory(100, 64) < defaults.planning_memory(100, 64, 5, 10)
    )


# -- ogcp evaluate: the plan file, field by field, and the settings file ------------------


@pytest.fixture(scope="module")
def plan(cache: Path) -> dict[str, Any]:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OGCP_CACHE", str(cache))
        status, out, err = _run(["plan", "box", "-n", "20", "--json"])
    assert status == 0, err
    return dict(json.loads(out))


def _edited(plan: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    record = copy.deepcopy(plan)
    *parents, last = path.split(".")
    node = record
    for key in parents:
        node = node[key]
    node[last] = value
    return record


PLAN_EDITS = [
    ("contacts", "x", "plan field contacts: expected an object, got str 'x'"),
    ("contacts.positions", "x", "plan field contacts.positions: expected a list of [x, y, z] rows"),
    ("contacts.normals", [[1, 0]], "plan field contacts.normals: expected a list of [x, y, z] rows"),
    ("contact_set", 5, "plan field contact_set: expected an object, got int 5"),
    ("contact_set.com", 0.5, "plan field contact_set.com: expected [x, y, z] of finite numbers, got 0.5"),
    ("contact_set.mu", None, "plan field contact_set.mu: expected a number > 0, got None"),
    ("contact_set.mu", 1e308, "plan field contact_set.mu: expected a number <= 10, got 1e+308"),
    ("contact_set.cone_edges", float("nan"), "plan field contact_set.cone_edges: expected an integer >= 3, got nan"),
    ("contact_set.cone_edges", 10**6, "plan field contact_set.cone_edges: expected an integer <= 64"),
    ("contact_set.size", "x", "plan field contact_set.size: expected an integer >= 1, got 'x'"),
    ("contact_set.torque_scale", [], "plan field contact_set.torque_scale: expected a number > 0, got []"),
    ("contact_set.source", "x", "plan field contact_set.source: expected an object, got str 'x'"),
    ("contact_set.source.n", None, "plan field contact_set.source.n: expected an integer >= 1, got None"),
    ("contact_set.source.seed", "x", "plan field contact_set.source.seed: expected an integer >= 0, got 'x'"),
    ("contact_set.source.tip_radius", [1], "plan field contact_set.source.tip_radius: expected a number >= 0"),
    ("contact_set.source.diagonal", 1e9, "plan field contact_set.source.diagonal: expected a number <= 100"),
    ("contact_set.source.name", 5, "plan field contact_set.source.name: expected a string, got 5"),
    ("source.kind", [], "plan field source.kind: expected a string, got []"),
    ("q1", "x", "plan field q1: expected a number >= 0, got 'x'"),
    ("q_ows", -1, "plan field q_ows: expected a number >= 0, got -1"),
    ("grasp", 7, "plan field grasp: expected a list, got int 7"),
    ("grasp", [0, "a", 2], "plan grasp 'best' must be a list of contact indices"),
    ("top", 5, "plan field top: expected a list, got int 5"),
    ("runs", [5], "plan field runs[0]: expected an object with a grasp, got 5"),
]


@pytest.mark.parametrize(("path", "value", "expected"), PLAN_EDITS, ids=[f"{p}={v!r}" for p, v, _ in PLAN_EDITS])
def test_a_malformed_plan_field_is_one_error_line(plan, tmp_path, path, value, expected):
    target = tmp_path / "plan.json"
    target.write_text(json.dumps(_edited(plan, path, value)))
    assert expected in _one_error(["evaluate", str(target)])


SETTINGS = [
    ("s.json", "not json", "not valid JSON (Expecting value at line 1 column 1); a TOML file needs the suffix .toml"),
    ("s.json", "[1, 2]", "simulation settings must be a JSON object of settings by name, got list"),
    ("s.json", '{"ramp_speed": 3}', "unknown simulation setting 'ramp_speed'; valid choices:"),
    ("s.json", '{"slide_armature": "x"}', "simulation setting slide_armature: expected a number > 0, got 'x'"),
    ("s.json", '{"max_normal_force": true}', "simulation setting max_normal_force: expected a number > 0, got True"),
    ("s.json", '{"contact_solref": 5}', "simulation setting contact_solref: expected a list of 2 finite numbers"),
    ("s.json", '{"contact_solimp": [0.9, 0.95, NaN]}', "contact_solimp: expected a list of 3 finite numbers"),
    ("s.json", '{"timestep": 1e-12}', "simulation setting timestep: expected a number >= 1e-05, got 1e-12"),
    ("s.json", '{"settle_time": 1e9}', "simulation setting settle_time: expected a number <= 60"),
    ("s.toml", "timestep = [", "not valid TOML"),
    ("s.toml", "threads = true", "simulation setting threads: expected an integer >= 1, got True"),
    ("missing.json", None, "cannot read simulation settings: No such file or directory"),
]


@pytest.mark.parametrize(("name", "content", "expected"), SETTINGS)
def test_a_malformed_settings_file_is_one_error_line(plan, tmp_path, name, content, expected):
    target, settings = tmp_path / "plan.json", tmp_path / name
    target.write_text(json.dumps(plan))
    if content is not None:
        settings.write_text(content)
    err = _one_error(["evaluate", str(target), "--settings", str(settings)])
    assert err.startswith(f"ogcp: error: {settings}: ") and expected in err


def test_a_toml_settings_file_reads_like_json(tmp_path):
    (tmp_path / "s.toml").write_text("timestep = 0.001\ncontact_solref = [0.004, 1.0]\n")
    assert SimSettings.from_dict(settings_file(tmp_path / "s.toml")).timestep == 0.001


def test_a_diverged_grasp_is_reported_not_a_traceback(plan, tmp_path):
    # The divergence settings of tests/sim_eval/test_sim.py: creep and every load come back NaN.
    target, settings = tmp_path / "plan.json", tmp_path / "s.json"
    target.write_text(json.dumps(plan))
    settings.write_text('{"timestep": 0.05, "slide_armature": 1e-4, "tip_mass": 1e-3}')
    argv = ["evaluate", str(target), "--settings", str(settings), "--directions", "0", "--max-grasps", "1"]
    status, out, err = _run([*argv, "--decomposition", "convex_hull", "-o", str(tmp_path / "sim.json")])
    assert status == 0 and "Traceback" not in err, err
    assert "valid False DIVERGED" in out and "creep - um" in out and "diverged while settling" in out
    record = json.loads((tmp_path / "sim.json").read_text())
    assert record["grasps"][0]["gates"]["creep"] is None  # infinite creep, written as null
    # Whatever a hand-edited record holds, the table prints "-" for it.
    record["grasps"][0].update(gates={"creep": "x"}, realized={"offsets": 3, "normal_angles": [None]}, q1=[1])
    record.update(wall_seconds=None, set_metrics={"median_q1_change": "y", "q1_vs_measured": 1})
    assert "creep - um" in sim_summary(record)


# -- output paths --------------------------------------------------------------------------


@contextlib.contextmanager
def _read_only(folder: Path) -> Iterator[Path]:
    folder.mkdir()
    folder.chmod(0o500)
    try:
        yield folder
    finally:
        folder.chmod(0o700)


def test_an_output_under_a_file_is_refused_before_the_work(plan, tmp_path):
    target, blocker = tmp_path / "plan.json", tmp_path / "file"
    target.write_text(json.dumps(plan))
    blocker.write_text("")
    err = _one_error(["evaluate", str(target), "-o", str(blocker / "sim.json")])
    assert f"cannot write {blocker / 'sim.json'}: {blocker} is a file, not a folder" in err
    assert f"cannot write {tmp_path}: it is a folder" in _one_error(["evaluate", str(target), "-o", str(tmp_path)])
    for argv in (["plan", "box", "-n", "10", "-o"], ["contacts", "box", "-n", "10", "-o"]):
        assert f"cannot write {blocker / 'x.json'}: " in _one_error([*argv, str(blocker / "x.json")])


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_output_folder_is_one_error_line(plan, tmp_path):
    target = tmp_path / "plan.json"
    target.write_text(json.dumps(plan))
    with _read_only(tmp_path / "ro") as folder:
        assert "is not writable" in _one_error(["evaluate", str(target), "-o", str(folder / "sim.json")])
        assert "Permission denied" in _one_error(["plan", "box", "-n", "10", "-o", str(folder / "p.json")])


def test_an_unwritable_output_folder_is_refused_before_the_simulation(plan, tmp_path, monkeypatch):
    # As root every folder is writable, so the refusal is shown by the check's own view of it.
    target = tmp_path / "plan.json"
    target.write_text(json.dumps(plan))
    monkeypatch.setattr(os, "access", lambda *_: False)
    err = _one_error(["evaluate", str(target), "-o", str(tmp_path / "out" / "sim.json")])
    assert f"cannot write {tmp_path / 'out' / 'sim.json'}: the folder {tmp_path} is not writable" in err


def test_an_unwritable_mesh_cache_is_refused_before_the_download(tmp_path, monkeypatch):
    def fetch(*_: Any, **__: Any) -> None:
        raise AssertionError("downloaded although the cache cannot be written")

    monkeypatch.setattr("ogcp.planner.objects.fetch.fetch_objects", fetch)
    blocker = tmp_path / "file"
    blocker.write_text("")
    err = _one_error(["assets", "fetch", "bunny", "--cache", str(blocker)])
    assert f"cannot write the cache folder {blocker / 'meshes'}: {blocker} is a file, not a folder" in err


@pytest.mark.parametrize(
    "name, value", [("resolution", 10**7), ("mcts_nodes", 10**6), ("mcts_iterations", 10**9), ("mcts_max_depth", 99)]
)
def test_coacd_search_settings_have_upper_limits(name, value):
    """A CoACD search that would run for hours is refused up front, naming the range."""
    from ogcp.sim_eval.decomposition.settings import DecompositionSettings

    with pytest.raises(OgcpError, match=f"{name}.*from 1 to"):
        DecompositionSettings(**{name: value})


def test_a_grasp_whose_simulation_fails_is_reported_in_one_line(plan, tmp_path, monkeypatch):
    """MuJoCo's own errors span two lines ("Element name ..."): the record and the table get one."""
    from ogcp.sim_eval import evaluate as evaluate_module

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise ValueError("Error: mocap body 'hand/palm' is not a fixed child of world\nElement name 'hand/palm', id 2")

    monkeypatch.setattr(evaluate_module, "simulate_grasp", refuse)
    target = tmp_path / "plan.json"
    target.write_text(json.dumps(plan))
    argv = ["evaluate", str(target), "--directions", "0", "--max-grasps", "1", "--decomposition", "convex_hull"]
    status, out, err = _run([*argv, "-o", str(tmp_path / "sim.json")])
    assert status == 0 and "Traceback" not in err, err
    error = json.loads((tmp_path / "sim.json").read_text())["grasps"][0]["error"]
    assert (
        error
        == "ValueError: Error: mocap body 'hand/palm' is not a fixed child of world Element name 'hand/palm', id 2"
    )
    (line,) = [row for row in out.splitlines() if "ERROR" in row]
    assert line.endswith("id 2")
