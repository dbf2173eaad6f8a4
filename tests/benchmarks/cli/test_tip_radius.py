"""``--tip-radius`` on ``contacts`` and ``plan``, and rebuilding the planned contacts from the plan record."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner import builtin_mesh
from ogcp.planner.grasp import ContactSet, sample_contacts
from ogcp.planner.grasp.reach import DEFAULT_TIP_RADIUS_RATIO, REACH_TOLERANCE, default_tip_radius
from ogcp.planner.records.plan import contact_sampling
from ogcp.sim_eval.inputs.plan_input import plan_input
from tests.cli_run import run_cli


@pytest.mark.parametrize("value", ["-0.01", "inf", "nan", "abc"])
@pytest.mark.parametrize("command", ["contacts", "plan"])
def test_a_bad_tip_radius_is_one_error_line(capsys, tmp_path, command, value):
    argv = [command, "box", "-n", "8", f"--tip-radius={value}"] + (
        ["-o", str(tmp_path / "c.json")] * (command == "contacts")
    )
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert "--tip-radius" in lines[-1] and ">= 0" in lines[-1] and "Traceback" not in lines[-1]
    assert not list(tmp_path.iterdir())


def test_tip_radius_does_not_apply_to_a_contact_file(tmp_path):
    path = tmp_path / "c.json"
    assert run_cli(["contacts", "box", "-n", "10", "-o", str(path)])[0] == 0
    status, out, err = run_cli(["plan", str(path), "--tip-radius", "0.01"])
    assert status == 2 and out == ""
    assert err.strip() == "ogcp: error: --tip-radius does not apply to a contact file (its contacts are fixed)"


def test_contacts_default_to_the_simulation_fingertip_and_zero_is_plain_sampling(tmp_path):
    mesh = builtin_mesh("amphora")
    tip = default_tip_radius(mesh)
    assert tip == pytest.approx(DEFAULT_TIP_RADIUS_RATIO * np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    default, plain, given = tmp_path / "d.json", tmp_path / "p.json", tmp_path / "g.json"
    assert run_cli(["contacts", "amphora", "-n", "60", "-o", str(default)])[0] == 0
    assert run_cli(["contacts", "amphora", "-n", "60", "--tip-radius", "0", "-o", str(plain)])[0] == 0
    assert run_cli(["contacts", "amphora", "-n", "60", "--tip-radius", repr(tip), "-o", str(given)])[0] == 0
    assert default.read_bytes() == given.read_bytes()
    default_set, plain_set = ContactSet.load(default), ContactSet.load(plain)
    assert default_set.source["tip_radius"] == tip
    assert default_set.source["reach_tolerance"] == REACH_TOLERANCE * tip
    assert "tip_radius" not in plain_set.source and "reach_tolerance" not in plain_set.source
    expected = sample_contacts(mesh, 60, 0, source=plain_set.source)
    assert np.array_equal(plain_set.positions, expected.positions)  # 0: the paper's plain sampling, bit for bit


def test_the_plan_summary_shows_the_tip_radius_only_for_reach_aware_contacts():
    status, out, _ = run_cli(["plan", "box", "-n", "20", "--tip-radius", "0.005"])
    assert status == 0 and out.splitlines()[0].startswith("object: box   |C| = 20   tip r = 0.005 m   mu = 0.5")
    status, out, _ = run_cli(["plan", "box", "-n", "20", "--tip-radius", "0"])
    assert status == 0 and "tip r" not in out


@pytest.fixture(scope="module")
def amphora_plans(tmp_path_factory):
    """Plans on the amphora at the default tip and with plain sampling: {name: (record, contacts)}."""
    folder = tmp_path_factory.mktemp("amphora")
    plans = {}
    for name, extra in (("default", []), ("plain", ["--tip-radius", "0"])):
        plan, contacts = folder / f"{name}-plan.json", folder / f"{name}-contacts.json"
        common = ["amphora", "-n", "150", "--seed", "2", *extra]
        status, out, err = run_cli(["plan", *common, "-m", "3", "--json"])
        assert status == 0, err
        plan.write_text(out)
        assert run_cli(["contacts", *common, "-o", str(contacts)])[0] == 0
        plans[name] = (json.loads(plan.read_text()), ContactSet.load(contacts))
    return plans


def test_evaluate_rebuilds_exactly_the_contacts_planned_with_a_tip_radius(amphora_plans):
    record, planned = amphora_plans["default"]
    _, plain = amphora_plans["plain"]
    # The tip mattered: some plain samples on the amphora are out of its reach and were replaced.
    assert not np.array_equal(planned.positions, plain.positions)
    sampling = contact_sampling(record)
    assert sampling.tip_radius == planned.source["tip_radius"] > 0
    assert sampling.reach_tolerance == planned.source["reach_tolerance"]
    assert "tip_radius" not in sampling.object and "reach_tolerance" not in sampling.object
    rebuilt = plan_input(record).contacts
    assert np.array_equal(rebuilt.positions, planned.positions) and np.array_equal(rebuilt.normals, planned.normals)
    assert rebuilt.source == planned.source


def test_plans_without_a_tip_rebuild_with_plain_sampling(amphora_plans):
    record, planned = amphora_plans["plain"]
    sampling = contact_sampling(record)
    assert sampling.tip_radius is None and sampling.reach_tolerance is None
    rebuilt = plan_input(record).contacts
    assert np.array_equal(rebuilt.positions, planned.positions)
