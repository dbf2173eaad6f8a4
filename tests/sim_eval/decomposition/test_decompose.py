"""Convex decomposition (cache, child process, CoACD) and the body's mass and distance geometry."""

from __future__ import annotations

import importlib
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from ogcp.planner.grasp import NonWatertightWarning, mass_properties
from ogcp.planner.infra import OgcpError
from ogcp.planner.infra.cache import ENTRY_MANIFEST, CacheEntryWarning
from ogcp.sim_eval.decomposition import Decomposition, DecompositionSettings, cache_key, decompose
from ogcp.sim_eval.scene.body import hull_part, is_closed_manifold, object_inertia
from ogcp.sim_eval.scene.collision import CollisionSurface

# Monkeypatching needs the module objects themselves (``decompose`` is also a function name).
dec = importlib.import_module("ogcp.sim_eval.decomposition.decompose")
coacd_runner = importlib.import_module("ogcp.sim_eval.decomposition.coacd_child")

#: CoACD settings small enough for a sub-second run on the test meshes.
TINY = {"preprocess_resolution": 20, "resolution": 500, "mcts_nodes": 10, "mcts_iterations": 30, "mcts_max_depth": 2}
HULL = DecompositionSettings(method="convex_hull")


def _ring() -> trimesh.Trimesh:
    """A concave, closed test object: a square-sectioned ring with 8 sides."""
    return trimesh.creation.annulus(r_min=0.03, r_max=0.06, height=0.03, sections=8)


def _open_box() -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    return trimesh.Trimesh(box.vertices, box.faces[:-1], process=False)


def _distance(parts, points) -> np.ndarray:
    return CollisionSurface.from_parts(parts).signed_distance(points, nearest=False)[0]


def _volume(parts: tuple) -> float:
    return sum(ConvexHull(np.array(v)).volume for v, _ in parts)


@pytest.fixture(scope="module")
def ring_decomposition(tmp_path_factory: pytest.TempPathFactory) -> tuple[Decomposition, Path]:
    cache = tmp_path_factory.mktemp("coacd_cache")
    return decompose(_ring(), DecompositionSettings(**TINY), cache=cache, name="ring"), cache


# --- settings and keys ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "bad, match",
    [
        ({"method": "vhacd"}, "valid choices: coacd, convex_hull"),
        ({"preprocess_mode": "maybe"}, "valid choices: auto, if_open, off, on"),
        ({"threshold": 0.001}, "threshold"),
        ({"threshold": float("nan")}, "threshold"),
        ({"preprocess_resolution": 2000}, "preprocess_resolution"),
        ({"mcts_iterations": 0}, "mcts_iterations"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"max_convex_hull": 0}, "max_convex_hull"),
        ({"merge": "yes"}, "merge"),
        ({"timeout_s": 0}, "timeout"),
    ],
)
def test_invalid_settings_are_refused(bad: dict, match: str) -> None:
    with pytest.raises(OgcpError, match=match):
        DecompositionSettings(**bad)


def test_settings_round_trip_through_json() -> None:
    settings = DecompositionSettings(seed=np.int64(7), threshold=np.float64(0.1), resolution=np.int32(800))
    data = json.loads(json.dumps(settings.to_dict()))
    assert DecompositionSettings.from_dict(data) == settings
    assert data["seed"] == 7 and data["resolution"] == 800
    with pytest.raises(OgcpError, match="unknown decomposition setting 'treshold'"):
        DecompositionSettings.from_dict({"treshold": 0.1})


def test_cache_key_follows_content_settings_and_not_timeout() -> None:
    mesh = _ring()
    base = cache_key(mesh, DecompositionSettings())
    assert cache_key(mesh.copy(), DecompositionSettings()) == base
    assert cache_key(mesh, DecompositionSettings(timeout_s=5)) == base
    assert cache_key(mesh, DecompositionSettings(threshold=0.1)) != base
    assert cache_key(mesh, DecompositionSettings(seed=1)) != base
    nudged = trimesh.Trimesh(mesh.vertices + [1e-9, 0.0, 0.0], mesh.faces, process=False)
    assert cache_key(nudged, DecompositionSettings()) != base
    rolled = trimesh.Trimesh(mesh.vertices, np.roll(mesh.faces, 1, axis=1), process=False)  # same surface
    assert cache_key(rolled, DecompositionSettings()) != base  # the key is of the arrays, not the shape
    # The hull does not depend on CoACD's parameters, so they do not split its entries.
    assert cache_key(mesh, DecompositionSettings(method="convex_hull", threshold=0.2)) == cache_key(mesh, HULL)


# --- convex hull method and the cache ----------------------------------------------------------


def test_convex_hull_of_a_box_is_one_part_with_the_box_volume(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path))
    result = decompose(trimesh.creation.box(extents=(0.3, 0.2, 0.1)), HULL)
    assert len(result.parts) == 1
    assert _volume(result.parts) == pytest.approx(0.3 * 0.2 * 0.1, rel=1e-12)
    assert result.meta["hull_count"] == 1 and result.meta["volume_ratio"] == pytest.approx(1.0, rel=1e-12)
    assert result.cache_path == tmp_path / "decompositions" / result.meta["key"]
    assert {p.name for p in result.cache_path.iterdir()} >= {"parts.npz", "meta.json"}
    assert not result.parts[0][0].flags.writeable
    assert (result.hull_count, result.volume_ratio) == (1, result.meta["volume_ratio"])
    assert result.compute_seconds == result.meta["compute_seconds"]


def test_metadata_not_recorded_reads_as_none() -> None:
    bare = Decomposition((), {"hull_count": "2", "volume_ratio": None})
    assert (bare.hull_count, bare.volume_ratio, bare.compute_seconds) == (None, None, 0.0)


@pytest.mark.parametrize("damage", ["garbage_npz", "truncated_npz", "missing_meta", "wrong_count"])
def test_a_damaged_entry_is_recomputed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, damage: str) -> None:
    mesh = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    first = decompose(mesh, HULL, cache=tmp_path)
    entry = first.cache_path
    if damage == "garbage_npz":
        (entry / "parts.npz").write_bytes(b"not a zip file")
    elif damage == "truncated_npz":
        data = (entry / "parts.npz").read_bytes()
        (entry / "parts.npz").write_bytes(data[: len(data) // 2])
    elif damage == "missing_meta":
        (entry / "meta.json").unlink()
    else:
        meta = json.loads((entry / "meta.json").read_text())
        (entry / "meta.json").write_text(json.dumps({**meta, "hull_count": 3}))
    calls = []
    original = dec.hull_part
    monkeypatch.setattr(dec, "hull_part", lambda v: calls.append(1) or original(v))
    with pytest.warns(CacheEntryWarning, match=f"cache entry {entry} is damaged"):
        again = decompose(mesh, HULL, cache=tmp_path)
    assert calls == [1]
    assert again.cache_path == entry
    assert np.array_equal(again.parts[0][0], first.parts[0][0])
    assert decompose(mesh, HULL, cache=tmp_path).meta == again.meta and calls == [1]  # repaired: a hit now
    assert [p.name for p in tmp_path.iterdir()] == [entry.name]  # no temporary or trash folders left


def test_an_entry_without_a_manifest_is_read_by_its_own_checks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    mesh = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    first = decompose(mesh, HULL, cache=tmp_path)
    (first.cache_path / ENTRY_MANIFEST).unlink()  # as written before entries had manifests
    monkeypatch.setattr(dec, "hull_part", lambda v: pytest.fail("a valid entry was recomputed"))
    assert decompose(mesh, HULL, cache=tmp_path).meta == first.meta


def test_the_first_writer_wins_and_the_other_uses_its_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    mesh = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    original = dec.hull_part
    winner: list[Decomposition] = []

    def slow_and_different(points: np.ndarray) -> tuple:
        # Another process finishes the same entry while this one computes: run it nested.
        monkeypatch.setattr(dec, "hull_part", original)
        winner.append(decompose(mesh, HULL, cache=tmp_path))
        return original(np.asarray(points) * 2.0)  # distinguishable from the winner's parts

    monkeypatch.setattr(dec, "hull_part", slow_and_different)
    loser = decompose(mesh, HULL, cache=tmp_path)
    assert loser.cache_path == winner[0].cache_path
    assert np.array_equal(loser.parts[0][0], winner[0].parts[0][0])
    assert _volume(loser.parts) == pytest.approx(0.006, rel=1e-12)
    assert [p.name for p in tmp_path.iterdir()] == [loser.cache_path.name]


def test_an_unwritable_cache_still_returns_the_parts(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder should be")
    with pytest.warns(dec.CacheWriteWarning):
        result = decompose(trimesh.creation.box(), HULL, cache=blocker)
    assert result.cache_path is None and len(result.parts) == 1


# --- CoACD in the child process -----------------------------------------------------------------


def test_coacd_splits_a_concave_ring_into_parts_of_its_volume(ring_decomposition: tuple) -> None:
    result, _ = ring_decomposition
    mesh = _ring()
    assert len(result.parts) > 1
    ratio = _volume(result.parts) / mesh.volume
    assert 0.9 <= ratio <= 1.3
    assert result.meta["volume_ratio"] == pytest.approx(ratio, rel=1e-9)
    assert result.meta["hull_count"] == len(result.parts)
    assert result.meta["remeshed"] is False  # closed manifold input: CoACD's "auto" keeps it
    assert result.meta["coacd_version"] == dec.coacd_version() and result.meta["compute_seconds"] > 0
    for vertices, faces in result.parts:  # every part is convex: all its vertices on or inside its hull
        planes = ConvexHull(np.array(vertices)).equations
        assert (np.array(vertices) @ planes[:, :3].T + planes[:, 3]).max() < 1e-9
        assert is_closed_manifold(faces)
    # The union covers the ring: its vertices are on or inside the parts.
    assert _distance(result.parts, mesh.vertices).max() < 1e-3 * 0.06


def test_a_cache_hit_does_not_run_coacd_again(ring_decomposition: tuple, monkeypatch: pytest.MonkeyPatch) -> None:
    first, cache = ring_decomposition

    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("CoACD ran on a cache hit")

    monkeypatch.setattr(dec, "_run_coacd", fail)
    again = decompose(_ring(), DecompositionSettings(**TINY, timeout_s=1.0), cache=cache)
    assert len(again.parts) == len(first.parts)
    for (v1, f1), (v2, f2) in zip(first.parts, again.parts, strict=True):
        assert np.array_equal(v1, v2) and np.array_equal(f1, f2)
    assert again.meta == first.meta
    with pytest.raises(AssertionError, match="cache hit"):
        decompose(_ring(), DecompositionSettings(**{**TINY, "seed": 1}), cache=cache)


def test_a_run_past_the_timeout_is_killed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pid_file = tmp_path / "pid"
    sleeper = f"import os, time; open({str(pid_file)!r}, 'w').write(str(os.getpid())); time.sleep(60)"
    monkeypatch.setattr(coacd_runner, "_child_command", lambda workdir: [sys.executable, "-c", sleeper])
    start = time.monotonic()
    with pytest.raises(OgcpError, match=r"CoACD did not finish within 1.5 s on tiny box; raise --timeout"):
        decompose(
            trimesh.creation.box(),
            DecompositionSettings(timeout_s=1.5),
            cache=tmp_path / "c",
            progress=True,
            name="tiny box",
        )
    assert time.monotonic() - start < 20
    pid = int(pid_file.read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    assert "CoACD tiny box" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_an_exception_in_the_child_surfaces_with_its_message(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(dec, "_coacd_kwargs", lambda settings: {"no_such_option": 1})
    with pytest.raises(OgcpError, match=r"CoACD failed on box: TypeError: .*no_such_option"):
        decompose(trimesh.creation.box(), DecompositionSettings(), cache=tmp_path, name="box")


def test_a_crashing_child_is_reported(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    crash = "import os; print('native trouble', flush=True); os.abort()"
    monkeypatch.setattr(coacd_runner, "_child_command", lambda workdir: [sys.executable, "-c", crash])
    with pytest.raises(OgcpError, match=r"CoACD crashed on box \(signal 6\): native trouble"):
        decompose(trimesh.creation.box(), DecompositionSettings(), cache=tmp_path, name="box")


def test_an_open_mesh_without_preprocessing_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(dec, "_run_coacd", lambda *a, **k: pytest.fail("CoACD must not run"))
    with pytest.raises(OgcpError, match="preprocess 'on' or 'auto'"):
        decompose(_open_box(), DecompositionSettings(preprocess_mode="off"), cache=tmp_path)


def test_closed_manifold_check() -> None:
    box = trimesh.creation.box()
    assert is_closed_manifold(box.faces)
    assert not is_closed_manifold(box.faces[:-1])
    flipped = box.faces.copy()
    flipped[0] = flipped[0, ::-1]
    assert not is_closed_manifold(flipped)


# --- mass properties ----------------------------------------------------------------------------


def test_inertia_of_a_box_matches_the_closed_form() -> None:
    a, b, c, mass = 0.3, 0.2, 0.1, 0.25
    rotation = Rotation.from_euler("xyz", [0.3, -0.7, 1.1]).as_matrix()
    offset = np.array([0.05, -0.02, 0.4])
    box = trimesh.creation.box(extents=(a, b, c))
    box.apply_transform(np.block([[rotation, offset[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]))
    com, inertia = object_inertia(box, mass)
    principal = mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(com, offset, atol=1e-12)
    np.testing.assert_allclose(inertia, rotation @ principal @ rotation.T, atol=1e-12 * mass)


def test_inertia_of_an_open_mesh_uses_the_planner_com_and_the_hull() -> None:
    mesh = _open_box()
    with pytest.warns(NonWatertightWarning, match="convex hull"):
        com, inertia = object_inertia(mesh, 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NonWatertightWarning)
        planner_com, _ = mass_properties(mesh)
    np.testing.assert_allclose(com, planner_com, atol=1e-15)
    np.testing.assert_allclose(inertia, 0.1 / 12.0 * np.diag([0.05, 0.1, 0.13]), atol=1e-12)


def test_inertia_refuses_bad_input() -> None:
    with pytest.raises(OgcpError, match="mass"):
        object_inertia(trimesh.creation.box(), 0.0)
    inverted = trimesh.creation.box()
    inverted.invert()
    with pytest.raises(OgcpError, match="not positive"):
        object_inertia(inverted, 0.1)


# --- distance to the union of parts -------------------------------------------------------------


def _box_part(extents: tuple[float, float, float], centre: tuple[float, float, float] = (0, 0, 0)) -> tuple:
    part = hull_part(trimesh.creation.box(extents=extents).vertices + np.asarray(centre))
    assert part is not None
    return part


def test_distance_to_a_box_matches_closed_forms() -> None:
    half = np.array([0.15, 0.1, 0.05])
    parts = [_box_part(tuple(2 * half))]
    rng = np.random.default_rng(0)
    on_face = rng.uniform(-half, half, size=(50, 3))
    axis = rng.integers(0, 3, size=50)
    on_face[np.arange(50), axis] = half[axis] * rng.choice([-1.0, 1.0], size=50)
    assert np.abs(_distance(parts, on_face)).max() < 1e-12
    queries = np.array(
        [
            [half[0] + 0.02, 0.01, -0.02],  # straight out of the +x face
            [half[0] + 0.03, half[1] + 0.04, 0.0],  # beyond an edge
            [-half[0] - 0.01, -half[1] - 0.02, half[2] + 0.02],  # beyond a corner
            [0.0, 0.0, 0.0],  # centre: depth = smallest half extent
            [0.14, 0.0, 0.0],  # inside near +x face
        ]
    )
    expected = [0.02, 0.05, 0.03, -0.05, -0.01]
    np.testing.assert_allclose(_distance(parts, queries), expected, atol=1e-12)


def test_distance_to_a_union_of_overlapping_parts() -> None:
    parts = [_box_part((0.2, 0.1, 0.1)), _box_part((0.1, 0.1, 0.3), centre=(0.1, 0.0, 0.0))]
    queries = np.array(
        [
            [-0.2, 0.0, 0.0],  # left of part 0 only: 0.1
            [0.1, 0.0, 0.25],  # above part 1 only: 0.1
            [0.0, 0.0, 0.2],  # above part 0 (0.15 away), part 1's corner edge 0.05 in x and 0.05 in z
            [0.075, 0.0, 0.0],  # in both: 0.025 deep in part 0 (x), 0.025 deep in part 1 (x): bound 0.025
            [0.1, 0.0, 0.12],  # only in part 1: 0.03 below its top face
        ]
    )
    expected = [0.1, 0.1, np.hypot(0.05, 0.05), -0.025, -0.03]
    np.testing.assert_allclose(_distance(parts, queries), expected, atol=1e-12)


def test_distance_refuses_bad_input() -> None:
    with pytest.raises(OgcpError, match="shape"):
        _distance([_box_part((1, 1, 1))], np.zeros(3))
    with pytest.raises(OgcpError, match="empty"):
        _distance([], np.zeros((1, 3)))


def test_if_open_remeshes_only_meshes_that_are_not_closed(tmp_path: Path) -> None:
    closed = decompose(_ring(), DecompositionSettings(**TINY), cache=tmp_path, name="ring")
    assert closed.meta["preprocess_mode_given"] == "if_open" and closed.meta["preprocess_mode"] == "off"
    assert closed.meta["remeshed"] is False
    # Not remeshed, the parts are hulls of pieces of the mesh: no vertex of theirs stands outside it.
    assert max(float(np.abs(v).max()) for v, _ in closed.parts) <= 0.06 + 1e-9
    opened = decompose(_open_box(), DecompositionSettings(**TINY), cache=tmp_path, name="open box")
    assert opened.meta["preprocess_mode"] == "on" and opened.meta["remeshed"] is True


def test_coacd_takes_a_mesh_of_several_shells_shell_by_shell_and_skips_the_enclosed_ones(tmp_path: Path) -> None:
    """A part modelled inside the object once crashed CoACD (signal 11); an enclosed shell adds
    nothing a finger touches, and overlapping shells each keep their parts."""
    inner = trimesh.creation.box([0.03] * 3)
    inner.apply_translation([0.005, 0.0, 0.0])
    nested = trimesh.util.concatenate([trimesh.creation.box([0.05] * 3), inner])
    ran: list[int] = []
    real = dec._run_coacd

    def counting(vertices, faces, *args, **kwargs):
        ran.append(len(faces))
        return real(vertices, faces, *args, **kwargs)

    settings = DecompositionSettings(method="coacd", **TINY)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(dec, "_run_coacd", counting)
        parts = decompose(nested, settings, cache=tmp_path / "a").parts
        assert ran == [12]  # the outer box only
        ran.clear()
        second = trimesh.creation.box([0.05] * 3)
        second.apply_translation([0.03, 0.0, 0.0])
        overlapping = trimesh.util.concatenate([trimesh.creation.box([0.05] * 3), second])
        both = decompose(overlapping, settings, cache=tmp_path / "b").parts
        assert ran == [12, 12]
    corners = np.vstack([v for v, _ in parts])
    assert np.allclose(corners.min(axis=0), -0.025, atol=2e-3) and np.allclose(corners.max(axis=0), 0.025, atol=2e-3)
    assert np.vstack([v for v, _ in both])[:, 0].max() == pytest.approx(0.055, abs=2e-3)
