"""A full disk while a suite writes ``results.jsonl``: no recorded cell is lost, the run ends in one line.

The real case runs ``ogcp suite`` in a child process under a file-size limit (``RLIMIT_FSIZE``),
so the third cell's line is cut short by the kernel (EFBIG); the in-process cases make the store's
``os.write`` and ``os.fsync`` fail with ENOSPC, whole or after part of the line. Each time every
line left in ``results.jsonl`` must parse, and ``--resume`` must finish the suite.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import resource
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from ogcp.benchmarks.cli import main
from ogcp.benchmarks.suite import store
from ogcp.benchmarks.suite.parse import load_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.planner.infra.errors import OgcpError

ROOT = Path(__file__).resolve().parents[2]
SUITE = """
schema_version = 1
name = "disk"
objects = ["box"]
contacts = 16
contact_seeds = [0, 1]

[[methods]]
method = "astar"
label = "A*"

[[methods]]
method = "es"
label = "ES"

[[methods]]
method = "wastar"
eps = 0.5
label = "WA*"
"""
CELLS = 6


@pytest.fixture
def suite_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("OGCP_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "disk.toml"
    path.write_text(SUITE)
    return path


def _lines(folder: Path) -> list[dict[str, Any]]:
    """Every line of the folder's results.jsonl, parsed; fails on a torn or invalid line."""
    data = (folder / "results.jsonl").read_bytes()
    assert not data or data.endswith(b"\n"), f"torn last line: {data[-80:]!r}"
    return [json.loads(line) for line in data.splitlines()]


def _ogcp(*argv: str, limit: int | None = None) -> subprocess.CompletedProcess[str]:
    def limited() -> None:
        if limit is not None:
            # Writes past the limit then fail with EFBIG instead of killing the process (CPython
            # ignores SIGXFSZ at start-up too; this does not rely on it).
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run(
        [sys.executable, "-m", "ogcp.benchmarks.cli", *argv],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        preexec_fn=limited,
    )


def test_a_file_size_limit_keeps_every_recorded_cell_and_resume_finishes(suite_file, tmp_path):
    # A first run fills the caches, so that the limited run writes nothing but its results folder.
    warm = _ogcp("suite", str(suite_file), "--out", str(tmp_path / "warm"))
    assert warm.returncode == 0, warm.stderr
    sizes = [len(line) + 1 for line in (tmp_path / "warm" / "results.jsonl").read_bytes().splitlines()]
    manifest = (tmp_path / "warm" / "manifest.json").stat().st_size
    limit = sum(sizes[:2]) + sizes[2] // 2  # two lines fit, the third is cut in the middle
    assert manifest < limit

    out = tmp_path / "run"
    full = _ogcp("suite", str(suite_file), "--out", str(out), "-q", limit=limit)  # -q: no progress lines
    assert full.returncode == 2, (full.returncode, full.stderr)
    lines = full.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"ogcp: error: cannot append to {out / 'results.jsonl'}: "), lines
    assert "the 2 cells recorded before are kept" in lines[0] and "--resume" in lines[0]
    kept = _lines(out)
    assert len(kept) == 2  # lines differ from the warm run's in their timings only, by a few bytes

    resumed = _ogcp("suite", str(suite_file), "--out", str(out), "--resume")
    assert resumed.returncode == 0, resumed.stderr
    final = _lines(out)
    assert final[:2] == kept and len({r["id"] for r in final}) == len(final) == CELLS
    assert "2 already recorded" in resumed.stdout


class _FailingOs:
    """``os`` for the store, whose ``write`` or ``fsync`` fails with ENOSPC from the ``after``-th line on."""

    def __init__(self, after: int, how: str) -> None:
        self.after, self.how, self.lines = after, how, 0

    def __getattr__(self, name: str) -> Any:
        return getattr(os, name)

    def write(self, fd: int, data: bytes) -> int:
        self.lines += 1
        if self.lines < self.after or self.how == "fsync":
            return os.write(fd, data)
        if self.how == "partial":
            return os.write(fd, data[: len(data) // 2])  # the disk filled in the middle of the line
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def fsync(self, fd: int) -> None:
        if self.how == "fsync" and self.lines >= self.after:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        os.fsync(fd)


@pytest.mark.parametrize("how", ["whole", "partial", "fsync"])
def test_a_full_disk_keeps_the_lines_before_and_resume_finishes(suite_file, tmp_path, monkeypatch, how):
    out = tmp_path / "run"
    failing = _FailingOs(after=4, how=how)
    monkeypatch.setattr(store, "os", failing)
    with pytest.raises(OgcpError) as info:
        SuiteRunner(load_suite(suite_file), out).run()
    message = str(info.value)
    assert "\n" not in message and ("No space left on device" in message or "bytes written" in message), message
    assert "the 3 cells recorded before are kept" in message
    kept = _lines(out)
    assert len(kept) == 3
    monkeypatch.setattr(store, "os", os)
    summary = SuiteRunner(load_suite(suite_file), out, resume=True).run()
    assert (summary.skipped, summary.ran, summary.errors) == (3, CELLS - 3, 0)
    final = _lines(out)
    assert final[:3] == kept and len({r["id"] for r in final}) == CELLS


def test_the_cli_reports_a_full_disk_in_one_line(suite_file, tmp_path, monkeypatch):
    monkeypatch.setattr(store, "os", _FailingOs(after=1, how="whole"))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["suite", str(suite_file), "--out", str(tmp_path / "run")])
    assert status == 2 and out.getvalue() == ""
    # One line of error, after the run's opening progress line (the suite had started).
    lines = err.getvalue().splitlines()
    errors = [line for line in lines if line.startswith("ogcp: error")]
    assert len(errors) == 1 and errors[0] == lines[-1] and errors[0].startswith("ogcp: error: cannot append to ")
    assert all(line.startswith("ogcp: disk: ") for line in lines[:-1])
    assert (tmp_path / "run" / "results.jsonl").read_bytes() == b""


def _fails(write: Callable[[], object]) -> str:
    with pytest.raises(OgcpError) as info:
        write()
    return str(info.value)


def test_a_results_folder_that_cannot_be_made_is_one_error(suite_file, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    message = _fails(lambda: SuiteRunner(load_suite(suite_file), blocker / "run").run())
    assert message.startswith(f"cannot create the results folder {blocker / 'run'}: Not a directory")
    message = _fails(lambda: SuiteRunner(load_suite(suite_file), blocker).run())
    assert message == f"--out {blocker} is a file, not a folder"
