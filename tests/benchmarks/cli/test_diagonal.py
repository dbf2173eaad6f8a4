"""``--diagonal`` on mesh files: normalised like the built-ins, recorded, and rebuilt by ``evaluate``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.planner import builtin_mesh, resolve_object
from ogcp.planner.grasp import ContactSet
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects.resolve import MeshScaleWarning
from ogcp.planner.records.plan import contact_sampling
from ogcp.sim_eval.inputs.plan_input import plan_input
from tests.cli_run import run_cli


@pytest.fixture
def box_mm(tmp_path):
    """The built-in box exported in millimetres (1000 x its 0.2 m diagonal), off-centre.

    OBJ keeps the vertices to ~1e-12; STL and PLY store float32, which would move the contacts by
    ~1e-8 m, past the 1e-9 check.
    """
    mesh = builtin_mesh("box")
    mesh.apply_translation([0.05, -0.02, 0.01])
    mesh.apply_scale(1000.0)
    path = tmp_path / "box-mm.obj"
    mesh.export(path)
    return path


def test_a_mesh_file_keeps_its_size_unless_a_diagonal_is_given(box_mm):
    with pytest.warns(MeshScaleWarning, match="in millimetres it would be 0.2 m"):  # read as given, and said
        native, source = resolve_object(str(box_mm))
    assert np.linalg.norm(np.ptp(native.vertices, axis=0)) == pytest.approx(200.0)
    assert "diagonal" not in source  # records of meshes at their own size are unchanged
    scaled, source = resolve_object(str(box_mm), 0.2)
    assert np.linalg.norm(np.ptp(scaled.vertices, axis=0)) == pytest.approx(0.2, rel=1e-12)
    assert np.allclose(scaled.bounds.sum(axis=0), 0.0, atol=1e-12)  # centred like the built-ins
    assert source["diagonal"] == 0.2
    with pytest.raises(OgcpError, match="positive number of metres"):
        resolve_object(str(box_mm), -1.0)


def test_a_millimetre_mesh_at_diagonal_0_2_gives_the_built_in_box_contacts(tmp_path, box_mm):
    mine, builtin = tmp_path / "mine.json", tmp_path / "builtin.json"
    assert run_cli(["contacts", str(box_mm), "-n", "60", "--diagonal", "0.2", "-o", str(mine)])[0] == 0
    assert run_cli(["contacts", "box", "-n", "60", "-o", str(builtin)])[0] == 0
    a, b = ContactSet.load(mine), ContactSet.load(builtin)
    assert np.allclose(a.positions, b.positions, atol=1e-9, rtol=0.0)
    assert np.allclose(a.normals, b.normals, atol=1e-9, rtol=0.0)
    assert a.source["diagonal"] == 0.2 and a.source["tip_radius"] == pytest.approx(b.source["tip_radius"], rel=1e-12)


def test_a_plan_on_a_scaled_mesh_file_rebuilds_in_evaluate(box_mm):
    status, out, err = run_cli(["plan", str(box_mm), "-n", "40", "-m", "3", "--diagonal", "0.2", "--json"])
    assert status == 0, err
    record = json.loads(out)
    assert contact_sampling(record).object["diagonal"] == 0.2
    rebuilt = plan_input(record)
    builtin = plan_input(json.loads(run_cli(["plan", "box", "-n", "40", "-m", "3", "--json"])[1]))
    assert np.allclose(rebuilt.contacts.positions, builtin.contacts.positions, atol=1e-9, rtol=0.0)
    assert rebuilt.grasps[0] == builtin.grasps[0]


def test_diagonal_does_not_apply_to_a_contact_file(tmp_path):
    path = tmp_path / "c.json"
    assert run_cli(["contacts", "box", "-n", "10", "-o", str(path)])[0] == 0
    status, out, err = run_cli(["plan", str(path), "--diagonal", "0.1"])
    assert status == 2 and out == ""
    assert err.strip() == "ogcp: error: --diagonal does not apply to a contact file (its contacts are fixed)"


def test_decompose_takes_a_diagonal():
    from ogcp.benchmarks.cli.app import build_parser

    args = build_parser().parse_args(["decompose", "box", "--diagonal", "0.05"])
    assert args.diagonal == 0.05
    assert build_parser().parse_args(["decompose", "box"]).diagonal is None


def test_a_suite_scales_a_mesh_file_only_when_it_gives_a_diagonal(box_mm):
    from ogcp.benchmarks.suite.cells import contact_set
    from ogcp.benchmarks.suite.parse import parse_suite

    text = f'schema_version = 1\nobjects = ["box", {json.dumps(str(box_mm))}]\ncontacts = 30\n{{extra}}\n'
    text += '[[methods]]\nmethod = "astar"\nlabel = "A*"\n'
    native = {c.object.spec: c for c in parse_suite(text.format(extra="")).cells}
    scaled = {c.object.spec: c for c in parse_suite(text.format(extra="diagonal = 0.2")).cells}
    mesh = str(box_mm)
    assert native[mesh].diagonal is None and native["box"].diagonal == 0.2
    assert scaled[mesh].diagonal == 0.2 and scaled["box"].id == native["box"].id
    assert scaled[mesh].id != native[mesh].id  # another contact set, another id
    box, mine = contact_set(scaled["box"]), contact_set(scaled[mesh])
    assert np.allclose(mine.positions, box.positions, atol=1e-9, rtol=0.0)
