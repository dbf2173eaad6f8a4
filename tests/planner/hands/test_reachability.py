"""Reachability of any hand: the sampled model, its cache, sound pruning against brute force, constrained search."""

from __future__ import annotations

import itertools
import json
import re

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner.grasp import q1
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.hands import HandKinematics, HandReachability, SDHReachability, load_descriptor
from ogcp.planner.hands.reachability import pair_code
from ogcp.planner.hands.sampled_model import SPAN_MARGIN, SPAN_SCALE
from ogcp.planner.infra import OgcpError
from ogcp.planner.infra.cache import CacheEntryWarning
from ogcp.planner.search import GraspPlanner

from .hand_files import write_mesh_hand


@pytest.fixture(scope="module")
def hand(tmp_path_factory):
    return SDHReachability(samples=4000, seed=1, threshold=1.0, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def donut(object_contacts):
    return object_contacts("donut", 18, 4)


def test_the_model_holds_the_kinematics_pads_and_collisions(hand):
    kinematics = HandKinematics(hand.descriptor)
    rows = [0, 17, 3999]
    points, normals = kinematics.pads_many(hand.q[rows])
    np.testing.assert_allclose(hand.sampled.points[rows], points, atol=1e-12)
    np.testing.assert_allclose(hand.sampled.normals[rows], normals, atol=1e-12)
    np.testing.assert_array_equal(hand.sampled.collisions[rows], kinematics.collisions(hand.q[rows]))
    assert hand.joint_names == kinematics.joint_names


def test_codes_are_rigid_invariants():
    rng = np.random.default_rng(3)
    points, normals = rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    turn *= np.sign(np.linalg.det(turn))
    np.testing.assert_allclose(
        pair_code(points @ turn.T + 1.0, normals @ turn.T), pair_code(points, normals), atol=1e-12
    )
    assert pair_code(points, normals).shape == (24,)  # 4 per pair, C(4, 2) pairs


def test_model_is_cached_and_survives_a_corrupt_entry(tmp_path):
    first = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
    files = list(tmp_path.glob("hand_reach_sdh_*/model.npz"))
    assert len(files) == 1 and [p.name for p in tmp_path.iterdir()] == [files[0].parent.name]
    again = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
    assert np.array_equal(first.q, again.q)
    for damage in (b"not an npz", files[0].read_bytes()[:-10]):
        files[0].write_bytes(damage)
        with pytest.warns(CacheEntryWarning, match="is damaged"):
            rebuilt = SDHReachability(samples=500, seed=2, cache_dir=tmp_path)
        assert np.array_equal(first.q, rebuilt.q)
        assert SDHReachability(samples=500, seed=2, cache_dir=tmp_path).q.shape == first.q.shape  # repaired


def test_a_changed_descriptor_is_a_new_model(tmp_path):
    path = write_mesh_hand(tmp_path / "hand")
    first = HandReachability(path, samples=300, cache_dir=tmp_path / "cache")
    path.write_text(path.read_text().replace("kp = 4.0", "kp = 5.0"))
    second = HandReachability(path, samples=300, cache_dir=tmp_path / "cache")
    assert len(list((tmp_path / "cache").glob("hand_reach_claw_*"))) == 2
    assert second.describe()["descriptor_sha256"] != first.describe()["descriptor_sha256"]


def test_residual_ignores_contact_order_and_reports_a_configuration(hand, donut):
    reach = hand.reach((2, 7, 11), donut)
    for order in itertools.permutations((2, 7, 11)):
        assert hand.reach(order, donut).residual == pytest.approx(reach.residual, abs=1e-12)
    assert len(reach.joint_angles) == 8 and sorted(reach.fingers) == [0, 1, 2]
    assert reach.finger_names == ("finger_1", "finger_2", "thumb")
    assert hand.accepts((2, 7, 11), donut) == (reach.residual <= hand.threshold)


def test_the_compiled_grasp_test_answers_as_the_nearest_sample_does(hand, donut):
    """accepts (compiled, no nearest sample) equals the k-d tree's residual <= threshold on every triple."""
    grasps = np.array(list(itertools.combinations(range(len(donut)), 3)))
    residuals = hand.residuals(donut.positions[grasps], donut.normals[grasps])
    accepted = np.array([hand.accepts(tuple(g), donut) for g in grasps])
    assert 0 < accepted.sum() < len(grasps)
    np.testing.assert_array_equal(accepted, residuals <= hand.threshold)


def test_pruning_is_sound_against_brute_force(hand, donut):
    rng = np.random.default_rng(0)
    pruned = 0
    for _ in range(300):
        sets = [np.sort(rng.choice(18, int(rng.integers(1, 3)), replace=False)) for _ in range(3)]
        reachable = any(len({a, b, c}) == 3 and hand.accepts((a, b, c), donut) for a, b, c in itertools.product(*sets))
        admitted = hand.admits(sets, donut)
        assert admitted or not reachable  # never prunes a state that holds a reachable grasp
        pruned += not admitted
    assert pruned > 0  # and it does prune


def _admits_in_numpy(hand, super_contacts, contacts):
    """admits as it was before it was compiled: every pair's code ranges, then every assignment's box."""
    m = len(super_contacts)
    model = hand._model(m)
    bounds = np.zeros((m, m, 2, 4))
    for x, y in itertools.permutations(range(m), 2):
        px, py = contacts.positions[super_contacts[x]], contacts.positions[super_contacts[y]]
        nx, ny = contacts.normals[super_contacts[x]], contacts.normals[super_contacts[y]]
        line = py[None, :, :] - px[:, None, :]
        length = np.linalg.norm(line, axis=-1)
        u = line / np.maximum(length, 1e-12)[..., None]
        values = (
            length,
            np.linalg.norm(nx[:, None, :] - ny[None, :, :], axis=-1),
            np.einsum("ak,abk->ab", nx, u),
            np.einsum("bk,abk->ab", ny, u),
        )
        bounds[x, y, 0] = [v.min() for v in values]
        bounds[x, y, 1] = [v.max() for v in values]
    pairs = list(itertools.combinations(range(m), 2))
    low = np.array(
        [np.concatenate([bounds[a[i], a[j], 0] for i, j in pairs]) for a in itertools.permutations(range(m))]
    )
    high = np.array(
        [np.concatenate([bounds[a[i], a[j], 1] for i, j in pairs]) for a in itertools.permutations(range(m))]
    )
    gap = np.maximum(low[:, None] / model.scale - model.codes[None], 0.0)
    gap += np.maximum(model.codes[None] - high[:, None] / model.scale, 0.0)
    # A pair's distances beyond its fingers' span of pad distances count as one more dimension.
    beyond = np.maximum(model.spans[:, 0] - high[:, 0::4], 0.0) + np.maximum(low[:, 0::4] - model.spans[:, 1], 0.0)
    beyond2 = np.sum((beyond / SPAN_SCALE) ** 2, axis=1)
    return bool((np.einsum("bnd,bnd->bn", gap, gap) + beyond2[:, None] <= hand.threshold**2).any())


def test_the_compiled_test_of_a_state_answers_as_numpy_did(hand, donut):
    rng = np.random.default_rng(7)
    answers = []
    for _ in range(400):
        sets = [np.sort(rng.choice(18, int(rng.integers(1, 5)), replace=False)) for _ in range(3)]
        answer = hand.admits(sets, donut)
        assert answer == _admits_in_numpy(hand, sets, donut)
        answers.append(answer)
    assert 0 < sum(answers) < len(answers)


def test_a_gripper_is_not_asked_to_span_more_than_its_jaws_open(tmp_path):
    """Two contacts farther apart than the jaws open are rejected, though the code alone admits them.

    The distance code of a parallel gripper spreads as widely as its jaws travel (16 mm), so within
    the threshold a nearest sample alone accepted a box 11 mm wider than the jaws open.
    """
    gripper = HandReachability("parallel_gripper", samples=4000, seed=0, cache_dir=tmp_path)
    model = gripper._model(2)
    widest = float(model.spans[0, 1]) - SPAN_MARGIN  # the opening (90 mm less two 4 mm jaws), sampled
    assert widest == pytest.approx(0.082, abs=1.5e-3)

    def pinch(width: float) -> ContactSet:
        positions = np.array([[0.0, 0.5 * width, 0.0], [0.0, -0.5 * width, 0.0]])
        normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
        return ContactSet(positions, normals, np.zeros(3), 0.05)

    widths = [0.05, widest + 0.5 * SPAN_MARGIN, widest + SPAN_MARGIN + 2e-3, 0.093]
    sets = [pinch(w) for w in widths]
    residuals = [float(gripper.residuals(c.positions[None], c.normals[None])[0]) for c in sets]
    assert [gripper.accepts((0, 1), c) for c in sets] == [True, True, False, False]
    assert [r <= gripper.threshold for r in residuals] == [True, True, False, False]
    assert residuals[3] > residuals[2] > 1.5  # millimetres beyond the span add to the residual
    assert not gripper.admits([np.array([0]), np.array([1])], sets[3])  # and a state of them is pruned
    code = pair_code(sets[3].positions[None], sets[3].normals[None])[0] / model.scale
    assert model.tree.query(code)[0] <= gripper.threshold  # what the code alone said


def test_constrained_astar_equals_constrained_enumeration(hand, donut):
    valid = [g for g in itertools.combinations(range(18), 3) if hand.accepts(g, donut)]
    assert 0 < len(valid) < 816
    best = max(q1(donut.subset_wrenches(np.array(g))) for g in valid)
    result = GraspPlanner(constraints=[hand]).plan(donut, 3)
    assert result.q1 == best and hand.accepts(result.grasp, donut)


def test_cli_reports_the_hand_configuration(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    assert main(["plan", "donut", "-n", "30", "-m", "3", "--hand", "sdh", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["hand"]["name"] == "sdh" and len(record["hand"]["joint_angles"]) == 8
    assert record["hand"]["residual"] <= 1.0 and record["hand"]["fingers"] == ["finger_1", "finger_2", "thumb"]
    assert sorted(record["hand"]["finger_contacts"]) == record["grasp"]
    assert len(record["hand"]["descriptor_sha256"]) == 64 and record["hand"]["joint_names"][3] == "base_2"
    assert main(["plan", "donut", "-n", "30", "-m", "4", "--hand", "sdh"]) == 2
    assert "the sdh hand has 3 fingers; a grasp of m = 4 contacts cannot use them" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["astar", "es"])
def test_a_search_that_finds_nothing_the_hand_reaches_says_what_to_change(capsys, tmp_path, monkeypatch, method):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    args = ["plan", "box", "-n", "12", "-m", "3", "--diagonal", "2.0", "--hand", "sdh", "--method", method]
    assert main(args) == 2  # a 2 m box: wider than the SDH opens
    err = capsys.readouterr().err.strip()
    assert err.startswith("ogcp: error: no grasp satisfies the constraints: the sdh hand's reachability model (10,000")
    assert err.endswith(
        "more [reachability] samples in its descriptor, a larger --hand-threshold (now 1) or other --hand-fingers may find one"
    )
    assert "\n" not in err


def test_fewer_contacts_than_fingers_use_the_named_fingers(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    args = ["plan", "donut", "-n", "30", "-m", "2", "--hand", "sdh", "--hand-fingers", "thumb,finger_2", "--json"]
    assert main(args) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["hand"]["fingers"] == ["thumb", "finger_2"] and len(record["hand"]["finger_contacts"]) == 2
    assert main([*args[:-3], "--hand-fingers", "thumb"]) == 2
    assert "1 hand fingers named (thumb) for a grasp of m = 2" in capsys.readouterr().err


def test_a_users_descriptor_plans_with_no_code_change(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    path = write_mesh_hand(tmp_path / "hand")
    assert main(["plan", "sphere", "-n", "40", "-m", "3", "--diagonal", "0.08", "--hand", str(path), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["hand"]["name"] == "claw" and record["hand"]["descriptor"] == str(path)
    assert record["hand"]["reachable"] and record["q1"] > 0
    with pytest.raises(OgcpError, match="the claw hand has 3 fingers"):
        HandReachability(load_descriptor(path), samples=100, cache_dir=tmp_path / "c").chosen(4)


def test_es_filtered_by_the_same_predicate(hand, donut):
    from ogcp.planner.baselines.es import ExhaustiveSearch

    grasps = list(itertools.combinations(range(18), 3))
    valid = [g for g in grasps if hand.accepts(g, donut)]
    values = {g: q1(donut.subset_wrenches(np.array(g))) for g in valid}
    best = max(values.values())
    result = ExhaustiveSearch(chunk=100, constraints=[hand]).run(donut, 3)
    assert result.q1 == best and result.grasp == min(g for g in valid if values[g] == best)
    assert result.excluded == len(grasps) - len(valid)
    assert result.zero == sum(v == 0 for v in values.values())
    assert result.q1 == GraspPlanner(constraints=[hand]).plan(donut, 3).q1


def test_hfts_penalises_the_residual(hand, object_contacts):
    from ogcp.planner.baselines.hfts import HFTS

    contacts = object_contacts("donut", 100, 0)
    free = HFTS(runs=12, seed=0).run(contacts, 3)
    with_hand = HFTS(runs=12, seed=0, hand=hand).run(contacts, 3)
    assert all(r.residual is None for r in free.runs) and all(r.residual is not None for r in with_hand.runs)
    free_residuals = hand.residuals(
        contacts.positions[[list(r.grasp) for r in free.runs]], contacts.normals[[list(r.grasp) for r in free.runs]]
    )
    assert np.mean([r.residual for r in with_hand.runs]) < np.mean(free_residuals)
    assert with_hand.config["hand"]["name"] == "sdh"


def test_hfts_takes_any_number_of_fingers_the_hand_has(object_contacts, tmp_path):
    """HFTS with a hand once took m = 3 only (the SDH's), and said any hand had 3 fingers."""
    from ogcp.planner.baselines.hfts import HFTS

    contacts = object_contacts("box", 60, 0)
    gripper = HandReachability("parallel_gripper", samples=2000, seed=0, cache_dir=tmp_path)
    pinch = HFTS(runs=2, seed=0, hand=gripper).run(contacts, 2)
    assert len(pinch.grasp) == 2 and all(r.residual is not None for r in pinch.runs)
    with pytest.raises(OgcpError, match="the parallel_gripper hand has 2 fingers; a grasp of m = 3 contacts"):
        HFTS(runs=2, seed=0, hand=gripper).run(contacts, 3)


def test_cli_es_summary_counts_admissible_grasps(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    assert main(["plan", "donut", "-n", "16", "-m", "3", "--method", "es", "--hand", "sdh"]) == 0
    out = capsys.readouterr().out
    excluded, admissible = map(int, re.search(r"constraints: (\d+) grasps excluded, (\d+) admissible", out).groups())
    assert excluded + admissible == 560  # C(16, 3)
    fc, of = map(int, re.search(r"force closure: (\d+) of (\d+)", out).groups())
    assert of == admissible and fc <= admissible


def test_contacts_for_a_hand_are_sampled_for_its_pads(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    out = tmp_path / "c.json"
    assert main(["contacts", "donut", "-n", "20", "--hand", "sdh", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["source"]["tip_radius"] == 0.009  # the SDH's pad rounding
    assert main(["contacts", "donut", "-n", "20", "--hand", "sdh", "--tip-radius", "0.004", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["source"]["tip_radius"] == 0.004
    assert main(["contacts", "donut", "-n", "20", "--hand", "nope", "-o", str(out)]) == 2
    assert "unknown hand 'nope'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("diagonal", "said"),
    [
        (20.0, r"no two contacts are nearer than [\d.]+ m, and no two of its pads are ever farther apart than "),
        (0.004, r"all contacts lie within 0\.004 m of each other, and no two of its pads ever come nearer than "),
    ],
)
def test_an_object_out_of_the_hands_size_is_named_as_such(hand, diagonal, said):
    """No sample, threshold or choice of fingers helps there: the line says to scale the object."""
    from ogcp.planner.grasp.contact_set import sample_contacts
    from ogcp.planner.objects import resolve_object

    contacts = sample_contacts(resolve_object("box", diagonal)[0], 30, seed=0)
    line = hand.why_none(3, contacts)
    assert re.search(said, line) and line.endswith("for the hand; scale it (--diagonal)")
    assert "more [reachability] samples" not in line
    fitting = sample_contacts(resolve_object("box", 0.2)[0], 30, seed=0)
    assert "more [reachability] samples" in hand.why_none(3, fitting) and hand.why_none(3) == hand.why_none(3, None)
