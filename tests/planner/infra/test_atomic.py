"""Atomic writes: the whole new file or the old one, never a temporary file left behind."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from ogcp.planner.infra import (
    OgcpError,
    write_atomic,
    write_bytes_atomic,
    write_json_atomic,
    write_text_atomic,
)


def test_every_writer_replaces_the_target_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    target = tmp_path / "deep" / "folder" / "f.json"
    write_json_atomic(target, {"a": [1, 2]})
    assert target.read_text() == '{\n "a": [\n  1,\n  2\n ]\n}\n'
    write_json_atomic(target, {"a": 1}, indent=None)
    assert target.read_text() == '{"a": 1}\n'
    write_text_atomic(target, "é\n")
    assert target.read_bytes() == "é\n".encode()
    write_bytes_atomic(target, b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"
    arrays = tmp_path / "a.npz"
    write_atomic(arrays, lambda handle: np.savez(handle, q=np.arange(6.0).reshape(2, 3), n=np.array([1, 2])))
    with np.load(arrays) as data:
        assert data["q"].shape == (2, 3) and data["n"].tolist() == [1, 2]
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a.npz", "deep", "f.json", "folder"]


def test_the_file_gets_the_permissions_of_a_plain_write(tmp_path: Path) -> None:
    write_bytes_atomic(tmp_path / "atomic", b"x")
    (tmp_path / "plain").write_bytes(b"x")
    mode = [stat.S_IMODE(os.stat(tmp_path / name).st_mode) for name in ("atomic", "plain")]
    assert mode[0] == mode[1]


def test_a_failing_writer_leaves_the_old_file_and_no_temporary_file(tmp_path: Path) -> None:
    target = tmp_path / "f.json"
    write_json_atomic(target, {"old": True})

    def half_then_fail(handle) -> None:
        handle.write(b'{"new": ')
        raise RuntimeError("disk on fire")

    with pytest.raises(RuntimeError, match="disk on fire"):
        write_atomic(target, half_then_fail)
    assert json.loads(target.read_text()) == {"old": True}
    assert [p.name for p in tmp_path.iterdir()] == ["f.json"]

    def os_error(handle) -> None:
        handle.write(b"partial")
        raise OSError(28, "No space left on device")

    with pytest.raises(OgcpError, match=f"cannot write {target}: No space left on device"):
        write_atomic(target, os_error)
    assert json.loads(target.read_text()) == {"old": True}
    assert [p.name for p in tmp_path.iterdir()] == ["f.json"]


def test_an_unserialisable_value_never_truncates_the_target(tmp_path: Path) -> None:
    target = tmp_path / "f.json"
    write_json_atomic(target, [1])
    with pytest.raises(TypeError):
        write_json_atomic(target, {"x": object()})
    assert target.read_text() == "[\n 1\n]\n" and len(list(tmp_path.iterdir())) == 1


def test_an_unwritable_folder_is_one_clear_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("a file where a folder should be")
    with pytest.raises(OgcpError, match="cannot write .*file/f.json"):
        write_bytes_atomic(blocker / "f.json", b"x")
