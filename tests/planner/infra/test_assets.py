"""The asset locator: ogcp/assets of a wheel or the checkout's assets/, clear errors."""

from __future__ import annotations

import pytest

from ogcp.planner.infra import OgcpError, assets


def test_finds_the_checkout_assets():
    assert "<mujoco" in assets.asset_path("hands/sdh.xml").read_text()


def test_reads_the_folder_it_is_given(monkeypatch, tmp_path):
    (tmp_path / "suites").mkdir()
    (tmp_path / "suites" / "x.toml").write_text("mine")
    monkeypatch.setattr(assets, "_FOLDER", tmp_path)
    assert assets.asset_path("suites/x.toml").read_text() == "mine"


def test_missing_file_names_it():
    with pytest.raises(OgcpError, match="ogcp data file hands/nope.xml not found at .*install is incomplete"):
        assets.asset_path("hands/nope.xml")


def test_missing_folder_is_a_broken_install(monkeypatch, tmp_path):
    monkeypatch.setattr(assets, "_FOLDER", tmp_path / "assets")
    with pytest.raises(OgcpError, match="data files are missing"):
        assets.asset_path("objects.toml")
