"""Cached contact sets: equal to a fresh sample, keyed by every input, rebuilt when damaged."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ogcp.planner.grasp.contact_set import ContactSet, sample_contacts
from ogcp.planner.infra.cache import CacheEntryWarning
from ogcp.planner.objects.builtin import builtin_mesh
from ogcp.planner.objects.contact_cache import ContactRequest, cached_contacts, request_key

ROOT = Path(__file__).resolve().parents[3]
REQUEST = ContactRequest("box", None, 24, 3, 0.5, 8, 0.0, 0.0)


@pytest.fixture(autouse=True)
def own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


class Sampler:
    """Samples a request's set and counts the calls."""

    def __init__(self, request: ContactRequest) -> None:
        self.request, self.calls = request, 0

    def __call__(self) -> ContactSet:
        self.calls += 1
        r = self.request
        return sample_contacts(
            builtin_mesh(r.spec),
            r.n,
            r.seed,
            r.mu,
            r.cone_edges,
            {"kind": "builtin", "name": r.spec},
            tip_radius=r.tip_radius,
        )


def assert_same(a: ContactSet, b: ContactSet) -> None:
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.normals, b.normals)
    assert np.array_equal(a.wrenches, b.wrenches) and np.array_equal(a.com, b.com)
    assert (a.torque_scale, a.mu, a.cone_edges, a.source) == (b.torque_scale, b.mu, b.cone_edges, b.source)


def test_a_hit_returns_the_sampled_set_bit_for_bit_without_sampling() -> None:
    sampler = Sampler(REQUEST)
    first = cached_contacts(REQUEST, sampler)
    second = cached_contacts(REQUEST, sampler)
    assert sampler.calls == 1
    assert_same(first, second)
    assert_same(second, Sampler(REQUEST)())


@pytest.mark.parametrize(
    "change",
    [
        {"seed": 4},
        {"n": 25},
        {"mu": 0.6},
        {"cone_edges": 6},
        {"tip_radius": 0.002},
        {"diagonal": 0.3},
        {"spec": "donut"},
    ],
)
def test_every_input_is_part_of_the_key(change: dict[str, object]) -> None:
    other = replace(REQUEST, **change)  # type: ignore[arg-type]
    assert request_key(other) != request_key(REQUEST)
    cached_contacts(REQUEST, Sampler(REQUEST))
    sampler = Sampler(other)
    cached_contacts(other, sampler)
    assert sampler.calls == 1


def test_a_damaged_entry_is_reported_discarded_and_sampled_again(own_cache: Path) -> None:
    cached_contacts(REQUEST, Sampler(REQUEST))
    (stored,) = (own_cache / "contacts").glob("*/contacts.json")
    data = json.loads(stored.read_text())
    data["positions"][0][0] += 0.01
    stored.write_text(json.dumps(data))
    sampler = Sampler(REQUEST)
    with pytest.warns(CacheEntryWarning, match="damaged"):
        again = cached_contacts(REQUEST, sampler)
    assert sampler.calls == 1
    assert_same(again, Sampler(REQUEST)())
    cached_contacts(REQUEST, sampler)  # the rebuilt entry is a hit
    assert sampler.calls == 1


def test_a_cache_that_cannot_be_written_costs_only_time(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("OGCP_CACHE", str(blocker / "cache"))
    sampler = Sampler(REQUEST)
    assert_same(cached_contacts(REQUEST, sampler), cached_contacts(REQUEST, sampler))
    assert sampler.calls == 2


def test_a_mesh_file_is_keyed_by_its_bytes_and_a_missing_one_is_not_cached(tmp_path: Path) -> None:
    path = tmp_path / "box.stl"
    builtin_mesh("box").export(path)
    request = replace(REQUEST, spec=str(path))
    before = request_key(request)
    assert before is not None
    builtin_mesh("donut").export(path)
    assert request_key(request) not in (None, before)
    assert request_key(replace(REQUEST, spec=str(tmp_path / "missing.stl"))) is None
    assert request_key(replace(REQUEST, spec="bunny")) is None  # fetched objects: not cached here


def test_the_cli_plans_from_a_cached_set_without_trimesh_and_the_same_result(own_cache: Path) -> None:
    script = (
        "import io, json, sys, contextlib\n"
        "from ogcp.benchmarks.cli.app import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        "    main(['plan', 'box', '-n', '16', '--seed', '2', '--json'])\n"
        "record = json.loads(out.getvalue())\n"
        "print(json.dumps({'trimesh': 'trimesh' in sys.modules, 'grasp': record['grasp'], 'q1': record['q1'],"
        " 'contacts': record['contacts'], 'contact_set': record['contact_set']}))\n"
    )
    env = {**os.environ, "OGCP_CACHE": str(own_cache)}

    def run() -> dict[str, object]:
        done = subprocess.run(
            [sys.executable, "-c", script], check=False, cwd=ROOT, env=env, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout.strip().splitlines()[-1])

    first, second = run(), run()
    assert first.pop("trimesh") is True and second.pop("trimesh") is False
    assert first == second
