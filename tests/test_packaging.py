"""What a wheel ships and what it requires.

From pyproject.toml: every code package listed, every file of ``assets/`` matched by a
package-data pattern and found by the asset locator, ``py.typed`` shipped; every dependency
bounded below and pinned by ``constraints.txt`` within its range. And one wheel, built offline
from a copy of the checkout: it installs the single top-level package ``ogcp`` (no ``planner``,
``sim_eval``, ``benchmarks`` or data folder beside it), and that install imports, finds its data
and answers ``ogcp --help``. No network: which wheels exist on PyPI is
``python -m ogcp.benchmarks.studies.wheels``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

from ogcp.planner.infra import asset_path

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]
# Run from a checkout only: study scripts and speed benchmarks.
NOT_SHIPPED = {"ogcp.benchmarks.studies", "ogcp.benchmarks.perf", "ogcp.sim_eval.studies"}
SUBPACKAGES = ("planner", "sim_eval", "benchmarks")


def _asset_files() -> list[str]:
    folder = ROOT / "assets"
    return sorted(
        path.relative_to(folder).as_posix()
        for path in folder.rglob("*")
        if path.is_file() and "__pycache__" not in path.parts and not path.name.startswith(".")
    )


def _shipped_assets() -> set[str]:
    folder = ROOT / "assets"
    return {
        path.relative_to(folder).as_posix()
        for p in SETUPTOOLS["package-data"]["ogcp.assets"]
        for path in folder.glob(p)
    }


def test_every_code_package_is_listed_and_no_study_code_is():
    found = {"ogcp"} | {
        ".".join(("ogcp", *init.parent.relative_to(ROOT).parts))
        for top in SUBPACKAGES
        for init in (ROOT / top).rglob("__init__.py")
    }
    listed = set(SETUPTOOLS["packages"]) - {"ogcp.assets"}
    missing = sorted(found - NOT_SHIPPED - listed)
    assert not missing, f"add {missing} to [tool.setuptools] packages in pyproject.toml"
    assert not listed & NOT_SHIPPED
    assert listed <= found


def test_every_package_is_under_the_one_import_name():
    assert all(package == "ogcp" or package.startswith("ogcp.") for package in SETUPTOOLS["packages"])
    assert "ogcp.assets" in SETUPTOOLS["packages"]
    assert "package-dir" not in SETUPTOOLS  # ogcp/ links to the folders: one layout for every tool
    for name in (*SUBPACKAGES, "assets"):
        link = ROOT / "ogcp" / name
        assert link.is_symlink() and link.resolve() == (ROOT / name).resolve(), f"ogcp/{name} must link to ../{name}"


def test_package_data_covers_every_asset_and_every_pattern_matches():
    assert _shipped_assets() == set(_asset_files())
    for pattern in SETUPTOOLS["package-data"]["ogcp.assets"]:
        assert list((ROOT / "assets").glob(pattern)), f"package-data pattern {pattern!r} matches nothing"


@pytest.mark.parametrize("relative", _asset_files())
def test_the_locator_finds_every_shipped_file(relative):
    assert asset_path(relative) == ROOT / "assets" / relative


@pytest.mark.parametrize("package", ["ogcp", *(f"ogcp.{name}" for name in SUBPACKAGES)])
def test_packages_are_marked_typed(package):
    assert (ROOT / package.replace(".", "/") / "py.typed").is_file()
    assert "py.typed" in SETUPTOOLS["package-data"][package]


def _requirements(*extras: str) -> list[Requirement]:
    """The runtime requirements and those of the given extras, without ogcp's own (``ogcp[test]``)."""
    project = PYPROJECT["project"]
    lines = list(project["dependencies"]) + [r for extra in extras for r in project["optional-dependencies"][extra]]
    return [r for r in map(Requirement, lines) if canonicalize_name(r.name) != "ogcp"]


def _pins() -> dict[str, Version]:
    """constraints.txt as {canonical name: pinned version}; every line must be ``name==version``."""
    pins: dict[str, Version] = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        requirement = Requirement(line)
        specs = list(requirement.specifier)
        assert len(specs) == 1 and specs[0].operator == "==", f"constraints.txt: {line!r} is not name==version"
        name = canonicalize_name(requirement.name)
        assert name not in pins, f"constraints.txt pins {name} twice"
        pins[name] = Version(specs[0].version)
    return pins


def test_constraints_pin_every_dependency_within_its_range():
    pins = _pins()
    for requirement in _requirements(*PYPROJECT["project"]["optional-dependencies"]):
        name = canonicalize_name(requirement.name)
        assert name in pins, f"constraints.txt does not pin {name}, a dependency in pyproject.toml"
        assert requirement.specifier.contains(pins[name], prereleases=True), (
            f"constraints.txt pins {name}=={pins[name]}, outside pyproject.toml's {requirement}"
        )


def test_every_dependency_has_a_lower_bound():
    for requirement in _requirements(*PYPROJECT["project"]["optional-dependencies"]):
        operators = {spec.operator for spec in requirement.specifier}
        assert operators & {">=", ">", "==", "~="}, f"{requirement} has no lower bound"


def test_dm_control_is_not_a_dependency():
    # It pulled labmaze, which has no wheels for Python 3.13; nothing in ogcp imports it.
    names = {canonicalize_name(r.name) for r in _requirements(*PYPROJECT["project"]["optional-dependencies"])}
    assert "dm-control" not in names and "labmaze" not in names
    assert "dm-control" not in _pins()


def test_the_version_comes_from_git_and_is_what_ogcp_reports():
    """setuptools-scm sets the version at install time: results from two commits never look alike."""
    import importlib.metadata

    import ogcp
    from ogcp import planner

    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["dynamic"] == ["version"] and "version" not in pyproject["project"]
    assert "setuptools-scm>=8" in pyproject["build-system"]["requires"]
    assert ogcp.__version__ == planner.__version__ == importlib.metadata.version("ogcp")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built offline from a copy of the checkout (the checkout gets no build/ or egg-info)."""
    work = tmp_path_factory.mktemp("wheel")
    source = work / "source"
    skip = shutil.ignore_patterns(".git", ".venv*", "results", "build", "dist", "*.egg-info", "__pycache__", ".*cache")
    shutil.copytree(ROOT, source, symlinks=True, ignore=skip)
    out = work / "dist"
    env = {**os.environ, "SETUPTOOLS_SCM_PRETEND_VERSION": "0.0.0"}  # the copy has no git metadata
    build = f"from setuptools import build_meta; print(build_meta.build_wheel({str(out)!r}))"
    done = subprocess.run(
        [sys.executable, "-c", build], cwd=source, env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return out / done.stdout.split()[-1]


def test_the_wheel_installs_one_top_level_package(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    tops = {name.split("/")[0] for name in names}
    dist_info = {top for top in tops if top.endswith(".dist-info")}
    assert tops - dist_info == {"ogcp"}, f"the wheel installs {sorted(tops - dist_info)} at the top level"
    assert {"ogcp/__init__.py", "ogcp/py.typed", "ogcp/planner/__init__.py", "ogcp/sim_eval/__init__.py"} <= set(names)
    assert {f"ogcp/assets/{relative}" for relative in _asset_files()} <= set(names)
    kernels = ROOT / "planner" / "grasp" / "kernel" / "shipped"  # compiled kernels: no compiling at first use
    assert {f"ogcp/planner/grasp/kernel/shipped/{p.name}" for p in kernels.iterdir()} <= set(names)
    shipped = {name.rsplit("/", 1)[0].replace("/", ".") for name in names if name.endswith("/__init__.py")}
    assert not {package for package in shipped for hidden in NOT_SHIPPED if package.startswith(hidden)}
    (entry_points,) = [name for name in names if name.endswith(".dist-info/entry_points.txt")]
    assert "ogcp = ogcp.benchmarks.cli.app:main" in zipfile.ZipFile(wheel).read(entry_points).decode()


def test_the_installed_wheel_imports_finds_its_data_and_answers_help(wheel, tmp_path):
    target = tmp_path / "site"
    with zipfile.ZipFile(wheel) as archive:
        archive.extractall(target)  # what pip install --target does for a pure-Python wheel
    probe = (
        "import sys; sys.path.insert(0, sys.argv[1]); import ogcp, ogcp.planner.infra as infra; "
        "assert ogcp.__file__.startswith(sys.argv[1]), ogcp.__file__; "
        "print(infra.asset_path('hands/sdh.xml')); "
        "import importlib.util as u; print([n for n in ('planner', 'sim_eval', 'benchmarks') if u.find_spec(n)]); "
        "from ogcp.benchmarks.cli.app import main; sys.argv = ['ogcp', '--help']; main()"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe, str(target)], cwd=tmp_path, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    assert lines[0] == str(target / "ogcp" / "assets" / "hands" / "sdh.xml")
    assert lines[1] == "[]"  # no bare planner, sim_eval or benchmarks anywhere on the path
    assert "usage: ogcp" in done.stdout
