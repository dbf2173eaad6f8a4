"""What a wheel ships and what it requires, checked statically from pyproject.toml (no wheel is built here).

The wheel install itself (``pip install`` of a built wheel, then ``ogcp`` from another folder) is
a release check; these tests keep its inputs right: every code package listed, every file of
``assets/`` matched by a package-data pattern and found by the asset locator, ``py.typed`` shipped;
every dependency bounded below and pinned by ``constraints.txt`` within its range. No network:
which wheels exist on PyPI is ``python -m benchmarks.studies.wheels``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

from planner.infra import asset_path

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]
# Run from a checkout only: study scripts and speed benchmarks.
NOT_SHIPPED = {"benchmarks.studies", "benchmarks.perf"}


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
        for p in SETUPTOOLS["package-data"]["ogcp_assets"]
        for path in folder.glob(p)
    }


def test_every_code_package_is_listed_and_no_study_code_is():
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for top in ("planner", "sim_eval", "benchmarks")
        for init in (ROOT / top).rglob("__init__.py")
    }
    listed = set(SETUPTOOLS["packages"]) - {"ogcp_assets"}
    missing = sorted(found - NOT_SHIPPED - listed)
    assert not missing, f"add {missing} to [tool.setuptools] packages in pyproject.toml"
    assert not listed & NOT_SHIPPED
    assert listed <= found


def test_assets_folder_ships_as_the_ogcp_assets_package():
    assert "ogcp_assets" in SETUPTOOLS["packages"]
    assert SETUPTOOLS["package-dir"] == {"ogcp_assets": "assets"}


def test_package_data_covers_every_asset_and_every_pattern_matches():
    assert _shipped_assets() == set(_asset_files())
    for pattern in SETUPTOOLS["package-data"]["ogcp_assets"]:
        assert list((ROOT / "assets").glob(pattern)), f"package-data pattern {pattern!r} matches nothing"


@pytest.mark.parametrize("relative", _asset_files())
def test_the_locator_finds_every_shipped_file(relative):
    assert asset_path(relative) == ROOT / "assets" / relative


@pytest.mark.parametrize("package", ["planner", "sim_eval", "benchmarks"])
def test_packages_are_marked_typed(package):
    assert (ROOT / package / "py.typed").is_file()
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

    import planner

    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["dynamic"] == ["version"] and "version" not in pyproject["project"]
    assert "setuptools-scm>=8" in pyproject["build-system"]["requires"]
    assert planner.__version__ == importlib.metadata.version("ogcp")
