"""The asset locator: the wheel's ogcp_assets first, the checkout's assets/ otherwise, clear errors."""

from __future__ import annotations

import pytest

from planner.infra import OgcpError, assets


def test_finds_the_checkout_assets():
    assert "<mujoco" in assets.asset_path("hands/sdh.xml").read_text()


def test_prefers_the_installed_package_over_a_folder_named_assets(monkeypatch, tmp_path):
    installed, checkout = tmp_path / "ogcp_assets", tmp_path / "assets"
    for folder in (installed, checkout):
        (folder / "suites").mkdir(parents=True)
        (folder / "suites" / "x.toml").write_text(folder.name)
    monkeypatch.setattr(assets, "_CANDIDATES", (installed, checkout))
    assert assets.asset_path("suites/x.toml").read_text() == "ogcp_assets"


def test_missing_file_names_it():
    with pytest.raises(OgcpError, match="ogcp data file hands/nope.xml not found at .*install is incomplete"):
        assets.asset_path("hands/nope.xml")


def test_missing_folder_is_a_broken_install(monkeypatch, tmp_path):
    monkeypatch.setattr(assets, "_CANDIDATES", (tmp_path / "ogcp_assets", tmp_path / "assets"))
    with pytest.raises(OgcpError, match="data files are missing"):
        assets.asset_path("objects.toml")
