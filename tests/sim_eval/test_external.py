"""Grasps from any planner (``ogcp.grasps/1``): the schema, the surface checks, and a plan's round trip.

The simulations stay small: the built-in box (convex, so one hull is its decomposition), one
thread, no sphere directions (the 12 axes and Q1's weakest), at most three grasps.
"""

from __future__ import annotations

import argparse
import copy
import json
import re
import warnings

import numpy as np
import pytest
import trimesh

from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts
from ogcp.planner.infra import OgcpError
from ogcp.planner.records.grasps import GRASPS_SCHEMA, ExternalGrasps, is_grasps_file, load_grasps, save_grasps
from ogcp.planner.records.plan import contact_set_record
from ogcp.sim_eval import evaluate_grasps, evaluate_plan, export_grasps
from ogcp.sim_eval.external import OffSurfaceWarning, external_input
from ogcp.sim_eval.result import SimRecord

SETTINGS = {"directions": 0, "threads": 1}
HULL = {"method": "convex_hull"}
RADIUS = 0.008  # the default tip at the box's 0.2 m diagonal [m]
# The built-in box is centred on the origin: its +x face lies at half its x extent.
BOX = builtin_mesh("box")
HALF = np.ptp(np.asarray(BOX.vertices), axis=0) / 2


def _minimal() -> dict:
    """The record of docs/external_grasps.md's minimal example: a pinch across the box's x faces."""
    x = float(HALF[0])
    return {
        "schema": GRASPS_SCHEMA,
        "object": {"mesh": "box"},
        "mu": 0.5,
        "grasps": [
            {
                "label": "mine",
                "contacts": [
                    {"position": [x, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0]},
                    {"position": [-x, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]},
                ],
            }
        ],
    }


def _set(record: dict, path: tuple, value: object) -> dict:
    record = copy.deepcopy(record)
    node = record
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return record


CONTACT = ("grasps", 0, "contacts", 1)


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("schema",), "ogcp.plan/1", "schema: expected 'ogcp.grasps/1'"),
        (("object",), "box", "object: expected an object"),
        (("object", "mesh"), 3, "object.mesh: expected a non-empty string"),
        (("object", "diagonal"), -1.0, "object.diagonal [m]: expected a number >= 0.001"),
        (("object", "sha256"), 5, "object.sha256: expected a non-empty string"),
        (("mu",), KeyError, "mu: missing"),
        (("mu",), 0, "mu: expected a number > 0"),
        (("mu",), "0.5", "mu: expected a number > 0"),
        (("cone_edges",), 2, "cone_edges: expected an integer >= 3"),
        (("method",), ["a"], "method: expected a non-empty string"),
        (("grasps",), [], "grasps: expected a non-empty list"),
        (("grasps", 0), [1, 2], "grasps[0]: expected an object with contacts"),
        (("grasps", 0, "label"), "", "grasps[0].label: expected a non-empty string"),
        (("grasps", 0, "method"), 7, "grasps[0].method: expected a non-empty string"),
        (("grasps", 0, "score"), "high", "grasps[0].score: expected a finite number or null"),
        (("grasps", 0, "contacts"), [], "grasps[0].contacts: expected a list of at least 2 contacts, got 0"),
        (CONTACT, [0, 0, 0], "grasps[0].contacts[1]: expected an object with position and normal"),
        ((*CONTACT, "position"), [1.0, 2.0], "grasps[0].contacts[1].position: expected 3 finite numbers"),
        ((*CONTACT, "position"), KeyError, "grasps[0].contacts[1].position: missing"),
        ((*CONTACT, "normal"), [1.0, "a", 0.0], "grasps[0].contacts[1].normal: expected 3 finite numbers"),
        ((*CONTACT, "normal"), [True, 0, 0], "grasps[0].contacts[1].normal: expected 3 finite numbers"),
        ((*CONTACT, "normal"), [0.0, 0.0, 0.0], "grasps[0].contacts[1].normal: expected a unit vector.*length zero"),
        ((*CONTACT, "normal"), [2.0, 0.0, 0.0], "grasps[0].contacts[1].normal: expected a unit vector.*length 2"),
        ((*CONTACT, "position"), [float(HALF[0]), 0.0, 0.0], "grasps[0].contacts[1].position: the same point as"),
    ],
)
def test_each_bad_field_is_one_line_naming_its_json_path(path, value, message):
    pattern = ".*".join(re.escape(part) for part in message.split(".*"))  # the paths' brackets are literal
    with pytest.raises(OgcpError, match=pattern) as caught:
        ExternalGrasps.from_dict(_set(_minimal(), path, value), where="g.json")
    text = str(caught.value)
    assert text.startswith("g.json: ") and "\n" not in text


def test_defaults_mixed_m_and_normalised_normals():
    record = _minimal()
    record["method"] = "theirs"
    third = {"position": [0.0, 0.0, float(HALF[2])], "normal": [0.0, 0.0, -1.0005]}
    record["grasps"].append({"contacts": [*record["grasps"][0]["contacts"], third], "method": "own", "score": 2})
    grasps = ExternalGrasps.from_dict(record)
    assert (grasps.cone_edges, grasps.diagonal, grasps.sha256) == (8, None, None)
    first, second = grasps.grasps
    assert (first.label, second.label) == ("mine", "grasp-1")
    assert (grasps.method_of(first), grasps.method_of(second), second.score) == ("theirs", "own", 2.0)
    assert len(first.positions) == 2 and len(second.positions) == 3
    assert np.linalg.norm(second.normals[2]) == pytest.approx(1.0, abs=1e-15)
    assert second.normals[0].tolist() == [-1.0, 0.0, 0.0]  # unit rows kept bit for bit


def test_a_written_record_reads_back_bit_for_bit(tmp_path):
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(3, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    grasps = ExternalGrasps.from_arrays([(rng.normal(size=(3, 3)), normals)], mu=0.3, scores=[0.25])
    with pytest.raises(OgcpError, match="name no object"):
        save_grasps(grasps, tmp_path / "g.json")
    named = ExternalGrasps(grasps.grasps, grasps.mu, 12, mesh="box", diagonal=0.1, method="random")
    save_grasps(named, tmp_path / "g.json")
    again = load_grasps(tmp_path / "g.json")
    assert is_grasps_file(tmp_path / "g.json") and again.path == tmp_path / "g.json"
    assert (again.mu, again.cone_edges, again.mesh, again.diagonal, again.method) == (0.3, 12, "box", 0.1, "random")
    np.testing.assert_array_equal(again.grasps[0].positions, grasps.grasps[0].positions)
    np.testing.assert_array_equal(again.grasps[0].normals, grasps.grasps[0].normals)
    assert again.grasps[0].score == 0.25


def test_unreadable_files_are_one_line_errors(tmp_path):
    with pytest.raises(OgcpError, match="no such grasps file"):
        load_grasps(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(OgcpError, match="not valid JSON"):
        load_grasps(tmp_path / "bad.json")
    assert not is_grasps_file(tmp_path / "bad.json")


def _offset(shift: float, normal: tuple = (-1.0, 0.0, 0.0)) -> ExternalGrasps:
    """The minimal pinch with its first contact moved ``shift`` [m] outwards along x."""
    record = _minimal()
    record["grasps"][0]["contacts"][0]["position"][0] += shift
    record["grasps"][0]["contacts"][0]["normal"] = list(normal)
    return ExternalGrasps.from_dict(record)


def test_a_contact_off_the_surface_is_projected_with_a_warning_and_recorded():
    with pytest.warns(OffSurfaceWarning, match=r"projected 1 of 2 contacts.*grasps\[0\]\.contacts\[0\].*1 mm outside"):
        given = external_input(BOX, _offset(1e-3), RADIUS)
    assert given.contacts.positions[0].tolist() == pytest.approx([HALF[0], 0.0, 0.0], abs=1e-12)
    assert given.fit.distance.tolist() == pytest.approx([1e-3, 0.0], abs=1e-12)
    assert given.fit.projected.tolist() == [True, False] and given.fit.normal_angle.max() == pytest.approx(0.0)
    block = given.record("project")
    assert block["n_projected"] == 1 and block["grasps"][0]["surface_distance"][0] == pytest.approx(1e-3)
    assert block["surface_tolerance"] == pytest.approx(0.01 * RADIUS)
    with pytest.warns(OffSurfaceWarning, match="inside"):
        inside = external_input(BOX, _offset(-1e-3), RADIUS)
    assert inside.fit.distance[0] == pytest.approx(-1e-3)


def test_off_surface_contacts_are_refused_on_request_or_beyond_the_tip_radius():
    with pytest.raises(OgcpError, match=r"grasps\[0\]\.contacts\[0\]\.position is 1 mm outside.*on_surface='project'"):
        external_input(BOX, _offset(1e-3), RADIUS, on_surface="refuse")
    with pytest.raises(OgcpError, match="20 mm outside.*beyond the 8 mm fingertip radius.*units metres"):
        external_input(BOX, _offset(0.02), RADIUS)
    with pytest.raises(OgcpError, match=r"contacts\[0\]\.normal points out of the object \(180\.0 deg.*negate"):
        external_input(BOX, _offset(0.0, (1.0, 0.0, 0.0)), RADIUS)
    with pytest.raises(OgcpError, match="unknown on_surface 'snap'"):
        external_input(BOX, _offset(0.0), RADIUS, on_surface="snap")


def test_a_contact_within_the_tolerance_stays_where_given():
    grasps = _offset(1e-5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        given = external_input(BOX, grasps, RADIUS, on_surface="refuse")
    np.testing.assert_array_equal(given.contacts.positions[:2], grasps.grasps[0].positions)
    assert not given.fit.projected.any()


@pytest.fixture(scope="module")
def round_trip(tmp_path_factory):
    """A box plan (optimum and two other grasps) evaluated as a plan and as exported grasps."""
    contacts = sample_contacts(BOX, 30, seed=0, source={"kind": "builtin", "name": "box", "diagonal": 0.2})
    record = GraspPlanner().plan(contacts, 3).to_dict(contact_set_record(contacts))
    record["top"] = [{"grasp": [0, 1, 2]}, {"grasp": [3, 7, 11]}]
    path = tmp_path_factory.mktemp("export") / "grasps.json"
    exported = export_grasps(record, path)
    planned = evaluate_plan(record, SETTINGS, HULL)
    external = evaluate_grasps(None, exported, SETTINGS, HULL)
    return record, exported, planned, external


def test_an_exported_plan_simulates_exactly_as_the_plan(round_trip):
    record, exported, planned, external = round_trip
    assert [g.label for g in exported.grasps] == ["best", "top-0", "top-1"] and exported.method == record["method"]
    assert len(planned.grasps) == len(external.grasps) == 3
    for a, b in zip(planned.grasps, external.grasps, strict=True):
        assert (a.label, a.q1, a.valid) == (b.label, b.q1, b.valid)
        np.testing.assert_array_equal(a.predicted, b.predicted)
        np.testing.assert_array_equal(a.measured, b.measured)
    assert planned.grasps[0].valid and planned.grasps[0].q1 == record["q1"]


def test_the_sim_record_carries_label_method_score_q1_and_distances(round_trip):
    record, exported, _, external = round_trip
    data = json.loads(json.dumps(external.to_dict(), allow_nan=False))
    obj = data["object"]
    assert (obj["kind"], obj["name"], obj["sampling"], obj["schema"]) == ("builtin", "box", "external", GRASPS_SCHEMA)
    assert obj["file"] == str(exported.path)
    first = obj["external"]["grasps"][0]
    assert (first["label"], first["method"], first["q1"], first["score"]) == (
        "best",
        "astar",
        record["q1"],
        record["q1"],
    )
    assert first["surface_distance"] == [0.0, 0.0, 0.0] and first["projected"] == [False] * 3
    assert SimRecord.from_dict(data).grasps[0].label == "best"


def test_the_cli_handler_writes_the_record_and_prints_the_grasps(round_trip, tmp_path, capsys):
    from ogcp.benchmarks.cli.external import is_external, run_external
    from ogcp.sim_eval import SimSettings

    _, exported, _, external = round_trip
    assert is_external(exported.path) and not is_external(tmp_path / "none.json")
    args = argparse.Namespace(plan=exported.path, max_grasps=1, output=tmp_path / "sim.json", json=False, render=None)
    assert run_external(args, SimSettings(**SETTINGS), _hull(), lambda data: "TABLE") == 0
    printed = capsys.readouterr().out
    assert "best (astar): score 0.1294" in printed and printed.rstrip().endswith("TABLE")
    written = json.loads((tmp_path / "sim.json").read_text())
    assert (
        len(written["grasps"]) == 1 and written["grasps"][0]["measured"] == external.to_dict()["grasps"][0]["measured"]
    )
    with pytest.raises(OgcpError, match="--render"):
        run_external(argparse.Namespace(**{**vars(args), "render": tmp_path / "a.png"}), SimSettings(), _hull())


def _hull():
    from ogcp.sim_eval import DecompositionSettings

    return DecompositionSettings(**HULL)


def test_array_grasps_of_mixed_m_simulate_with_defaults():
    x, z = float(HALF[0]), float(HALF[2])
    pinch = ([[x, 0, 0], [-x, 0, 0]], [[-1, 0, 0], [1, 0, 0]])
    tripod = ([[x, 0, 0], [-x, 0, 0], [0, 0, z]], [[-1, 0, 0], [1, 0, 0], [0, 0, -1]])
    result = evaluate_grasps(BOX, [pinch, tripod], SETTINGS, HULL, source={"kind": "builtin", "name": "box"})
    block = result.object["external"]
    assert [g.label for g in result.grasps] == ["grasp-0", "grasp-1"] and block["mu"] == 0.5
    assert [g.q1 for g in result.grasps] == [e["q1"] for e in block["grasps"]]
    assert result.grasps[0].q1 == 0.0 < result.grasps[1].q1  # a pinch is not in force closure
    assert result.grasps[1].error is None and block["grasps"][1]["method"] is None
    with pytest.raises(OgcpError, match="come from the grasps record"):
        evaluate_grasps(BOX, ExternalGrasps.from_dict(_minimal()), mu=0.3)


def test_a_mesh_path_is_relative_to_the_json_file_and_its_digest_is_checked(tmp_path, monkeypatch):
    from ogcp.planner.objects import file_sha256, resolve_object

    (tmp_path / "meshes").mkdir()
    mesh_file = tmp_path / "meshes" / "block.stl"
    trimesh.creation.box([0.1, 0.06, 0.04]).export(mesh_file)
    record = _minimal()
    record["object"] = {"mesh": "../meshes/block.stl", "diagonal": 0.2, "sha256": file_sha256(mesh_file)}
    (tmp_path / "grasps").mkdir()
    (tmp_path / "grasps" / "g.json").write_text(json.dumps(record))
    monkeypatch.chdir(tmp_path / "meshes")  # not the JSON's folder
    grasps = load_grasps(tmp_path / "grasps" / "g.json")
    mesh, source = grasps.load_object()
    expected, _ = resolve_object(str(mesh_file), 0.2)  # --diagonal's scaling
    np.testing.assert_array_equal(mesh.vertices, expected.vertices)
    assert source["kind"] == "mesh" and source["diagonal"] == 0.2
    save_grasps(grasps, tmp_path / "elsewhere" / "deeper" / "g.json")  # the path follows the file
    assert json.loads((tmp_path / "elsewhere" / "deeper" / "g.json").read_text())["object"]["mesh"] == (
        "../../meshes/block.stl"
    )
    record["object"]["sha256"] = "0" * 64
    (tmp_path / "grasps" / "g.json").write_text(json.dumps(record))
    with pytest.raises(OgcpError, match="object.sha256: the mesh .*block.stl has SHA-256"):
        load_grasps(tmp_path / "grasps" / "g.json").load_object()


def test_a_plan_on_a_mesh_file_exports_its_path_relative_to_the_grasps(tmp_path, monkeypatch):
    from ogcp.planner.objects import resolve_object

    monkeypatch.chdir(tmp_path)
    trimesh.creation.box([0.1, 0.06, 0.04]).export(tmp_path / "block.stl")
    mesh, source = resolve_object("block.stl", None)
    contacts = sample_contacts(mesh, 20, seed=1, source=source)
    result = GraspPlanner().plan(contacts, 3)
    exported = export_grasps(result, tmp_path / "out" / "g.json", contacts=contacts)
    assert exported.mesh == "../block.stl" and exported.sha256 == source["sha256"]
    assert exported.grasps[0].score == pytest.approx(result.q1, abs=1e-12)
    monkeypatch.chdir(tmp_path / "out")
    given = external_input(exported.load_object()[0], exported, 0.004)
    np.testing.assert_array_equal(given.contacts.positions, result.positions)
    np.testing.assert_array_equal(given.contacts.com, contacts.com)
    assert given.contacts.torque_scale == contacts.torque_scale and given.q1[0] == pytest.approx(result.q1, abs=1e-12)
    with pytest.raises(OgcpError, match="pass the contact set"):
        export_grasps(result, tmp_path / "x.json")


def test_the_converter_reads_a_csv_table_and_a_numpy_array(tmp_path):
    from ogcp.benchmarks.studies.convert_grasps import convert, main

    x, z = 1e3 * float(HALF[0]), 1e3 * float(HALF[2])
    (tmp_path / "in.csv").write_text(
        "# fingertips in millimetres, normals outward\n"
        "grasp,px,py,pz,nx,ny,nz,method,score\n"
        f"a,{x},0,0,1,0,0,mine,0.5\n"
        f"a,{-x},0,0,-1,0,0,,\n"
        "\n"
        f"b,{x},0,0,1,0,0,,\n"
        f"b,{-x},0,0,-1,0,0,,\n"
        f"b,0,0,{z},0,0,1,,\n"
    )
    grasps = convert(tmp_path / "in.csv", tmp_path / "out.json", "box", 0.4, units="mm", outward=True)
    assert [g.label for g in grasps.grasps] == ["a", "b"] and [len(g.positions) for g in grasps.grasps] == [2, 3]
    assert (grasps.grasps[0].method, grasps.grasps[0].score, grasps.mu) == ("mine", 0.5, 0.4)
    np.testing.assert_allclose(grasps.grasps[1].positions[2], [0, 0, HALF[2]], atol=1e-15)
    assert grasps.grasps[1].normals[2].tolist() == [0.0, 0.0, -1.0]
    assert not external_input(BOX, grasps, RADIUS).fit.projected.any()

    rows = np.array([[[HALF[0], 0, 0, -1, 0, 0], [-HALF[0], 0, 0, 1, 0, 0]]])
    np.save(tmp_path / "in.npy", rows)
    assert main([str(tmp_path / "in.npy"), "-o", str(tmp_path / "n.json"), "--mesh", "box", "--mu", "0.5"]) == 0
    assert load_grasps(tmp_path / "n.json").grasps[0].positions.tolist() == rows[0, :, :3].tolist()

    (tmp_path / "bad.csv").write_text("grasp,px,py,pz,nx,ny,nz\na,1,x,0,1,0,0\n")
    with pytest.raises(OgcpError, match=r"bad.csv:2: column py: expected a number, got 'x'"):
        convert(tmp_path / "bad.csv", tmp_path / "b.json", "box", 0.5)
    assert not (tmp_path / "b.json").exists()
