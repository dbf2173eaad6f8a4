"""A reachability model with no fixed size grows until it recalls the hand's own configurations."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ogcp.benchmarks.cli import main
from ogcp.planner import resolve_object, sample_contacts
from ogcp.planner.hands import (
    HandKinematics,
    HandReachability,
    load_descriptor,
    model_file,
    reachability,
    resolve_hand,
    sampled_model,
)
from ogcp.planner.infra import NoGraspError
from ogcp.planner.infra.cache import CacheEntryWarning, write_entry
from ogcp.planner.methods import runners
from ogcp.planner.search import GraspPlanner
from ogcp.sim_eval.evaluate import plan_hand


@pytest.fixture
def small(monkeypatch):
    """Growth in small steps: 1,000 samples first, at most 4,000, recall measured on 300 probes."""
    for module in (sampled_model, model_file):
        monkeypatch.setattr(module, "FIRST_SAMPLES", 1_000)
        monkeypatch.setattr(module, "MAX_AUTO_SAMPLES", 4_000)
    monkeypatch.setattr(reachability, "MAX_AUTO_SAMPLES", 4_000)
    monkeypatch.setattr(sampled_model, "RECALL_PROBES", 300)
    return monkeypatch


def test_a_model_that_recalls_enough_keeps_its_first_samples(tmp_path, small):
    model = HandReachability("parallel_gripper", cache_dir=tmp_path)  # two slides: every pose recalled
    assert model.samples == 1_000 and model.sampled.recall == 1.0
    assert model.describe()["recall"] == 1.0


def test_a_model_that_recalls_too_little_doubles_until_the_cap(tmp_path, small):
    small.setattr(sampled_model, "AUTO_RECALL", 0.999)  # the SDH's 1,000 samples recall far less
    grown = HandReachability("sdh", cache_dir=tmp_path / "grown")
    assert grown.samples == 4_000 and 0.0 < grown.sampled.recall < 0.999
    # Its first samples are a fixed-size model's with the same seed; the doublings add other ones.
    fixed = HandReachability("sdh", samples=1_000, cache_dir=tmp_path / "fixed")
    np.testing.assert_array_equal(grown.q[:1_000], fixed.q)
    assert len(np.unique(grown.q.round(12), axis=0)) == 4_000
    # Pads and collisions of an added sample are the hand's.
    kinematics = HandKinematics(grown.descriptor)
    points, _ = kinematics.pads_many(grown.q[[3_999]])
    np.testing.assert_allclose(grown.sampled.points[[3_999]], points, atol=1e-12)
    # Read back from the cache as it was written, recall included.
    again = HandReachability("sdh", cache_dir=tmp_path / "grown")
    np.testing.assert_array_equal(again.q, grown.q)
    assert again.sampled.recall == grown.sampled.recall


def test_recall_rises_with_the_samples(tmp_path, small):
    small.setattr(sampled_model, "AUTO_RECALL", 0.999)
    kinematics = HandKinematics(resolve_hand("sdh"))
    recalls = []
    probes = sampled_model.pose_samples(kinematics, kinematics.sample(300, 99), sampled_model.tqdm(disable=True))
    for count in (500, 4_000):
        sampled = sampled_model.pose_samples(kinematics, kinematics.sample(count, 0), sampled_model.tqdm(disable=True))
        recalls.append(sampled_model._recall(sampled, probes, (0, 1, 2)))
    assert recalls[0] < recalls[1]


def test_a_grown_model_without_its_recall_is_rebuilt(tmp_path, small):
    model = HandReachability("parallel_gripper", cache_dir=tmp_path)
    (entry,) = tmp_path.glob("hand_reach_parallel_gripper_*")
    with np.load(entry / reachability.MODEL_FILE) as data:
        arrays = {k: data[k] for k in data.files if k != "recall"}
    # A sealed entry (its manifest matches) that lacks the recall: the model's own check finds it.
    write_entry(entry, lambda stage: np.savez(stage / reachability.MODEL_FILE, **arrays), replace=True)
    with pytest.warns(CacheEntryWarning, match="grown model of 1000 configurations and recall None"):
        rebuilt = HandReachability("parallel_gripper", cache_dir=tmp_path)
    assert rebuilt.sampled.recall == model.sampled.recall


def test_a_one_finger_hand_keeps_its_first_samples_and_its_cache_entry(tmp_path, small):
    import warnings

    from tests.planner.hands.hand_files import write_gripper_variant

    (tmp_path / "hand").mkdir()
    path = write_gripper_variant(tmp_path / "hand", lambda text: text)
    text = path.read_text()
    path.write_text(
        text[: text.index("[[fingers]]", text.index("[[fingers]]") + 1)] + text[text.index("[actuation]") :]
    )
    model = HandReachability(load_descriptor(path), cache_dir=tmp_path / "cache")
    assert model.samples == 1_000 and model.sampled.recall is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # read back as it was written, not rebuilt
        again = HandReachability(load_descriptor(path), cache_dir=tmp_path / "cache")
    np.testing.assert_array_equal(again.q, model.q)


def test_a_search_that_finds_nothing_under_a_grown_model_tries_a_denser_one(tmp_path, small, capsys):
    """A 10 cm sphere on 12 contacts: no grasp within 1,000 SDH samples (the best at 1.22 thresholds), some
    within 4,000; the plan is made under the denser model and says so."""
    small.setattr(sampled_model, "AUTO_RECALL", 0.0)  # the first 1,000 samples are kept
    small.setenv("OGCP_CACHE", str(tmp_path))
    runners.hand_model.cache_clear()  # the runners keep models by hand name, whatever the cache
    args = ["plan", "sphere", "-n", "12", "-m", "3", "--diagonal", "0.1", "--hand", "sdh", "--json"]
    try:
        # Under a time limit it does not try: sampling a denser model takes longer than any limit bounds.
        assert main([*args, "--time-limit", "60"]) == 2
        assert "reachability model (1,000 sampled configurations" in capsys.readouterr().err
        assert main(args) == 0
    finally:
        runners.hand_model.cache_clear()
    record = json.loads(capsys.readouterr().out)
    (constraint,) = record["config"]["constraints"]
    assert constraint["samples"] == record["hand"]["samples"] == 4_000 and record["hand"]["reachable"]
    assert plan_hand(record).reach.samples == 4_000  # the fit starts from the plan's model
    for damaged in (10**9, -3, "many"):  # a record's size past the cap or not a size: the hand's own model
        record["hand"]["samples"] = damaged
        assert plan_hand(record).reach.samples == 1_000
    first = HandReachability("sdh", cache_dir=tmp_path)
    contacts = sample_contacts(resolve_object("sphere", 0.1)[0], n=12, seed=0)
    assert first.samples == 1_000 and first.growable
    with pytest.raises(NoGraspError):
        GraspPlanner(constraints=[first]).plan(contacts, 3)
    assert 1.0 < first.near_miss(contacts, 3) < reachability.NEAR_MISS
    denser = first.denser(contacts, 3)
    assert denser is not None and denser.samples == 4_000 and denser.growable
    assert GraspPlanner(constraints=[denser]).plan(contacts, 3).q1 > 0
    assert denser.denser(contacts, 3) is None  # at the cap
    assert HandReachability("sdh", samples=1_000, cache_dir=tmp_path).denser(contacts, 3) is None  # fixed: kept


def test_no_denser_model_is_tried_where_no_grasp_comes_near(tmp_path, small):
    small.setattr(sampled_model, "AUTO_RECALL", 0.0)
    first = HandReachability("sdh", cache_dir=tmp_path)
    contacts = sample_contacts(resolve_object("box", 2.0)[0], n=12, seed=0)  # far wider than the SDH opens
    assert first.near_miss(contacts, 3) > 3 * reachability.NEAR_MISS
    assert first.denser(contacts, 3) is None
