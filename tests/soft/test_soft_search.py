"""Soft fingers in every method: A*, WA*, Dijkstra and ES against brute force, HFTS, the CLI."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner import builtin_mesh
from ogcp.planner.baselines import HFTS, ExhaustiveSearch
from ogcp.planner.grasp import q1, sample_contacts
from ogcp.planner.search import GraspPlanner
from tests.conftest import exhaustive_best

# (object, n, m, seed): m = 2 is where only soft fingers reach force closure.
INSTANCES = (("box", 18, 2, 1), ("sphere", 16, 2, 2), ("amphora", 16, 3, 3), ("donut", 14, 3, 4), ("box", 11, 4, 5))
TORSION = 0.02


def _soft(name: str, n: int, seed: int, torsion: float = TORSION):
    return sample_contacts(builtin_mesh(name), n, seed=seed, torsional_friction=torsion)


@pytest.fixture(scope="module")
def optimum():
    cache: dict[tuple, float] = {}

    def best(name, n, m, seed):
        if (name, n, m, seed) not in cache:
            cache[(name, n, m, seed)] = exhaustive_best(_soft(name, n, seed), m, prefilter=False)
        return cache[(name, n, m, seed)]

    return best


@pytest.mark.parametrize("name,n,m,seed", INSTANCES)
def test_astar_and_dijkstra_find_the_brute_force_optimum(name, n, m, seed, optimum):
    contacts = _soft(name, n, seed)
    expected = optimum(name, n, m, seed)
    assert expected > 0
    for planner in (
        GraspPlanner(seed=seed),
        GraspPlanner(successor="ru", heuristic="ru", seed=seed),
        GraspPlanner(method="dijkstra", seed=seed),
    ):
        result = planner.plan(contacts, m)
        assert result.q1 == pytest.approx(expected, abs=1e-9) and result.bound == pytest.approx(result.q1, abs=1e-12)
        assert result.q1 == q1(contacts.subset_wrenches(np.array(result.grasp)))


@pytest.mark.parametrize("eps", [0.3, 1.0])
@pytest.mark.parametrize("name,n,m,seed", INSTANCES[:3])
def test_wastar_respects_its_bound(name, n, m, seed, eps, optimum):
    best = optimum(name, n, m, seed)
    result = GraspPlanner(method="wastar", eps=eps, seed=seed).plan(_soft(name, n, seed), m)
    assert result.q_ows - result.q1 <= (1 + eps) * (result.q_ows - best) + 1e-9
    assert result.q1 <= best + 1e-12 <= result.bound + 2e-12


@pytest.mark.parametrize("name,n,m,seed", INSTANCES[:4])
def test_es_agrees_with_astar_bit_for_bit(name, n, m, seed):
    contacts = _soft(name, n, seed)
    es = ExhaustiveSearch(chunk=101).run(contacts, m)
    astar = GraspPlanner(seed=seed).plan(contacts, m)
    assert es.q1 == astar.q1  # the same Q1 of the same grasp, bit for bit
    grasps = list(itertools.combinations(range(n), m))
    values = np.array([q1(contacts.subset_wrenches(np.array(g))) for g in grasps])
    assert es.grasp == grasps[int(np.argmax(values))] and es.q1 == values.max()


def test_hfts_runs_on_soft_contacts_and_stays_below_the_optimum(optimum):
    name, n, m, seed = INSTANCES[2]
    result = HFTS(runs=4, iterations=10, seed=seed).run(_soft(name, n, seed), m)
    assert 0 <= result.q1 <= optimum(name, n, m, seed) + 1e-12


def test_more_torsion_never_lowers_the_optimum():
    values = [GraspPlanner().plan(_soft("box", 16, 0, t), 2).q1 for t in (0.005, 0.01, 0.02, 0.04)]
    assert all(b >= a for a, b in itertools.pairwise(values)) and values[0] > 0


def test_plan_cli_records_the_model_and_evaluate_reads_it_back(tmp_path, capsys):
    out = tmp_path / "plan.json"
    args = ["plan", "box", "-n", "20", "-m", "2", "--contact-model", "soft", "--torsional-friction", "0.01"]
    assert main([*args, "--json", "-o", str(out)]) == 0
    record = json.loads(capsys.readouterr().out)
    block = record["contact_set"]
    assert (block["contact_model"], block["torsional_friction"]) == ("soft", 0.01) and record["q1"] > 0
    hard = ["plan", "box", "-n", "20", "-m", "2", "--json"]
    assert main(hard) == 0 and json.loads(capsys.readouterr().out)["q1"] == 0.0
    from ogcp.planner.records.plan import load_plan, recorded_contacts

    contacts = recorded_contacts(load_plan(out))
    assert contacts is not None and contacts.torsional_friction == 0.01
    assert q1(contacts.subset_wrenches(np.array(record["grasp"]))) == record["q1"]


@pytest.mark.parametrize(
    "args,message",
    [
        (["--contact-model", "hard", "--torsional-friction", "0.01"], "needs the soft contact model"),
        (["--contact-model", "soft", "--torsional-friction", "0"], "> 0"),
        (["--contact-model", "jelly"], "invalid choice"),
    ],
)
def test_plan_cli_refuses_bad_models_in_one_line(args, message, capsys):
    try:
        status = main(["plan", "box", "-n", "10", *args])
    except SystemExit as exc:  # argparse's own refusals exit
        status = exc.code
    err = capsys.readouterr().err
    assert status == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_contact_file_refuses_a_model_flag(tmp_path, capsys):
    path = tmp_path / "c.json"
    assert main(["contacts", "box", "-n", "10", "--contact-model", "soft", "-o", str(path)]) == 0
    assert json.loads(path.read_text())["torsional_friction"] == 0.02
    capsys.readouterr()
    assert main(["plan", str(path), "-m", "2", "--torsional-friction", "0.01"]) == 2
    assert "do not apply to a contact file" in capsys.readouterr().err
