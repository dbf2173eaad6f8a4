"""Provenance: the git commit recorded with results belongs to ogcp's own checkout only."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from ogcp.planner.infra.provenance import checkout_commit

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    root = tmp_path / "project"
    (root / "lib" / "site-packages").mkdir(parents=True)
    _git(root, "init", "-q")
    (root / "tracked.txt").write_text("one\n")
    _git(root, "add", "tracked.txt")
    _git(root, "commit", "-q", "-m", "first")
    return root


def test_checkout_commit_reports_head_and_dirty_state(repo):
    head = _git(repo, "rev-parse", "HEAD")
    assert checkout_commit(repo) == head
    (repo / "tracked.txt").write_text("two\n")
    assert checkout_commit(repo) == head + "-dirty"


def test_folder_inside_another_repository_is_not_a_checkout(repo):
    # An installed copy of ogcp in a venv inside a user's project must not claim the project's commit.
    assert checkout_commit(repo / "lib" / "site-packages") is None


def test_folder_outside_any_repository_has_no_commit(tmp_path, monkeypatch):
    monkeypatch.setenv("GIT_CEILING_DIRECTORIES", str(tmp_path))  # even if the temp folder sits in a repo
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    assert checkout_commit(lonely) is None
