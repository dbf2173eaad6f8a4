"""What a wheel ships, checked statically from pyproject.toml (no wheel is built here).

The wheel install itself (``pip install`` of a built wheel, then ``ogcp`` from another folder) is
a release check; these tests keep its inputs right: every code package listed, every file of
``assets/`` matched by a package-data pattern and found by the asset locator, ``py.typed`` shipped.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from planner.infra import asset_path

ROOT = Path(__file__).resolve().parent.parent
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
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
