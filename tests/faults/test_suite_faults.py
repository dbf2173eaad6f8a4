"""Malformed suites and damaged results folders: one line ``ogcp: error: ...``, never a traceback.

A suite is refused as a whole before any cell runs: fields of the wrong type or out of range,
two method variants under one label (plots and tables would merge them silently), labels that
reach into values or build huge strings, and suites too large to list. ``ogcp compare`` and
``ogcp plot`` read a results folder with a corrupted line or manifest and say what they skipped.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from ogcp.benchmarks.suite.parse import builtin_suites, load_suite, parse_suite
from ogcp.planner.grasp import defaults
from ogcp.planner.infra.errors import OgcpError
from tests.faults import run_cli

HEAD = 'schema_version = 1\nobjects = ["box"]\ncontacts = 16\n'
ASTAR = '[[methods]]\nmethod = "astar"\n'
TINY = HEAD + "contact_seeds = [0, 1]\n" + ASTAR + 'label = "A*"\n[[methods]]\nmethod = "es"\nlabel = "ES"\n'


_run = run_cli


def _refused(text: str) -> str:
    with pytest.raises(OgcpError) as info:
        parse_suite(text)
    message = str(info.value)
    assert "\n" not in message and message.startswith("suite <string>: ")
    return message


@pytest.fixture(autouse=True)
def _machine(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path_factory.getbasetemp() / "suite-faults-cache"))
    monkeypatch.setattr(defaults, "memory_size", lambda: 16 * 2**30)


def test_two_method_variants_under_one_label_are_refused_naming_both():
    message = _refused(HEAD + ASTAR + 'label = "same"\n[[methods]]\nmethod = "wastar"\neps = 0.5\nlabel = "same"\n')
    assert "top level.methods[1].label: 'same' already labels top level.methods[0] (method astar); " in message
    assert "this entry is method wastar eps=0.5: give each method variant its own label" in message


def test_a_swept_parameter_needs_a_placeholder_in_its_label():
    message = _refused(HEAD + '[[methods]]\nmethod = "wastar"\neps = [0.5, 1.0]\nlabel = "WA*"\n')
    assert "'WA*' already labels top level.methods[0] (method wastar eps=0.5); this entry is method wastar eps=1.0" in (
        message
    )
    labels = {
        c.label for c in parse_suite(HEAD + '[[methods]]\nmethod = "wastar"\neps = [0.5, 1.0]\nlabel = "{eps}"\n').cells
    }
    assert labels == {"0.5", "1.0"}


def test_a_label_names_one_variant_across_groups_too():
    groups = "".join(
        f'[[group]]\nname = "{name}"\nobjects = ["{obj}"]\n[[group.methods]]\nmethod = "{method}"\nlabel = "X"\n'
        for name, obj, method in (("a", "box", "astar"), ("b", "sphere", "dijkstra"))
    )
    message = _refused("schema_version = 1\ncontacts = 16\n" + groups)
    assert message.startswith("suite <string>: group[1].methods[0].label: 'X' already labels group[0].methods[0]")


def test_repeats_of_one_variant_may_share_a_label():
    # Seeds (and recording the tree) repeat a series, as do the same variant in two groups.
    suite = parse_suite(HEAD + ASTAR + 'label = "A*"\nseed = {start = 0, count = 3}\n' + ASTAR + 'label = "A*"\n')
    assert {c.label for c in suite.cells} == {"A*"} and len(suite.cells) == 3
    for name in builtin_suites():
        load_suite(name)  # the shipped suites keep to the rule


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("contacts = 100000000", "top level.contacts: 100000000 contacts with 8 cone edges need about 2e+03 GiB"),
        ("contacts = '16'", "top level.contacts: expected an integer >= 2, got '16'"),
        ("mu = 1e308", "top level.mu: expected a number <= 10, got 1e+308 (valid: > 0 and <= 10)"),
        ("mu = [0.5, 0.5]", "top level.mu: repeated values in [0.5, 0.5]"),
        ("cone_edges = 100000", "top level.cone_edges: expected an integer <= 64, got 100000 (valid: 3 to 64)"),
        ("diagonal = 1e9", "top level.diagonal: expected a number <= 100, got 1000000000.0 (valid: 0.001 to 100)"),
        ("diagonal = 1e-300", "top level.diagonal: expected a number >= 0.001, got 1e-300"),
        ("tip_radius = 1e9", "top level.tip_radius: expected a number <= 100"),
        ("contact_seeds = 99999999999999999999", "contact_seeds: expected an integer <= 4294967295"),
        ("contact_seeds = {start = 0, count = 1000000000000}", "contact_seeds.count: expected an integer <= 10000"),
        ("contact_seeds = {start = 4294967295, count = 2}", "contact_seeds.start + count - 1: expected an integer <="),
        ("simulate = 'yes'", "top level.simulate: expected true or false, got 'yes'"),
    ],
)
def test_a_group_field_of_the_wrong_type_or_range_is_refused(line, expected):
    assert expected in _refused(HEAD.replace("contacts = 16\n", "") + line + "\n" + ASTAR)


@pytest.mark.parametrize(
    ("table", "expected"),
    [
        ('method = ["astar"]', "unknown top level.methods[0].method ['astar']; valid choices: astar"),
        ('method = "astar"\nbranching = 1000000000', "methods[0].branching: expected an integer <= 64"),
        ('method = "astar"\nkmeans_iterations = 1000000000', "kmeans_iterations: expected an integer <= 1000"),
        ('method = "wastar"\neps = 1e308', "methods[0].eps: expected a number <= 100, got 1e+308"),
        ('method = "es"\nchunk = 1000000000000', "methods[0].chunk: expected an integer <= 10000000"),
        ('method = "es"\nbins = 1000000000000', "methods[0].bins: expected an integer <= 10000,"),
        ('method = "hfts"\nruns = 1000000000', "methods[0].runs: expected an integer <= 10000,"),
        ('method = "astar"\nseed = {start = 0, count = 100000000}', "methods[0].seed.count: expected an integer <= "),
        ('method = "astar"\nlabel = "{seed[0]}"', "label: cannot fill '{seed[0]}' ('seed[0]')"),
        ('method = "astar"\nlabel = "{seed.real}"', "label: cannot fill '{seed.real}' ('seed.real')"),
        ('method = "astar"\nlabel = "{seed:999999999999}"', "width or precision in {seed:999999999999} above 200"),
        ('method = "astar"\nlabel = "' + "x" * 300 + '"', "label: 300 characters; at most 200"),
    ],
)
def test_a_method_field_of_the_wrong_type_or_range_is_refused(table, expected):
    assert expected in _refused(HEAD + "[[methods]]\n" + table + "\n")


def test_a_suite_too_large_to_list_is_refused():
    contacts = "contacts = [" + ", ".join(str(n) for n in range(16, 36)) + "]\n"
    message = _refused(
        HEAD.replace("contacts = 16\n", contacts) + "contact_seeds = {start = 0, count = 10000}\n" + ASTAR
    )
    assert "top level: 200000 cells (1 objects x 20 contact counts x 10000 seeds" in message
    assert "at most 100000 per suite: split it into several suites" in message
    # Counted over the groups, before each group's cells are made.
    group = (
        '[[group]]\nname = "{}"\ncontacts = [16, 17, 18, 19, 20, 21]\ncontact_seeds = {{start = 0, count = 10000}}\n'
    )
    table = group + ASTAR.replace("[[", "[[group.")
    message = _refused(HEAD.replace("contacts = 16\n", "") + table.format("a") + table.format("b"))
    assert message.startswith("suite <string>: group[1]: 60000 cells (") and "120000 with the groups before" in message


@pytest.mark.parametrize(
    ("table", "expected"),
    [
        (
            "enabled = false\ntimestep = 'x'",
            "simulation: simulation setting timestep: expected a number >= 1e-05, got 'x'",
        ),
        ("enabled = true\nslide_armature = 'x'", "simulation setting slide_armature: expected a number > 0, got 'x'"),
        (
            "enabled = true\ncontact_solref = 5",
            "simulation setting contact_solref: expected a list of 2 finite numbers",
        ),
        ("enabled = true\nmax_grasps = 0", "simulation.max_grasps: expected an integer >= 1, got 0"),
    ],
)
def test_the_simulation_table_is_checked_even_while_disabled(table, expected):
    assert expected in _refused(HEAD + ASTAR + "[simulation]\n" + table + "\n")


# -- results folders ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    base = tmp_path_factory.mktemp("run")
    (base / "tiny.toml").write_text(TINY)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OGCP_CACHE", str(tmp_path_factory.getbasetemp() / "suite-faults-cache"))
        status, _, err = _run(["suite", str(base / "tiny.toml"), "--out", str(base / "out")])
    assert status == 0, err
    return base / "out"


def _damaged(run_folder: Path, tmp_path: Path, results: str | None = None, manifest: str | None = None) -> Path:
    folder = tmp_path / "damaged"
    shutil.copytree(run_folder, folder)
    if results is not None:
        (folder / "results.jsonl").write_text(results)
    if manifest is not None:
        (folder / "manifest.json").write_text(manifest)
    return folder


def _lines(run_folder: Path) -> list[str]:
    return (run_folder / "results.jsonl").read_text().splitlines()


@pytest.mark.parametrize("bad", [b"{not json", b"[1, 2]", b"\xff\xfe"], ids=["garbage", "list", "binary"])
def test_compare_and_plot_skip_a_corrupted_line_and_say_so(run_folder, tmp_path, bad):
    lines = (run_folder / "results.jsonl").read_bytes().splitlines()
    folder = _damaged(run_folder, tmp_path)
    (folder / "results.jsonl").write_bytes(b"\n".join([*lines[:1], bad, *lines[1:]]) + b"\n")
    status, out, err = _run(["compare", str(folder), str(run_folder)])
    assert status == 0 and "Traceback" not in err and "note: RUN: results.jsonl line 2: " in out, (out, err)
    status, out, err = _run(["plot", str(folder), "--only", "fig9_times", "--out", str(tmp_path / "figures")])
    assert status == 0 and "ogcp: note: results.jsonl line 2: " in err and "Traceback" not in err, err


def test_a_record_that_is_not_a_cell_is_one_error_line(run_folder, tmp_path):
    lines = _lines(run_folder)
    record = json.loads(lines[0])
    record["params"] = "x"
    folder = _damaged(run_folder, tmp_path, "\n".join([json.dumps(record), *lines[1:]]) + "\n")
    status, _, err = _run(["compare", str(folder), str(run_folder)])
    assert status == 2 and err.count("\n") == 1 and f"{folder / 'results.jsonl'}: record {record['id']}" in err


@pytest.mark.parametrize("manifest", ["{not json", "[1]", ""], ids=["garbage", "list", "empty"])
def test_a_corrupted_manifest_is_one_error_line(run_folder, tmp_path, manifest):
    folder = _damaged(run_folder, tmp_path, manifest=manifest)
    for argv in (["compare", str(folder), str(run_folder)], ["suite", "x.toml", "--out", str(folder), "--resume"]):
        if argv[0] == "suite":
            argv[1] = str(run_folder.parent / "tiny.toml")
        status, _, err = _run(argv)
        assert status == 2 and err.count("\n") == 1 and "manifest.json" in err and "Traceback" not in err, err
    status, _, err = _run(["plot", str(folder), "--only", "fig9_times", "--out", str(tmp_path / "figures")])
    assert status == 0 and "Traceback" not in err


def test_resume_skips_a_corrupted_line_with_a_warning(run_folder, tmp_path):
    lines = _lines(run_folder)
    folder = _damaged(run_folder, tmp_path, "\n".join([*lines[:1], "{not json", *lines[2:]]) + "\n")
    status, out, err = _run(["suite", str(run_folder.parent / "tiny.toml"), "--out", str(folder), "--resume"])
    assert status == 0 and "ogcp: warning: results.jsonl line 2: not valid JSON (ignored)" in err
    assert "1 cells run, 3 already recorded" in out


@pytest.mark.parametrize("where", ["file", "under a file"])
def test_an_out_folder_that_cannot_be_is_one_error_line(run_folder, tmp_path, where):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker if where == "file" else blocker / "run"
    for argv in (
        ["suite", str(run_folder.parent / "tiny.toml"), "--out", str(out)],
        ["plot", str(run_folder), "--only", "fig9_times", "--out", str(out)],
    ):
        status, _, err = _run(argv)
        assert status == 2 and err.count("\n") == 1 and str(blocker) in err and "Traceback" not in err, err
