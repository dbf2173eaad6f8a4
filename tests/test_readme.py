"""The README's two set-up commands stay true: CI runs the same test command."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def readme_commands() -> list[str]:
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.DOTALL)
    return [line for block in blocks for line in block.splitlines() if line.startswith("python3 -m venv")]


def test_readme_has_exactly_a_main_command_and_a_test_command():
    commands = readme_commands()
    assert len(commands) == 2
    main = next(c for c in commands if not c.endswith("-m pytest"))
    assert "bin/ogcp suite quick " in main and "--resume" in main and "bin/ogcp plot results/quick" in main
    assert any(c.endswith("-m pytest") for c in commands)


def test_ci_runs_the_readme_test_command():
    test_command = next(c for c in readme_commands() if c.endswith("-m pytest"))
    ci = (ROOT / ".ci" / "run").read_text()
    assert test_command in ci.splitlines()
