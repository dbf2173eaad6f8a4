"""Cache entries: staged and sealed with a manifest, verified on load, damaged ones rebuilt."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ogcp.planner.infra import OgcpError
from ogcp.planner.infra.cache import (
    ENTRY_MANIFEST,
    ENTRY_SCHEMA,
    CacheEntryWarning,
    DamagedEntryError,
    read_entry,
    verify_entry,
    write_entry,
)


def _build(value: float):
    def build(stage: Path) -> None:
        np.savez(stage / "arrays.npz", x=np.full(4, value))
        (stage / "meta.json").write_text(json.dumps({"value": value}))

    return build


def _load(folder: Path) -> float:
    with np.load(folder / "arrays.npz") as data:
        x = data["x"]
    if x.shape != (4,) or not np.isfinite(x).all():
        raise ValueError(f"x of shape {x.shape}")
    return float(x[0])


def _cached(folder: Path, value: float, built: list[float]) -> float:
    """The caller's pattern: read the entry, or build, store and return it."""
    found = read_entry(folder, _load)
    if found is not None:
        return found
    built.append(value)
    write_entry(folder, _build(value))
    return value


def test_an_entry_is_sealed_with_a_manifest_and_reads_back(tmp_path: Path) -> None:
    folder = write_entry(tmp_path / "cache" / "key", _build(2.0))
    assert folder == tmp_path / "cache" / "key"
    assert sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["key"]  # no staging folder left
    manifest = json.loads((folder / ENTRY_MANIFEST).read_text())
    assert manifest["schema"] == ENTRY_SCHEMA and sorted(manifest["files"]) == ["arrays.npz", "meta.json"]
    assert manifest["files"]["meta.json"]["bytes"] == (folder / "meta.json").stat().st_size
    assert verify_entry(folder) and read_entry(folder, _load) == 2.0


@pytest.mark.parametrize("damage", ["truncate", "flip_byte", "delete", "garble_manifest", "same_size_bad_content"])
def test_a_damaged_entry_is_reported_discarded_and_rebuilt(tmp_path: Path, damage: str) -> None:
    folder, built = tmp_path / "key", []
    assert _cached(folder, 3.0, built) == 3.0 and built == [3.0]
    npz = folder / "arrays.npz"
    data = npz.read_bytes()
    if damage == "truncate":
        npz.write_bytes(data[: len(data) // 2])
    elif damage == "flip_byte":
        npz.write_bytes(data[:-1] + bytes([data[-1] ^ 1]))
    elif damage == "delete":
        npz.unlink()
    elif damage == "garble_manifest":
        (folder / ENTRY_MANIFEST).write_text("{not json")
    else:
        (folder / "meta.json").write_text(json.dumps({"value": 9.0}))  # same length, other bytes
    with pytest.raises(DamagedEntryError):
        verify_entry(folder)
    with pytest.warns(CacheEntryWarning, match=f"cache entry {folder} is damaged"):
        assert _cached(folder, 3.0, built) == 3.0
    assert built == [3.0, 3.0] and verify_entry(folder)
    assert _cached(folder, 3.0, built) == 3.0 and built == [3.0, 3.0]  # a hit again
    assert [p.name for p in tmp_path.iterdir()] == ["key"]  # no trash or staging folders left


def test_content_failing_the_loaders_checks_is_damage_too(tmp_path: Path) -> None:
    folder = write_entry(tmp_path / "key", _build(float("nan")))
    assert verify_entry(folder)  # the files are as written; their values are not usable
    with pytest.warns(CacheEntryWarning, match=r"ValueError: x of shape \(4,\)"):
        assert read_entry(folder, _load) is None
    assert not folder.exists()


def test_an_entry_without_a_manifest_is_left_to_the_loader(tmp_path: Path) -> None:
    folder = tmp_path / "legacy"
    folder.mkdir()
    _build(5.0)(folder)  # as written before entries had manifests
    assert verify_entry(folder) is False and read_entry(folder, _load) == 5.0
    assert read_entry(tmp_path / "absent", _load) is None


def test_a_concurrent_writers_entry_wins_unless_replacing(tmp_path: Path) -> None:
    folder = write_entry(tmp_path / "key", _build(1.0))
    write_entry(folder, _build(2.0))
    assert read_entry(folder, _load) == 1.0  # same key, first writer kept
    write_entry(folder, _build(2.0), replace=True)
    assert read_entry(folder, _load) == 2.0
    (folder / "arrays.npz").write_bytes(b"damaged")
    write_entry(folder, _build(4.0))  # a damaged entry in the way is replaced
    assert read_entry(folder, _load) == 4.0 and [p.name for p in tmp_path.iterdir()] == ["key"]


def test_a_failing_build_leaves_no_entry_and_no_staging_folder(tmp_path: Path) -> None:
    def broken(stage: Path) -> None:
        (stage / "half.npz").write_bytes(b"x")
        raise OgcpError("repair failed")

    with pytest.raises(OgcpError, match="repair failed"):
        write_entry(tmp_path / "key", broken)
    assert list(tmp_path.iterdir()) == []
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder should be")
    with pytest.raises(OgcpError, match="cannot write the cache folder"):
        write_entry(blocker / "key", _build(1.0))


def test_a_build_may_not_write_subfolders_or_the_manifest(tmp_path: Path) -> None:
    with pytest.raises(OgcpError, match="plain files"):
        write_entry(tmp_path / "key", lambda stage: (stage / "sub").mkdir())
    with pytest.raises(OgcpError, match="plain files"):
        write_entry(tmp_path / "key", lambda stage: (stage / ENTRY_MANIFEST).write_text("{}"))
    assert list(tmp_path.iterdir()) == []
