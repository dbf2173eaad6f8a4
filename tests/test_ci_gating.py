"""docs/ci_gating.md works as written: its suite, its baseline command and its workflow's ogcp steps, run in order."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from ogcp.benchmarks.cli import main

PAGE = Path(__file__).resolve().parent.parent / "docs" / "ci_gating.md"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", PAGE.read_text(encoding="utf-8"), flags=re.DOTALL)


def _ogcp_steps() -> list[list[str]]:
    """The workflow's ``run: ogcp ...`` steps, as argument lists (comments dropped)."""
    (workflow,) = _blocks("yaml")
    steps = re.findall(r"run: (ogcp .*)", workflow)
    return [shlex.split(step.split("#")[0])[1:] for step in steps]


def test_the_pages_commands_gate_a_run_against_its_baseline(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (suite,) = _blocks("toml")
    (setup,) = _blocks("bash")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ci").mkdir()
    (tmp_path / "ci" / "grasps.toml").write_text(suite, encoding="utf-8")
    steps = [shlex.split(setup.strip())[1:], *_ogcp_steps()]
    assert [s[0] for s in steps] == ["suite", "suite", "compare", "plot"]
    for argv in steps:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            status = main(argv)
        assert status == 0, f"ogcp {' '.join(argv)} exited {status}"
    assert (tmp_path / "run" / "results.jsonl").is_file() and any((tmp_path / "run" / "figures").glob("*.pdf"))
