"""The README's two set-up commands stay true: CI runs the same test command."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def readme_commands() -> list[str]:
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.DOTALL)
    return [line for block in blocks for line in block.splitlines() if line.startswith("python3 -m venv")]


def test_readme_has_a_set_up_a_main_command_and_a_test_command():
    commands = readme_commands()
    assert len(commands) == 3
    setup = "python3 -m venv .venv && .venv/bin/pip install -e '.[test]'"
    assert setup in commands  # set-up alone, its own command
    main = next(c for c in commands if "bin/ogcp suite" in c)
    assert main.startswith(setup) and "bin/ogcp suite quick " in main and "--resume" in main
    assert "bin/ogcp plot results/quick" in main
    test = next(c for c in commands if c.endswith("-m pytest"))
    assert test.startswith(setup)  # each complete on its own on a fresh machine


def test_readme_fits_a_screen_and_links_only_to_files_that_exist():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 250
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    assert links and all((ROOT / link).exists() for link in links if "://" not in link), links


def test_ci_runs_the_readme_test_command():
    test_command = next(c for c in readme_commands() if c.endswith("-m pytest"))
    ci = (ROOT / ".ci" / "run").read_text()
    assert test_command in ci.splitlines()


def test_the_documentation_home_page_is_the_readme():
    # docs/index.md is the README with links relative to docs/ (regenerate it with this sed):
    # sed 's#](docs/#](#g' README.md > docs/index.md
    readme = (ROOT / "README.md").read_text()
    assert (ROOT / "docs" / "index.md").read_text() == readme.replace("](docs/", "](")
