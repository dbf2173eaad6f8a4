"""Benchmark suites: validation, stable cell ids, the runner (serial, loky, Dask), resume, errors."""

from __future__ import annotations

import contextlib
import io
import itertools
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from ogcp import sim_eval
from ogcp.benchmarks import cli
from ogcp.benchmarks.suite.parse import builtin_suites, load_suite, parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import q1, sample_contacts
from ogcp.planner.infra import OgcpError

ROOT = Path(__file__).resolve().parents[3]
TINY = """
schema_version = 1
name = "tiny"
objects = ["box", "sphere"]
contacts = 16
contact_seeds = [0]
m = [3]

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "wastar"
eps = [0.5, 1.0]
label = "WA* {eps:g}"

[[methods]]
method = "dijkstra"

[[methods]]
method = "es"

[[methods]]
method = "hfts"
runs = 3
iterations = 5

[[methods]]
method = "astar"
max_spread = 0.15

[[methods]]
method = "es"
max_spread = 0.15
"""
TINY_CELLS = 2 * 8


def _ogcp(argv: list[str], monkeypatch: pytest.MonkeyPatch) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(argv)
    return status, out.getvalue(), err.getvalue()


def _comparable(value):
    """A record without what legitimately differs between runs: timings, memory, finish times, provenance.

    Provenance holds the checkout's commit with ``-dirty``: a process started after a file was
    edited (a worker) records another value than one started before it.
    """
    if isinstance(value, dict):
        skip = ("finished_at", "provenance", "peak_rss_bytes")
        return {k: _comparable(v) for k, v in value.items() if not k.endswith("_seconds") and k not in skip}
    if isinstance(value, list):
        return [_comparable(v) for v in value]
    return value


def _results(directory: Path) -> dict[str, dict]:
    records = ResultStore(directory).read().records
    ids = [r["id"] for r in records]
    assert len(ids) == len(set(ids)), "a cell was recorded twice"
    return {r["id"]: _comparable(r) for r in records}


@pytest.fixture(scope="module")
def tiny_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("suite") / "tiny.toml"
    path.write_text(TINY)
    return path


@pytest.fixture(scope="module")
def serial_run(tiny_file, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("serial") / "out"
    summary = SuiteRunner(load_suite(tiny_file), out).run()
    assert summary.ran == TINY_CELLS and summary.errors == 0
    return out


# -- suite files ---------------------------------------------------------------------------------


def test_cells_are_the_cartesian_product_with_stable_ids():
    suite = parse_suite(TINY)
    assert len(suite.cells) == TINY_CELLS
    assert len({c.id for c in suite.cells}) == TINY_CELLS
    wastar = [c for c in suite.cells if c.method == "wastar"]
    assert sorted(dict(c.variant)["eps"] for c in wastar) == [0.5, 0.5, 1.0, 1.0]
    assert {c.label for c in wastar} == {"WA* 0.5", "WA* 1"}
    # Reordered objects, methods and eps, comments added, defaults spelled out: the same cells.
    blocks = TINY.split("[[methods]]")
    reordered = (
        blocks[0].replace('["box", "sphere"]', '["sphere", "box"]')
        + "# comment\n"
        + "[[methods]]".join(["", *reversed(blocks[1:])])
        .replace("[0.5, 1.0]", "[1.0, 0.5]")
        .replace('method = "astar"', 'method = "astar"\nbranching = 2\nsymmetry = false')
    )
    again = parse_suite(reordered)
    assert sorted(c.id for c in again.cells) == sorted(c.id for c in suite.cells)
    assert again.hash == suite.hash
    # A changed parameter is another cell; a changed label the same cell in another suite.
    changed = parse_suite(TINY.replace("eps = [0.5, 1.0]", "eps = [0.5, 1.5]"))
    assert len({c.id for c in changed.cells} - {c.id for c in suite.cells}) == 2
    relabelled = parse_suite(TINY.replace('label = "A*"', 'label = "A star"'))
    assert {c.id for c in relabelled.cells} == {c.id for c in suite.cells} and relabelled.hash != suite.hash


def test_groups_inherit_defaults_and_share_cells():
    text = """
    schema_version = 1
    contacts = 20
    m = [3]
    objects = ["box"]
    [[group]]
    name = "a"
    [[group.methods]]
    method = "astar"
    [[group]]
    name = "b"
    objects = ["box", "donut"]
    m = [3, 4]
    [[group.methods]]
    method = "astar"
    seed = { start = 0, count = 2 }
    """
    suite = parse_suite(textwrap.dedent(text))
    assert len(suite.cells) == 2 * 2 * 2  # group a's cell is group b's (box, m=3, seed 0)
    shared = [c for c in suite.cells if c.groups == ("a", "b")]
    assert len(shared) == 1 and shared[0].object.spec == "box" and shared[0].m == 3
    assert {c.contacts for c in suite.cells} == {20}
    assert suite.seeds() == {"contact_seeds": [0], "method_seeds": [0, 1]}


BAD_SUITES = [
    ("objects = ['box']", "schema_version: missing; valid values: 1"),
    ("schema_version = 2", "schema_version: unsupported value 2; valid values: 1"),
    (
        "schema_version = 1\nobjects = ['box']\nmethodz = 1\n[[methods]]\nmethod = 'astar'",
        "top level: unknown key 'methodz'; valid keys: cone_edges, contact_model, contact_seeds, contacts",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astra'",
        "methods[0].method 'astra'; valid choices: astar, dijkstra, es, es-pruned, hfts, wastar",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'wastar'\nepsilon = 1",
        "methods[0] (method wastar): unknown key 'epsilon'; valid keys: branching, eps, hand",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'wastar'\neps = [0.4, -1]",
        "methods[0].eps[1]: expected a number >= 0, got -1",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'wastar'\neps = 'big'",
        "methods[0].eps: expected a number >= 0, got 'big'",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\neps = 0.4",
        "methods[0] (method astar): unknown key 'eps'",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\nbranching = true",
        "methods[0].branching: expected an integer >= 2, got True",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\nheuristic = 'rnd'",
        "methods[0].heuristic 'rnd'; valid choices: fc, none, ru",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'dijkstra'\nheuristic = 'fc'",
        "methods[0].heuristic 'fc'; valid choices: none",
    ),
    ("schema_version = 1\nobjects = ['box']\nm = []\n[[methods]]\nmethod = 'astar'", "top level.m: empty list"),
    (
        "schema_version = 1\nobjects = ['box']\ncontacts = 5\nm = [3, 6]\n[[methods]]\nmethod = 'astar'",
        "m = 6 exceeds the contact count 5",
    ),
    (
        "schema_version = 1\nobjects = ['box']\nm = [4]\n[[methods]]\nmethod = 'astar'\nhand = 'sdh'",
        "methods[0].hand: the sdh hand has 3 fingers",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\nhand = 'allegro'",
        "hand 'allegro'; built-in hands are sdh, shadow_hand, parallel_gripper, or give FILE.toml",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'es'\nhand_threshold = 0.2",
        "methods[0].hand_threshold: applies only with a hand",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\nlabel = 'A* {epz}'",
        "methods[0].label: cannot fill 'A* {epz}'",
    ),
    (
        "schema_version = 1\nobjects = ['missing/part.obj']\n[[methods]]\nmethod = 'astar'",
        "objects[0]: mesh file not found",
    ),
    (
        "schema_version = 1\nobjects = ['boxx']\n[[methods]]\nmethod = 'astar'",
        "objects[0] object 'boxx'; valid choices: <path to a mesh file>, amphora, bone, box, bunny",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\n[simulation]\nenabled = true\nF_max = 1",
        "simulation: unknown simulation setting 'F_max'; valid choices: cone",
    ),
    ("schema_version = 1\nobjects = ['box', 'box']\n[[methods]]\nmethod = 'astar'", "an object is listed twice"),
    ("schema_version = 1\nobjects = ['box']", "top level: missing key 'methods'"),
    (
        "schema_version = 1\nobjects = ['box']\ncontact_seeds = {start = 0}\n[[methods]]\nmethod = 'astar'",
        "contact_seeds: a seed range needs exactly the keys count, start",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\n[simulation]\nenabled = 'yes'",
        "simulation.enabled: expected true or false",
    ),
    (
        "schema_version = 1\nobjects = ['box']\n[[group]]\nname = 'g'\nm = 0\n[[group.methods]]\nmethod = 'es'",
        "group[0].m: expected an integer >= 2, got 0",
    ),
    (
        (
            "schema_version = 1\nobjects = ['box']\n[[methods]]\nmethod = 'astar'\nlabel = 'x'\n"
            "[[methods]]\nmethod = 'astar'\nbranching = 2\nlabel = 'y'"
        ),
        "labelled both 'x' and 'y'",
    ),
    ("schema_version = 1\nobjects = [\n", "invalid TOML"),
]


@pytest.mark.parametrize("text,message", BAD_SUITES)
def test_bad_suites_name_the_key_and_the_valid_values(text, message):
    with pytest.raises(OgcpError) as info:
        parse_suite(text, source="bad.toml")
    assert message in str(info.value) and str(info.value).startswith("suite bad.toml: ")
    assert "\n" not in str(info.value)


def test_builtin_suites_load_and_cover_the_paper(tmp_path):
    assert set(builtin_suites()) >= {"quick", "paper", "sdh"}
    quick = load_suite("quick")
    assert {c.object.spec for c in quick.cells} == {"box", "donut"} and {c.contacts for c in quick.cells} == {200}
    assert {c.method for c in quick.cells} >= {"astar", "wastar", "hfts", "es"} and quick.simulate
    paper = load_suite("paper")
    objects = {"box", "sphere", "donut", "amphora", "bunny", "homer", "plane"}
    assert {c.object.spec for c in paper.cells if c.method == "es"} == objects
    assert {c.contacts for c in paper.cells if c.method == "es"} == {1000}
    assert {(c.object.spec, c.m) for c in paper.cells if c.m > 3} == {
        (o, m) for o in ("bunny", "plane") for m in (4, 5, 6)
    }
    eps = {dict(c.variant)["eps"] for c in paper.cells if c.method == "wastar"}
    assert eps == {0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4}
    assert {dict(c.variant)["symmetry"] for c in paper.cells if c.object.spec == "homer" and c.method == "astar"} == {
        True,
        False,
    }
    sdh = load_suite("sdh")
    assert all(dict(c.variant)["hand"] == "sdh" or dict(c.variant).get("max_spread") for c in sdh.cells)
    with pytest.raises(OgcpError, match="unknown suite 'nope'; valid choices: <path to a suite .toml file>, paper"):
        load_suite("nope")
    mesh = tmp_path / "meshes" / "part.stl"
    mesh.parent.mkdir()
    builtin_mesh("box").export(mesh)
    (tmp_path / "s.toml").write_text("schema_version = 1\nobjects = ['meshes/part.stl']\n[[methods]]\nmethod = 'es'\n")
    cell = load_suite(tmp_path / "s.toml").cells[0]
    assert cell.object.path == str(mesh) and cell.object.key.startswith("mesh:") and cell.diagonal is None


# -- running -------------------------------------------------------------------------------------


def test_tiny_suite_end_to_end(serial_run):
    records = ResultStore(serial_run).read().records
    assert len(records) == TINY_CELLS and all(r["status"] == "ok" and r["error"] is None for r in records)
    by_label = {(r["params"]["object"], r["params"]["label"]): r for r in records}
    assert len(by_label) == TINY_CELLS
    for obj in ("box", "sphere"):
        contacts = sample_contacts(builtin_mesh(obj), 16, seed=0)
        grasps = [np.array(g) for g in itertools.combinations(range(16), 3)]
        best = max(q1(contacts.subset_wrenches(g)) for g in grasps)
        spread = [
            g
            for g in grasps
            if np.max(np.linalg.norm(contacts.positions[g][:, None] - contacts.positions[g][None], axis=-1)) <= 0.15
        ]
        best_spread = max(q1(contacts.subset_wrenches(g)) for g in spread)
        for label in ("A*", "Dijkstra", "ES"):
            assert by_label[(obj, label)]["plan"]["q1"] == pytest.approx(best, abs=1e-9)
        for label in ("A* max_spread=0.15", "ES max_spread=0.15"):
            assert by_label[(obj, label)]["plan"]["q1"] == pytest.approx(best_spread, abs=1e-9)
        es, hfts = by_label[(obj, "ES")]["plan"], by_label[(obj, "HFTS iterations=5 runs=3")]["plan"]
        assert sum(es["histogram"]["counts"]) + es["histogram"]["zero"] == len(grasps)
        assert by_label[(obj, "ES max_spread=0.15")]["plan"]["stats"]["excluded_by_constraints"] == len(grasps) - len(
            spread
        )
        assert len(hfts["runs"]) == 3 and hfts["q1"] == max(run["q1"] for run in hfts["runs"]) <= best + 1e-12
        for eps in (0.5, 1.0):
            plan = by_label[(obj, f"WA* {eps:g}")]["plan"]
            assert plan["eps"] == eps and plan["q1"] >= plan["q_ows"] - (1 + eps) * (plan["q_ows"] - best) - 1e-12
        stats = by_label[(obj, "A*")]["plan"]["stats"]
        assert sum(stats["created_per_level"]) == stats["created"] and stats["trace"]
    record = records[0]
    assert set(record) == {
        "schema",
        "id",
        "params",
        "groups",
        "status",
        "error",
        "plan",
        "simulation",
        "simulation_seconds",
        "wall_seconds",
        "cpu_seconds",
        "finished_at",
    }
    assert set(record["params"]) == {
        "object",
        "contacts",
        "contact_seed",
        "m",
        "mu",
        "cone_edges",
        "diagonal",
        "tip_radius",
        "method",
        "variant",
        "label",
    }
    manifest = ResultStore(serial_run).read_manifest()
    assert manifest["suite"]["content"] == TINY and manifest["suite"]["cells"] == TINY_CELLS
    assert set(manifest["versions"]) >= {"ogcp", "numpy", "scipy", "mujoco", "coacd"}
    assert {"git_commit", "cpu", "seeds", "started_at", "sessions"} <= set(manifest)


def test_parallel_processes_and_dask_match_serial(tiny_file, serial_run, tmp_path):
    distributed = pytest.importorskip("distributed")
    expected = _results(serial_run)
    suite = load_suite(tiny_file)
    SuiteRunner(suite, tmp_path / "loky", jobs=2).run()
    assert _results(tmp_path / "loky") == expected
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        SuiteRunner(suite, tmp_path / "dask", backend="dask", address=cluster.scheduler_address).run()
    assert _results(tmp_path / "dask") == expected


def test_resume_after_a_partial_run_and_a_torn_line(tiny_file, serial_run, tmp_path, monkeypatch):
    out = tmp_path / "out"
    first = SuiteRunner(load_suite(tiny_file), out, max_cells=5).run()
    assert (first.ran, first.remaining) == (5, TINY_CELLS - 5)
    with open(out / "results.jsonl", "ab") as handle:  # a crash mid-write
        handle.write(b'{"schema": "ogcp.cell/1", "id": "')
    status, _, err = _ogcp(["suite", str(tiny_file), "--out", str(out)], monkeypatch)
    assert status == 2 and "not empty; pass --resume" in err
    status, text, err = _ogcp(["suite", str(tiny_file), "--out", str(out), "--resume"], monkeypatch)
    assert status == 0 and "removed an incomplete last line" in err
    assert f"{TINY_CELLS - 5} cells run, 5 already recorded, 0 errors, 0 remaining" in text
    assert _results(out) == _results(serial_run)
    assert len(ResultStore(out).read_manifest()["sessions"]) == 2
    again = SuiteRunner(load_suite(tiny_file), out, resume=True).run()
    assert again.ran == 0 and again.skipped == TINY_CELLS
    other = tmp_path / "other.toml"
    other.write_text(TINY.replace("runs = 3", "runs = 4"))
    with pytest.raises(OgcpError, match="the suite changed, use another --out"):
        SuiteRunner(load_suite(other), out, resume=True).run()


def test_resume_after_the_process_is_killed(tiny_file, serial_run, tmp_path):
    out = tmp_path / "killed"
    script = (
        "import sys\nfrom ogcp.benchmarks.suite.runner import SuiteRunner\nfrom ogcp.benchmarks.suite.parse import load_suite\n"
        "SuiteRunner(load_suite(sys.argv[1]), sys.argv[2]).run()\n"
    )
    process = subprocess.Popen([sys.executable, "-c", script, str(tiny_file), str(out)], cwd=ROOT)
    results = out / "results.jsonl"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if results.exists() and results.read_bytes().count(b"\n") >= 2:
            process.send_signal(signal.SIGKILL)
            break
        time.sleep(0.01)
    process.wait(timeout=60)
    recorded = len(ResultStore(out).read().records)
    summary = SuiteRunner(load_suite(tiny_file), out, resume=True).run()
    assert summary.ran == TINY_CELLS - recorded and summary.remaining == 0
    assert _results(out) == _results(serial_run)


def test_failing_cells_are_recorded_and_the_suite_goes_on(tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "empty-cache"))  # bunny is not fetched there
    suite_file = tmp_path / "s.toml"
    suite_file.write_text(
        "schema_version = 1\nobjects = ['box', 'bunny']\ncontacts = 12\n[[methods]]\nmethod = 'astar'\n"
    )
    out = tmp_path / "out"
    status, text, err = _ogcp(["suite", str(suite_file), "--out", str(out)], monkeypatch)
    assert status == 1 and "objects not fetched yet: bunny" in err and "failed: OgcpError" in err
    records = {r["params"]["object"]: r for r in ResultStore(out).read().records}
    assert records["box"]["status"] == "ok"
    error = records["bunny"]["error"]
    assert records["bunny"]["status"] == "error" and records["bunny"]["plan"] is None
    assert error["type"] == "OgcpError" and "ogcp assets fetch bunny" in error["message"]
    assert "benchmarks/suite/cells.py" in error["traceback"] and "1 errors" in text
    summary = SuiteRunner(load_suite(suite_file), out, resume=True, retry_errors=True).run()
    assert summary.ran == 1 and summary.errors == 1
    assert len(ResultStore(out).read().latest()) == 2 and len(ResultStore(out).read().records) == 3


def test_simulation_is_called_lazily_with_the_plan(tmp_path, monkeypatch):
    calls = []

    def evaluate_plan(plan: dict, settings: dict, **options) -> SimpleNamespace:
        calls.append((settings, options))
        record = {
            "schema": "ogcp.sim/1",
            "grasps": [{"label": "best", "grasp": plan["grasp"], "valid": True, "measured_min": 2 * plan["q1"]}],
        }
        return SimpleNamespace(to_dict=lambda: record)

    text = (
        "schema_version = 1\nobjects = ['box']\ncontacts = 12\n[[methods]]\nmethod = 'astar'\n"
        "[simulation]\nenabled = true\ndirections = 8\nmax_normal_force = 20.0\nmax_grasps = 1\n"
    )
    monkeypatch.setattr(sim_eval, "evaluate_plan", evaluate_plan, raising=False)
    record = SuiteRunner(parse_suite(text), tmp_path / "a").run().records.popitem()[1]
    assert calls == [({"directions": 8, "max_normal_force": 20.0}, {"max_grasps": 1})]
    simulated = record["simulation"]["grasps"][0]
    assert simulated["grasp"] == record["plan"]["grasp"] and record["simulation_seconds"] >= 0
    assert simulated["measured_min"] == 2 * record["plan"]["q1"]
    no_sim = SuiteRunner(parse_suite(text).without_simulation(), tmp_path / "b").run().records.popitem()[1]
    assert len(calls) == 1 and no_sim["simulation"] is None and no_sim["status"] == "ok"

    def broken(plan: dict, settings: dict, **options) -> SimpleNamespace:
        raise RuntimeError("the simulator crashed")

    monkeypatch.setattr(sim_eval, "evaluate_plan", broken)
    failed = SuiteRunner(parse_suite(text), tmp_path / "c").run().records.popitem()[1]
    assert failed["status"] == "error" and failed["plan"]["q1"] == record["plan"]["q1"]
    assert failed["error"]["type"] == "RuntimeError" and "the simulator crashed" in failed["error"]["message"]


def test_record_tree_is_passed_through(tmp_path):
    text = "schema_version = 1\nobjects = ['box']\ncontacts = 12\n[[methods]]\nmethod = 'astar'\nrecord_tree = true\n"
    record = SuiteRunner(parse_suite(text), tmp_path).run().records.popitem()[1]
    assert record["status"] == "ok"
    tree = record["plan"]["tree"]
    path = tree["path"]
    assert path[0] == 0 and all(tree["parent"][child] == parent for parent, child in itertools.pairwise(path))
    assert all(tree["visited"][state] for state in path[:-1])


def test_slices_selected_with_only_add_up_to_the_full_run(tiny_file, serial_run, tmp_path, monkeypatch):
    out = tmp_path / "out"
    status, text, _ = _ogcp(
        ["suite", str(tiny_file), "--out", str(out), "--only", "object=box", "--only", "method=es,hfts"], monkeypatch
    )
    assert status == 0 and "3 cells run, 0 already recorded, 0 errors, 13 remaining" in text
    assert {(r["params"]["object"], r["params"]["method"]) for r in _results(out).values()} == {
        ("box", "es"),
        ("box", "hfts"),
    }
    again = SuiteRunner(load_suite(tiny_file), out, resume=True, only=["object=box"]).run()
    assert (again.ran, again.remaining) == (5, 8)
    rest = SuiteRunner(load_suite(tiny_file), out, resume=True).run()
    assert rest.ran == 8 and _results(out) == _results(serial_run)
    assert [s["only"] for s in ResultStore(out).read_manifest()["sessions"]] == [
        ["object=box", "method=es,hfts"],
        ["object=box"],
        [],
    ]
    for only, message in [
        (["object=bunny"], "no cell of this suite has it; the suite has object = box, sphere"),
        (["colour=red"], "valid choices: contact_model, contacts, group, label, m, method, mu, object"),
        (["object"], "--only takes KEY=VALUE"),
    ]:
        with pytest.raises(OgcpError, match=message):
            SuiteRunner(load_suite(tiny_file), tmp_path / "bad", only=only).run()


def test_runner_refuses_bad_options_and_foreign_folders(tmp_path):
    suite = parse_suite(TINY)
    with pytest.raises(OgcpError, match="valid choices: dask, loky"):
        SuiteRunner(suite, tmp_path / "a", backend="spark").run()
    with pytest.raises(OgcpError, match="--retry-errors applies with --resume only"):
        SuiteRunner(suite, tmp_path / "a", retry_errors=True).run()
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(OgcpError, match="no manifest.json"):
        SuiteRunner(suite, foreign, resume=True).run()
    assert os.listdir(foreign) == ["notes.txt"]  # not even a lock file left in a foreign folder
    (tmp_path / "file").write_text("")
    with pytest.raises(OgcpError, match="is a file"):
        SuiteRunner(suite, tmp_path / "file").run()
    with ResultStore(tmp_path / "busy").lock(), pytest.raises(OgcpError, match="in use"):
        SuiteRunner(suite, tmp_path / "busy").run()
    assert json.loads(json.dumps(suite.seeds())) == {"contact_seeds": [0], "method_seeds": [0]}


def test_time_limit_records_search_cells_as_stopped_and_retry_completes(tiny_file, serial_run, tmp_path):
    out = tmp_path / "out"
    limited = SuiteRunner(load_suite(tiny_file), out, time_limit=1e-9).run()
    failed = [r for r in limited.records.values() if r["status"] == "stopped"]
    # Every method keeps the limit: ES and HFTS as well (they once ignored it).
    assert {r["params"]["method"] for r in failed} == {"astar", "wastar", "dijkstra", "es", "hfts"}
    assert limited.errors == len(failed)  # to rerun, like errors
    for r in failed:  # the best grasp found, with its certificate
        plan = r["plan"]
        assert plan["status"] == "stopped" and len(set(plan["grasp"])) == 3
        assert 0 <= plan["q1"] <= plan["bound"] <= plan["q_ows"]
        assert plan["gap"] == pytest.approx(plan["bound"] - plan["q1"], abs=1e-15)
    retried = SuiteRunner(load_suite(tiny_file), out, resume=True, retry_errors=True).run()
    assert retried.ran == len(failed) and retried.errors == 0
    latest = ResultStore(out).read().latest()  # a retried cell's new record supersedes its error
    assert len(latest) == TINY_CELLS and {k: _comparable(v) for k, v in latest.items()} == _results(serial_run)
    assert [s["time_limit"] for s in ResultStore(out).read_manifest()["sessions"]] == [1e-9, None]
    with pytest.raises(OgcpError, match="time_limit must be a number of seconds > 0"):
        SuiteRunner(load_suite(tiny_file), tmp_path / "bad", time_limit=-1).run()


def test_memory_limit_records_search_cells_as_stopped_with_status_memory(tmp_path, monkeypatch):
    """The process allowance shrunk so that a few kilobytes of open states reach the limit."""
    from ogcp.planner.search import memory

    suite = tmp_path / "forty.toml"
    suite.write_text(
        'schema_version = 1\nname = "forty"\nobjects = ["sphere"]\ncontacts = 40\ncontact_seeds = [0]\n'
        'm = [4]\n\n[[methods]]\nmethod = "astar"\n'
    )
    monkeypatch.setattr(memory, "PROCESS_BYTES", 2**30 - 8 * 1024)
    monkeypatch.setattr(memory, "MIN_STATES_BYTES", 1024)
    out = tmp_path / "out"
    limited = SuiteRunner(load_suite(suite), out, memory_limit=1.0).run()
    (record,) = limited.records.values()
    plan = record["plan"]
    assert record["status"] == "stopped" and plan["status"] == "memory" and plan["stats"]["forgotten"] > 0
    assert 0 <= plan["q1"] < plan["bound"] <= plan["q_ows"]
    monkeypatch.undo()  # the real allowance: the cell ends within it
    retried = SuiteRunner(load_suite(suite), out, resume=True, retry_errors=True).run()
    assert retried.ran == 1 and retried.errors == 0
    assert ResultStore(out).read().latest()[record["id"]]["plan"]["status"] == "optimal"
    assert [s["memory_limit"] for s in ResultStore(out).read_manifest()["sessions"]] == [1.0, 4.0]
    with pytest.raises(OgcpError, match="memory_limit"):
        SuiteRunner(load_suite(suite), tmp_path / "bad", memory_limit=0).run()
    with pytest.raises(OgcpError, match="memory_limit 0.1 GiB is too small for a search in 1 process"):
        SuiteRunner(load_suite(suite), tmp_path / "bad", memory_limit=0.1).run()
