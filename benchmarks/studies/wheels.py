"""Which of ogcp's dependencies install from wheels on CPython 3.11-3.13, manylinux x86_64.

Run: ``python -m ogcp.benchmarks.studies.wheels [--python 3.11 3.12 3.13] [--glibc 2.28] [--extras test]``.
Asks the package index through pip, for every dependency that ``pyproject.toml`` names (runtime and
the chosen extras) and every Python version, for the newest release within the declared range that
has a wheel for that CPython on x86_64 Linux with the given glibc (any manylinux tag up to it, or a
pure-Python wheel). Each question is ``pip install --dry-run --only-binary=:all:`` for a foreign
target, which reads the index's metadata and downloads no wheel. The last row resolves all of them
together with their own dependencies, which is what ``pip install ogcp[test]`` on that Python needs.

Prints a Markdown table: per cell the version pip would pick and the platform tag of its wheel, or
``no wheel``. Exits 1 when a cell has no wheel. Needs the network; nothing else of ogcp runs here.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import tomllib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[2]
PYTHONS = ("3.11", "3.12", "3.13")
#: The oldest glibc of the mainstream distributions still supported (RHEL 8, Debian 10: 2.28).
GLIBC = "2.28"
NO_WHEEL = "no wheel"


def requirements(extras: list[str]) -> list[str]:
    """The requirement strings of pyproject.toml: runtime, then the given extras (ogcp's own left out)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lines = list(project["dependencies"])
    for extra in extras:
        lines += project["optional-dependencies"][extra]
    unique = dict.fromkeys(line for line in lines if Requirement(line).name != "ogcp")
    return list(unique)


def platforms(glibc: str) -> list[str]:
    """pip ``--platform`` values for x86_64 Linux with this glibc: every manylinux tag it runs.

    pip (23.x) does not expand a ``manylinux_2_X`` platform to the older ones, so each is listed.
    """
    major, minor = (int(part) for part in glibc.split("."))
    tags = [f"manylinux_{major}_{m}_x86_64" for m in range(minor, 4, -1)]
    return tags + ["manylinux2014_x86_64", "manylinux2010_x86_64", "manylinux1_x86_64"]


def ask_pip(specs: list[str], python: str, glibc: str, with_deps: bool) -> tuple[bool, str]:
    """Whether pip finds wheels for ``specs`` on ``python``; the chosen versions, or pip's reason.

    Returns:
        ``(found, text)``: for one spec without dependencies ``"1.2.3 (manylinux_2_28)"``; for a
        resolution of several, the number of packages; when nothing fits, ``"no wheel"`` with the
        package pip names.
    """
    with tempfile.TemporaryDirectory(prefix="ogcp-wheels-") as tmp:
        report = Path(tmp) / "report.json"
        command = [sys.executable, "-m", "pip", "install", "--dry-run", "--quiet", "--ignore-installed"]
        command += ["--disable-pip-version-check", "--no-input", "--only-binary=:all:", "--implementation", "cp"]
        command += ["--python-version", python, "--target", str(Path(tmp) / "never-written"), "--report", str(report)]
        command += [arg for tag in platforms(glibc) for arg in ("--platform", tag)]
        command += ([] if with_deps else ["--no-deps"]) + specs
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            errors = [line for line in done.stderr.splitlines() if line.startswith("ERROR:")]
            # "ERROR: Could not find a version that satisfies the requirement labmaze (from ...)", after
            # lines such as "ERROR: Ignored the following versions that require a different python".
            unmet = [line for line in errors if "satisfies the requirement" in line]
            if unmet:
                return False, f"{NO_WHEEL}: {unmet[0].split('requirement ', 1)[-1].split(' ')[0]}"
            reason = errors[-1] if errors else (done.stderr.strip().splitlines() or ["pip failed"])[-1]
            return False, f"error: {reason.removeprefix('ERROR: ')}"
        installs = json.loads(report.read_text())["install"]
    if with_deps:
        return True, f"all {len(installs)} packages"
    item = installs[0]
    return True, f"{item['metadata']['version']} ({_platform_tag(item['download_info']['url'])})"


def _platform_tag(url: str) -> str:
    """The short platform tag of a wheel's file name: ``manylinux_2_28``, ``any``."""
    tag = url.rsplit("/", 1)[-1].removesuffix(".whl").split("-")[-1]
    # A wheel may carry several tags joined by dots; the first names the oldest glibc it needs.
    return tag.split(".")[0].removesuffix("_x86_64")


def main(argv: list[str] | None = None) -> int:
    """Print the table; 1 if some dependency has no wheel for some Python, else 0."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--python", nargs="+", default=list(PYTHONS), help="CPython versions (default: %(default)s)")
    parser.add_argument("--glibc", default=GLIBC, help="glibc of the target systems (default: %(default)s)")
    parser.add_argument("--extras", nargs="*", default=["test"], help="extras besides the runtime (default: test)")
    parser.add_argument("--jobs", type=int, default=4, help="pip processes at once (default: %(default)s)")
    args = parser.parse_args(argv)
    specs = requirements(args.extras)
    rows = [([spec], False) for spec in specs] + [(specs, True)]
    questions = [(row, python) for row in rows for python in args.python]
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        answers = list(pool.map(lambda q: ask_pip(q[0][0], q[1], args.glibc, q[0][1]), questions))
    cells = iter(answers)
    print(f"Wheels on PyPI for CPython on x86_64 Linux, glibc {args.glibc} (pip --only-binary=:all:)\n")
    print("| dependency | " + " | ".join(f"cp{p.replace('.', '')}" for p in args.python) + " |")
    print("|---|" + "---|" * len(args.python))
    missing = False
    for row_specs, with_deps in rows:
        row = [next(cells) for _ in args.python]
        missing |= not all(found for found, _ in row)
        name = "all of the above, with their dependencies" if with_deps else f"`{row_specs[0]}`"
        print(f"| {name} | " + " | ".join(text for _, text in row) + " |")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
